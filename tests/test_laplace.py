"""The Laplace step that centres and whitens the thrust and RWA4 samplers
(cassini_bayes.inference.laplace): its mode and its finite-difference Hessian."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.inference.laplace import laplace


def _log_density(x, data):
    """A correlated Gaussian in ``x`` with scales from 1e-4 to 10 (as the thrust's parameters
    span), plus a quartic term that makes the Hessian depend on the point."""
    d = x - data["mode"]
    return -0.5 * d @ data["prec"] @ d - 0.1 * jnp.sum((d / data["scale"]) ** 4)


def test_laplace_finds_the_mode_and_the_inverse_hessian():
    """From a start far out in the raw coordinates (10⁴ of the narrowest scale): the mode within
    1e-4 posterior sd (the Newton decrement's tolerance, 1e-8, is that distance squared), and
    ``tril trilᵀ`` equal to the inverse of ``jax.hessian``'s negative Hessian there to 1e-7
    relative (the central differences' error is ~1e-9)."""
    rng = np.random.default_rng(0)
    scale = np.array([1e-4, 3e-3, 0.2, 1.0, 10.0])
    corr = np.corrcoef(rng.normal(size=(5, 12)))
    cov = corr * np.outer(scale, scale)
    data = {"mode": jnp.asarray(rng.normal(size=5) * scale + 1.0),
            "prec": jnp.asarray(np.linalg.inv(cov)), "scale": jnp.asarray(scale)}
    centre, tril = laplace(_log_density, np.ones(5) + scale, data)
    whitened = np.linalg.solve(tril, centre - np.asarray(data["mode"]))
    assert np.linalg.norm(whitened) < 1e-4
    h = -np.asarray(jax.hessian(_log_density)(jnp.asarray(centre), data))
    np.testing.assert_allclose(tril @ tril.T, np.linalg.inv(h), rtol=1e-7,
                               atol=1e-7 * np.outer(scale, scale).max())


def _noise_density(x, data):
    """A location ``x[0]`` and a log noise scale ``x[1]`` of residuals with sd ``e^{x[1]}``."""
    r = data["y"] - x[0]
    return -r.size * x[1] - 0.5 * jnp.sum(r * r) * jnp.exp(-2.0 * x[1]) - 0.5 * x[0] ** 2


def test_the_scan_starts_the_search_at_the_best_scale():
    """``scan`` sets the scale coordinate to the grid value of highest density before any Newton
    round (``rounds=0`` returns that start): for residuals of sd e³ about 0, the value 3 of the
    grid 0…6, the location left at its start. With the rounds, the search reaches the mode
    (within 1e-4 of the scale's posterior sd, 1/√(2n): the Newton decrement's tolerance)."""
    y = jnp.asarray(np.random.default_rng(1).normal(size=400) * np.exp(3.0))
    data = {"y": y}
    start, _ = laplace(_noise_density, np.zeros(2), data, rounds=0,
                       scan=(np.array([1]), np.arange(0.0, 6.5, 1.0)))
    assert start[0] == 0.0 and start[1] == 3.0
    centre, _ = laplace(_noise_density, np.zeros(2), data,
                        scan=(np.array([1]), np.arange(0.0, 6.5, 1.0)))
    r = np.asarray(y) - centre[0]
    np.testing.assert_allclose(centre[1], 0.5 * np.log(np.mean(r * r)),
                               atol=1e-4 / np.sqrt(2 * r.size))
