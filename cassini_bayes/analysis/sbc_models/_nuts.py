"""A vectorisable NUTS fit: the package's one compiled NUTS program as a pure JAX function."""

from __future__ import annotations

import functools
from collections.abc import Callable

import jax
import jax.numpy as jnp
from jax import lax

from cassini_bayes.analysis.sbc_models._contract import SbcFit

__all__ = ["nuts_fit"]


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
