"""The spin-axis model's prior: the axis (uniform on the sphere or on the wheel's articulation
cone from the model file) and the inertia (Gaussian times the smooth physical factor), and draws
from it (:mod:`cassini_bayes.inference.rwa4`, "Priors").
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.errors import InputError
from cassini_bayes.names import AXIS_PRIORS, INERTIA_NAMES, U4_NAMES
from cassini_bayes.physics.momentum import inertia_matrix
from cassini_bayes.spacecraft import WheelCone

if TYPE_CHECKING:
    from cassini_bayes.inference.rwa4.data import Rwa4Problem

__all__ = ["PRIORS", "cone_log_factor", "sample_inertia_prior", "sample_rwa4_prior"]

PRIORS = AXIS_PRIORS
_MARGIN_FRACTION = 2.0       # physical-factor scale s = (prior mean's margin) / this
_FACTOR_POWER = 3            # the physical factor is 1 − exp(−(m/s)^this)


def _physical_margin(pi):
    """Smallest eigenvalue (kg m²) of ``½ tr(I) 1 − I``: positive exactly when ``I`` is positive
    definite and obeys the triangle inequalities (the smallest second moment of the mass)."""
    i_m = inertia_matrix(pi)
    return jnp.linalg.eigvalsh(0.5 * jnp.trace(i_m) * jnp.eye(3) - i_m)[0]


def margin_scale(mean) -> jax.Array:
    """The physical factor's scale ``s`` (kg m²): the prior mean's margin / ``_MARGIN_FRACTION``."""
    return jnp.asarray(float(_physical_margin(jnp.asarray(mean, float))) / _MARGIN_FRACTION)


def log_physical_factor(pi, scale):
    """``log(1 − exp(−(m/s)³))`` for margin ``m > 0`` (:func:`_physical_margin`), ``−∞`` for
    ``m ≤ 0``: the physical truncation of the inertia prior, made smooth so that NUTS
    trajectories are turned back before the boundary instead of diverging on a cliff there.

    ``s`` (kg m²) = ½ the prior mean's margin (:data:`_MARGIN_FRACTION`), power 3
    (:data:`_FACTOR_POWER`): the factor is 1 − 3e-4 at the mean, 0.63 half-way to the boundary,
    and near it ``≈ (m/s)³``, a log barrier ``3 log m`` whose curvature at a NUTS turning point of
    energy ``K`` grows as ``e^{2K/3}``; a softer power (``1 − exp(−m/s)``, curvature ``e^{2K}``)
    or a hard cut diverge near the boundary (docs/performance.md, "Other model choices,
    measured").
    """
    m = _physical_margin(pi)
    safe = jnp.where(m > 0, m, 1.0)
    return jnp.where(m > 0, jnp.log(-jnp.expm1(-(safe / scale) ** _FACTOR_POWER)), -jnp.inf)


def cone_log_factor(u, cone: WheelCone):
    """``−½ ((θ − θ_c)/σ_c)²``, ``θ`` the angle (deg) of the unit axis ``u`` (…, 3) from the
    cone's axis: the articulation-cone prior's factor on the sphere (any articulation angle; the
    module docstring of :mod:`cassini_bayes.inference.rwa4`)."""
    theta = np.degrees(np.arccos(np.clip(np.asarray(u, float) @ cone.axis, -1.0, 1.0)))
    return -0.5 * ((theta - cone.angle_deg) / cone.sd_deg) ** 2


def _sample_u4(key, n: int, cone: WheelCone | None) -> np.ndarray:
    """``n`` unit axes uniform on the sphere, times the cone factor by rejection when ``cone``."""
    out, have, r = [], 0, 0
    while have < n:
        x = np.asarray(jax.random.normal(jax.random.fold_in(key, r), (max(4 * n, 1000), 3)))
        u = x / np.linalg.norm(x, axis=1, keepdims=True)
        if cone is not None:
            keep = np.asarray(jax.random.uniform(jax.random.fold_in(key, 10_000 + r),
                                                 (u.shape[0],)))
            u = u[keep < np.exp(cone_log_factor(u, cone))]
        out.append(u)
        have += u.shape[0]
        r += 1
    return np.concatenate(out)[:n]


_log_factors = jax.jit(jax.vmap(log_physical_factor, in_axes=(0, None)))


def sample_inertia_prior(key, mean, cov, n: int) -> np.ndarray:
    """``n`` draws (n, 6) kg m² of the stated inertia prior of both charts: ``Normal(mean, cov)``
    times the physical factor :func:`log_physical_factor` (scale from ``mean`` as in
    :func:`prepare_rwa4`), by rejection: a Gaussian draw is kept with probability
    ``exp(log_physical_factor)`` (0 when unphysical). The one sampler of this prior, used by
    :func:`sample_rwa4_prior` and the SBC truth draws."""
    mean = np.asarray(mean, float)
    chol = np.linalg.cholesky(np.asarray(cov, float))
    scale = margin_scale(mean)
    kept, have = [], 0
    for r in range(1000):
        k_g, k_a = jax.random.split(jax.random.fold_in(key, r))
        pi = mean + np.asarray(jax.random.normal(k_g, (2 * n + 16, 6))) @ chol.T
        log_v = np.log(np.asarray(jax.random.uniform(k_a, (pi.shape[0],))))
        kept.append(pi[log_v < np.asarray(_log_factors(jnp.asarray(pi), scale))])
        have += kept[-1].shape[0]
        if have >= n:
            return np.concatenate(kept)[:n]
    raise InputError("the inertia prior puts almost no mass on physical tensors (< 1e-3 of "
                     "draws kept); check the prior mean and its uncertainties")


def sample_rwa4_prior(key, problem: Rwa4Problem, n: int) -> dict[str, np.ndarray]:
    """``n`` draws of ``u4`` and the inertia entries from the stated prior."""
    k_u, k_i = jax.random.split(key)
    u = _sample_u4(k_u, n, problem.cone if problem.prior == "cone" else None)
    out = {name: u[:, i] for i, name in enumerate(U4_NAMES)}
    pi = sample_inertia_prior(k_i, problem.inertia.mean, problem.inertia.cov, n)
    out.update({name: pi[:, i] for i, name in enumerate(INERTIA_NAMES)})
    return out
