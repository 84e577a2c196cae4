"""Inertia tensor from reaction-wheel slews by least squares (Feldman & Lee 2006 §IV).

Three estimators, all on telemetry arrays in SI units:

* :func:`fit_axis_by_axis` — Eq 7 on single-axis slew segments, the products of inertia averaged
  over the two axes that see them (how the paper obtained Eq 8);
* :func:`fit_all_axes` — Eq 11, all six entries at once, momentum anchored on a quiescent sample;
* :func:`fit_free_momentum` — the same regression with the inertial momentum ``H_N`` (and
  optionally a constant inertial torque ``T_N``, App. A) as extra unknowns; no anchor sample.

Inputs: ``q`` (n, 4) attitude quaternions (scalar last, inertial → body), ``omega`` (n, 3) body
rates (rad/s), ``h_wheels_body`` (n, 3) wheel momentum in body axes (N m s,
:func:`cassini_bayes.physics.momentum.wheel_momentum_body`), ``t`` (n,) s.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import numpy as np

from cassini_bayes.errors import UnidentifiableError
from cassini_bayes.estimators.lstsq import solve_lstsq
from cassini_bayes.frames import quat_continuous
from cassini_bayes.physics.momentum import (INERTIA_NAMES, free_momentum_system, inertia_matrix,
                                            q_vector, stacked_system)

__all__ = ["InertiaFit", "fit_all_axes", "fit_free_momentum", "fit_axis_by_axis",
           "single_axis_mask", "DOMINANCE", "table1_errors"]

# Jitted once per input shape: eager JAX would compile every primitive separately.
_continuous = jax.jit(quat_continuous)
_stacked = jax.jit(stacked_system, static_argnames="ref")
_free = jax.jit(free_momentum_system, static_argnames="torque")
_q_vector = jax.jit(q_vector, static_argnames="ref")

# A sample belongs to a single-axis slew about axis k when |ω_k| ≥ DOMINANCE |ω|.
DOMINANCE = 0.995

_HINT = ("slew about all three body axes, or add multi-axis slews (Feldman & Lee §IV: S must "
         "have full column rank)")


class InertiaFit(NamedTuple):
    """Least-squares inertia estimate.

    Attributes
    ----------
    inertia : (3, 3) estimated inertia tensor, kg m², body axes.
    pi : (6,) the same as ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)``, kg m².
    residual_rms : rms of the momentum residuals, N m s.
    rank : rank of the regression matrix (6, 9 or 12 columns; for the axis-by-axis method the
        number of axes with usable single-axis samples).
    condition : condition number of the column-scaled regression matrix (max over the per-axis
        problems for the axis-by-axis method).
    warnings : human-readable warnings.
    momentum : (3,) estimated inertial momentum ``H_0`` (N m s) for :func:`fit_free_momentum`,
        else ``None``.
    torque : (3,) estimated constant inertial torque ``T_N`` (N m) when asked for, else ``None``.
    """

    inertia: np.ndarray
    pi: np.ndarray
    residual_rms: float
    rank: int
    condition: float
    warnings: tuple[str, ...]
    momentum: np.ndarray | None = None
    torque: np.ndarray | None = None


def _arrays(q, omega, h):
    q = np.asarray(_continuous(np.asarray(q, float)))
    return q, np.asarray(omega, float), np.asarray(h, float)


def _anchor_warning(w, ref) -> list[str]:
    w_ref = float(np.linalg.norm(w[ref]))
    if w_ref > 0.01 * np.max(np.linalg.norm(w, axis=1)):
        return [f"anchor sample {ref} is not quiescent (|ω| = {w_ref:.3g} rad/s); Eq 4 assumes "
                "ω ≈ 0 there — prefer fit_free_momentum"]
    return []


def fit_all_axes(q, omega, h_wheels_body, ref: int = 0) -> InertiaFit:
    """All six inertia entries at once, Feldman & Lee Eq 11: ``π̂ = (SᵀS)⁻¹ SᵀΓ``.

    The conserved momentum is anchored on sample ``ref``, assumed quiescent (``ω ≈ 0``, Eq 4).
    Raises :class:`~cassini_bayes.errors.UnidentifiableError` naming the entries the slews do
    not excite (e.g. slews about X only leave Iyy, Izz, Iyz unidentified).
    """
    q, w, h = _arrays(q, omega, h_wheels_body)
    warns = _anchor_warning(w, ref)
    # Feldman & Lee Eq 11
    s, gamma = _stacked(q, w, h, ref=ref)
    fit = solve_lstsq(s, gamma, INERTIA_NAMES, "inertia entries", _HINT)
    return InertiaFit(np.asarray(inertia_matrix(fit.estimate)), fit.estimate, fit.residual_rms,
                      fit.rank, fit.condition, fit.warnings + tuple(warns))


def fit_free_momentum(q, omega, h_wheels_body, t, torque: bool = False) -> InertiaFit:
    """Inertia with the inertial momentum ``H_0`` (and optionally a torque ``T_N``) unknown.

    Model ``A(q_t)ᵀ (I ω_t + H_RWA,t) = H_0 + T_N (t − t_0)`` (Feldman & Lee Eq 3 with the
    App. A torque), solved by least squares for ``(π, H_0[, T_N])``. Needs no quiescent anchor.
    """
    q, w, h = _arrays(q, omega, h_wheels_body)
    m, y = _free(q, w, h, np.asarray(t, float), torque=torque)
    names = INERTIA_NAMES + ("H0_x", "H0_y", "H0_z") + (("T_x", "T_y", "T_z") if torque else ())
    fit = solve_lstsq(m, y, names, "inertia entries and inertial momentum", _HINT)
    x = fit.estimate
    return InertiaFit(np.asarray(inertia_matrix(x[:6])), x[:6], fit.residual_rms, fit.rank,
                      fit.condition, fit.warnings, x[6:9], x[9:12] if torque else None)


def single_axis_mask(omega, min_rate_rad_s: float | None = None,
                     dominance: float = DOMINANCE) -> np.ndarray:
    """(n, 3) bool: sample ``i`` is part of a single-axis slew about axis ``k``.

    True when ``|ω| > min_rate_rad_s`` (default 5 % of the largest rate in the data) and
    ``|ω_k| ≥ dominance |ω|``.
    """
    w = np.asarray(omega, float)
    norm = np.linalg.norm(w, axis=1)
    floor = 0.05 * norm.max() if min_rate_rad_s is None else min_rate_rad_s
    moving = norm > floor
    return moving[:, None] & (np.abs(w) >= dominance * norm[:, None])


def fit_axis_by_axis(q, omega, h_wheels_body, ref: int = 0, min_rate_rad_s: float | None = None,
                     dominance: float = DOMINANCE) -> InertiaFit:
    """Axis-by-axis estimate, Feldman & Lee Eq 7, products of inertia averaged (their Eq 8).

    For the samples of single-axis slews about axis ``k`` (:func:`single_axis_mask`),
    ``Î_jk = (ω_kᵀ ω_k)⁻¹ ω_kᵀ Q_j`` for ``j = x, y, z`` with ``Q`` of Eq 6 anchored on sample
    ``ref``. Each moment comes from its own axis; each product from the two axes that see it,
    averaged. Moving samples that belong to no single-axis slew (multi-axis motion) are left out
    with a warning — use :func:`fit_all_axes` for those. Raises
    :class:`~cassini_bayes.errors.UnidentifiableError` when an axis has no single-axis samples.
    """
    q, w, h = _arrays(q, omega, h_wheels_body)
    qv = np.asarray(_q_vector(q, h, ref=ref))
    mask = single_axis_mask(w, min_rate_rad_s, dominance)
    axes = "xyz"
    missing = [axes[k] for k in range(3) if not mask[:, k].any()]
    if missing:
        names = {"x": "Ixx", "y": "Iyy", "z": "Izz"}
        raise UnidentifiableError(
            "axis-by-axis inertia (Feldman & Lee Eq 7) needs single-axis slews about every axis; "
            f"none about {', '.join(missing)} (so {', '.join(names[a] for a in missing)} are "
            "unidentified); use fit_all_axes for multi-axis slews")
    warns = _anchor_warning(w, ref)
    norm = np.linalg.norm(w, axis=1)
    floor = 0.05 * norm.max() if min_rate_rad_s is None else min_rate_rad_s
    unused = (norm > floor) & ~mask.any(axis=1)
    if unused.any():
        warns.append(f"{int(unused.sum())} of {int((norm > floor).sum())} moving samples are "
                     "multi-axis motion and were left out of the axis-by-axis fit")
    col = np.zeros((3, 3))  # col[j, k]: estimate of I_jk from slews about k
    rms2 = []
    for k in range(3):
        wk = w[mask[:, k], k]
        qk = qv[mask[:, k]]
        # Feldman & Lee Eq 7: I_jk = (w_k^T w_k)^-1 w_k^T Q_j
        col[:, k] = wk @ qk / (wk @ wk)
        rms2.append(np.mean((qk - np.outer(wk, col[:, k])) ** 2))
    inertia = 0.5 * (col + col.T)  # moments once; products averaged over the two axes (Eq 8)
    pi = np.array([inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2],
                   inertia[1, 2]])
    # rank: the three per-axis problems; condition 1: each is a one-column regression
    return InertiaFit(inertia, pi, float(np.sqrt(np.mean(rms2))), 3, 1.0, tuple(warns))


def table1_errors(predicted, estimated) -> np.ndarray:
    """Table 1 error columns: moments in % (Feldman & Lee Eq 12), products in kg m² (Eq 13).

    ``predicted``, ``estimated``: (6,) ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)``, kg m². Returns (6,):
    the first three ``(pred − est)/pred × 100`` (%), the last three ``pred − est`` (kg m²).
    """
    p = np.asarray(predicted, float)
    e = np.asarray(estimated, float)
    # Feldman & Lee Eq 12 (moments, %) and Eq 13 (products, kg m^2)
    return np.concatenate([(p[:3] - e[:3]) / p[:3] * 100.0, p[3:] - e[3:]])
