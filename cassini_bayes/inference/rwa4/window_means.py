"""The window means of the RWA4 model's momentum balance (Brown 2012 §III): each window's
weighted sums of the per-sample terms of
:func:`~cassini_bayes.inference.rwa4.likelihood.loglik`, with the RWA method's slopes against
time, and the robust model's nuisance columns averaged the same way.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from cassini_bayes.frames import dcm
from cassini_bayes.inference.nuisance import NuisanceLayout, robust_columns
from cassini_bayes.physics.momentum import regressor

__all__ = ["window_means", "nuisance_means", "no_nuisance"]


def _window_weights(t, masks) -> tuple[list, list]:
    """Per window (A, B of each pair in order) ``(mask, weights)`` of its mean, ``1/n``, and,
    given the sample times ``t`` (s), of its least-squares slope against time,
    ``(t_i − t̄_w)/Σ(t − t̄_w)²`` (1/s); no slopes without ``t``. The two are orthogonal
    (``Σ_i (t_i − t̄_w) = 0``), so the slope's white noise is independent of the mean's."""
    means, slopes = [], []
    for m in (m for pair in masks for m in pair):
        means.append((m, np.full(int(m.sum()), 1.0 / m.sum())))
        if t is not None:
            dt = np.asarray(t, float)[m] - np.mean(np.asarray(t, float)[m])
            slopes.append((m, dt / np.sum(dt * dt)))
    return means, slopes


_SHAPES = {"m_pi": (3, 6), "r_u": (3, 3), "k_h": (3,), "n": (), "t_aa": (3, 3, 3, 3)}


def _weighted_sums(a_all, reg, rho, h_known, weights) -> dict:
    """Per window ``(mask, w)`` the weighted sums ``Σ_i w_i x_i`` of the per-sample quantities
    of :func:`~cassini_bayes.inference.rwa4.likelihood.loglik` (``x = Aᵀ Y(ω)``, ``ρ_4 Aᵀ``,
    ``Aᵀ h_known``), ``n = 1/Σ w²`` and
    ``t_aa = Σ w² A⊗A / Σ w²`` (white noise of a weighted sum: ``Σ w_i² C_i = ⟨C⟩_w²/n``)."""
    out = {k: [] for k in _SHAPES}
    for m, w in weights:
        at = np.swapaxes(a_all[m], -1, -2)                              # body → inertial
        w2 = float(np.sum(w * w))
        out["m_pi"].append(np.einsum("n,nij,njk->ik", w, at, reg[m]))
        out["r_u"].append(np.einsum("n,nij->ij", w * rho[m], at))
        out["k_h"].append(np.einsum("n,nij,nj->i", w, at, h_known[m]))
        out["n"].append(1.0 / w2)
        out["t_aa"].append(np.einsum("n,nja,nkb->jakb", w * w, a_all[m], a_all[m]) / w2)
    return {k: jnp.asarray(np.stack(v) if v else np.zeros((0, *_SHAPES[k])))
            for k, v in out.items()}


def window_means(q, omega, rates, axes, js, k_u, known, masks, t=None) -> dict:
    """The window averages of :func:`~cassini_bayes.inference.rwa4.likelihood.loglik` (its
    docstring), as JAX arrays; with the sample times ``t`` (s; the RWA method's quiet windows)
    also each window's least-squares slope against time (the ``*_s`` arrays), else none
    (``S = 0``)."""
    a_all = np.asarray(dcm(jnp.asarray(q)))
    h_known_all = ((np.nan_to_num(rates[:, known]) * js[known]) @ axes[known] if known
                   else np.zeros((q.shape[0], 3)))
    reg = np.asarray(regressor(jnp.asarray(omega)))
    rho = np.nan_to_num(rates[:, k_u])
    means, slopes = _window_weights(t, masks)
    data = _weighted_sums(a_all, reg, rho, h_known_all, means)
    data["n_w"] = data.pop("n")
    data.update({f"{k}_s": v for k, v in
                 _weighted_sums(a_all, reg, rho, h_known_all, slopes).items()})
    known_cov = sum((js[k]**2 * np.outer(axes[k], axes[k]) for k in known), np.zeros((3, 3)))
    return dict(data, j4=jnp.asarray(js[k_u]), known_cov=jnp.asarray(known_cov))


def nuisance_means(layout: NuisanceLayout, q, omega, rates, axes, js, known, names, masks,
                   t, slopes: bool = False) -> dict:
    """The robust model's nuisance columns of ``d_g``
    (:func:`~cassini_bayes.inference.rwa4.likelihood.loglik`), as JAX arrays; with ``slopes``,
    also those of each window's slope, ``nu_cols_s`` (S, 3, R): the same per-sample
    inertial columns' slopes against time (:func:`_window_weights`), so an external torque
    enters as its value at the window (Euler: ``dH/dt = T``).

    The body-axis columns of :func:`~cassini_bayes.inference.nuisance.robust_columns` (the
    known wheels' spin-inertia scales; the known wheels' axis tilts; a body-fixed torque through
    ``−A(q_t) ∫ A(q_s)ᵀ ds``) rotated to inertial axes and window-averaged like the momentum,
    B − A per pair: ``nu_cols`` (G, 3, R). The gyro bias and scale-factor columns, ``−I b`` and
    ``−I diag(ω) s``, are linear in the sampled inertia, ``−S(b) π`` (:func:`~cassini_bayes.
    physics.momentum.regressor`), averaged the same way: ``nu_pi`` (G, 3, R, 6) and ``nu_pi_s``
    (S, 3, R, 6), whose product with ``π`` the likelihood adds: the measured momentum carries
    the bias through the true inertia, which a fixed tensor would miss by ``(I − I*) b``.
    ``nu_wheel`` (R,) marks the solved wheel's scale columns (per wheel: its own, the layout's
    last scale, and the shared one; common: the one scale), whose solved-wheel part
    :func:`~cassini_bayes.inference.rwa4.likelihood.nuisance_cols` adds; ``nu_sd`` (R,) the
    prior sd.
    """
    a_all = np.asarray(dcm(jnp.asarray(q)))
    rho = np.nan_to_num(rates)
    wheel_h = {names[k]: js[k] * rho[:, k] for k in known}
    h_known = sum((wheel_h[names[k]][:, None] * axes[k] for k in known),
                  np.zeros((q.shape[0], 3)))
    cols = robust_columns(layout, 0, np.zeros((3, 3)), omega, h_known, wheel_h, a_all, t)
    inertial = np.einsum("nji,njr->nir", a_all, cols)                  # A(q)ᵀ · column
    weights = _window_weights(t if slopes else None, masks)[1]

    def by_pi(m):                       # the gyro columns of a window's samples only (n × 6 × R)
        return np.einsum("nji,njrp->nirp", a_all[m], _gyro_columns(layout, omega[m]))

    def reduce(x, shape):
        diff = [x(mb).mean(0) - x(ma).mean(0) for ma, mb in masks]
        slope = [np.einsum("n,n...->...", w, x(m)) for m, w in weights]
        return (jnp.asarray(np.stack(diff)),
                jnp.asarray(np.stack(slope) if slope else np.zeros((0, *shape))))

    nu_cols, nu_cols_s = reduce(lambda m: inertial[m], (3, layout.size))
    nu_pi, nu_pi_s = reduce(by_pi, (3, layout.size, 6))
    one_hot = np.zeros(layout.size)
    one_hot[layout.slices["wheel_inertia"].stop - 1] = 1.0
    if layout.has_common:                   # the shared scale reaches the solved wheel too
        one_hot[layout.slices["wheel_inertia_common"]] = 1.0
    return dict(nu_cols=nu_cols, nu_cols_s=nu_cols_s, nu_pi=nu_pi, nu_pi_s=nu_pi_s,
                nu_sd=jnp.asarray(layout.sd), nu_wheel=jnp.asarray(one_hot))


def _gyro_columns(layout: NuisanceLayout, omega) -> np.ndarray:
    """(n, 3, R, 6) body-axis gyro bias and scale-factor columns per unit inertia entry:
    ``−I e_j = −S(e_j) π`` and ``−I ω_j e_j = −ω_j S(e_j) π`` (``S`` the regressor, Feldman &
    Lee Eq 10); zero for the other effects."""
    unit = -np.asarray(regressor(jnp.eye(3)))                          # (3 axes, 3, 6)
    out = np.zeros((omega.shape[0], 3, layout.size, 6))
    bias, scale = layout.slices["gyro_bias"], layout.slices["gyro_scale"]
    out[:, :, bias.start:bias.start + 3] = np.swapaxes(unit, 0, 1)[None]
    out[:, :, scale] = np.einsum("nj,jap->najp", omega, unit)
    return out


def no_nuisance(n_pairs: int, n_slopes: int = 0) -> dict:
    """The idealised model: no nuisance columns (R = 0) for ``n_pairs`` pair rows and
    ``n_slopes`` slope rows."""
    return dict(nu_cols=jnp.zeros((n_pairs, 3, 0)), nu_cols_s=jnp.zeros((n_slopes, 3, 0)),
                nu_pi=jnp.zeros((n_pairs, 3, 0, 6)), nu_pi_s=jnp.zeros((n_slopes, 3, 0, 6)),
                nu_sd=jnp.zeros(0), nu_wheel=jnp.zeros(0))
