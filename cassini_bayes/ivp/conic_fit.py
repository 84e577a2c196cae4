"""A conic fitted to a perturbed trajectory over a span (Lee §3.3.1: "each conic is chosen such
that across one segment the deviations of the true path from the conic approximation are kept
small").

Rule: the seven numbers ``r0, v0, mu`` at a chosen epoch minimise the sum of squared relative
position errors ``|conic(t) − f(t)| / |f(t)|`` on a grid over the span (Gauss–Newton, with the
Jacobian of Goodyear's propagation by ``jax.jacfwd``). Fitting ``mu`` lets the conic absorb the
mean-motion change of a steady perturbation (an oblate planet's J2), which an osculating conic
(the state at one instant) cannot.
"""

from __future__ import annotations

from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.ivp._checks import check_finite, check_interval, check_mu, \
    check_nonzero_vectors
from cassini_bayes.ivp.conic import Conic, propagate_conic_unchecked

__all__ = ["fit_conic"]


def _unpack(p, r0, v0, scales, mu, *, fit_mu):
    m = scales[2] * (1.0 + p[6]) if fit_mu else mu
    return r0 + scales[0] * p[:3], v0 + scales[1] * p[3:6], m


def _residual_fn(p, r0, v0, scales, mu, dt, target, norm, *, fit_mu):
    r, v, m = _unpack(p, r0, v0, scales, mu, fit_mu=fit_mu)
    pos = propagate_conic_unchecked(r, v, m, dt).r
    return ((pos - target) / norm).reshape(-1)


_residual = jax.jit(_residual_fn, static_argnames="fit_mu")
_jacobian = jax.jit(jax.jacfwd(_residual_fn), static_argnames="fit_mu")


def fit_conic(f: Callable[[np.ndarray], np.ndarray], t_start_s: float, t_end_s: float, *,
              r0, v0, mu: float, t0_s: float, fit_mu: bool = True, n_points: int = 400,
              iterations: int = 12) -> Conic:
    """Least-squares conic to the vector ``f`` (times (N,) s → (N, 3) m) over
    ``[t_start_s, t_end_s]`` (module docstring).

    Parameters
    ----------
    r0, v0 : first guess of the state at ``t0_s`` (m, m/s), e.g. the osculating one.
    mu : first guess (or, with ``fit_mu=False``, the value) of the gravitational parameter,
        m³/s².
    t0_s : the conic's epoch, s.
    n_points : grid points over the span (Chebyshev-spaced, denser at the ends).
    iterations : Gauss–Newton steps.
    """
    check_interval(float(t_start_s), float(t_end_s), "the span to fit")
    r0, v0 = np.asarray(r0, float), np.asarray(v0, float)
    for x, name in ((r0, "r0"), (v0, "v0")):
        check_finite(x, name)
    check_nonzero_vectors(r0, "r0")
    check_mu(np.asarray(mu, float), "mu")
    k = np.arange(n_points)
    t = 0.5 * (t_start_s + t_end_s) + 0.5 * (t_end_s - t_start_s) * np.cos(
        np.pi * (k + 0.5) / n_points)
    target = jnp.asarray(np.asarray(f(t), float))
    norm = jnp.linalg.norm(target, axis=-1, keepdims=True)
    dt = jnp.asarray(t - t0_s)
    r_scale, v_scale = float(np.linalg.norm(r0)), max(float(np.linalg.norm(v0)), 1e-300)
    mu_scale = float(mu) if mu > 0 else 1.0

    scales = jnp.asarray([r_scale, v_scale, mu_scale])
    args = (jnp.asarray(r0), jnp.asarray(v0), scales, jnp.asarray(float(mu)), dt, target, norm)
    p = jnp.zeros(7)
    n_free = 7 if fit_mu else 6
    for _ in range(iterations):
        j = np.asarray(_jacobian(p, *args, fit_mu=fit_mu))[:, :n_free]
        res = np.asarray(_residual(p, *args, fit_mu=fit_mu))
        step, *_ = np.linalg.lstsq(j, -res, rcond=None)
        p = p.at[:n_free].add(step)
        if np.max(np.abs(step)) < 1e-15:
            break
    r, v, m = _unpack(p, *args[:4], fit_mu=fit_mu)
    return Conic(np.asarray(r), np.asarray(v), float(m), float(t0_s))
