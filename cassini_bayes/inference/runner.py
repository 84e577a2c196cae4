"""The MCMC runner shared by every model: NUTS on the CPU, results as ArviZ InferenceData.

A model package (``inference/inertia``, ``inference/thrust``, ``inference/rwa4``) writes a
NumPyro model whose data arrive as keyword arguments, prepares those arrays once, and calls
:func:`run_nuts`. The runner

* runs NUTS (NumPyro's ``hmc(algo="NUTS")`` kernel: windowed step-size and dense mass-matrix
  adaptation by default — the inertia entries, momenta and torques are strongly correlated; the
  models already whiten their coordinates, so the dense adaptation only corrects what is left),
* compiles the sampling of all chains into three XLA programs (start; a ``lax.scan`` piece of
  the loop over warm-up and draws, called about ten times; the deterministic sites of the draws
  by ``vmap``), cached per (model, settings, chain method) and called with the data as
  arguments: fitting new data of the same shapes never recompiles (tested by counting XLA
  compilations). ``numpyro.infer.MCMC`` is not used because its ``pmap`` path builds
  a new program on every ``run`` (docs/performance.md, "The sampler loop"),
* runs the chains ``"parallel"`` (``pmap``, one CPU device per chain) when the process has enough
  CPU devices, else ``"vectorized"`` (``vmap``: all chains in lock-step, each iteration as long as
  the deepest tree). The command line and the fit functions ask JAX for one CPU device per
  core, and at least 4 (the default chains; more threads than cores still beats lock-step),
  before the backend starts (``jax_num_cpu_devices``, :func:`cassini_bayes.setup_jax`):
  parallel chains finish sooner than lock-step ones (docs/performance.md, "The sampler loop"),
* shows a rich progress bar when asked, as a step of :mod:`cassini_bayes.inference.progress`:
  the loop runs in about ten calls of one program (:func:`_build_sampler`), so the bar needs no
  callback inside the compiled code and the same programs, all kept by the persistent
  compilation cache, run with and without it,
* converts to InferenceData (``posterior``, ``sample_stats``) and adds a ``prior`` group from the
  model's own prior sampler (or ``numpyro.infer.Predictive`` when the model's sites are proper).

Determinism: the key is split into (sampler, prior, initial values); chain ``c`` gets the ``c``-th
split of the sampler key, initial values are ``Uniform(−2, 2)`` in the unconstrained (whitened)
space. Same key, same data, same settings → the same draws, bit for bit.

Model modules then add their own groups (``observed_data``, ``constant_data``, ``residuals``);
see :func:`cassini_bayes.inference.inertia.fit_inertia` for the pattern to copy.

Diagnostics (:func:`diagnostics`) come from ArviZ: rank-normalised split R-hat, bulk and tail ESS,
divergences from ``sample_stats.diverging``, judged by the package's convergence rule
(:mod:`cassini_bayes.diagnostics`).
"""

from __future__ import annotations

from functools import partial
from typing import TYPE_CHECKING, Callable, Mapping, NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np
import numpyro
from jax import lax
from numpyro.infer import Predictive
from numpyro.infer.hmc import hmc
from numpyro.infer.util import constrain_fn, potential_energy

from cassini_bayes._arviz import load_arviz
from cassini_bayes._devices import request_host_devices, require_x64
from cassini_bayes.diagnostics import ESS_BULK_MIN, R_HAT_MAX, Diagnostics
from cassini_bayes.inference import progress

if TYPE_CHECKING:
    import arviz

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


def choose_chain_method(chains: int) -> str:
    """``"parallel"`` when there are at least ``chains`` CPU devices, else ``"vectorized"``."""
    if chains > 1 and jax.local_device_count() >= chains:
        return "parallel"
    return "vectorized"


_SAMPLER_CACHE: dict[tuple, "_Sampler"] = {}
_UPDATES = 10  # progress updates per run, at least: the loop runs in about this many pieces


def clear_cache() -> None:
    """Forget the cached samplers (and their compiled code)."""
    _SAMPLER_CACHE.clear()


def _piece(total: int) -> int:
    """Iterations per call of the sampler's loop: the largest divisor of ``total`` that is at
    most ``total / _UPDATES`` (so every call is the same program; 1 when ``total`` is prime)."""
    top = max(1, total // _UPDATES)
    return next(d for d in range(top, 0, -1) if total % d == 0)


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


class _Sampler(NamedTuple):
    """The three compiled pieces of a run, all chains at once (:func:`_build_sampler`)."""

    start: Callable      # (keys, init_z, kwargs) -> NUTS states
    advance: Callable    # (states, kwargs) -> (states, per-iteration records), ``piece`` its
    finish: Callable     # (zs, stats, kwargs) -> (posterior sites, sample stats)
    piece: int           # iterations per ``advance``


def _build_sampler(model: Callable, s: SamplerSettings, method: str) -> _Sampler:
    """The sampler of ``model`` under ``s``, all chains batched by ``method``, in three programs.

    ``start`` places each chain (a start outside a hard support is halved toward the Laplace
    centre until the density is finite) and initialises NumPyro's NUTS kernel; ``advance`` runs
    ``piece`` iterations of it (one ``lax.scan``; the kernel adapts step size and dense mass
    matrix, NumPyro's windowed scheme, while its iteration count is below the warm-up length);
    ``finish`` maps the kept draws to the model's sites (deterministics included) and the
    sample statistics. The loop over warm-up and draws is ``advance`` called
    ``(warmup + draws) / piece`` times from Python, so the programs hold no callback: a
    progress bar costs nothing, the programs are the same with and without one (so are the
    draws), and the persistent compilation cache keeps them (JAX never caches a program that
    calls back into Python). Cached per (model, settings, chain method) and reused for any
    data of the same shapes.
    """
    def potential_for(**kwargs):
        return lambda z: potential_energy(model, (), kwargs, z)

    init_kernel, sample_kernel = hmc(potential_fn_gen=potential_for, algo="NUTS")

    def start(key, init_z, kwargs):
        pot = potential_for(**kwargs)
        # a start outside a hard support (e.g. RWA4's physical inertia) leaves the chain stuck:
        # halve it toward w = 0 (the Laplace centre) until the density is finite; finite starts
        # are left as they are
        init_z = lax.while_loop(
            lambda c: ~jnp.isfinite(pot(c[0])) & (c[1] < 30),
            lambda c: (jax.tree.map(lambda x: 0.5 * x, c[0]), c[1] + 1), (init_z, 0))[0]
        return init_kernel(init_z, s.warmup, dense_mass=s.dense_mass,
                           target_accept_prob=s.target_accept,
                           max_tree_depth=s.max_tree_depth, rng_key=key, model_kwargs=kwargs)

    piece = _piece(s.warmup + s.draws)

    def advance(state, kwargs):
        def draw(st, _):
            st = sample_kernel(st, model_kwargs=kwargs)
            return st, (st.z, st.diverging, st.energy, st.num_steps, st.accept_prob,
                        st.potential_energy, st.adapt_state.step_size)

        return lax.scan(draw, state, None, length=piece)

    def finish(zs, stats, kwargs):
        div, energy, nsteps, acc, pe, eps = stats
        samples = jax.vmap(lambda z: constrain_fn(model, (), kwargs, z,
                                                  return_deterministic=True))(zs)
        return samples, {"diverging": div, "energy": energy, "n_steps": nsteps,
                         "tree_depth": jnp.floor(jnp.log2(nsteps + 1)).astype(int),
                         "acceptance_rate": acc, "lp": -pe, "step_size": eps}

    if method == "parallel":
        batch = lambda f, n: jax.pmap(f, in_axes=(0,) * n + (None,))  # noqa: E731
    elif method == "sequential":
        def batch(f, n):
            return jax.jit(lambda *a: lax.map(lambda b: f(*b, a[-1]), a[:-1]))
    else:
        batch = lambda f, n: jax.jit(jax.vmap(f, in_axes=(0,) * n + (None,)))  # noqa: E731
    return _Sampler(batch(start, 2), batch(advance, 1), batch(finish, 2), piece)


def _run_chains(fn: _Sampler, s: SamplerSettings, keys, init_z, kwargs, on_piece=None):
    """Warm-up and draws of every chain: ``fn.advance`` over the whole loop, the warm-up rows
    dropped on the host, then ``fn.finish`` on the draws. ``on_piece(done)`` (iterations done
    per chain) after each piece, when given."""
    state = fn.start(keys, init_z, kwargs)
    kept = []
    for first in range(0, s.warmup + s.draws, fn.piece):
        state, rec = fn.advance(state, kwargs)
        if first + fn.piece > s.warmup:   # a piece with draws in it: keep those rows
            skip = max(0, s.warmup - first)
            kept.append(jax.tree.map(lambda x: np.asarray(x)[:, skip:], rec))
        if on_piece is not None:
            jax.block_until_ready(state)
            on_piece(first + fn.piece)
    rec = jax.tree.map(lambda *x: np.concatenate(x, 1), *kept)
    return fn.finish(jax.device_put(rec[0]), jax.device_put(rec[1:]), kwargs)


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


def _sampler_for(model: Callable, s: SamplerSettings, method: str) -> _Sampler:
    require_x64("NUTS")  # every sampler is built here, the SBC campaigns' included
    key = (model, s.chains, s.warmup, s.draws, s.dense_mass, float(s.target_accept),
           s.max_tree_depth, method)
    fn = _SAMPLER_CACHE.get(key)
    if fn is None:
        fn = _SAMPLER_CACHE[key] = _build_sampler(model, s, method)
    return fn


def run_nuts(key, model: Callable, *, model_kwargs: Mapping[str, object],
             settings: SamplerSettings = SamplerSettings(),
             coords: Mapping[str, Sequence] | None = None,
             dims: Mapping[str, Sequence[str]] | None = None,
             prior: Callable[[object, int], Mapping[str, np.ndarray]] | None = None,
             prior_draws: int = 500) -> arviz.InferenceData:
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
    kwargs = {k: jax.tree.map(_on_device, v) for k, v in model_kwargs.items()}
    shapes = _site_shapes(model, kwargs)
    key_prior, keys, init_z = _start(key, s.chains, tuple(sorted(shapes.items())))
    if s.progress:  # a bar: "compiling" until the first piece is done, then warm-up, sampling
        label = f"NUTS, {s.chains} chains × {s.warmup} warm-up + {s.draws} draws"
        with progress.shown(), progress.step(f"{label}: compiling the sampler",
                                             total=s.warmup + s.draws) as task:
            def on_piece(done):
                bar = progress.active()
                if bar is not None:
                    phase = "warm-up" if done <= s.warmup else "sampling"
                    bar.update(task, completed=done, description=f"{label}: {phase}")

            samples, stats = _run_chains(fn, s, keys, init_z, kwargs, on_piece)
    else:
        samples, stats = _run_chains(fn, s, keys, init_z, kwargs)
    posterior = {k: np.asarray(v) for k, v in samples.items()}
    sample_stats = {k: np.asarray(v) for k, v in stats.items()}
    az = load_arviz()
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


def diagnostics(idata: arviz.InferenceData, var_names: Sequence[str] | None = None
                ) -> Diagnostics:
    """R-hat, bulk/tail ESS (ArviZ) and divergences over ``var_names`` (default: all), judged
    by the package's rule (:mod:`cassini_bayes.diagnostics`)."""
    az = load_arviz()
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
    return Diagnostics.judge(div, max_r, min_b, min_t, worst)
