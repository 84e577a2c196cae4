"""One batch of an SBC campaign: draw, simulate, fit and rank ``B`` replicates.

Replicate ``i`` uses the key ``fold_in(key(seed), i)`` whatever batch or worker runs it
(:mod:`cassini_bayes.analysis.campaign`); the compiled programs are cached per model and shapes.
"""


import functools
import warnings
from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes._devices import jax_entry, release_compiled_programs
from cassini_bayes.analysis.sbc import ranks
from cassini_bayes.analysis.sbc_models import ModelSpec, SbcModel, build_model


class BatchResult(NamedTuple):
    """Results of one batch of ``B`` replicates (``P`` parameters, ``L`` thinned draws).

    Attributes
    ----------
    index : numpy.ndarray
        Replicate indices ``bB … bB + B − 1``, shape ``(B,)``.
    truth : numpy.ndarray
        Parameters drawn from the prior, shape ``(B, P)``.
    draws : numpy.ndarray
        Thinned posterior draws (chains concatenated), shape ``(B, P, L)``.
    rank : numpy.ndarray
        Rank of the truth among the draws, ``0..L``, or ``-1`` for a failed replicate, ``(B, P)``.
    n_divergent : numpy.ndarray
        Divergent transitions after warm-up, shape ``(B,)``.
    rhat : numpy.ndarray
        Split R-hat of the thinned chains (NaN when too short), shape ``(B, P)``.
    ess : numpy.ndarray
        Smallest effective sample size over the parameters, of the draws before thinning
        (NaN when too short), shape ``(B,)``; ``ess ≥ L`` means the thinning left draws about as
        good as independent ones.
    failed : numpy.ndarray
        Non-finite truth or draws, shape ``(B,)``.
    """

    index: np.ndarray
    truth: np.ndarray
    draws: np.ndarray
    rank: np.ndarray
    n_divergent: np.ndarray
    rhat: np.ndarray
    ess: np.ndarray
    failed: np.ndarray



def replicate_keys(seed: int, index: np.ndarray) -> jax.Array:
    """Keys of replicates ``index``: ``fold_in(key(seed), i)`` — independent of batching."""
    root = jax.random.key(seed)
    return jax.vmap(lambda i: jax.random.fold_in(root, i))(jnp.asarray(index, dtype=jnp.uint32))


@functools.lru_cache(maxsize=16)
def _programs(spec: ModelSpec) -> tuple[SbcModel, Callable, Callable, Callable]:
    """Compiled batch programs of a model: simulate, fit, rank (cached per process).

    The fit program is cached by the model's ``fit`` function, so two specs sharing a sampler
    (e.g. the same model with another simulator setting) share one compilation.
    """
    model = build_model(spec)
    names = model.parameter_names

    def simulate_one(key):
        k_prior, k_sim, _, _ = jax.random.split(key, 4)
        params = model.prior_sample(k_prior)
        truth = jnp.stack([jnp.asarray(params[n], dtype=jnp.float64) for n in names])
        return truth, model.simulate(k_sim, params)

    if model.simulate_batch is None:
        simulate_batch = jax.jit(jax.vmap(simulate_one))
    else:
        def simulate_batch(keys):
            split = jax.vmap(lambda k: jax.random.split(k, 4))(keys)
            params, data = model.simulate_batch(split[:, 0], split[:, 1])
            truth = np.stack([np.asarray(params[n], dtype=np.float64) for n in names], axis=1)
            return truth, data

    return model, simulate_batch, _fit_program(model), _rank_program()


@functools.lru_cache(maxsize=16)
def _vmapped_fit(fit: Callable, names: tuple[str, ...]) -> Callable:
    """One compiled program ``(keys (B,), data (B, ...)) -> (chains (B, P, C, D), n_div (B,))``:
    ``jax.vmap`` of a pure ``fit`` over replicates (cached by ``fit``, so two specs sharing a
    sampler share the compilation)."""

    def fit_one(key, data):
        _, _, k_fit, _ = jax.random.split(key, 4)
        out = fit(k_fit, data)
        return jnp.stack([out.draws[n] for n in names]), jnp.asarray(out.n_divergent)

    return jax.jit(jax.vmap(fit_one))


def _warn_failed(e: Exception) -> None:
    warnings.warn(f"SBC replicate fit failed ({type(e).__name__}: {e}); recorded as a failure",
                  RuntimeWarning, stacklevel=3)


def _prepared(prepare: Callable, data, b: int) -> tuple[Any, np.ndarray]:
    """``prepare`` of each replicate of a batch, stacked; a replicate whose preparation raises is
    given another replicate's data (one shape for the compiled fit) and flagged ``False``."""
    out: list = [None] * b
    for i in range(b):
        try:
            out[i] = prepare(jax.tree.map(lambda a, i=i: np.asarray(a[i]), data))
        except Exception as e:  # noqa: BLE001 - any failure of one replicate is recorded
            _warn_failed(e)
    ok = np.array([o is not None for o in out])
    if not ok.any():
        raise RuntimeError("every replicate of the batch failed; see the warnings above")
    good = out[int(np.argmax(ok))]
    out = [o if o is not None else good for o in out]
    return jax.tree.map(lambda *xs: jnp.stack([jnp.asarray(x) for x in xs]), *out), ok


def _fit_program(model: SbcModel) -> Callable:
    """``(keys (B,), data (B, ...)) -> (chains (B, P, C, D), n_div (B,))``, all post-warm-up
    draws; a failed replicate's are NaN."""
    names = model.parameter_names
    if model.vectorized:
        vmapped = _vmapped_fit(model.fit, names)
        if model.prepare is None:
            return vmapped

        def fit_prepared(keys, data):
            stacked, ok = _prepared(model.prepare, data, keys.shape[0])
            chains, n_div = vmapped(keys, stacked)
            nan = np.where(ok[:, None, None, None], 0.0, np.nan)
            return np.asarray(chains) + nan, np.where(ok, np.asarray(n_div), 0)

        return fit_prepared

    def fit_batch(keys, data):
        # One replicate whose fit raises (a numerical failure, an unidentifiable draw) must not
        # sink its batch: it is recorded with NaN draws and counted as a failure.
        outs: list = [None] * keys.shape[0]
        for i in range(keys.shape[0]):
            try:
                _, _, k_fit, _ = jax.random.split(keys[i], 4)
                out = model.fit(k_fit, jax.tree.map(lambda a, i=i: a[i], data))
                outs[i] = (np.stack([np.asarray(out.draws[n]) for n in names]),
                           int(out.n_divergent))
            except Exception as e:  # noqa: BLE001 - any failure of one fit is recorded
                _warn_failed(e)
            release_compiled_programs()
        good = next((o for o in outs if o is not None), None)
        if good is None:
            raise RuntimeError("every fit of the batch failed; see the warnings above")
        outs = [o if o is not None else (np.full_like(good[0], np.nan), 0) for o in outs]
        return np.stack([o[0] for o in outs]), np.array([o[1] for o in outs])

    return fit_batch


@functools.lru_cache(maxsize=1)
def _rank_program() -> Callable:
    def rank_one(key, draws, truth):
        _, _, _, k_rank = jax.random.split(key, 4)
        return ranks(k_rank, draws, truth)

    return jax.jit(jax.vmap(rank_one))


def _split_rhat(chains: np.ndarray) -> np.ndarray:
    """Split R-hat per replicate and parameter from ``(B, P, chains, draws)`` thinned draws."""
    from numpyro.diagnostics import split_gelman_rubin

    b, p, _, d = chains.shape
    if d < 4:
        return np.full((b, p), np.nan)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.asarray(split_gelman_rubin(np.transpose(chains, (2, 3, 0, 1))))


def _min_ess(chains: np.ndarray) -> np.ndarray:
    """Smallest effective sample size over the parameters per replicate, from the ``(B, P,
    chains, draws)`` draws before thinning (NumPyro's estimator: Geyer's initial monotone
    sequence over the chains' autocorrelations, Stan's definition); NaN when too short."""
    from numpyro.diagnostics import effective_sample_size

    b, _, c, d = chains.shape
    if d < 4:
        return np.full(b, np.nan)
    with np.errstate(invalid="ignore", divide="ignore"):
        ess = np.asarray(effective_sample_size(np.transpose(chains, (2, 3, 0, 1))))
    return ess.min(axis=1)


@jax_entry
def run_batch(spec: ModelSpec, seed: int, batch_index: int, batch_size: int) -> dict[str, Any]:
    """Simulate, fit and rank replicates ``batch_index·B … (batch_index+1)·B − 1``.

    This is the unit of work of every executor (a Dask task runs exactly this); its arguments
    and result are plain, picklable data. The fits' draws are thinned by the model's
    ``settings["thin"]`` (default 1) before ranking: ``L = chains · ⌊draws / thin⌋`` draws,
    every ``thin``-th of each chain; the effective sample size of the draws before thinning is
    recorded, and ``ess ≥ L`` says the ``L`` ranked draws are about as good as independent ones
    (Talts et al. 2018, Sec. 5.1: ranks among autocorrelated draws are not uniform).

    Returns
    -------
    dict
        The fields of :class:`BatchResult` as NumPy arrays.
    """
    model, simulate_batch, fit_batch, rank_batch = _programs(spec)
    thin = int(model.settings.get("thin", 1))
    index = np.arange(batch_index * batch_size, (batch_index + 1) * batch_size, dtype=np.int64)
    keys = replicate_keys(seed, index)
    truth, data = simulate_batch(keys)
    chains, n_div = fit_batch(keys, data)
    chains = np.asarray(chains, dtype=np.float64)
    kept = chains[..., thin - 1::thin]
    draws = kept.reshape(kept.shape[:2] + (-1,))
    rank = np.asarray(rank_batch(keys, jnp.asarray(draws), truth))
    truth = np.asarray(truth)
    failed = ~(np.isfinite(truth).all(axis=1) & np.isfinite(draws).all(axis=(1, 2)))
    rank = np.where(failed[:, None], -1, rank)
    release_compiled_programs()
    return BatchResult(index, truth, draws, rank, np.asarray(n_div, dtype=np.int64),
                       _split_rhat(kept), _min_ess(chains), failed)._asdict()


