"""Gaussian algebra shared by the likelihoods: closed-form 3×3 inverses and the exact
marginalisation of a flat per-event offset and of linear nuisance parameters with Gaussian priors
(the thrust model's offsets and robust effects; Feldman & Lee 2006 Eq 17 with the robust terms).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

__all__ = ["inv3_spd", "ColumnStatistics", "column_statistics", "OffsetMarginal", "offset_marginal",
           "nuisance_marginal"]


def inv3_spd(b):
    """Inverse and log-determinant of batches (..., 3, 3) of symmetric positive-definite
    matrices, in closed form (LAPACK calls on 3×3 matrices cost far more than the arithmetic)."""
    c00 = b[..., 1, 1] * b[..., 2, 2] - b[..., 1, 2] * b[..., 1, 2]
    c11 = b[..., 0, 0] * b[..., 2, 2] - b[..., 0, 2] * b[..., 0, 2]
    c22 = b[..., 0, 0] * b[..., 1, 1] - b[..., 0, 1] * b[..., 0, 1]
    c01 = b[..., 0, 2] * b[..., 1, 2] - b[..., 0, 1] * b[..., 2, 2]
    c02 = b[..., 0, 1] * b[..., 1, 2] - b[..., 0, 2] * b[..., 1, 1]
    c12 = b[..., 0, 1] * b[..., 0, 2] - b[..., 0, 0] * b[..., 1, 2]
    det = b[..., 0, 0] * c00 + b[..., 0, 1] * c01 + b[..., 0, 2] * c02
    adj = jnp.stack([jnp.stack([c00, c01, c02], -1), jnp.stack([c01, c11, c12], -1),
                     jnp.stack([c02, c12, c22], -1)], -2)
    return adj / det[..., None, None], jnp.log(det)


class ColumnStatistics(NamedTuple):
    """Data-only sums of one event's nuisance columns ``C_i`` (n, 3, R) over its samples, which
    :func:`offset_marginal` contracts with the parameter-dependent ``B⁻¹`` instead of forming
    ``Σ_i C_iᵀ B⁻¹ C_i`` sample by sample at every gradient."""

    gram: object        # (3, 3, R, R) Σ_i mask_i C_i[a, :]ᵀ C_i[b, :]
    total: object       # (3, R) Σ_i mask_i C_i


def column_statistics(cols, mask) -> ColumnStatistics:
    """:class:`ColumnStatistics` of columns ``cols`` (n, 3, R) over the rows with ``mask`` 1."""
    masked = cols * mask[:, None, None]
    return ColumnStatistics(jnp.einsum("nar,nbs->abrs", masked, cols), jnp.sum(masked, 0))


class OffsetMarginal(NamedTuple):
    """What :func:`offset_marginal` returns for one event."""

    loglik: object      # log ∫ Π_i N(r_i − β; 0, Σ_i) dβ at ν = 0
    info: object        # (R, R) Σ D̄_iᵀ P_i D̄_i: the event's information on ν, offset removed
    score: object       # (R,) Σ D̄_iᵀ P_i d_i: the linear term, ∂ loglik/∂ν at ν = 0
    resid: object       # (n, 3) r − β̂, N m s


def offset_marginal(r, b, m, mask, cols, stats: ColumnStatistics):
    """The flat offset ``β`` (3,) of one event integrated out, exactly, with per-sample
    covariances ``Σ_i = B + m_i m_iᵀ``; rows with ``mask`` 0 are left out.

    The per-sample precisions ``P_i`` come from Sherman–Morrison,
    ``(B + m mᵀ)⁻¹ = B⁻¹ − u_i u_iᵀ/g_i``, ``u_i = B⁻¹m_i``, ``g_i = 1 + mᵢᵀB⁻¹m_i``;
    ``β̂ = (Σ P_i)⁻¹ Σ P_i r_i`` and the integral adds ``(3/2) log 2π − ½ log|Σ_i P_i|``. ``cols``
    (n, 3, R) are the columns of the nuisance ``ν`` in the residual ``r_i − cols_i ν``: the
    log-likelihood is exactly quadratic in ``ν``, ``loglik − ½ νᵀ info ν + scoreᵀ ν``
    (:class:`OffsetMarginal`), with the columns' offset part removed
    (``D̄_i = D_i − (Σ P)⁻¹ Σ P_j D_j``), so the events' terms add up. ``stats`` =
    :func:`column_statistics` ``(cols, mask)``.

    The information ``Σ_i C_iᵀ P_i C_i`` is split the same way: ``Σ_ab B⁻¹_ab gram_ab`` (the
    data-only ``gram`` contracted with ``B⁻¹``, 9R² work) less ``Σ_i v_i v_iᵀ/g_i``,
    ``v_i = C_iᵀ u_i`` (nR² instead of 3nR² work; the thrust gradient's largest term).
    """
    # Every sum over samples is a product of (n, 3) arrays with 3-vectors or 3×3 matrices: no
    # (n, 3, 3) array of per-sample precisions is formed (docs/performance.md: the robust thrust
    # density's value and gradient, 481 samples, R = 19, ~15 % faster than with them).
    b_inv, logdet = inv3_spd(b)
    u = m @ b_inv                                                     # B⁻¹ m_i (n, 3)
    g = 1.0 + jnp.sum(u * m, -1)
    a = mask / g                                                      # 0 on padding
    ur = jnp.sum(u * r, -1)
    p_inv, p_logdet = inv3_spd(jnp.sum(mask) * b_inv - (u * a[:, None]).T @ u)   # (Σ P_i)⁻¹
    beta = p_inv @ (b_inv @ (mask @ r) - u.T @ (a * ur))              # β̂ = (Σ P_i)⁻¹ Σ P_i r_i
    d = r - beta[None, :]
    ud = ur - u @ beta                                                # u_i · d_i
    db = d @ b_inv
    quad = jnp.sum(db * d, -1) - ud**2 / g                            # d_iᵀ P_i d_i
    ll_i = -0.5 * (quad + logdet + jnp.log(g) + 3.0 * jnp.log(2.0 * jnp.pi))
    ll = jnp.sum(ll_i * mask) + 1.5 * jnp.log(2.0 * jnp.pi) - 0.5 * p_logdet
    v = jnp.sum(cols * u[:, :, None], 1)                              # C_iᵀ u_i (n, R)
    vg = v * a[:, None]
    s_bd = b_inv @ stats.total - u.T @ vg                             # Σ P_i C_i (3, R)
    info = (jnp.einsum("ab,abrs->rs", b_inv, stats.gram) - vg.T @ v
            - s_bd.T @ p_inv @ s_bd)
    w = db * mask[:, None]                                            # B⁻¹ d_i, masked rows
    score = jnp.sum(cols * w[:, :, None], (0, 1)) - vg.T @ ud         # Σ C_iᵀ P_i d_i
    return OffsetMarginal(ll, info, score, d)


def nuisance_marginal(info, score, nu_sd):
    """``log ∫ exp(scoreᵀν − ½ νᵀ info ν) N(ν; 0, diag(nu_sd²)) dν`` and the Gaussian
    conditional of the whitened ``z = ν / nu_sd``: its mean ``A⁻¹ s̃`` and the lower Cholesky
    factor ``L`` of ``A = diag(sd) info diag(sd) + I`` (the conditional covariance is
    ``A⁻¹ = L⁻ᵀ L⁻¹``). The integral is ``½ s̃ᵀ A⁻¹ s̃ − log|L|``, ``s̃ = sd ⊙ score``."""
    a = nu_sd[:, None] * info * nu_sd[None, :] + jnp.eye(nu_sd.shape[0])
    chol = jnp.linalg.cholesky(0.5 * (a + a.T))
    y = jax.scipy.linalg.solve_triangular(chol, nu_sd * score, lower=True)
    mean = jax.scipy.linalg.solve_triangular(chol.T, y, lower=False)
    return 0.5 * y @ y - jnp.sum(jnp.log(jnp.diag(chol))), mean, chol
