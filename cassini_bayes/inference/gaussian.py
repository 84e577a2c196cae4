"""Gaussian algebra shared by the likelihoods: closed-form 3×3 inverses and the exact
marginalisation of a flat per-event offset and of linear nuisance parameters with Gaussian priors
(the thrust model's offsets and robust effects; Feldman & Lee 2006 Eq 17 with the robust terms).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

__all__ = ["inv3_spd", "ColumnStatistics", "column_statistics", "OffsetMarginal", "RankOneRows",
           "offset_marginal", "nuisance_marginal", "nuisance_log_marginal"]


@jax.custom_jvp
def inv3_spd(b):
    """Inverse and log-determinant of batches (..., 3, 3) of symmetric positive-definite
    matrices, in closed form (LAPACK calls on 3×3 matrices cost far more than the arithmetic).
    Its derivative is stated (``d B⁻¹ = −B⁻¹ dB B⁻¹``, ``d log|B| = tr(B⁻¹ dB)``): the
    derivative of the cofactors, element by element, was some thirty XLA kernels per call."""
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


@inv3_spd.defjvp
def _inv3_spd_jvp(primals, tangents):
    (b,), (db,) = primals, tangents
    inv, logdet = inv3_spd(b)
    return (inv, logdet), (-inv @ db @ inv, jnp.sum(inv * jnp.swapaxes(db, -1, -2), (-2, -1)))


class ColumnStatistics(NamedTuple):
    """Data-only sums of one event's nuisance columns ``C_i`` (3, R) over its samples, which
    :func:`offset_marginal` contracts with the parameter-dependent ``B⁻¹`` instead of forming
    ``Σ_i C_iᵀ B⁻¹ C_i`` sample by sample at every gradient."""

    gram: object        # (R, R, 3, 3) Σ_i mask_i C_i[a, r] C_i[b, s], indexed [r, s, a, b]
    total: object       # (3, R) Σ_i mask_i C_i


def column_statistics(cols, mask) -> ColumnStatistics:
    """:class:`ColumnStatistics` (NumPy, data only) of columns ``cols`` (R, 3, n) over the
    samples with ``mask`` (n,) 1."""
    cols = np.asarray(cols, float)
    masked = cols * np.asarray(mask, float)[None, None, :]
    return ColumnStatistics(np.einsum("rai,sbi->rsab", masked, cols, optimize=True),
                            masked.sum(-1).T)


class OffsetMarginal(NamedTuple):
    """What :func:`offset_marginal` returns for one event."""

    loglik: object      # log ∫ Π_i N(r_i − β; 0, Σ_i) dβ at ν = 0
    info: object        # (R, R) Σ D̄_iᵀ P_i D̄_i: the event's information on ν, offset removed
    score: object       # (R,) Σ D̄_iᵀ P_i d_i: the linear term, ∂ loglik/∂ν at ν = 0
    resid: object       # (3, n) r − β̂, N m s


class RankOneRows(NamedTuple):
    """The samples whose covariance has a rank-one term ``m_i m_iᵀ`` (:func:`offset_marginal`):
    every other sample's ``m_i`` is zero, so its precision is ``B⁻¹`` itself."""

    rows: object        # (p,) int, their sample indices (padding: any index, with m_i = 0)
    cols: object        # 3 × (R, p): the nuisance columns at those samples, one array per axis


def offset_marginal(r, b, m, mask, rank_one: RankOneRows, cols, stats: ColumnStatistics):
    """The flat offset ``β`` (3,) of one event integrated out, exactly, with per-sample
    covariances ``Σ_i = B + m_i m_iᵀ``; samples with ``mask`` 0 are left out.

    Arrays hold one axis component per row (``r`` (3, n), ``m`` (3, p), ``cols`` (R, 3, n)):
    every per-sample product is then a few fused vector operations and every sum over samples
    a matrix product, where the (n, 3) layout made XLA's CPU backend reduce over the short axis
    (docs/performance.md). ``m`` is given only at the samples ``rank_one.rows``; elsewhere it
    is zero (:class:`RankOneRows`).

    The per-sample precisions ``P_i`` come from Sherman–Morrison,
    ``(B + m mᵀ)⁻¹ = B⁻¹ − u_i u_iᵀ/g_i``, ``u_i = B⁻¹m_i``, ``g_i = 1 + mᵢᵀB⁻¹m_i``;
    ``β̂ = (Σ P_i)⁻¹ Σ P_i r_i`` and the integral adds ``(3/2) log 2π − ½ log|Σ_i P_i|``. ``cols``
    are the columns of the nuisance ``ν`` in the residual ``r_i − cols_i ν``: the
    log-likelihood is exactly quadratic in ``ν``, ``loglik − ½ νᵀ info ν + scoreᵀ ν``
    (:class:`OffsetMarginal`), with the columns' offset part removed
    (``D̄_i = D_i − (Σ P)⁻¹ Σ P_j D_j``), so the events' terms add up. ``stats`` =
    :func:`column_statistics` ``(cols, mask)``.

    The information ``Σ_i C_iᵀ P_i C_i`` is split the same way: ``Σ_ab B⁻¹_ab gram_ab`` (the
    data-only ``gram`` contracted with ``B⁻¹``, 9R² work) less ``Σ_i v_i v_iᵀ/g_i``,
    ``v_i = C_iᵀ u_i`` over the rank-one samples only.
    """
    b_inv, logdet = inv3_spd(b)
    n_eff = jnp.sum(mask)
    r_p = r[:, rank_one.rows]                                         # (3, p)
    u = b_inv @ m                                                     # B⁻¹ m_i (3, p)
    g = 1.0 + jnp.sum(u * m, 0)                                       # (p,)
    ug = u / g[None, :]
    ur = jnp.sum(u * r_p, 0)
    p_inv, p_logdet = inv3_spd(n_eff * b_inv - ug @ u.T)              # (Σ P_i)⁻¹
    beta = p_inv @ (b_inv @ (r @ mask) - ug @ ur)                     # β̂ = (Σ P_i)⁻¹ Σ P_i r_i
    d = r - beta[:, None]
    ud = ur - beta @ u                                                # u_i · d_i
    db = (b_inv @ d) * mask[None, :]                                  # B⁻¹ d_i, masked samples
    quad = jnp.sum(db * d) - jnp.sum(ud * ud / g)                     # Σ d_iᵀ P_i d_i
    ll = (-0.5 * (quad + n_eff * (logdet + 3.0 * jnp.log(2.0 * jnp.pi)) + jnp.sum(jnp.log(g)))
          + 1.5 * jnp.log(2.0 * jnp.pi) - 0.5 * p_logdet)
    rc = rank_one.cols
    v = rc[0] * u[0][None] + rc[1] * u[1][None] + rc[2] * u[2][None]   # C_iᵀ u_i (R, p)
    # (three arrays, not slices of one: XLA copied each slice at every gradient)
    vg = v / g[None, :]
    s_bd = b_inv @ stats.total - ug @ v.T                             # Σ P_i C_i (3, R)
    info = (jnp.tensordot(stats.gram, b_inv, 2) - vg @ v.T - s_bd.T @ p_inv @ s_bd)
    score = (jnp.reshape(cols, (cols.shape[0], db.size)) @ jnp.reshape(db, (-1,))
             - vg @ ud)                                               # Σ C_iᵀ P_i d_i
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


@jax.custom_jvp
def nuisance_log_marginal(info, score, nu_sd):
    """The log-integral of :func:`nuisance_marginal` alone, with its derivative stated:
    ``½ s̃ᵀ A⁻¹ s̃ − ½ log|A|`` changes by ``μᵀ ds̃ − ½ μᵀ dA μ − ½ tr(A⁻¹ dA)`` (``μ = A⁻¹ s̃``),
    one triangular inverse where the derivative of the Cholesky factorisation and of the two
    triangular solves took some twenty XLA kernels (LAPACK calls among them) per gradient."""
    return nuisance_marginal(info, score, nu_sd)[0]


@nuisance_log_marginal.defjvp
def _nuisance_log_marginal_jvp(primals, tangents):
    info, score, sd = primals
    d_info, d_score, d_sd = tangents
    value, mean, chol = nuisance_marginal(info, score, sd)
    l_inv = jax.scipy.linalg.solve_triangular(chol, jnp.eye(sd.shape[0]), lower=True)
    g = -0.5 * (jnp.outer(mean, mean) + l_inv.T @ l_inv)        # ∂ value / ∂A
    coef_info = sd[:, None] * g * sd[None, :]
    tangent = jnp.sum(coef_info * d_info) + (sd * mean) @ d_score
    tangent = tangent + 2.0 * jnp.sum(g * info * sd[None, :], 1) @ d_sd + (mean * score) @ d_sd
    return value, tangent
