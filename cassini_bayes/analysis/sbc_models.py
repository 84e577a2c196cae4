"""Models that simulation-based calibration can run: the adapter contract and the registry.

An SBC campaign (:mod:`cassini_bayes.analysis.campaign`) needs four things from a model, bundled
in :class:`SbcModel`:

``prior_sample(key) -> {name: scalar}``
    One draw of the parameters from the *same* prior the posterior uses, one scalar per name in
    ``parameter_names`` (vector parameters are split into named scalars, e.g. the inertia vector
    into ``Ixx Iyy Izz Ixy Ixz Iyz``), in the units the posterior reports.
``simulate(key, params) -> data``
    Synthetic data (any pytree of arrays with fixed shapes, e.g. a ``Telemetry``) for those
    parameters, from the package's simulator.
``fit(key, data) -> SbcFit``
    Posterior draws of every named parameter, shape ``(chains, draws)`` each, **already thinned**
    so the draws are close to independent (Talts et al. 2018, Sec. 5.1), plus the number of
    divergent transitions after warm-up.
``parameter_names``
    The scalar parameters to rank, in a fixed order.

When ``vectorized`` is true all three functions are pure JAX (jit- and vmap-able, no Python
control flow on values): a batch of replicates is then simulated with one ``jax.vmap`` and fitted
with one ``jax.vmap`` of the sampler, every replicate's chains advancing in lock-step in one
compiled program (see :func:`nuts_fit`). A model whose fit is not traceable (e.g. one that calls
``numpyro.infer.MCMC`` with Python-side checks) sets ``vectorized=False``; its replicates are then
simulated in a vmapped batch and fitted one after the other.

Adapters are built by name from a :class:`ModelSpec` (plain data: the model name, an optional
scenario file's *text* and options), so that a Dask worker on another machine can rebuild the same
adapter, with the same compiled functions, from what the client sends it. Register a new model with
:func:`register`::

    @register("inertia")
    def _inertia(spec: ModelSpec) -> SbcModel: ...

Registered here:

``toy``
    A linear-Gaussian regression with unknown noise that tests the machinery (fully vectorised),
    with ``likelihood_noise_factor`` / ``simulator_noise_factor`` options that mis-specify it.
``inertia``
    The inertia posterior (:func:`cassini_bayes.inference.inertia.fit_inertia`) on RWA slews from
    the simulator (:func:`cassini_bayes.simulate.run.simulate_batch`); truth from the posterior's
    own prior (:func:`cassini_bayes.inference.inertia.sample_prior`). ``--scenario`` takes a
    simulator scenario TOML (default :data:`INERTIA_SCENARIO`: three one-axis slews, one hour).

``thrust`` and ``rwa4`` plug in the same way: a factory decorated with ``@register("thrust")``
that draws the truth from the fit's prior (thrust, ``tau_delay``, ``tau_rise``, ``tau_fall``;
``u4_x u4_y u4_z`` for RWA4), puts it into :class:`cassini_bayes.simulate.run.TruthParams`
(``thrust_n``, ``tau_s``, ``wheel_axes``) for ``simulate_batch`` and returns thinned draws of the
same names from the fit — see ``_inertia`` below, which is the pattern to copy.
"""

from __future__ import annotations

import functools
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from cassini_bayes.errors import InputError

__all__ = [
    "SbcFit",
    "SbcModel",
    "ModelSpec",
    "register",
    "registered_models",
    "build_model",
    "nuts_fit",
    "toy_model",
]


class SbcFit(NamedTuple):
    """Posterior draws of one replicate.

    Attributes
    ----------
    draws : dict of str to jax.Array
        ``name -> (chains, draws)`` thinned posterior draws, in the units of ``prior_sample``.
    n_divergent : jax.Array
        Number of divergent transitions after warm-up (all chains), integer scalar.
    """

    draws: dict[str, jax.Array]
    n_divergent: jax.Array


@dataclass(frozen=True)
class SbcModel:
    """A model as SBC sees it (see the module docstring for the contract).

    Attributes
    ----------
    name : str
        Registry name (``toy``, ``inertia``, …).
    parameter_names : tuple of str
        Scalar parameters to rank, in order.
    prior_sample : callable
        ``(key) -> {name: scalar}``.
    simulate : callable
        ``(key, params) -> data``.
    fit : callable
        ``(key, data) -> SbcFit``.
    vectorized : bool
        Whether the three functions are pure JAX and can be vmapped over replicates.
    settings : dict
        Sampler and scenario settings recorded in the run's ``summary.json``/``config.toml``.
    rhat_max : float
        A replicate with a split R-hat above this (any parameter, thinned draws) or any
        divergence counts as not converged. Its rank is kept (dropping replicates would bias SBC).
    simulate_batch : callable, optional
        ``(prior_keys (B,), sim_keys (B,)) -> ({name: (B,)}, batched data)``: a model whose prior
        sampler is not traceable (e.g. rejection sampling in NumPy) draws its truths here and
        calls the simulator's own vmapped batch. Default: ``jax.vmap`` of ``prior_sample`` and
        ``simulate``. Either way replicate ``i``'s truth and data depend on its keys only.
    """

    name: str
    parameter_names: tuple[str, ...]
    prior_sample: Callable[[jax.Array], dict[str, jax.Array]]
    simulate: Callable[[jax.Array, dict[str, jax.Array]], Any]
    fit: Callable[[jax.Array, Any], SbcFit]
    vectorized: bool = True
    settings: Mapping[str, Any] = field(default_factory=dict)
    rhat_max: float = 1.05
    simulate_batch: Callable[[jax.Array, jax.Array], tuple[dict[str, Any], Any]] | None = None


@dataclass(frozen=True)
class ModelSpec:
    """Plain-data recipe for an adapter: picklable, hashable, the same on every Dask worker.

    Attributes
    ----------
    name : str
        Registered model name.
    scenario_text : str or None
        Contents of the ``--scenario`` TOML file (not its path: workers may not share files).
    options : tuple of (str, value) pairs
        Extra settings (sampler sizes, mis-specification switches), sorted by name.
    scenario_source : str
        Where the scenario text came from (its file name), for error messages only.
    """

    name: str
    scenario_text: str | None = None
    options: tuple[tuple[str, Any], ...] = ()
    scenario_source: str = "<scenario>"

    @classmethod
    def make(cls, name: str, scenario_text: str | None = None, *,
             scenario_source: str = "<scenario>", **options: Any) -> ModelSpec:
        """Build a spec with options given as keywords."""
        return cls(name, scenario_text, tuple(sorted(options.items())), scenario_source)

    def scenario(self) -> dict[str, Any]:
        """The scenario TOML parsed into a dict (empty without one)."""
        if not self.scenario_text:
            return {}
        try:
            return tomllib.loads(self.scenario_text)
        except tomllib.TOMLDecodeError as e:
            raise InputError(f"not valid TOML ({e}); fix the file",
                             path=self.scenario_source) from None


_REGISTRY: dict[str, Callable[[ModelSpec], SbcModel]] = {}


def register(name: str):
    """Decorator registering an adapter factory ``(ModelSpec) -> SbcModel`` under ``name``."""

    def deco(factory):
        _REGISTRY[name] = factory
        return factory

    return deco


def registered_models() -> tuple[str, ...]:
    """Names of the registered models, sorted."""
    return tuple(sorted(_REGISTRY))


@functools.lru_cache(maxsize=16)
def build_model(spec: ModelSpec) -> SbcModel:
    """The adapter for ``spec``; cached, so repeated batches reuse the same compiled functions."""
    if spec.name not in _REGISTRY:
        raise InputError(f"unknown SBC model {spec.name!r}; choose one of "
                         f"{', '.join(registered_models())}")
    return _REGISTRY[spec.name](spec)


# ------------------------------------------------------------------- vectorisable NUTS fit


def nuts_fit(model: Callable, example_data: Any, names: tuple[str, ...], *,
             num_warmup: int, num_draws: int, num_chains: int = 2, thin: int = 1,
             init_radius: float = 2.0, target_accept_prob: float = 0.8,
             max_tree_depth: int = 10, dense_mass: bool = False) -> Callable:
    """A pure ``fit(key, data) -> SbcFit`` running NumPyro's NUTS, vmappable over replicates.

    NumPyro's functional sampler (:func:`numpyro.infer.hmc.hmc`, the core behind ``MCMC``) is
    driven by a ``lax.scan``; the model's data enter through ``potential_fn_gen`` so the same
    compiled program serves every replicate. ``jax.vmap`` of this function over replicates runs
    every replicate's chains in lock-step — the "vectorised chains across replicates" a campaign
    uses. Chains start uniformly in ``[-init_radius, init_radius]`` of the unconstrained space
    (NumPyro's ``init_to_uniform``) and adapt step size and a diagonal (or dense) mass matrix
    (Stan's windowed adaptation) during ``num_warmup`` steps.

    Parameters
    ----------
    model : callable
        NumPyro model ``model(data)``; ``names`` are sample or deterministic sites of it.
    example_data : pytree
        Data of the shapes the fit will see (used once, to find the parameter layout).
    names : tuple of str
        Sites to return, each a scalar.
    num_warmup, num_draws, num_chains, thin : int
        Warm-up steps, kept steps per chain, chains, thinning (keeps every ``thin``-th draw).

    Returns
    -------
    callable
        ``fit(key, data) -> SbcFit`` with draws of shape ``(num_chains, num_draws // thin)``.
    """
    from numpyro.infer.hmc import hmc
    from numpyro.infer.util import initialize_model

    info = initialize_model(jax.random.key(0), model, model_args=(example_data,),
                            dynamic_args=True)
    potential_fn_gen, postprocess_fn_gen = info.potential_fn, info.postprocess_fn
    z_layout = jax.tree.map(jnp.shape, info.param_info.z)
    leaves, treedef = jax.tree.flatten(z_layout, is_leaf=lambda x: isinstance(x, tuple))

    def init_z(key):
        keys = jax.random.split(key, len(leaves))
        vals = [jax.random.uniform(k, s, minval=-init_radius, maxval=init_radius)
                for k, s in zip(keys, leaves)]
        return jax.tree.unflatten(treedef, vals)

    def fit(key, data):
        init_kernel, sample_kernel = hmc(potential_fn_gen=potential_fn_gen, algo="NUTS")

        def chain(key):
            key_init, key_run = jax.random.split(key)
            state = init_kernel(init_z(key_init), num_warmup, model_args=(data,),
                                rng_key=key_run, target_accept_prob=target_accept_prob,
                                max_tree_depth=max_tree_depth, dense_mass=dense_mass)

            def step(s, _):
                s = sample_kernel(s, model_args=(data,))
                return s, (s.z, s.diverging)

            # one scan over warm-up and sampling: the NUTS kernel is compiled once
            _, (zs, diverging) = jax.lax.scan(step, state, None, length=num_warmup + num_draws)
            zs = jax.tree.map(lambda a: a[num_warmup + thin - 1::thin], zs)
            diverging = diverging[num_warmup:]
            values = jax.vmap(postprocess_fn_gen(data))(zs)
            return {n: values[n] for n in names}, jnp.sum(diverging)

        draws, diverging = jax.vmap(chain)(jax.random.split(key, num_chains))
        return SbcFit(draws, jnp.sum(diverging))

    return fit


# ------------------------------------------------------------------------------ toy model


def toy_model(*, n_obs: int = 20, likelihood_noise_factor: float = 1.0,
              simulator_noise_factor: float = 1.0, num_warmup: int = 150, num_draws: int = 150,
              num_chains: int = 2, thin: int = 3) -> SbcModel:
    """Linear-Gaussian regression with unknown noise, to test the SBC machinery.

    ``y_i = alpha + beta x_i + sigma ε_i`` on ``x`` evenly spaced in ``[-1, 1]`` (dimensionless),
    priors ``alpha, beta ~ Normal(0, 1)``, ``sigma ~ LogNormal(log 0.5, 0.3)``. The posterior is
    fitted by NUTS (:func:`nuts_fit`); ``2 · num_draws / thin`` draws are ranked.

    Two switches mis-specify it on purpose (SBC must then fail): the fit's likelihood uses
    ``likelihood_noise_factor · sigma``, the simulator ``simulator_noise_factor · sigma``. With
    ``likelihood_noise_factor = 0.5`` (or, equivalently for the ratio, ``simulator_noise_factor =
    2``) the likelihood's noise scale is half the data's: the posterior of ``sigma`` sits near twice
    the truth (or the truth's double is fitted), and its ranks pile up at one end. The
    simulator switch leaves the compiled sampler untouched, which the tests use to compile once.
    """
    x = jnp.linspace(-1.0, 1.0, n_obs)
    names = ("alpha", "beta", "sigma")

    def prior_sample(key):
        k_a, k_b, k_s = jax.random.split(key, 3)
        return {"alpha": jax.random.normal(k_a), "beta": jax.random.normal(k_b),
                "sigma": jnp.exp(_TOY_LOG_SIGMA_LOC + _TOY_LOG_SIGMA_SCALE
                                 * jax.random.normal(k_s))}

    def simulate(key, params):
        mean = params["alpha"] + params["beta"] * x
        return mean + simulator_noise_factor * params["sigma"] * jax.random.normal(key, x.shape)

    fit = _toy_fit(n_obs, likelihood_noise_factor, num_warmup, num_draws, num_chains, thin)
    settings = {"n_obs": n_obs, "likelihood_noise_factor": likelihood_noise_factor,
                "simulator_noise_factor": simulator_noise_factor, "num_warmup": num_warmup,
                "num_draws": num_draws, "num_chains": num_chains, "thin": thin}
    return SbcModel("toy", names, prior_sample, simulate, fit, True, settings)


_TOY_LOG_SIGMA_LOC = float(jnp.log(0.5))
_TOY_LOG_SIGMA_SCALE = 0.3


@functools.lru_cache(maxsize=8)
def _toy_fit(n_obs, likelihood_noise_factor, num_warmup, num_draws, num_chains, thin):
    import numpyro
    import numpyro.distributions as dist

    x = jnp.linspace(-1.0, 1.0, n_obs)

    def model(y):
        alpha = numpyro.sample("alpha", dist.Normal(0.0, 1.0))
        beta = numpyro.sample("beta", dist.Normal(0.0, 1.0))
        sigma = numpyro.sample("sigma", dist.LogNormal(_TOY_LOG_SIGMA_LOC, _TOY_LOG_SIGMA_SCALE))
        numpyro.sample("y", dist.Normal(alpha + beta * x, likelihood_noise_factor * sigma), obs=y)

    return nuts_fit(model, jnp.zeros(n_obs), ("alpha", "beta", "sigma"), num_warmup=num_warmup,
                    num_draws=num_draws, num_chains=num_chains, thin=thin)


_TOY_KEYS = {"n_obs", "likelihood_noise_factor", "simulator_noise_factor", "num_warmup",
             "num_draws", "num_chains", "thin"}


@register("toy")
def _toy(spec: ModelSpec) -> SbcModel:
    settings = {**spec.scenario().get("toy", spec.scenario()), **dict(spec.options)}
    unknown = set(settings) - _TOY_KEYS
    if unknown:
        raise InputError(f"unknown toy-model setting(s) {sorted(unknown)}; allowed: "
                         f"{sorted(_TOY_KEYS)}", path=spec.scenario_source)
    return toy_model(**settings)


# --------------------------------------------------------------------------- inertia model

INERTIA_SCENARIO = """\
# Default SBC scenario of the inertia model: one hour of RWA slews about Y, X and Z (40°, 30°,
# 30° at 2.5 mrad/s), telemetry at 0.25 Hz, the March-2000 spacecraft as prior, flight noise.
name = "sbc_inertia_slews"
description = "SBC: three RWA slews (Y, X, Z), one hour at 0.25 Hz"
seed = 0

[run]
duration_s = 3600.0
dt_s = 0.25
sample_period_s = 4.0
control = "rwa"

[truth]
model = "models/cassini_2000_03_15.toml"

[prior]
model = "models/cassini_2000_03_15.toml"

[initial]
wheels_on = ["RWA1", "RWA2", "RWA3"]
q = [0.0, 0.0, 0.0, 1.0]
wheel_rpm = { RWA1 = 300.0, RWA2 = -400.0, RWA3 = 350.0 }

[rwa_controller]
bandwidth_rad_s = 0.1
damping = 0.7

[[slew]]
t_start_s = 300.0
axis = [0.0, 1.0, 0.0]
angle_deg = 40.0
rate_mrad_s = 2.5
accel_mrad_s2 = 0.025

[[slew]]
t_start_s = 1400.0
axis = [1.0, 0.0, 0.0]
angle_deg = 30.0
rate_mrad_s = 2.5
accel_mrad_s2 = 0.025

[[slew]]
t_start_s = 2500.0
axis = [0.0, 0.0, 1.0]
angle_deg = 30.0
rate_mrad_s = 2.5
accel_mrad_s2 = 0.025

[noise]
gyro_rad_s = 1.0e-6
star_tracker_rad = 5.0e-5
tach_noise_rpm = 0.05
tach_quantum_rpm = 0.1
"""

_INERTIA_KEYS = {"num_warmup", "num_draws", "num_chains", "thin", "torque",
                 "wheel_inertia_factor"}


@register("inertia")
def _inertia(spec: ModelSpec) -> SbcModel:
    """Inertia tensor from RWA slews: truth from the model's own prior, the slew simulator, NUTS.

    Truth per replicate: ``Ixx … Iyz`` from :func:`cassini_bayes.inference.inertia.sample_prior`
    (the stated prior of the posterior, rejection of non-physical tensors) with the scenario's
    ``[prior]`` spacecraft, and a constant inertial torque from its ``T_N`` prior; the rest of the
    truth (wheels, noise levels) is the scenario's. Data: the scenario's slews through
    :func:`cassini_bayes.simulate.run.simulate_batch` (one vmapped call per batch). Fit:
    :func:`cassini_bayes.inference.inertia.fit_inertia` per replicate (its Laplace centring is
    NumPy, so fits run one after the other; the compiled sampler is reused). Options:
    ``num_warmup, num_draws, num_chains, thin`` (default 300, 300, 2, 3), ``torque`` (True), and
    ``wheel_inertia_factor`` (1.0): the simulator's wheel spin inertias times this factor while
    the fit keeps the model's — a deliberate mis-specification (the wheel/spacecraft inertia
    scale, Psiaki 2005) that SBC must detect.
    """
    import numpy as np

    from cassini_bayes.inference.inertia import INERTIA_NAMES, fit_inertia, inertia_prior
    from cassini_bayes.inference.inertia import sample_prior as inertia_sample_prior
    from cassini_bayes.inference.runner import SamplerSettings
    from cassini_bayes.simulate.run import TruthParams, simulate_batch, truth_params
    from cassini_bayes.simulate.scenario import scenario_from_dict
    from cassini_bayes.telemetry import Telemetry

    scenario = scenario_from_dict(spec.scenario() if spec.scenario_text
                                  else tomllib.loads(INERTIA_SCENARIO), src=spec.scenario_source)
    opts = {"num_warmup": 300, "num_draws": 300, "num_chains": 2, "thin": 3, "torque": True,
            "wheel_inertia_factor": 1.0, **dict(spec.options)}
    unknown = set(opts) - _INERTIA_KEYS
    if unknown:
        raise InputError(f"unknown inertia SBC option(s) {sorted(unknown)}; allowed: "
                         f"{sorted(_INERTIA_KEYS)}")
    names = tuple(INERTIA_NAMES)
    prior = inertia_prior(scenario.prior)
    base = truth_params(scenario)
    torque = bool(opts["torque"])
    settings = SamplerSettings(chains=opts["num_chains"], warmup=opts["num_warmup"],
                               draws=opts["num_draws"], chain_method="vectorized")
    thin = int(opts["thin"])

    def draw_truth(key):
        d = inertia_sample_prior(key, prior, 1, torque=torque)
        pi = np.array([d[n][0] for n in names])
        tq = d["T_N"][0, 0] if torque else np.zeros(3)
        return pi, tq

    def prior_sample(key):
        pi, _ = draw_truth(key)
        return dict(zip(names, pi))

    def simulate_batch_fn(prior_keys, sim_keys):
        drawn = [draw_truth(k) for k in prior_keys]
        pi = np.stack([d[0] for d in drawn])
        tq = np.stack([d[1] for d in drawn])
        b = pi.shape[0]

        def tile(a):
            return jnp.broadcast_to(jnp.asarray(a), (b,) + jnp.shape(a))

        # The scenario's truth for everything else, tiled over the batch (any field the
        # simulator adds later is carried along unchanged).
        tiled = TruthParams(*(tile(x) for x in base))
        truth = tiled._replace(
            inertia=jnp.asarray(pi), torque_inertial_nm=jnp.asarray(tq),
            wheel_inertias=tiled.wheel_inertias * float(opts["wheel_inertia_factor"]))
        arrays = simulate_batch(sim_keys, scenario, truth)
        return dict(zip(names, pi.T)), arrays

    def simulate(key, params):
        raise NotImplementedError("the inertia adapter simulates in batches (simulate_batch)")

    def fit(key, arrays):
        tel = Telemetry(t=np.asarray(arrays.t), q=np.asarray(arrays.q_meas),
                        omega=np.asarray(arrays.omega_meas),
                        wheel_rates=np.asarray(arrays.wheel_rates_meas),
                        wheel_names=scenario.wheel_names, on_times=None,
                        source="<sbc inertia replicate>")
        post = fit_inertia(key, [tel], scenario.prior, torque=torque, settings=settings,
                           prior_draws=0)
        idata = post.idata
        draws = {n: jnp.asarray(idata.posterior[n].values[:, thin - 1::thin]) for n in names}
        n_div = jnp.asarray(int(idata.sample_stats["diverging"].values.sum()))
        return SbcFit(draws, n_div)

    record = {**opts, "scenario": scenario.name, "prior_model": scenario.prior_model_path}
    return SbcModel("inertia", names, prior_sample, simulate, fit, vectorized=False,
                    settings=record, rhat_max=1.05, simulate_batch=simulate_batch_fn)
