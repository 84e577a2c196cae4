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


def noise_cov(u, pi, log_sigma, *, n_w, t_aa, j4, known_cov):
    """(G, 3, 3) covariance of ``d_g`` from white gyro and wheel-rate noise:
    ``C_A/n_A + C_B/n_B``, ``C_w = ⟨A_iᵀ B A_i⟩_w``,
    ``B = σ_ω² I I + σ_ρ² (Σ_known J_k² g_k g_kᵀ + J_4² u4 u4ᵀ)``."""
    i_m = inertia_matrix(pi)
    s2 = jnp.exp(2.0 * log_sigma)
    b = s2[0] * (i_m @ i_m) + s2[1] * (known_cov + j4**2 * jnp.outer(u, u))
    c_w = jnp.einsum("wjakb,jk->wab", t_aa, b) / n_w[:, None, None]
    return c_w[1::2] + c_w[0::2]


def nuisance_cols(u, *, r_u, j4, nu_cols, nu_wheel):
    """(G, 3, R) columns of the robust nuisance vector ``ν`` in ``d_g``: the fixed inertial
    columns of :func:`_nuisance_means` plus the solved wheel's part of its spin-inertia scale
    (its own per-wheel scale, or the common one), ``J_4 Δ⟨ρ_4 Aᵀ⟩ u4`` (it depends on ``u4``)."""
    d_r = (r_u[1::2] - r_u[0::2]) @ u                                  # (G, 3)
    return nu_cols + j4 * d_r[:, :, None] * nu_wheel[None, None, :]


def loglik(u, pi, log_sigma, *, m_pi, r_u, k_h, n_w, t_aa, j4, known_cov, nu_cols, nu_sd,
            nu_wheel):
    """Log-likelihood of the window-mean momentum balance of all A/B pairs (Brown Eqs 1, 3):
    ``d = (d_1 … d_G) ~ N(0, blockdiag(C_g) + D diag(ν_sd²) Dᵀ)``.

    ``d_g`` is :func:`balance`, ``C_g`` :func:`noise_cov`; ``D`` (:func:`nuisance_cols`)
    holds the robust model's nuisance effects, which enter ``d`` linearly with zero-mean Normal
    priors and are integrated out exactly (``R = 0`` columns: the idealised model). One effect
    is shared by every pair, so the pairs are correlated. Window arrays (index ``w = 2g`` for A,
    ``2g + 1`` for B): ``m_pi`` (W, 3, 6) with ``⟨Aᵀ I ω⟩ = m_pi π``; ``r_u`` (W, 3, 3) =
    ``⟨ρ_4 Aᵀ⟩``; ``k_h`` (W, 3) = ``⟨Aᵀ h_known⟩``; ``n_w`` (W,) sample counts; ``t_aa``
    (W, 3, 3, 3, 3) = ``⟨A_jk A_lm⟩``.
    """
    d = balance(u, pi, m_pi=m_pi, r_u=r_u, k_h=k_h, j4=j4).ravel()
    cov = jax.scipy.linalg.block_diag(*noise_cov(u, pi, log_sigma, n_w=n_w, t_aa=t_aa, j4=j4,
                                                  known_cov=known_cov))
    cols = nuisance_cols(u, r_u=r_u, j4=j4, nu_cols=nu_cols, nu_wheel=nu_wheel)
    cols = cols.reshape(d.shape[0], -1) * nu_sd[None, :]
    chol = jnp.linalg.cholesky(cov + cols @ cols.T)
    r = jax.scipy.linalg.solve_triangular(chol, d, lower=True)
    logdet = 2.0 * jnp.sum(jnp.log(jnp.diag(chol)))
    return -0.5 * (r @ r + logdet + d.shape[0] * jnp.log(2.0 * jnp.pi))


def balance_misfit(problem: Rwa4Problem, u, pi) -> tuple[float, int]:
    """``χ² = dᵀ S⁻¹ d`` of the window-mean balances ``d`` (:func:`balance`) at the axis ``u``
    (3,) and inertia ``pi`` (6,) kg m², with ``S`` the likelihood's covariance (white noise plus
    the integrated-out nuisance effects, :func:`loglik`), and its degrees of freedom ``3G − 2``
    (the axis's two are fitted; an inertia the balance also informs makes χ² smaller still). A
    model that fits gives ``χ²`` about its dof; an unmodelled effect larger than its prior
    allows shows as a large one."""
    kw = problem.data
    u = jnp.asarray(np.asarray(u, float) / np.linalg.norm(u))
    pi = jnp.asarray(pi, float)
    d = np.asarray(balance(u, pi, m_pi=kw.m_pi, r_u=kw.r_u, k_h=kw.k_h,
                            j4=kw.j4)).ravel()
    cov = np.asarray(jax.scipy.linalg.block_diag(*noise_cov(
        u, pi, kw.log_noise_hat, n_w=kw.n_w, t_aa=kw.t_aa, j4=kw.j4,
        known_cov=kw.known_cov)))
    cols = np.asarray(nuisance_cols(u, r_u=kw.r_u, j4=kw.j4, nu_cols=kw.nu_cols,
                                     nu_wheel=kw.nu_wheel)).reshape(d.size, -1)
    cols = cols * np.asarray(kw.nu_sd)[None, :]
    chi2 = float(d @ np.linalg.solve(cov + cols @ cols.T, d))
    return chi2, max(d.size - 2, 1)
