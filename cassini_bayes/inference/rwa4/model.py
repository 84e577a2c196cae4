"""The RWA4 model's charts (gnomonic axis, the RWA and RCS inertia coordinates), the log
density and the NumPyro model per chart (:mod:`cassini_bayes.inference.rwa4`, "Sampler
coordinates").
"""

from __future__ import annotations

from functools import lru_cache

import jax
import jax.numpy as jnp
import numpyro
import numpyro.distributions as dist
from numpyro.distributions import constraints

from cassini_bayes.inference.inertia import pi_from_cholesky_params
from cassini_bayes.inference.rwa4.likelihood import DATA_KEYS, loglik
from cassini_bayes.inference.rwa4.prior import log_physical_factor
from cassini_bayes.names import INERTIA_NAMES, U4_NAMES

__all__ = ["rwa4_model"]


def _gnomonic(v, kw):
    """Unit vector of the gnomonic chart ``v`` (2,) about ``u0`` and ``log dΩ/dv``."""
    s = 1.0 + jnp.sum(v**2)
    u = (kw.u0 + v @ kw.basis) / jnp.sqrt(s)
    return u, -1.5 * jnp.log(s)


def _physical_rwa(theta, kw):
    """``u`` (3,), ``π`` (6,) kg m², ``ξ = L⁻¹(π − μ)`` and the log Jacobian of
    ``θ = (v (2), ζ (6))`` plus the log physical factor (:func:`log_physical_factor`):
    log-Cholesky inertia coordinates ``lp = lp₀ + T ζ`` (physical by construction,
    :func:`~cassini_bayes.inference.inertia.pi_from_cholesky_params`)."""
    u, log_jac = _gnomonic(theta[:2], kw)
    lp = kw.lp_centre + kw.lp_tril @ theta[2:8]
    pi = pi_from_cholesky_params(lp)
    xi = jax.scipy.linalg.solve_triangular(kw.pi_chol, pi - kw.pi_mean, lower=True)
    # log|det ∂π/∂lp| up to a constant: exp of the diagonal gives Σ lp_ii, L → L Lᵀ gives
    # 2³ L00³ L11² L22, Σ → I = tr(Σ) 1 − Σ is linear
    return u, pi, xi, (log_jac + 4.0 * lp[0] + 3.0 * lp[1] + 2.0 * lp[2]
                       + log_physical_factor(pi, kw.margin_scale))


_KNEE = 0.5          # the RCS chart's radial map is the identity up to this fraction of the way
_BOX_DIM = 5         # to the nearest wall of the physical region of (s, ω)
_Q_MAX = 12.0        # beyond, 1 − tanh(q) < 1e-10 would not resolve the wall: density 0 there


def _radial(y, kw):
    """The RCS chart's radial map ``y`` (5,) → ``x = (s, ω)`` (5,) inside the physical region,
    boundary at infinity, and ``log|det ∂x/∂y|``.

    ``x = c + C y φ(f)/f`` with ``f = λ_max(−Σ_k y_k W_k)`` the fraction of the way from the
    centre ``c`` to the wall along the ray (:func:`~cassini_bayes.inference.rwa4.data._rcs_chart`:
    the region is convex and ``A(c + C y) = L_c (1 + Σ_k y_k W_k) L_cᵀ``), ``φ(f) = f`` up to
    ``_KNEE``, then ``_KNEE + (1 − _KNEE) tanh((f − _KNEE)/(1 − _KNEE))`` (twice differentiable,
    → 1 at infinity). A radial map's Jacobian is ``(φ(f)/f)^(n−1) φ'(f)``. Where ``tanh`` no
    longer resolves the wall (``_Q_MAX``, ~100 log-units below the knee) the density is 0.
    """
    def fraction(y):
        return jnp.linalg.eigvalsh(-jnp.einsum("k,kab->ab", y, kw.rcs_walls))[-1]

    # the branch from an undifferentiated value: at y = 0 the eigenvalues are degenerate and
    # their derivatives not finite; where the map is the identity f is evaluated elsewhere
    over = jax.lax.stop_gradient(fraction(y)) > _KNEE
    f = fraction(jnp.where(over, y, jnp.eye(_BOX_DIM)[0]))
    q = jnp.where(over, (f - _KNEE) / (1.0 - _KNEE), 0.0)
    ratio = jnp.where(over, (_KNEE + (1.0 - _KNEE) * jnp.tanh(q)) / jnp.where(over, f, 1.0), 1.0)
    log_sech2 = jnp.where(q < _Q_MAX, -2.0 * (q + jnp.log1p(jnp.exp(-2.0 * q)) - jnp.log(2.0)),
                          -jnp.inf)
    x = kw.rcs_centre + kw.rcs_scale @ (y * ratio)
    return x, (_BOX_DIM - 1) * jnp.log(ratio) + log_sech2


def _physical_rcs(theta, kw):
    """As :func:`_physical_rwa` for ``θ = (δ (2), log|z| (1), y (5))`` (module docstring,
    "Sampler coordinates"): ``x = (s, ω)`` from ``y`` (:func:`_radial`); ``z = z_a + t ζ(s)``
    on the ray from the zero-inertia point ``z_a`` in the direction ``ζ(s)`` of the gnomonic
    chart about ``−u0``, ``|z| = e^ρ``; ``π = (t/√(1 + |s|²)) P [1; x]``; the axis
    ``u = g(v_z + δ)`` with ``v_z`` the chart of ``−z``."""
    delta, rho, y = theta[:2], theta[2], theta[3:8]
    x, log_jac_box = _radial(y, kw)
    s = x[:2]
    q2 = 1.0 + jnp.sum(s**2)
    zeta = -(kw.u0 + s @ kw.basis) / jnp.sqrt(q2)
    b = kw.rcs_apex @ zeta
    root = jnp.sqrt(b**2 - jnp.sum(kw.rcs_apex**2) + jnp.exp(2.0 * rho))
    t = root - b                                   # |z − z_a|: the positive root of |z| = e^ρ
    z = kw.rcs_apex + t * zeta
    v_z = (kw.basis @ z) / (kw.u0 @ z)
    u, log_jac_u = _gnomonic(v_z + delta, kw)
    scale = t / jnp.sqrt(q2)
    pi = scale * (kw.rcs_pi @ jnp.concatenate([jnp.ones(1), x]))
    xi = jax.scipy.linalg.solve_triangular(kw.pi_chol, pi - kw.pi_mean, lower=True)
    # d³z = t² dt dΩ(ζ), dt/dρ = e^{2ρ}/root, dΩ = (1 + |s|²)^(−3/2) ds; w = w_a + scale ω;
    # π linear in (z, w): the physical truncation is an explicit factor
    log_jac_z = 2.0 * jnp.log(t) + 2.0 * rho - jnp.log(root) - 1.5 * jnp.log(q2)
    return u, pi, xi, (log_jac_u + log_jac_z + 3.0 * jnp.log(scale) + log_jac_box
                       + log_physical_factor(pi, kw.margin_scale))


def _log_density_with(physical, theta, kw):
    u, pi, xi, log_jac = physical(theta, kw)
    # Gaussian inertia prior (physical truncation in the chart's Jacobian term); uniform u on
    # the sphere (chart Jacobian), times the articulation-cone factor when chosen
    log_prior = -0.5 * jnp.sum(xi**2) + log_jac
    angle = jnp.arccos(jnp.clip(u @ kw.cone_axis, -1.0, 1.0))
    log_prior += -0.5 * kw.cone_weight * ((angle - kw.cone_angle) / kw.cone_sd) ** 2
    data = {k: getattr(kw, k) for k in DATA_KEYS}
    return log_prior + loglik(u, pi, kw.log_noise_hat, u_ref=kw.u0, pi_ref=kw.pi_mean, **data)


def _log_density_rcs(theta, kw):
    """Log prior + log likelihood, RCS chart (module docstring)."""
    return _log_density_with(_physical_rcs, theta, kw)


def _log_density_rwa(theta, kw):
    """Log prior + log likelihood, direct chart (module docstring)."""
    return _log_density_with(_physical_rwa, theta, kw)


LOG_DENSITY = {"rcs": _log_density_rcs, "rwa": _log_density_rwa}
PHYSICAL = {"rcs": _physical_rcs, "rwa": _physical_rwa}


@lru_cache(maxsize=None)
def rwa4_model(chart: str = "rwa"):
    """The NumPyro model of a chart (``Rwa4Problem.chart``); one function object per chart, so
    compiled samplers are reused.

    Call it with ``data=Rwa4Problem.data``. Posterior sites: ``u4_x``, ``u4_y``, ``u4_z``
    (the solved wheel's axis), ``Ixx … Iyz`` (kg m²) and the sampler's whitened ``w``
    (``θ = centre + tril w``).
    """
    log_density, physical = LOG_DENSITY[chart], PHYSICAL[chart]

    def model(data):
        w = numpyro.sample("w", dist.ImproperUniform(constraints.real_vector, (),
                                                     data.centre.shape))
        theta = data.centre + data.tril @ w
        numpyro.factor("log_density", log_density(theta, data))
        u, pi, _, _ = physical(theta, data)
        for i, name in enumerate(U4_NAMES):
            numpyro.deterministic(name, u[i])
        for i, name in enumerate(INERTIA_NAMES):
            numpyro.deterministic(name, pi[i])

    model.__name__ = f"rwa4_model_{chart}"
    return model
