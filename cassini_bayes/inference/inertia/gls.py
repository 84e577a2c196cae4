"""The numerical steps of :func:`~cassini_bayes.inference.inertia.prepare_inertia`: iterated
generalised least squares with empirical-Bayes noise levels, the per-file sufficient statistics
at the mode, the identification check and the Laplace whitening of the sampler's coordinates
(:mod:`cassini_bayes.inference.inertia`, "Noise levels and the fast likelihood").

``files`` are the per-file dicts of :func:`~cassini_bayes.inference.inertia.data.file_data`;
``setup`` the layout of the full parameter vector ``[π (6), (H_0 (3), T_N (3)) per file, ν (R)]``
(:class:`~cassini_bayes.inference.inertia.data.Setup`).
"""

from __future__ import annotations

from typing import Sequence

import jax
import numpy as np

from cassini_bayes.errors import UnidentifiableError
from cassini_bayes.inference.inertia.prior import (NOISE_PRIOR_LOG_SD, cholesky_params_from_pi,
                                                   inertia_matrix_jit, is_physical,
                                                   pi_from_cholesky_params)
from cassini_bayes.inference.nuisance import robust_columns
from cassini_bayes.names import INERTIA_NAMES
from cassini_bayes.telemetry import Telemetry

__all__ = ["set_robust_columns", "full_prior", "gls", "sufficient_statistics",
           "information_ratio", "whitening"]


def _body_cov_terms(inertia: np.ndarray, wheel_cov: np.ndarray, h_body: np.ndarray):
    """The three (n, 3, 3) terms of ``B_t`` per unit variance.

    ``I I``, ``Σ_k J_k² g_k g_kᵀ`` and ``[h×][h×]ᵀ = |h|² 1 − h hᵀ``.
    """
    n = h_body.shape[0]
    k = (np.sum(h_body**2, -1)[:, None, None] * np.eye(3)
         - h_body[:, :, None] * h_body[:, None, :])
    return (np.broadcast_to(inertia @ inertia, (n, 3, 3)), np.broadcast_to(wheel_cov, (n, 3, 3)),
            k)


def set_robust_columns(files: list[dict], setup, pi) -> None:
    """Rebuild each file's robust columns of ``ν``, linear around the inertia ``pi`` (the prior
    mean when ``pi`` is not physical)."""
    i_star = np.asarray(inertia_matrix_jit(pi if is_physical(pi) else setup.prior.mean))
    for f, fd in enumerate(files):
        fd["cols"][:, :, setup.p_base:] = robust_columns(setup.layout, f, i_star, fd["w"],
                                                         fd["h_w"], fd["wheel_h"], fd["a"],
                                                         fd["t"])


def _fitted(x, fit_map):
    """The fitted columns ``x @ fit_map`` of (n, 3, p_full) columns ``x`` (``fit_map``: the
    columns wanted of the (p_full, p_full) map). A matrix product: NumPy's ``einsum`` of the same
    (its batched path) took ~10 ms a call, half of an SBC replicate's preparation."""
    return x @ fit_map


def _weights(fd: dict, f: int, th_full, ls, prior_mean):
    """``B_t⁻¹``, the three terms of ``B_t`` per unit variance, and ``B_t`` of file ``f`` at the
    full vector ``th_full`` and log noise levels ``ls`` (3,)."""
    i_m = np.asarray(inertia_matrix_jit(th_full[:6] if is_physical(th_full[:6]) else prior_mean))
    j0 = 6 + 6 * f
    h_n = th_full[j0:j0 + 3] + np.outer(fd["dt"], th_full[j0 + 3:j0 + 6])
    h_body = np.einsum("nij,nj->ni", fd["a"], np.broadcast_to(h_n, fd["w"].shape))
    terms = _body_cov_terms(i_m, fd["wcov"], h_body)
    s2 = np.exp(2 * ls)
    b = sum(s2[j] * terms[j] for j in range(3))
    return np.linalg.inv(b), terms, b


def full_prior(setup, n_files: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """sd, precision and mean of the full vector's prior (a zero sd pins the effect at zero)."""
    prior, layout = setup.prior, setup.layout
    full_sd = np.r_[prior.sd, np.tile(prior.file_sd, n_files), layout.sd]
    full_prec = 1.0 / np.maximum(full_sd, 1e-300)**2
    full_prec = np.minimum(full_prec, 1e30)
    full_mean = np.r_[prior.mean, np.zeros(setup.p_full - 6)]
    return full_sd, full_prec, full_mean


def _noise_step(fd: dict, f: int, theta_full, log_s_f, log_s_hat_f, setup) -> np.ndarray:
    """One Fisher-scoring step of ``log σ_f`` (3,) (prior ``N(log σ̂, 1)``), clipped to ±1."""
    w_inv, terms, _ = _weights(fd, f, theta_full, log_s_f, setup.prior.mean)
    e = np.einsum("nip,p->ni", fd["cols"], setup.fit_map @ theta_full) - fd["y"]
    we = np.einsum("nij,nj->ni", w_inv, e)
    s2 = np.exp(2 * log_s_f)
    d = [2 * s2[j] * terms[j] for j in range(3)]
    wd = [np.einsum("nij,njk->nik", w_inv, dj) for dj in d]
    grad = np.array([0.5 * (np.einsum("ni,nij,nj->", we, d[j], we)
                            - np.einsum("nii->", wd[j])) for j in range(3)])
    fisher = np.array([[0.5 * np.einsum("nij,nji->", wd[j], wd[k]) for k in range(3)]
                       for j in range(3)])
    grad -= (log_s_f - log_s_hat_f) / NOISE_PRIOR_LOG_SD**2
    fisher += np.eye(3) / NOISE_PRIOR_LOG_SD**2
    return np.clip(np.linalg.solve(fisher, grad), -1.0, 1.0)


def gls(files: list[dict], setup, full_prec, full_mean, *, robust: bool,
        max_iter: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Iterated GLS: alternate the posterior mode of the model's parameters (prior included)
    and a Fisher-scoring step of each file's ``log σ`` until the steps are < 1e-6. Returns the
    full vector at the mode, the empirical-Bayes ``log σ*`` (F, 3) and the data's ``log σ̂``."""
    active = setup.active
    p_tot = active.size
    prior_prec = full_prec[active]
    prior_mean = full_mean[active]
    log_s = np.log(np.stack([fd["s_hat"] for fd in files]))
    log_s_hat = log_s.copy()
    theta_full = full_mean.copy()
    for it in range(max_iter):
        info = np.zeros((p_tot, p_tot))
        rhs = np.zeros(p_tot)
        for f, fd in enumerate(files):
            w_inv, _, _ = _weights(fd, f, theta_full, log_s[f], setup.prior.mean)
            c = _fitted(fd["cols"], setup.fit_map[:, active])
            wc = np.einsum("nij,njq->niq", w_inv, c)
            info += np.einsum("nip,niq->pq", c, wc, optimize=True)
            rhs += np.einsum("niq,ni->q", wc, fd["y"], optimize=True)
        theta_full = full_mean.copy()
        theta_full[active] = np.linalg.solve(info + np.diag(prior_prec),
                                             rhs + prior_prec * prior_mean)
        if robust:
            set_robust_columns(files, setup, theta_full[:6])
        max_step = 0.0
        for f, fd in enumerate(files):
            step = _noise_step(fd, f, theta_full, log_s[f], log_s_hat[f], setup)
            log_s[f] += step
            max_step = max(max_step, float(np.abs(step).max()))
        if max_step < 1e-6:
            break
    return theta_full, log_s, log_s_hat


def sufficient_statistics(files: list[dict], setup, theta_full, log_s) -> tuple:
    """Per file, the sufficient statistics of ``Q_f(θ) = Σ_t e_tᵀ B̂_t⁻¹ e_t`` around the mode
    with the empirical-Bayes covariance ``B̂_t``: ``F_f`` (F, P, P), ``g_f`` (F, P), ``Q_f(θ*)``
    (F,) and the counts ``3 n_f`` (F,); and the information of the full vector (every effect,
    for the sensitivity analysis)."""
    active, fit_map = setup.active, setup.fit_map
    p_tot, n_files = active.size, len(files)
    info_full = np.zeros((setup.p_full, setup.p_full))
    fmat = np.zeros((n_files, p_tot, p_tot))
    gvec = np.zeros((n_files, p_tot))
    q_star = np.zeros(n_files)
    n_obs = np.zeros(n_files)
    for f, fd in enumerate(files):
        w_inv, _, _ = _weights(fd, f, theta_full, log_s[f], setup.prior.mean)
        wc_full = np.einsum("nij,njq->niq", w_inv, fd["cols"])
        f_full = np.einsum("nip,niq->pq", fd["cols"], wc_full, optimize=True)
        info_full += f_full
        f_fit = fit_map.T @ f_full @ fit_map
        fmat[f] = f_fit[np.ix_(active, active)]
        e = np.einsum("nip,p->ni", fd["cols"], fit_map @ theta_full) - fd["y"]
        gvec[f] = np.einsum("niq,ni->q", _fitted(wc_full, fit_map[:, active]), e,
                            optimize=True)
        q_star[f] = np.einsum("ni,nij,nj->", e, w_inv, e)
        n_obs[f] = 3 * e.shape[0]
    return info_full, fmat, gvec, q_star, n_obs


def information_ratio(info, prior_prec, prior,
                      telemetries: Sequence[Telemetry]) -> tuple[np.ndarray, tuple[str, ...]]:
    """Eigenvalues of ``D F D`` (the data information of π with ``H_0``, ``T_N``, ``ν`` profiled
    out under their priors, ``D`` the prior sd) and the prior-dominated combinations (ratio < 1).
    Raises :class:`UnidentifiableError` when every direction is prior-dominated."""
    nuis_prec = prior_prec[6:]
    f_nn = info[6:, 6:] + np.diag(nuis_prec)
    f_pi = info[:6, :6] - info[:6, 6:] @ np.linalg.solve(f_nn, info[6:, :6])
    dmat = np.diag(prior.sd)
    ratio, vecs = np.linalg.eigh(dmat @ f_pi @ dmat)
    ratio = np.maximum(ratio, 0.0)
    weak = tuple(" + ".join(f"{v:+.2f} {INERTIA_NAMES[i]}" for i, v in enumerate(vec)
                            if abs(v) > 0.3)
                 for r, vec in zip(ratio, vecs.T) if r < 1.0)
    if ratio.max() < 1.0:
        src = ", ".join(t.source for t in telemetries)
        raise UnidentifiableError(
            f"{src}: the slews do not excite the inertia: the data inform none of "
            f"{', '.join(INERTIA_NAMES)} beyond the prior (largest information/prior ratio "
            f"{ratio.max():.2g}); give telemetry that rotates the spacecraft about its axes")
    return ratio, weak


# one XLA program (run eagerly, the forward-mode Jacobian compiles some thirty)
_pi_jacobian = jax.jit(jax.jacfwd(pi_from_cholesky_params))


def whitening(info, prior_prec, theta, setup, *, robust: bool) -> tuple:
    """The Laplace approximation (prior included) pushed through the log-Cholesky map: the
    sampler's ``centre`` and ``tril`` (``θ = centre + tril z``), the covariance of the model's
    parameters and the Laplace sd of the common wheel scale ``c`` (0 unless ``robust``)."""
    cov = np.linalg.inv(info + np.diag(prior_prec))
    cov = 0.5 * (cov + cov.T)
    c_sd = 0.0  # Laplace sd of the common wheel scale c = ωᵀ w (robust; π = (1 + c) π̃)
    if robust:
        w_act = np.searchsorted(setup.active, setup.w_index)
        scale_w = setup.layout.scale_weights
        c_sd = float(np.sqrt(scale_w @ cov[np.ix_(w_act, w_act)] @ scale_w))
    pi_c = theta[:6] if is_physical(theta[:6]) else setup.prior.mean
    lp_c = cholesky_params_from_pi(pi_c)
    jac = np.asarray(_pi_jacobian(lp_c))
    tmat = np.eye(setup.active.size)
    tmat[:6, :6] = np.linalg.inv(jac)
    cov_theta = tmat @ cov @ tmat.T
    tril = np.linalg.cholesky(0.5 * (cov_theta + cov_theta.T))
    centre = np.r_[lp_c, theta[6:]]
    return centre, tril, cov, c_sd
