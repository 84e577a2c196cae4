"""The MCMC runner shared by every model: NUTS on the CPU, results as ArviZ InferenceData.

A model module (``inertia.py``, and the thrust and RWA4 models) writes a NumPyro model whose data
arrive as keyword arguments, prepares those arrays once, and calls :func:`run_nuts`. The runner

* runs NUTS (NumPyro's ``hmc(algo="NUTS")`` kernel: windowed step-size and dense mass-matrix
  adaptation by default — the inertia entries, momenta and torques are strongly correlated; the
  models already whiten their coordinates, so the dense adaptation only corrects what is left),
* compiles warmup and sampling of all chains into **one** XLA program (one ``lax.scan`` loop
  over warm-up and draws, then the deterministic sites by ``vmap``), cached per (model, settings, chain method) and called
  with the data as arguments: fitting new data of the same shapes never recompiles (tested by
  counting XLA compilations). ``numpyro.infer.MCMC`` is not used because its ``pmap`` path builds
  a new program on every ``run`` (measured: 25 s of recompilation per fit on the 2-core machine),
* runs the chains ``"parallel"`` (``pmap``, one CPU device per chain) when the process has enough
  CPU devices, else ``"vectorized"`` (``vmap``: all chains in lock-step, each iteration as long as
  the deepest tree). The CLI asks JAX for one CPU device per core, and at least 4 (the default
  chains; more threads than cores still beats lock-step), before the backend starts
  (``jax_num_cpu_devices``); measured with benchmarks/bench_inertia.py on the 2-core machine,
  4 × 2000 iterations: 1.8 s parallel vs 3.1 s vectorized (loaded machine),
* shows a rich progress bar when asked (``jax.debug.callback`` every 50 iterations; compiled in
  only then), as a step of :mod:`cassini_bayes.inference.progress`,
* converts to InferenceData (``posterior``, ``sample_stats``) and adds a ``prior`` group from the
  model's own prior sampler (or ``numpyro.infer.Predictive`` when the model's sites are proper).

Determinism: the key is split into (sampler, prior, initial values); chain ``c`` gets the ``c``-th
split of the sampler key, initial values are ``Uniform(−2, 2)`` in the unconstrained (whitened)
space. Same key, same data, same settings → the same draws, bit for bit.

Model modules then add their own groups (``observed_data``, ``constant_data``, ``residuals``);
see :func:`cassini_bayes.inference.inertia.fit_inertia` for the pattern to copy.

Diagnostics (:func:`diagnostics`) come from ArviZ: rank-normalised split R-hat, bulk and tail ESS,
divergences from ``sample_stats.diverging``. ``converged`` means ``max R-hat ≤ 1.01``,
``min bulk ESS ≥ 400`` and no divergences (Vehtari et al. 2021 thresholds).
"""

from __future__ import annotations

from functools import partial
from typing import Callable, Mapping, NamedTuple, Sequence

import arviz as az
import jax
import jax.numpy as jnp
import numpy as np
import numpyro
from jax import lax
from numpyro.infer import Predictive
from numpyro.infer.hmc import hmc
from numpyro.infer.util import constrain_fn, potential_energy

from cassini_bayes._devices import request_host_devices
from cassini_bayes.inference import progress

__all__ = [
    "SamplerSettings",
    "Diagnostics",
    "R_HAT_MAX",
    "ESS_BULK_MIN",
    "run_nuts",
    "diagnostics",
    "choose_chain_method",
    "request_host_devices",
    "clear_cache",
]

R_HAT_MAX = 1.01
ESS_BULK_MIN = 400.0


class SamplerSettings(NamedTuple):
    """NUTS settings (all have the CLI's defaults).

    chains, warmup, draws : number of chains, warmup iterations and kept draws per chain.
    dense_mass : adapt a dense mass matrix (else diagonal).
    target_accept : target acceptance probability of the step-size adaptation.
    max_tree_depth : NUTS tree-depth limit (2^depth leapfrog steps at most).
    chain_method : ``"parallel"``, ``"vectorized"``, ``"sequential"`` or ``None`` (choose:
        :func:`choose_chain_method`).
    progress : show NumPyro's progress bar (only meaningful on a terminal; it costs a Python
        round-trip per iteration, so benchmarks switch it off).
    """

    chains: int = 4
    warmup: int = 1000
    draws: int = 1000
    dense_mass: bool = True
    target_accept: float = 0.9
    max_tree_depth: int = 10
    chain_method: str | None = None
    progress: bool = False


class Diagnostics(NamedTuple):
    """Convergence diagnostics over the parameters asked for (ArviZ).

    divergences : number of divergent transitions after warmup, all chains.
    max_r_hat : largest rank-normalised split R-hat.
    min_ess_bulk, min_ess_tail : smallest bulk / tail effective sample size.
    converged : ``max_r_hat ≤ 1.01 and min_ess_bulk ≥ 400 and divergences == 0``.
    worst : the parameter (element) with the largest R-hat, for messages.
    """

    divergences: int
    max_r_hat: float
    min_ess_bulk: float
    min_ess_tail: float
    converged: bool
    worst: str

    def to_dict(self) -> dict:
        """The ``diagnostics`` entry of ``summary.json`` (docs/design.md §4.5) plus extras."""
        return {"divergences": int(self.divergences), "max_r_hat": float(self.max_r_hat),
                "min_ess_bulk": float(self.min_ess_bulk), "min_ess_tail": float(self.min_ess_tail),
                "converged": bool(self.converged)}

    def message(self) -> str:
        """One line saying what failed (empty when converged)."""
        bad = []
        if self.max_r_hat > R_HAT_MAX or not np.isfinite(self.max_r_hat):
            bad.append(f"max R-hat {self.max_r_hat:.3f} > {R_HAT_MAX} ({self.worst})")
        if self.min_ess_bulk < ESS_BULK_MIN or not np.isfinite(self.min_ess_bulk):
            bad.append(f"min bulk ESS {self.min_ess_bulk:.0f} < {ESS_BULK_MIN:.0f}")
        if self.divergences:
            bad.append(f"{self.divergences} divergent transitions")
        return "; ".join(bad)


def choose_chain_method(chains: int) -> str:
    """``"parallel"`` when there are at least ``chains`` CPU devices, else ``"vectorized"``."""
    if chains > 1 and jax.local_device_count() >= chains:
        return "parallel"
    return "vectorized"


_SAMPLER_CACHE: dict[tuple, Callable] = {}
_PROGRESS: dict = {}
_PROGRESS_EVERY = 50


def clear_cache() -> None:
    """Forget the cached samplers (and their compiled code)."""
    _SAMPLER_CACHE.clear()


def _progress_tick(i):
    bar = _PROGRESS.get("bar")
    if bar is not None:
        phase = "warm-up" if int(np.max(i)) <= _PROGRESS["warmup"] else "sampling"
        bar.update(_PROGRESS["task"], advance=_PROGRESS_EVERY * int(np.size(i)),
                   description=f"{_PROGRESS['label']}: {phase}")


def _site_shapes(model: Callable, model_kwargs: Mapping) -> dict[str, tuple]:
    """Shapes of the model's latent sample sites, by abstract tracing (no computation)."""
    def sites(kwargs):
        def fill(site):
            if site["type"] != "sample":
                return None
            return jnp.zeros(site["fn"].shape())
        tr = numpyro.handlers.trace(numpyro.handlers.substitute(
            numpyro.handlers.seed(model, 0), substitute_fn=fill)).get_trace(**kwargs)
        return {k: v["value"] for k, v in tr.items()
                if v["type"] == "sample" and not v["is_observed"]}
    out = jax.eval_shape(sites, dict(model_kwargs))
    return {k: v.shape for k, v in out.items()}


def _build_sampler(model: Callable, s: SamplerSettings, method: str) -> Callable:
    """One compiled function ``(keys, init_z, model_kwargs) -> draws`` for all chains.

    Warmup (step size and mass-matrix adaptation, NumPyro's windowed scheme) and sampling are one
    ``lax.scan`` loop inside one program (NumPyro's kernel adapts while its iteration count is
    below the warm-up length), so a fit is a single call into XLA and the kernel is traced and
    compiled once; the program is cached per (model, settings, chain method) and reused for any
    data of the same shapes.
    """
    def one_chain(key, init_z, kwargs):
        def pot(z):
            return potential_energy(model, (), kwargs, z)

        init_kernel, sample_kernel = hmc(potential_fn=pot, algo="NUTS")
        # a start outside a hard support (e.g. RWA4's physical inertia) leaves the chain stuck:
        # halve it toward w = 0 (the Laplace centre) until the density is finite; finite starts
        # are left as they are
        init_z = lax.while_loop(
            lambda c: ~jnp.isfinite(pot(c[0])) & (c[1] < 30),
            lambda c: (jax.tree.map(lambda x: 0.5 * x, c[0]), c[1] + 1), (init_z, 0))[0]
        state = init_kernel(init_z, s.warmup, dense_mass=s.dense_mass,
                            target_accept_prob=s.target_accept, max_tree_depth=s.max_tree_depth,
                            rng_key=key)

        def step(st, _):
            st = sample_kernel(st)
            if s.progress:
                lax.cond(st.i % _PROGRESS_EVERY == 0,
                         lambda: jax.debug.callback(_progress_tick, st.i), lambda: None)
            return st, None

        def draw(st, _):
            st, _ = step(st, None)
            return st, (st.z, st.diverging, st.energy, st.num_steps, st.accept_prob,
                        st.potential_energy, st.adapt_state.step_size)

        # one loop over warm-up and draws (the kernel adapts while ``i < warmup``): the NUTS
        # kernel is traced and compiled once, not once per loop; the warm-up rows are dropped
        _, out = lax.scan(draw, state, None, length=s.warmup + s.draws)
        zs, div, energy, nsteps, acc, pe, eps = jax.tree.map(lambda x: x[s.warmup:], out)
        samples = jax.vmap(lambda z: constrain_fn(model, (), kwargs, z,
                                                  return_deterministic=True))(zs)
        stats = {"diverging": div, "energy": energy, "n_steps": nsteps,
                 "tree_depth": jnp.floor(jnp.log2(nsteps + 1)).astype(int),
                 "acceptance_rate": acc, "lp": -pe, "step_size": eps}
        return samples, stats

    if method == "parallel":
        return jax.pmap(one_chain, in_axes=(0, 0, None))
    if method == "sequential":
        return jax.jit(lambda keys, z, kw: lax.map(lambda a: one_chain(a[0], a[1], kw), (keys, z)))
    return jax.jit(jax.vmap(one_chain, in_axes=(0, 0, None)))


def _on_device(x):
    """``jnp.asarray(x)`` without its cost: for a NumPy array or a Python number that compiles a
    one-operation XLA program per shape (in every process); ``device_put`` only copies (Python
    numbers stay weakly typed either way)."""
    if isinstance(x, jax.Array):
        return x
    if isinstance(x, (np.ndarray, np.generic, int, float, bool)):
        return jax.device_put(x)
    return jnp.asarray(x)


@partial(jax.jit, static_argnums=(1, 2))
def _start(key, chains: int, shapes: tuple):
    """The prior's key, the chains' keys and their initial values, one XLA program.

    The key is split into (sampler, prior, initial values); chain ``c`` gets the ``c``-th split of
    the sampler key; initial values are ``Uniform(−2, 2)`` in the unconstrained (whitened)
    space (NumPyro's ``init_to_uniform(radius=2)``), one key per site in name order (``shapes``:
    sorted ``(name, shape)`` pairs).
    """
    key_mcmc, key_prior, key_init = jax.random.split(key, 3)
    init_keys = jax.random.split(key_init, len(shapes))
    init_z = {name: jax.random.uniform(k, (chains,) + shp, minval=-2.0, maxval=2.0)
              for k, (name, shp) in zip(init_keys, shapes)}
    return key_prior, jax.random.split(key_mcmc, chains), init_z


def _sampler_for(model: Callable, s: SamplerSettings, method: str) -> Callable:
    key = (model, s.chains, s.warmup, s.draws, s.dense_mass, float(s.target_accept),
           s.max_tree_depth, method, bool(s.progress))
    fn = _SAMPLER_CACHE.get(key)
    if fn is None:
        fn = _SAMPLER_CACHE[key] = _build_sampler(model, s, method)
    return fn


def run_nuts(key, model: Callable, *, model_kwargs: Mapping[str, object],
             settings: SamplerSettings = SamplerSettings(),
             coords: Mapping[str, Sequence] | None = None,
             dims: Mapping[str, Sequence[str]] | None = None,
             prior: Callable[[object, int], Mapping[str, np.ndarray]] | None = None,
             prior_draws: int = 500) -> az.InferenceData:
    """Run NUTS on ``model(**model_kwargs)``; return InferenceData with posterior and prior.

    Parameters
    ----------
    key : jax.random key; the same key and data give the same draws (bit for bit).
    model : NumPyro model taking its data as keyword arguments (arrays only: they are traced, so
        new data of the same shapes reuse the compiled sampler). Its latent sites must be
        unconstrained (real support): the models here sample whitened, non-dimensional
        coordinates and map them to physical parameters themselves (docs/design.md §7.4).
    model_kwargs : the data.
    settings : :class:`SamplerSettings`.
    coords, dims : ArviZ coordinates and dimensions of the posterior variables.
    prior : ``prior(key, n) -> {name: (n, ...) array}``, draws from the model's prior (needed when
        the model uses improper or reparameterised sites); when ``None``, ``Predictive`` of the
        model is tried, and the group is left out if that fails.
    prior_draws : number of prior draws (0: no prior group).

    Returns
    -------
    arviz.InferenceData
        Groups ``posterior`` (latent sites and deterministics), ``sample_stats`` (``diverging``,
        ``energy``, ``n_steps``, ``tree_depth``, ``acceptance_rate``, ``lp``, ``step_size``) and,
        when drawn, ``prior``.
    """
    s = settings
    method = s.chain_method or choose_chain_method(s.chains)
    fn = _sampler_for(model, s, method)
    kwargs = {k: _on_device(v) for k, v in model_kwargs.items()}
    shapes = _site_shapes(model, kwargs)
    key_prior, keys, init_z = _start(key, s.chains, tuple(sorted(shapes.items())))
    if s.progress:  # the bar: "compiling" until the first tick, then warm-up, sampling
        label = f"NUTS, {s.chains} chains × {s.warmup} warm-up + {s.draws} draws"
        with progress.shown(), progress.step(f"{label}: compiling the sampler",
                                             total=s.chains * (s.warmup + s.draws)) as task:
            _PROGRESS.update(bar=progress.active(), task=task, label=label, warmup=s.warmup)
            try:
                samples, stats = jax.block_until_ready(fn(keys, init_z, kwargs))
            finally:
                _PROGRESS.clear()
    else:
        samples, stats = fn(keys, init_z, kwargs)
    posterior = {k: np.asarray(v) for k, v in samples.items()}
    sample_stats = {k: np.asarray(v) for k, v in stats.items()}
    idata = az.from_dict(posterior=posterior, sample_stats=sample_stats,
                         coords=dict(coords or {}),
                         dims={k: v for k, v in (dims or {}).items() if k in posterior})
    if prior_draws > 0:
        draws = None
        if prior is not None:
            draws = prior(key_prior, prior_draws)
        else:
            try:
                draws = Predictive(model, num_samples=prior_draws)(key_prior, **kwargs)
            except Exception:  # improper sites: no generic prior available
                draws = None
        if draws:
            prior_dict = {k: np.asarray(v)[None] for k, v in draws.items()}
            pdims = {k: v for k, v in (dims or {}).items() if k in prior_dict}
            idata.extend(az.from_dict(prior=prior_dict, coords=dict(coords or {}), dims=pdims))
    return idata


def _flat_max(ds) -> tuple[float, str]:
    worst, name = -np.inf, ""
    for var, da in ds.data_vars.items():
        v = np.asarray(da.values, float)
        if v.size == 0:
            continue
        vv = np.where(np.isfinite(v), v, np.inf)
        i = int(np.argmax(vv))
        if vv.flat[i] > worst:
            idx = np.unravel_index(i, v.shape) if v.ndim else ()
            worst, name = float(vv.flat[i]), var + (str([int(j) for j in idx]) if idx else "")
    return worst, name


def _flat_min(ds) -> float:
    vals = [np.asarray(da.values, float).ravel() for da in ds.data_vars.values()]
    vals = [v for v in vals if v.size]
    if not vals:
        return float("nan")
    v = np.concatenate(vals)
    return float(np.min(np.where(np.isfinite(v), v, -np.inf)))


def diagnostics(idata: az.InferenceData, var_names: Sequence[str] | None = None, *,
                r_hat_max: float = R_HAT_MAX, ess_bulk_min: float = ESS_BULK_MIN) -> Diagnostics:
    """R-hat, bulk/tail ESS (ArviZ) and divergences over ``var_names`` (default: all)."""
    names = list(var_names) if var_names is not None else None
    rhat = az.rhat(idata, var_names=names)
    ess_b = az.ess(idata, var_names=names, method="bulk")
    ess_t = az.ess(idata, var_names=names, method="tail")
    max_r, worst = _flat_max(rhat)
    min_b = _flat_min(ess_b)
    min_t = _flat_min(ess_t)
    div = 0
    if "sample_stats" in idata.groups() and "diverging" in idata.sample_stats:
        div = int(np.asarray(idata.sample_stats["diverging"]).sum())
    ok = bool(np.isfinite(max_r) and max_r <= r_hat_max and min_b >= ess_bulk_min and div == 0)
    return Diagnostics(div, max_r, min_b, min_t, ok, worst)
