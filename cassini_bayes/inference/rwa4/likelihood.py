"""The RWA4 model's likelihood: the change of the window-mean inertial momentum per A/B pair
(Brown 2012 Eqs 1, 3), its white-noise covariance and the robust effects integrated out
(:mod:`cassini_bayes.inference.rwa4`, "Model").
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.physics.momentum import inertia_matrix

if TYPE_CHECKING:
    from cassini_bayes.inference.rwa4.data import Rwa4Problem

__all__ = ["balance_misfit"]


def balance(u, pi, *, m_pi, r_u, k_h, j4):
    """Change of the window-mean inertial momentum per pair, ``d_g`` (G, 3) N m s (Brown Eqs 1,
    3): ``⟨Aᵀ(I ω + h_known + J_4 ρ_4 u4)⟩_B − ⟨…⟩_A``, zero for a perfect model."""
    h = m_pi @ pi + j4 * r_u @ u + k_h                                  # (W, 3) inertial means
    return h[1::2] - h[0::2]


def slopes(u, pi, *, m_pi_s, r_u_s, k_h_s, j4):
    """Each quiet window's least-squares slope of the inertial momentum against time, ``s_w``
    (S, 3) N m: ``Σ_i w_i Aᵀ(I ω + h_known + J_4 ρ_4 u4)_i``, ``w_i = (t_i − t̄)/Σ(t − t̄)²``.
    Euler's law in inertial axes (Feldman & Lee Eq 2 with the wheels' momentum; Brown Eqs 1, 3
    hold ``H`` constant): ``dH/dt = T``, so ``s_w`` is the external torque at the window,
    zero for a perfect model."""
    return m_pi_s @ pi + j4 * r_u_s @ u + k_h_s


def window_cov(u, pi, log_sigma, *, n, t_aa, j4, known_cov):
    """(W, 3, 3) white-noise covariance of a weighted window sum ``Σ_i w_i Aᵢᵀ c_i`` (a mean
    or a slope) from gyro and wheel-rate noise: ``⟨A_iᵀ B A_i⟩_w / n`` (``t_aa`` the
    ``w²``-weighted ``⟨A ⊗ A⟩``, ``n = 1/Σ w²``),
    ``B = σ_ω² I I + σ_ρ² (Σ_known J_k² g_k g_kᵀ + J_4² u4 u4ᵀ)``."""
    i_m = inertia_matrix(pi)
    s2 = jnp.exp(2.0 * log_sigma)
    b = s2[0] * (i_m @ i_m) + s2[1] * (known_cov + j4**2 * jnp.outer(u, u))
    return jnp.einsum("wjakb,jk->wab", t_aa, b) / n[:, None, None]


def noise_cov(u, pi, log_sigma, *, n_w, t_aa, j4, known_cov):
    """(G, 3, 3) covariance of ``d_g`` from white gyro and wheel-rate noise:
    ``C_A/n_A + C_B/n_B`` (:func:`window_cov`)."""
    c_w = window_cov(u, pi, log_sigma, n=n_w, t_aa=t_aa, j4=j4, known_cov=known_cov)
    return c_w[1::2] + c_w[0::2]


def nuisance_cols(u, pi, *, r_u, j4, nu_cols, nu_pi, nu_wheel):
    """(G, 3, R) columns of the robust nuisance vector ``ν`` in ``d_g``: the fixed inertial
    columns of :func:`~cassini_bayes.inference.rwa4.window_means.nuisance_means`, the gyro
    columns at the inertia ``π`` (``nu_pi · π``), and the solved wheel's part of its
    spin-inertia scale (its own per-wheel scale, or the common one), ``J_4 Δ⟨ρ_4 Aᵀ⟩ u4`` (it
    depends on ``u4``)."""
    d_r = (r_u[1::2] - r_u[0::2]) @ u                                  # (G, 3)
    return nu_cols + nu_pi @ pi + j4 * d_r[:, :, None] * nu_wheel[None, None, :]


def rows(u, pi, log_sigma, *, m_pi, r_u, k_h, n_w, t_aa, j4, known_cov, m_pi_s, r_u_s, k_h_s,
         n_s, t_aa_s, nu_cols, nu_cols_s, nu_pi, nu_pi_s, nu_sd, nu_wheel):
    """The data vector of :func:`loglik`, ``(d_1 … d_G, s_1 … s_S)`` (N m s, N m), its
    white-noise covariance and its nuisance columns scaled by the prior sds, ``D diag(ν_sd)``.

    A window's mean and slope weights are orthogonal, so their white noise is uncorrelated to
    first order (exactly for a constant per-sample covariance): the covariance is block
    diagonal. The slope rows' columns are the slopes of the same per-sample columns
    (:func:`~cassini_bayes.inference.rwa4.window_means.nuisance_means`) plus the solved wheel's
    scale part ``J_4 (Σ w ρ_4 Aᵀ) u4``."""
    d = jnp.concatenate([balance(u, pi, m_pi=m_pi, r_u=r_u, k_h=k_h, j4=j4).ravel(),
                         slopes(u, pi, m_pi_s=m_pi_s, r_u_s=r_u_s, k_h_s=k_h_s, j4=j4).ravel()])
    cov = jax.scipy.linalg.block_diag(
        *noise_cov(u, pi, log_sigma, n_w=n_w, t_aa=t_aa, j4=j4, known_cov=known_cov),
        *window_cov(u, pi, log_sigma, n=n_s, t_aa=t_aa_s, j4=j4, known_cov=known_cov))
    cols_s = nu_cols_s + nu_pi_s @ pi + j4 * (r_u_s @ u)[:, :, None] * nu_wheel[None, None, :]
    cols = jnp.concatenate([
        nuisance_cols(u, pi, r_u=r_u, j4=j4, nu_cols=nu_cols, nu_pi=nu_pi,
                      nu_wheel=nu_wheel).reshape(3 * nu_cols.shape[0], nu_sd.size),
        cols_s.reshape(3 * nu_cols_s.shape[0], nu_sd.size)])
    return d, cov, cols * nu_sd[None, :]


def loglik(u, pi, log_sigma, *, u_ref, pi_ref, **data):
    """Log-likelihood of the window-mean momentum balance of all A/B pairs (Brown Eqs 1, 3) and,
    RWA method, of each quiet window's momentum slope (:func:`slopes`):
    ``(d, s) ~ N(0, blockdiag(C) + D diag(ν_sd²) Dᵀ)`` (:func:`rows`), the white-noise part of
    the normalising determinant taken at the fixed ``(u_ref, pi_ref)``: ``d`` is computed from
    the measured rates, so its noise already carries ``π`` and ``u`` (``I ε``, ``J₄ δρ₄ u``),
    and a determinant of ``C(π, u)`` would count that twice (expected score at the truth
    ``−tr(S⁻¹ ∂C/∂π)``, a pull towards smaller inertia; with gyro noise alone the rates'
    density ``N(d/I; 0, σ²)`` has no ``I`` in its normaliser).

    ``d_g`` is :func:`balance`, its ``C_g`` :func:`noise_cov`, a slope's :func:`window_cov`;
    ``D`` (:func:`nuisance_cols`) holds the robust model's nuisance effects, which enter both
    linearly with zero-mean Normal priors and are integrated out exactly (``R = 0`` columns: the
    idealised model). One effect is shared by every row, so the rows are correlated: an
    external torque moves the balance by its integral between the windows and each slope by
    its value, so the slopes measure it. Window arrays (index ``w = 2g`` for A, ``2g + 1`` for
    B): ``m_pi`` (W, 3, 6) with ``⟨Aᵀ I ω⟩ = m_pi π``; ``r_u`` (W, 3, 3) = ``⟨ρ_4 Aᵀ⟩``;
    ``k_h`` (W, 3) = ``⟨Aᵀ h_known⟩``; ``n_w`` (W,) sample counts; ``t_aa`` (W, 3, 3, 3, 3) =
    ``⟨A_jk A_lm⟩``; the ``*_s`` arrays the same with the slope weights (S = W or 0).
    """
    d, cov, cols = rows(u, pi, log_sigma, **data)
    chol = jnp.linalg.cholesky(cov + cols @ cols.T)
    r = jax.scipy.linalg.solve_triangular(chol, d, lower=True)
    _, cov_ref, _ = rows(u_ref, pi_ref, log_sigma, **data)
    logdet = 2.0 * jnp.sum(jnp.log(jnp.diag(jnp.linalg.cholesky(cov_ref + cols @ cols.T))))
    return -0.5 * (r @ r + logdet + d.shape[0] * jnp.log(2.0 * jnp.pi))


DATA_KEYS = ("m_pi", "r_u", "k_h", "n_w", "t_aa", "j4", "known_cov", "m_pi_s", "r_u_s", "k_h_s",
             "n_s", "t_aa_s", "nu_cols", "nu_cols_s", "nu_pi", "nu_pi_s", "nu_sd", "nu_wheel")
"""The :class:`~cassini_bayes.inference.rwa4.data.Rwa4Data` fields :func:`loglik` reads."""


def balance_misfit(problem: Rwa4Problem, u, pi) -> tuple[float, int]:
    """``χ² = dᵀ S⁻¹ d`` of the rows ``d`` (window-mean balances and, RWA method, the windows'
    slopes; :func:`rows`) at the axis ``u`` (3,) and inertia ``pi`` (6,) kg m², with ``S`` the
    likelihood's covariance (white noise plus the integrated-out nuisance effects,
    :func:`loglik`), and its degrees of freedom, the number of rows less 2 (the axis's two are
    fitted; an inertia the balance also informs makes χ² smaller still). A model that fits
    gives ``χ²`` about its dof; an unmodelled effect larger than its prior allows shows as a
    large one."""
    kw = problem.data
    u = jnp.asarray(np.asarray(u, float) / np.linalg.norm(u))
    d, cov, cols = (np.asarray(x) for x in rows(
        u, jnp.asarray(pi, float), kw.log_noise_hat, **{k: getattr(kw, k) for k in DATA_KEYS}))
    chi2 = float(d @ np.linalg.solve(cov + cols @ cols.T, d))
    return chi2, max(d.size - 2, 1)
