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
    All post-warm-up posterior draws of every named parameter, shape ``(chains, draws)`` each,
    plus the number of divergent transitions after warm-up. The campaign thins them by the
    model's ``settings["thin"]`` (so the ``L`` ranked draws are close to independent, Talts et al.
    2018, Sec. 5.1) and checks that thinning against each replicate's effective sample size.
``parameter_names``
    The scalar parameters to rank, in a fixed order.

When ``vectorized`` is true ``fit`` is pure JAX (jit- and vmap-able, no Python control flow on
values): a batch of replicates is fitted with one ``jax.vmap`` of the package's NUTS program,
every replicate's chains advancing in lock-step in one compiled program (see :func:`nuts_fit`).
A model may then also give ``prepare(data_i) -> fit data``, a per-replicate step that is not
traceable (the inertia model's NumPy data preparation): the campaign runs it replicate by
replicate and stacks its outputs, which must have the same shapes for every replicate, before the
one vmapped fit. A model whose fit is not traceable at all (the thrust and RWA4 fits, whose
Laplace steps run in NumPy/SciPy between compiled programs) sets ``vectorized=False``; its
replicates are simulated in a vmapped batch and fitted one after the other.

Adapters are built by name from a :class:`ModelSpec` (plain data: the model name, an optional
scenario file's *text* and options), so that a Dask worker on another machine can rebuild the same
adapter, with the same compiled functions, from what the client sends it. Register a new model with
:func:`register`::

    @register("inertia")
    def _inertia(spec: ModelSpec) -> SbcModel: ...

Registered here (the simulator models' default scenarios are shipped files under
``experiments/scenarios/sbc/``, which a worker reads from its own installed package):

``toy``
    A linear-Gaussian regression with unknown noise that tests the machinery (fully vectorised),
    with ``likelihood_noise_factor`` / ``simulator_noise_factor`` options that mis-specify it.
``inertia``
    The inertia posterior (:func:`cassini_bayes.inference.inertia.fit_inertia`) on RWA slews from
    the simulator (:func:`cassini_bayes.simulate.run.simulate_batch`); truth from the posterior's
    own prior (:func:`cassini_bayes.inference.inertia.sample_prior`). ``--scenario`` takes a
    simulator scenario TOML (default :data:`INERTIA_SCENARIO`: three one-axis slews, one hour).
    Vectorised: the package's data preparation per replicate, then one vmapped NUTS program.
    ``--set robust=true``: the robust model (the CLI fit's default), every nuisance truth drawn
    from its prior and flown (:func:`robust_inertia_truth`).
``thrust``
    Mean thrust and pulse time constants (:func:`cassini_bayes.inference.thrust.fit_thrust`,
    mode ``mean``) on a short RCS-controlled wheel-biasing event (:data:`THRUST_SCENARIO`); truth
    ``F, tau_delay, tau_rise, tau_fall`` from the fit's prior into ``TruthParams.thrust_n`` and
    ``tau_s``. Mis-specification: ``pulse_dynamics=False`` (ideal rectangular pulses simulated),
    ``thrust_factor``. ``--set robust=true``: the robust model (the CLI fit's default), every
    truth drawn from its prior and flown (:mod:`cassini_bayes.analysis.sbc_thrust_robust`; option
    ``mode``, ``thruster`` for per-thruster thrusts and the centre of mass).
``rwa4``
    A wheel's spin axis and the inertia (:func:`cassini_bayes.inference.rwa4.fit_rwa4`; options
    ``wheel``, default RWA4, and ``method``, default Brown's RCS method) on a short spin-up with
    widened dead-bands (:data:`RWA4_SCENARIO`); truth ``u4`` uniform on the sphere (or the cone
    prior) into ``TruthParams.wheel_axes`` and the inertia from its prior. ``--set robust=true``:
    the robust model, every nuisance truth drawn from its prior and flown
    (:func:`robust_rwa4_truth`). Mis-specification: ``rwa4_inertia_factor``.

The thrust and RWA4 fits prepare their data (a Laplace step) in NumPy/SciPy inside
``fit_thrust``/``fit_rwa4`` and are not traceable: they run one replicate after the other
(``vectorized=False``), and a campaign uses many cores through the Dask executor (one
single-threaded worker per core). Vectorising them as ``inertia`` is — their preparation as
``prepare``, their NumPyro model through :func:`nuts_fit` — needs those steps as functions of their
own in :mod:`cassini_bayes.inference.thrust` and :mod:`cassini_bayes.inference.rwa4`.
"""

from __future__ import annotations

import functools
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
from jax import lax

from cassini_bayes._paths import SCENARIOS_DIR
from cassini_bayes.errors import InputError, spelled

__all__ = [
    "SbcFit",
    "SbcModel",
    "ModelSpec",
    "register",
    "registered_models",
    "build_model",
    "nuts_fit",
    "robust_inertia_truth",
    "robust_rwa4_truth",
]


class SbcFit(NamedTuple):
    """Posterior draws of one replicate.

    Attributes
    ----------
    draws : dict of str to jax.Array
        ``name -> (chains, draws)`` post-warm-up posterior draws (not thinned), in the units of
        ``prior_sample``.
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
        ``(key, data) -> SbcFit``; with ``prepare``, ``data`` is what ``prepare`` returns.
    vectorized : bool
        Whether ``fit`` is pure JAX and is vmapped over replicates (and, without
        ``simulate_batch``, ``prior_sample`` and ``simulate`` too).
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
    prepare : callable, optional
        ``(data of one replicate, NumPy) -> fit data`` (a pytree of arrays of the same shapes for
        every replicate), run replicate by replicate before a vectorised ``fit``; an exception
        there marks that replicate failed.
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
    prepare: Callable[[Any], Any] | None = None


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


@functools.lru_cache(maxsize=32)
def nuts_fit(model: Callable, names: tuple[str, ...], settings) -> Callable:
    """A pure ``fit(key, data) -> SbcFit``: the package's NUTS sampler, vmappable over data sets.

    This is not a second sampler: it calls the one compiled NUTS program of
    :mod:`cassini_bayes.inference.runner` (its windowed step-size and mass-matrix adaptation,
    warm-up and draws in one XLA program, chains vectorised) and sets up its initial values and
    keys exactly as :func:`~cassini_bayes.inference.runner.run_nuts` does, so ``fit(key, kwargs)``
    draws what ``run_nuts(key, model, model_kwargs=kwargs, settings=settings)`` draws (tested for
    the inertia model to rounding: vmapping over replicates may reorder floating-point
    reductions). What ``run_nuts`` adds — the InferenceData, its prior group, the ArviZ
    diagnostics — is exactly what a campaign does not need per replicate; leaving it out makes the
    fit a pure JAX function, and ``jax.vmap`` of it over replicates runs every replicate's chains
    in lock-step in one compiled program (one compilation per model and shapes; see
    :mod:`cassini_bayes.analysis.campaign`).

    Parameters
    ----------
    model : callable
        NumPyro model taking its data as keyword arguments, with unconstrained latent sites (the
        runner's contract); ``names`` are sample or deterministic sites of it, each a scalar.
    names : tuple of str
        Sites to return.
    settings : cassini_bayes.inference.runner.SamplerSettings
        Chains, warm-up, draws, mass matrix, target acceptance, tree depth (``chain_method`` and
        ``progress`` are ignored: chains are vectorised, no progress bar).

    Returns
    -------
    callable
        ``fit(key, kwargs) -> SbcFit`` with all post-warm-up draws, shape ``(chains, draws)``
        each (the campaign thins them); one object per (model, names, settings), so adapters
        that share a sampler share its compiled programs.
    """
    from cassini_bayes.inference.runner import _sampler_for, _site_shapes

    settings = settings._replace(chain_method="vectorized", progress=False)
    sampler = _sampler_for(model, settings, "vectorized")

    def fit(key, kwargs):
        key_mcmc, _, key_init = jax.random.split(key, 3)  # as run_nuts: sampler, prior, init
        shapes = _site_shapes(model, kwargs)
        init_keys = jax.random.split(key_init, len(shapes))
        init_z = {name: jax.random.uniform(k, (settings.chains,) + shp, minval=-2.0, maxval=2.0)
                  for k, (name, shp) in zip(init_keys, sorted(shapes.items()))}
        state = sampler.start(jax.random.split(key_mcmc, settings.chains), init_z, kwargs)
        # the runner's loop (``advance`` called piece by piece from Python) as one scan, so that
        # the whole fit is one traced function that vmaps over replicates
        n_pieces = (settings.warmup + settings.draws) // sampler.piece
        _, rec = lax.scan(lambda st, _: sampler.advance(st, kwargs), state, None,
                          length=n_pieces)

        def kept(x):  # (pieces, chains, piece, ...) -> the draws, (chains, draws, ...)
            x = jnp.moveaxis(x, 0, 1)
            return x.reshape((x.shape[0], -1) + x.shape[3:])[:, settings.warmup:]

        rec = jax.tree.map(kept, rec)
        samples, stats = sampler.finish(rec[0], rec[1:], kwargs)
        return SbcFit({n: samples[n] for n in names}, jnp.sum(stats["diverging"]))

    return fit


# ------------------------------------------------------------------------------ toy model


def _toy_model(*, n_obs: int = 20, likelihood_noise_factor: float = 1.0,
              simulator_noise_factor: float = 1.0, num_warmup: int = 150, num_draws: int = 150,
              num_chains: int = 2, thin: int = 3) -> SbcModel:
    """Linear-Gaussian regression with unknown noise, to test the SBC machinery.

    ``y_i = alpha + beta x_i + sigma ε_i`` on ``x`` evenly spaced in ``[-1, 1]`` (dimensionless),
    priors ``alpha, beta ~ Normal(0, 1)``, ``sigma ~ LogNormal(log 0.5, 0.3)``. The posterior is
    fitted by the package's NUTS (:func:`nuts_fit`; ``sigma`` sampled as ``log sigma``, the
    runner's unconstrained coordinates, with a diagonal mass matrix and target acceptance 0.8);
    ``num_chains · num_draws / thin`` draws are ranked.

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
        noise = simulator_noise_factor * params["sigma"] * jax.random.normal(key, x.shape)
        return {"y": mean + noise}

    fit = _toy_fit(n_obs, likelihood_noise_factor, num_warmup, num_draws, num_chains)
    settings = {"n_obs": n_obs, "likelihood_noise_factor": likelihood_noise_factor,
                "simulator_noise_factor": simulator_noise_factor, "num_warmup": num_warmup,
                "num_draws": num_draws, "num_chains": num_chains, "thin": thin}
    return SbcModel("toy", names, prior_sample, simulate, fit, True, settings)


_TOY_LOG_SIGMA_LOC = float(jnp.log(0.5))
_TOY_LOG_SIGMA_SCALE = 0.3


@functools.lru_cache(maxsize=8)
def _toy_numpyro_model(n_obs: int, likelihood_noise_factor: float) -> Callable:
    """The toy model's NumPyro model ``model(y)`` (one object per setting: compiled once)."""
    import numpyro
    import numpyro.distributions as dist

    x = jnp.linspace(-1.0, 1.0, n_obs)

    def model(y):
        alpha = numpyro.sample("alpha", dist.Normal(0.0, 1.0))
        beta = numpyro.sample("beta", dist.Normal(0.0, 1.0))
        log_sigma = numpyro.sample("log_sigma", dist.Normal(_TOY_LOG_SIGMA_LOC,
                                                            _TOY_LOG_SIGMA_SCALE))
        sigma = numpyro.deterministic("sigma", jnp.exp(log_sigma))
        numpyro.sample("y", dist.Normal(alpha + beta * x, likelihood_noise_factor * sigma), obs=y)

    return model


def _toy_settings(num_warmup: int, num_draws: int, num_chains: int):
    """The toy model's NUTS settings: a diagonal mass matrix, target acceptance 0.8."""
    from cassini_bayes.inference.runner import SamplerSettings

    return SamplerSettings(chains=num_chains, warmup=num_warmup, draws=num_draws,
                           dense_mass=False, target_accept=0.8)


@functools.lru_cache(maxsize=8)
def _toy_fit(n_obs, likelihood_noise_factor, num_warmup, num_draws, num_chains):
    return nuts_fit(_toy_numpyro_model(n_obs, likelihood_noise_factor), ("alpha", "beta", "sigma"),
                    _toy_settings(num_warmup, num_draws, num_chains))


_TOY_KEYS = {"n_obs", "likelihood_noise_factor", "simulator_noise_factor", "num_warmup",
             "num_draws", "num_chains", "thin"}


@register("toy")
def _toy(spec: ModelSpec) -> SbcModel:
    from_file = spec.scenario().get("toy", spec.scenario())
    settings = {**from_file, **dict(spec.options)}
    for where, keys in ((spec.scenario_source, set(from_file)),
                        (spelled("--set", "options"), set(dict(spec.options)))):
        unknown = keys - _TOY_KEYS
        if unknown:
            raise InputError(f"unknown toy-model setting(s) {sorted(unknown)}; allowed: "
                             f"{sorted(_TOY_KEYS)}", path=where)
    return _toy_model(**settings)


# --------------------------------------------------------------------------- inertia model

# default scenario: one hour of RWA slews about Y, X and Z (the file's header says more)
INERTIA_SCENARIO = SCENARIOS_DIR / "sbc" / "sbc_inertia_slews.toml"

_INERTIA_KEYS = {"num_warmup", "num_draws", "num_chains", "thin", "torque",
                 "wheel_inertia_factor", "robust", "rank_nuisance"}
_AXES = ("x", "y", "z")


def _nuisance_names(wheels: tuple[str, ...]) -> tuple[str, ...]:
    """The robust inertia model's ranked nuisance scalars: gyro scale factor and bias per axis
    (one file) and each active wheel's spin-inertia scale ``c_k``."""
    return (tuple(f"gyro_scale[{a}]" for a in _AXES) + tuple(f"gyro_bias[{a}]" for a in _AXES)
            + tuple(f"wheel_scale[{w}]" for w in wheels))


def _nuisance_scalars(sites: Mapping[str, Any], wheels: tuple[str, ...]) -> dict[str, Any]:
    """:func:`_nuisance_names` from the sites ``gyro_scale`` (..., 3), ``gyro_bias``
    (..., 1, 3) and ``wheel_scale`` (..., K) of one file's draws or prior draws."""
    out = {f"gyro_scale[{a}]": sites["gyro_scale"][..., i] for i, a in enumerate(_AXES)}
    out.update({f"gyro_bias[{a}]": sites["gyro_bias"][..., 0, i] for i, a in enumerate(_AXES)})
    out.update({f"wheel_scale[{w}]": sites["wheel_scale"][..., k] for k, w in enumerate(wheels)})
    return out


def robust_inertia_truth(key, scenario, *, torque: bool = True) -> dict[str, Any]:
    """One draw of every parameter of the robust inertia model from its own prior, for
    ``scenario``'s ``[prior]`` spacecraft and active wheels (one telemetry file).

    :func:`~cassini_bayes.inference.inertia.sample_prior` with the model's nuisance layout
    (:func:`~cassini_bayes.inference.nuisance.nuisance_layout`, as
    :func:`~cassini_bayes.inference.inertia.prepare_inertia` builds it): ``Ixx … Iyz``, ``T_N``
    and, for the one file, ``gyro_bias`` (3,) rad/s, ``gyro_scale`` (3,), ``wheel_scale`` (K,)
    each wheel's total ``c_k = c_s + d_k``, ``wheel_scale_common`` (the shared ``c_s``, when the
    model has it), ``wheel_tilt`` (K, 2) rad, ``T_body`` (3,) N m and, with ``torque``,
    ``T_N_rate`` (3,) N m/s; and ``wheels``, the K wheel names. The same function the fit's
    ``prior`` group uses, so the truth's prior is the model's.
    """
    import numpy as np

    from cassini_bayes.inference.inertia import inertia_prior, sample_prior
    from cassini_bayes.inference.nuisance import nuisance_layout

    layout = nuisance_layout(scenario.prior, 1, _active_wheels(scenario), torque_rate=torque)
    d = sample_prior(key, inertia_prior(scenario.prior), 1, torque=torque, layout=layout)
    out = {n: np.asarray(v)[0] for n, v in d.items()}
    for site in ("gyro_bias", "T_body", "T_N_rate", "T_N", "H0"):
        if site in out:
            out[site] = out[site][0]                        # the one file
    out["wheels"] = layout.wheels
    return out


def _active_wheels(scenario) -> tuple[str, ...]:
    """The wheels the scenario runs, in its order (the robust model's nuisance wheels)."""
    return tuple(scenario.prior.wheel(n).name
                 for n, on in zip(scenario.wheel_names, scenario.wheels_on) if on)


@register("inertia")
def _inertia(spec: ModelSpec) -> SbcModel:
    """Inertia tensor from RWA slews: truth from the model's own prior, the slew simulator, NUTS.

    Truth per replicate: ``Ixx … Iyz`` from :func:`cassini_bayes.inference.inertia.sample_prior`
    (the stated prior of the posterior, rejection of non-physical tensors) with the scenario's
    ``[prior]`` spacecraft, and a constant inertial torque from its ``T_N`` prior; the rest of the
    truth (wheels, noise levels) is the scenario's. Data: the scenario's slews through
    :func:`cassini_bayes.simulate.run.simulate_batch` (one vmapped call per batch). Fit: the
    idealised model of :func:`cassini_bayes.inference.inertia.fit_inertia` (``robust=False``: the
    simulator draws no sensor or wheel errors), in its two steps: per replicate the package's own
    data preparation :func:`~cassini_bayes.inference.inertia.prepare_inertia` (empirical-Bayes GLS,
    sufficient statistics, Laplace whitening; NumPy), then one ``jax.vmap`` over the batch of the
    package's NUTS program on those statistics (:func:`nuts_fit` on
    :func:`~cassini_bayes.inference.inertia.inertia_model`): the same draws ``fit_inertia`` gives
    with the same key, all replicates of a batch in one compiled call.

    ``robust=True`` checks the robust model instead (``fit inertia``'s default): each replicate
    also draws every nuisance parameter from that model's prior (:func:`robust_inertia_truth`:
    gyro bias and scale factor, each wheel's spin-inertia scale with the shared part, wheel-axis
    tilts, body-fixed torque, the inertial torque's rate), flies the slews with them
    (:func:`~cassini_bayes.simulate.with_errors`, the torques into the truth) and fits the robust
    model; with ``rank_nuisance`` (default True) the gyro scale factors and biases and each
    wheel's scale ``c_k`` are ranked beside the inertia (:func:`_nuisance_names`).

    Options: ``num_warmup, num_draws, num_chains, thin`` (default 300, 300, 2, 3), ``torque``
    (True), ``robust`` (False), ``rank_nuisance`` (True), and ``wheel_inertia_factor`` (1.0): the
    simulator's wheel spin inertias times this factor while the fit keeps the model's — a
    deliberate mis-specification (the wheel/spacecraft inertia scale, Psiaki 2005) that SBC must
    detect.
    """
    import numpy as np

    from cassini_bayes.inference.inertia import (
        INERTIA_NAMES,
        inertia_model,
        inertia_prior,
        prepare_inertia,
    )
    from cassini_bayes.inference.inertia import sample_prior as inertia_sample_prior
    from cassini_bayes.inference.nuisance import nuisance_layout
    from cassini_bayes.simulate.run import noise_params, simulate_batch, truth_params, with_errors

    scenario = _scenario(spec, INERTIA_SCENARIO)
    opts = {"num_warmup": 300, "num_draws": 300, "num_chains": 2, "thin": 3, "torque": True,
            "wheel_inertia_factor": 1.0, "robust": False, **dict(spec.options)}
    _check_options("inertia", opts, _INERTIA_KEYS)
    robust = bool(opts["robust"])
    if robust:
        opts.setdefault("rank_nuisance", True)
    elif opts.get("rank_nuisance"):
        raise InputError("inertia SBC option rank_nuisance needs robust=true (the idealised "
                         "model has no nuisance parameters)")
    torque = bool(opts["torque"])
    wheels = _active_wheels(scenario)
    extra = _nuisance_names(wheels) if robust and opts["rank_nuisance"] else ()
    names = tuple(INERTIA_NAMES) + extra
    prior = inertia_prior(scenario.prior)
    base, base_noise = truth_params(scenario), noise_params(scenario)
    factor = float(opts["wheel_inertia_factor"])
    if robust:
        layout = nuisance_layout(scenario.prior, 1, wheels, torque_rate=torque)
        model = inertia_model(torque, True, layout.wheel_errors, common=layout.has_common,
                              torque_rate=torque)
    else:
        model = inertia_model(torque, False)

    def draw_truth(key):
        if robust:
            return robust_inertia_truth(key, scenario, torque=torque)
        d = inertia_sample_prior(key, prior, 1, torque=torque)
        return {**{n: d[n][0] for n in INERTIA_NAMES},
                "T_N": d["T_N"][0, 0] if torque else np.zeros(3)}

    def ranked(d):
        out = {n: d[n] for n in INERTIA_NAMES}
        if extra:
            out.update(_nuisance_scalars({"gyro_scale": d["gyro_scale"],
                                          "gyro_bias": d["gyro_bias"][None],
                                          "wheel_scale": d["wheel_scale"]}, wheels))
        return out

    def prior_sample(key):
        return ranked(draw_truth(key))

    def one_truth(d):
        """The simulator's truth and noise of one drawn replicate."""
        zero = np.zeros(3)
        tp = base._replace(inertia=jnp.asarray([d[n] for n in INERTIA_NAMES]),
                           torque_inertial_nm=jnp.asarray(d.get("T_N", zero)))
        nz = base_noise
        if robust:
            tp = tp._replace(torque_body_nm=jnp.asarray(d["T_body"]),
                             torque_inertial_rate_nm_s=jnp.asarray(d.get("T_N_rate", zero)))
            tp, nz = with_errors(scenario, tp, nz,
                                 wheel_scale=dict(zip(d["wheels"], d["wheel_scale"])),
                                 wheel_tilt_rad=dict(zip(d["wheels"], d["wheel_tilt"])),
                                 gyro_bias_rad_s=d["gyro_bias"], gyro_scale_factor=d["gyro_scale"])
        return tp._replace(wheel_inertias=tp.wheel_inertias * factor), nz

    def simulate_batch_fn(prior_keys, sim_keys):
        drawn = [draw_truth(k) for k in prior_keys]
        pairs = [one_truth(d) for d in drawn]
        stack = functools.partial(jax.tree.map, lambda *xs: jnp.stack([jnp.asarray(x)
                                                                       for x in xs]))
        truth = stack(*[p[0] for p in pairs])
        if robust:
            arrays = simulate_batch(sim_keys, scenario, truth, stack(*[p[1] for p in pairs]),
                                    noise_batched=True)
        else:
            arrays = simulate_batch(sim_keys, scenario, truth)
        params = [ranked(d) for d in drawn]
        return {n: np.array([p[n] for p in params]) for n in names}, arrays

    def simulate(key, params):
        raise NotImplementedError("the inertia adapter simulates in batches (simulate_batch)")

    def prepare(arrays):
        tel = _telemetry(arrays, scenario, "<sbc inertia replicate>")
        problem = prepare_inertia([tel], scenario.prior, torque=torque, robust=robust)
        if robust and problem.layout.wheels != wheels:
            raise RuntimeError(f"replicate's active wheels {problem.layout.wheels} are not the "
                               f"scenario's {wheels}")
        return {"data": problem.data}

    sites = tuple(INERTIA_NAMES) + (("gyro_scale", "gyro_bias", "wheel_scale") if extra else ())
    site_fit = nuts_fit(model, sites, _sampler_settings(opts))

    def fit(key, kwargs):
        out = site_fit(key, kwargs)
        draws = {n: out.draws[n] for n in INERTIA_NAMES}
        if extra:
            draws.update(_nuisance_scalars(out.draws, wheels))
        return SbcFit(draws, out.n_divergent)

    record = {**opts, "scenario": scenario.name, "prior_model": scenario.prior_model_path}
    return SbcModel("inertia", names, prior_sample, simulate, fit if extra else site_fit,
                    vectorized=True, settings=record, rhat_max=1.05,
                    simulate_batch=simulate_batch_fn, prepare=prepare)


# ---------------------------------------------------------------------------- shared helpers


def _scenario(spec: ModelSpec, default: Path):
    """The :class:`~cassini_bayes.simulate.scenario.Scenario` of ``spec``: its ``--scenario``
    text, else the model's shipped default scenario file ``default``."""
    from cassini_bayes.simulate.scenario import load_scenario, scenario_from_dict

    if spec.scenario_text:
        return scenario_from_dict(spec.scenario(), src=spec.scenario_source)
    return load_scenario(default)


def _sampler_settings(opts: Mapping[str, Any]):
    """The :class:`~cassini_bayes.inference.runner.SamplerSettings` of an adapter's options."""
    from cassini_bayes.inference.runner import SamplerSettings

    return SamplerSettings(chains=int(opts["num_chains"]), warmup=int(opts["num_warmup"]),
                           draws=int(opts["num_draws"]), chain_method="vectorized")


def _check_options(model: str, opts: Mapping[str, Any], allowed: set[str]) -> None:
    unknown = set(opts) - allowed
    if unknown:
        raise InputError(f"unknown {model} SBC option(s) {sorted(unknown)}; allowed: "
                         f"{sorted(allowed)}")


def _tiled_truth(base, b: int):
    """The scenario's :class:`~cassini_bayes.simulate.run.TruthParams` tiled over a batch."""
    from cassini_bayes.simulate.run import TruthParams

    return TruthParams(*(jnp.broadcast_to(jnp.asarray(x), (b,) + jnp.shape(x)) for x in base))


def _replicate(arrays, i: int):
    """Replicate ``i`` of batched simulator output, as NumPy."""
    import numpy as np

    return jax.tree.map(lambda a: np.asarray(a[i]), arrays)


def _telemetry(arrays, scenario, source: str):
    """The noisy :class:`~cassini_bayes.telemetry.Telemetry` of one simulated replicate."""
    import numpy as np

    from cassini_bayes.telemetry import Telemetry

    return Telemetry(t=np.asarray(arrays.t), q=np.asarray(arrays.q_meas),
                     omega=np.asarray(arrays.omega_meas),
                     wheel_rates=np.asarray(arrays.wheel_rates_meas),
                     wheel_names=scenario.wheel_names,
                     on_times=np.asarray(arrays.on_times) if scenario.uses_thrusters else None,
                     source=source)


def _posterior_draws(idata, names: tuple[str, ...]) -> SbcFit:
    """The ``(chains, draws)`` posterior draws of ``names`` and the divergence count."""
    draws = {n: jnp.asarray(idata.posterior[n].values) for n in names}
    return SbcFit(draws, jnp.asarray(int(idata.sample_stats["diverging"].values.sum())))


def _quiet(fn: Callable) -> Callable:
    """``fn`` with the expected warnings of synthetic replicates (pulses at the span's end,
    prior-dominated thrusters) silenced."""
    import warnings

    @functools.wraps(fn)
    def wrapped(*args, **kwargs):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            return fn(*args, **kwargs)

    return wrapped


# ---------------------------------------------------------------------------- thrust model

# default scenario: the day 028 RWA biasing event cut to 80 s (the file's header says more)
THRUST_SCENARIO = SCENARIOS_DIR / "sbc" / "sbc_thrust_biasing.toml"

THRUST_SBC_NAMES = ("F", "tau_delay", "tau_rise", "tau_fall")
_IDEAL_PULSE_TAU_S = 1e-6   # "no pulse dynamics": every time constant 1 µs, impulse = F·width
_THRUST_KEYS = {"num_warmup", "num_draws", "num_chains", "thin", "robust", "pulse_dynamics",
                "thrust_factor"}


@register("thrust")
def _thrust(spec: ModelSpec) -> SbcModel:
    """Mean thrust and pulse time constants from a biasing event: prior truth, simulator, NUTS.

    Truth per replicate, from the prior the fit states (:mod:`cassini_bayes.inference.thrust`):
    ``log F ~ Normal(log F_pred, THRUST_PRIOR_LOG_SD)`` with ``F_pred`` the ``[prior]``
    spacecraft's thrust (one ``F`` for all eight thrusters, mode ``mean``), and
    ``τd, τr, τf`` from :func:`~cassini_bayes.inference.thrust.tau_prior` (half-normal delay,
    log-normal rise and fall; :func:`~cassini_bayes.inference.thrust.draw_tau_prior`).
    They go into ``TruthParams.thrust_n`` (8,) and ``tau_s`` (3,); the truth's inertia is the
    ``[prior]`` model's (the fit holds it fixed), the rest is the scenario's. Data: the scenario
    (default :data:`THRUST_SCENARIO`, RCS-controlled wheel biasing, so the pulse train depends on
    the truth) through :func:`~cassini_bayes.simulate.run.simulate_batch`; the fit gets the noisy
    telemetry and the commanded pulse log. Fit: :func:`~cassini_bayes.inference.thrust.fit_thrust`
    (mode ``mean``) per replicate.

    Options: ``num_warmup, num_draws, num_chains, thin`` (default 300, 300, 2, 3), ``robust``
    (False: the idealised model, which matches a simulator without sensor/wheel errors; True:
    the robust model ``fit thrust`` runs by default, every truth drawn from its prior and flown,
    :func:`~cassini_bayes.analysis.sbc_thrust_robust.robust_thrust_model`), and two
    deliberate mis-specifications SBC must detect: ``pulse_dynamics=False`` makes the simulator
    fire ideal rectangular pulses (every time constant 1 µs, impulse ``F·Δ``) while the fit models
    the pulse response of Feldman & Lee §V (impulse ``F(Δ + c)``, ``c ≈ 45 ms``); and
    ``thrust_factor`` multiplies the simulated thrust (the recorded truth stays the drawn ``F``).
    """
    if dict(spec.options).get("robust"):
        from cassini_bayes.analysis.sbc_thrust_robust import robust_thrust_model

        return robust_thrust_model(spec)

    import numpy as np

    from cassini_bayes.inference.thrust import (THRUST_PRIOR_LOG_SD, draw_tau_prior, fit_thrust,
                                                tau_prior)
    from cassini_bayes.physics.momentum import inertia_vector
    from cassini_bayes.simulate.run import pulse_log, simulate_batch, truth_params

    scenario = _scenario(spec, THRUST_SCENARIO)
    if not scenario.uses_thrusters:
        raise InputError("the thrust SBC scenario fires no thrusters; give a biasing event "
                         "(control = \"rcs\" or [[pulse]] entries)", path=spec.scenario_source)
    opts = {"num_warmup": 300, "num_draws": 300, "num_chains": 2, "thin": 3, "robust": False,
            "pulse_dynamics": True, "thrust_factor": 1.0, **dict(spec.options)}
    _check_options("thrust", opts, _THRUST_KEYS)
    names = THRUST_SBC_NAMES
    spacecraft = scenario.prior
    tp = tau_prior(spacecraft)
    log_f_mu = float(np.log(spacecraft.thrust))
    base = truth_params(scenario)._replace(
        inertia=jnp.asarray(inertia_vector(spacecraft.inertia)))
    settings = _sampler_settings(opts)

    def prior_sample(key):
        k_f, k_t = jax.random.split(key)
        f = jnp.exp(log_f_mu + THRUST_PRIOR_LOG_SD * jax.random.normal(k_f))
        tau = draw_tau_prior(k_t, tp)
        return dict(zip(names, (f, tau[0], tau[1], tau[2])))

    def simulate_batch_fn(prior_keys, sim_keys):
        params = jax.vmap(prior_sample)(prior_keys)
        b = prior_keys.shape[0]
        tau = jnp.stack([params[n] for n in names[1:]], axis=1)
        if not opts["pulse_dynamics"]:
            tau = jnp.full_like(tau, _IDEAL_PULSE_TAU_S)
        thrust = params["F"] * float(opts["thrust_factor"])
        truth = _tiled_truth(base, b)._replace(
            thrust_n=jnp.broadcast_to(thrust[:, None], (b, 8)), tau_s=tau)
        return params, simulate_batch(sim_keys, scenario, truth)

    def simulate(key, params):
        raise NotImplementedError("the thrust adapter simulates in batches (simulate_batch)")

    @_quiet
    def fit(key, arrays):
        log = pulse_log(arrays, scenario)
        if log is None:
            raise RuntimeError("no thruster fired in this replicate")
        tel = _telemetry(arrays, scenario, "<sbc thrust replicate>")
        # the replicates' inertia is the model's prediction, so the fit holds it there: SBC of
        # the stated model, whose inertia prior is then a point
        post = fit_thrust(key, [(tel, log)], spacecraft, mode="mean", settings=settings,
                          prior_draws=0, robust=False, inertia="fixed")
        return _posterior_draws(post.idata, names)

    record = {**opts, "scenario": scenario.name, "prior_model": scenario.prior_model_path}
    return SbcModel("thrust", names, prior_sample, simulate, fit, vectorized=False,
                    settings=record, rhat_max=1.05, simulate_batch=simulate_batch_fn)


# ------------------------------------------------------------------------------ RWA4 model

# default scenario: Brown's RCS-method calibration cut to 450 s (the file's header says more)
RWA4_SCENARIO = SCENARIOS_DIR / "sbc" / "sbc_rwa4_rcs.toml"

_RWA4_KEYS = {"num_warmup", "num_draws", "num_chains", "thin", "prior", "rank_inertia",
              "rwa4_inertia_factor", "robust", "wheel", "method"}


def robust_rwa4_truth(key, spacecraft, wheel: str, known) -> dict[str, Any]:
    """One draw of the robust spin-axis model's nuisance vector ``ν`` from its own prior, split
    into named effects (:func:`~cassini_bayes.inference.nuisance.split_nuisance`).

    The layout is the one :func:`~cassini_bayes.inference.rwa4.prepare_rwa4` builds for one file
    with the ``known`` running wheels and the solved ``wheel`` (each with its own spin-inertia
    scale, tilts for the known ones, body-fixed and inertial torques and the inertial torque's
    rate); its prior is independent zero-mean Normal with sds ``layout.sd``, so the draw is
    ``layout.sd · N(0, 1)``. Returns the sites of :func:`split_nuisance` of the one file (the
    file axis dropped) plus ``scale_wheels`` and ``tilt_wheels``, the wheel names of
    ``wheel_scale`` and ``wheel_tilt``.
    """
    import numpy as np

    from cassini_bayes.inference.nuisance import nuisance_layout, split_nuisance

    known = tuple(known)
    layout = nuisance_layout(spacecraft, 1, known, wheel_errors="per_wheel",
                             scaled=known + (wheel,), inertial_torque=True, torque_rate=True)
    nu = layout.sd * np.asarray(jax.random.normal(key, (layout.size,)))
    out = split_nuisance(nu, layout)
    for site in ("gyro_bias", "T_body", "T_inertial", "T_N_rate"):
        out[site] = np.asarray(out[site])[0]                    # the one file
    out["scale_wheels"], out["tilt_wheels"] = layout.scale_wheels, layout.wheels
    return out


def _draw_rwa4_truth(key, mean, sd, cone):
    """One draw of ``u4`` (3,) and ``π`` (6,) from the RWA4 fit's prior (NumPy, by rejection).

    Same distribution as :func:`cassini_bayes.inference.rwa4.sample_rwa4_prior`: ``u4`` uniform
    on the sphere (a normalised standard normal), times the articulation-cone factor of
    ``cone`` (the prior model's :class:`~cassini_bayes.spacecraft.WheelCone`; ``None``: none)
    by rejection; ``π`` from ``Normal(mean, diag sd²)`` times the model's smooth
    physical factor, by the model's own sampler
    (:func:`~cassini_bayes.inference.rwa4.sample_inertia_prior`).
    """
    import numpy as np

    from cassini_bayes.inference.rwa4 import cone_log_factor, sample_inertia_prior

    k_u, k_i = jax.random.split(key)
    for r in range(10_000):
        k_x, k_a = jax.random.split(jax.random.fold_in(k_u, r))
        x = np.asarray(jax.random.normal(k_x, (3,)))
        u = x / np.linalg.norm(x)
        if cone is None or float(jax.random.uniform(k_a)) < np.exp(cone_log_factor(u, cone)):
            break
    return u, sample_inertia_prior(k_i, mean, np.diag(np.asarray(sd, float) ** 2), 1)[0]


@register("rwa4")
def _rwa4(spec: ModelSpec) -> SbcModel:
    """A wheel's spin axis by Brown's RCS or RWA method: prior truth, simulator, NUTS.

    Truth per replicate, from the prior :func:`~cassini_bayes.inference.rwa4.fit_rwa4` states:
    ``u4`` (the solved wheel's axis) uniform on the sphere (option ``prior="cone"``: the
    articulation-cone prior) and the inertia ``π ~ Normal(predicted, knowledge sd²)`` times the
    model's smooth physical factor (:func:`~cassini_bayes.inference.inertia.inertia_prior` of the
    ``[prior]`` model; see :func:`_draw_rwa4_truth`). They go into ``TruthParams.wheel_axes``
    (the wheel's row) and ``inertia``; the rest is the scenario's. Data: the scenario (default
    :data:`RWA4_SCENARIO`) through :func:`~cassini_bayes.simulate.run.simulate_batch`. Fit:
    ``fit_rwa4(method=method, wheel=wheel, robust=robust)`` with the scenario's ``A``/``B``
    windows as the pair (detected from quiet periods when the scenario names none).

    ``robust=True`` checks the robust model (``fit wheel-axis``'s default): each replicate also
    draws every nuisance effect that model integrates out from its prior
    (:func:`robust_rwa4_truth`: gyro bias and scale factor, each running wheel's spin-inertia
    scale, the solved wheel's included, the known wheels' axis tilts, body-fixed and inertial
    torques, the inertial torque's rate) and flies them (:func:`~cassini_bayes.simulate.
    with_errors`, the torques into the truth). Every other truth (noise levels, the known wheels'
    nominal axes) is the scenario's, so a scenario used here must not add errors of its own
    beyond those the prior draws (they are all replaced).

    Ranked: ``u4_x u4_y u4_z`` and, with ``rank_inertia`` (default True), ``Ixx … Iyz`` (the
    nuisance is integrated out analytically, so it has no draws to rank).
    Options: ``num_warmup, num_draws, num_chains, thin`` (default 300, 300, 2, 3), ``prior``
    (``uniform``), ``robust`` (False), ``wheel`` (``RWA4``), ``method`` (``rcs``), and a
    deliberate mis-specification SBC must detect: ``rwa4_inertia_factor`` multiplies the solved
    wheel's spin inertia in the simulator while the fit keeps the model's (the spin-up momentum
    ``J4 Δρ4`` is then mis-stated, which the fit can only absorb in the inertia).
    """
    import numpy as np

    from cassini_bayes.inference.inertia import INERTIA_NAMES, inertia_prior
    from cassini_bayes.inference.rwa4 import METHODS, PRIORS, U4_NAMES, fit_rwa4
    from cassini_bayes.simulate.run import noise_params, simulate_batch, truth_params, with_errors

    scenario = _scenario(spec, RWA4_SCENARIO)
    opts = {"num_warmup": 300, "num_draws": 300, "num_chains": 2, "thin": 3,
            "prior": "uniform", "rank_inertia": True, "rwa4_inertia_factor": 1.0,
            "robust": False, "wheel": "RWA4", "method": "rcs", **dict(spec.options)}
    _check_options("rwa4", opts, _RWA4_KEYS)
    if opts["prior"] not in PRIORS:
        raise InputError(f"rwa4 SBC option prior={opts['prior']!r}: choose one of "
                         f"{', '.join(PRIORS)}")
    if opts["method"] not in METHODS:
        raise InputError(f"rwa4 SBC option method={opts['method']!r}: choose one of "
                         f"{', '.join(METHODS)}")
    wheel, method, robust = str(opts["wheel"]), str(opts["method"]), bool(opts["robust"])
    if wheel not in scenario.wheel_names:
        raise InputError(f"rwa4 SBC option wheel={wheel!r}: the scenario has no such wheel "
                         f"(its wheels: {', '.join(scenario.wheel_names)})",
                         path=spec.scenario_source)
    k4 = scenario.wheel_names.index(wheel)
    if not scenario.wheels_on[k4]:
        raise InputError(f"the rwa4 SBC scenario must run {wheel} ([initial] wheels_on)",
                         path=spec.scenario_source)
    known = tuple(n for n, on in zip(scenario.wheel_names, scenario.wheels_on)
                  if on and n != wheel)
    wins = {w.name: (w.t0_s, w.t1_s) for w in scenario.windows}
    pairs = [(wins["A"], wins["B"])] if {"A", "B"} <= set(wins) else None
    names = tuple(U4_NAMES) + (tuple(INERTIA_NAMES) if opts["rank_inertia"] else ())
    spacecraft = scenario.prior
    ip = inertia_prior(spacecraft)
    cone = spacecraft.wheel(wheel).cone if opts["prior"] == "cone" else None
    if opts["prior"] == "cone" and cone is None:
        raise InputError(f"rwa4 SBC option prior='cone': the prior model gives {wheel} no "
                         "articulation cone ('cone_axis', 'cone_deg')", path=spec.scenario_source)
    base, base_noise = truth_params(scenario), noise_params(scenario)
    factor = float(opts["rwa4_inertia_factor"])
    settings = _sampler_settings(opts)

    def draw(key):
        # the idealised model's truths keep their key (its campaign in docs/sbc/rwa4/ reruns)
        k_a, k_n = jax.random.split(key) if robust else (key, None)
        u, pi = _draw_rwa4_truth(k_a, ip.mean, ip.sd, cone)
        d = dict(zip(U4_NAMES + tuple(INERTIA_NAMES), np.concatenate([u, pi])))
        if robust:
            d["nuisance"] = robust_rwa4_truth(k_n, spacecraft, wheel, known)
        return d

    def prior_sample(key):
        d = draw(key)
        return {n: d[n] for n in names}

    def one_truth(d):
        """The simulator's truth and noise of one drawn replicate."""
        tp = base._replace(inertia=jnp.asarray([d[n] for n in INERTIA_NAMES]))
        nz = base_noise
        if robust:
            nu = d["nuisance"]
            tp = tp._replace(torque_body_nm=jnp.asarray(nu["T_body"]),
                             torque_inertial_nm=jnp.asarray(nu["T_inertial"]),
                             torque_inertial_rate_nm_s=jnp.asarray(nu["T_N_rate"]))
            tp, nz = with_errors(scenario, tp, nz,
                                 wheel_scale=dict(zip(nu["scale_wheels"], nu["wheel_scale"])),
                                 wheel_tilt_rad=dict(zip(nu["tilt_wheels"], nu["wheel_tilt"])),
                                 gyro_bias_rad_s=nu["gyro_bias"],
                                 gyro_scale_factor=nu["gyro_scale"])
        u = jnp.asarray([d[n] for n in U4_NAMES])
        return tp._replace(wheel_axes=jnp.asarray(tp.wheel_axes).at[k4].set(u),
                           wheel_inertias=jnp.asarray(tp.wheel_inertias).at[k4].multiply(
                               factor)), nz

    def simulate_batch_fn(prior_keys, sim_keys):
        drawn = [draw(k) for k in prior_keys]
        flown = [one_truth(d) for d in drawn]
        stack = functools.partial(jax.tree.map, lambda *xs: jnp.stack([jnp.asarray(x)
                                                                       for x in xs]))
        arrays = simulate_batch(sim_keys, scenario, stack(*[f[0] for f in flown]),
                                stack(*[f[1] for f in flown]), noise_batched=True)
        params = {n: np.array([d[n] for d in drawn]) for n in names}
        return params, arrays

    def simulate(key, params):
        raise NotImplementedError("the rwa4 adapter simulates in batches (simulate_batch)")

    @_quiet
    def fit(key, arrays):
        tel = _telemetry(arrays, scenario, f"<sbc rwa4 replicate, {wheel}>")
        post = fit_rwa4(key, tel, spacecraft, method=method, pairs=pairs, prior=opts["prior"],
                        settings=settings, prior_draws=0, wheel=wheel, robust=robust)
        if robust and post.problem.layout.wheels != known:
            raise RuntimeError(f"replicate's known wheels {post.problem.layout.wheels} are not "
                               f"the scenario's {known}")
        return _posterior_draws(post.idata, names)

    record = {**opts, "scenario": scenario.name, "prior_model": scenario.prior_model_path}
    return SbcModel("rwa4", names, prior_sample, simulate, fit, vectorized=False,
                    settings=record, rhat_max=1.05, simulate_batch=simulate_batch_fn)
