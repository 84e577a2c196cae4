"""Thruster magnitude from wheel-biasing events by least squares (Feldman & Lee 2006 §V).

The integrated Euler equation ``V(t_i) = Q J(t_i)`` (Eq 17, :mod:`cassini_bayes.physics.impulse`)
is linear in the thrusts. The paper stacks it four ways:

* :func:`fit_z_thrusters` — ``F_Z1 … F_Z4`` from the X, Y rows (Eq 19);
* :func:`fit_y_thrusters` — ``F_Y1 … F_Y4`` from the Z row (Eq 20); rank 2 when {Y1, Y3} and
  {Y2, Y4} fire in pairs, and then it raises, naming the pairs;
* :func:`fit_y_pairs` — the pair means ``(F_Y1+F_Y3)/2, (F_Y2+F_Y4)/2`` (Eq 21);
* :func:`fit_y_mean` — the mean Y thrust (Eq 22);
* :func:`fit_mean` — one thrust for all eight (Eq 23).

Each takes ``v`` (N, 3), the left side ``I Δω + ΔH_RWA + ΔG`` (N m s), and ``j`` (N, 8), the
accumulated impulse per newton of thrust (s) — either the cumulative on-times ``Δτ`` (the paper's
Eq 17) or, with the pulse-dynamics correction, the actual per-newton impulse of the pulse log
under given time constants. :func:`regression_inputs` builds both from telemetry. The paper's
other correction, dividing the plain estimate by the impulse ratio ``R`` (Table 2), is
:func:`ratio_corrected`.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import numpy as np

from cassini_bayes.errors import InputError
from cassini_bayes.estimators.lstsq import solve_lstsq
from cassini_bayes.physics.impulse import (impulse_from_on_times,
                                           impulse_from_pulses, impulse_lhs, system_xy,
                                           system_xyz, system_z, system_zz, system_zzz)

__all__ = ["ThrustFit", "regression_inputs", "fit_z_thrusters", "fit_y_thrusters", "fit_y_pairs",
           "fit_y_mean", "fit_mean", "ratio_corrected"]


_lhs = jax.jit(impulse_lhs)
_pulse_impulse = jax.jit(impulse_from_pulses)


class ThrustFit(NamedTuple):
    """Least-squares thrust estimate.

    Attributes
    ----------
    estimate : (p,) the fitted unknowns, N (see ``names``).
    names : their names (``F_Z1`` …, ``F_Y13`` for a pair mean, ``F_Y`` for the Y mean, ``F``).
    per_thruster : (8,) the estimate spread onto ``Z1 … Y4`` (N); NaN for thrusters the
        regression does not involve.
    residual_rms : rms of ``V − U P`` (N m s).
    rank, condition, warnings : as in :class:`~cassini_bayes.estimators.lstsq.LstsqFit`.
    """

    estimate: np.ndarray
    names: tuple[str, ...]
    per_thruster: np.ndarray
    residual_rms: float
    rank: int
    condition: float
    warnings: tuple[str, ...]


def regression_inputs(t, omega, h_wheels_body, inertia, on_times=None, pulses=None,
                      tau=None):
    """``(v, j)`` for the thrust regressions from telemetry.

    Parameters
    ----------
    t : (n,) s. omega : (n, 3) rad/s. h_wheels_body : (n, 3) N m s. inertia : (3, 3) kg m².
    on_times : (n, 8) cumulative on-times (s): ``j = Δτ`` (Feldman & Lee Eq 17).
    pulses : ``(t_on, thruster, width)`` arrays of a pulse log, with ``tau = (τd, τr, τf)`` in s:
        ``j`` = actual per-newton impulse delivered by each ``t_i`` (pulse-dynamics correction).
        Without ``tau`` the pulses are taken as instantaneous (``j`` = commanded on-time elapsed).
    """
    v = np.asarray(_lhs(np.asarray(t, float), np.asarray(omega, float), np.asarray(inertia),
                               np.asarray(h_wheels_body, float)))
    if pulses is not None:
        t_on, thr, width = (np.asarray(x) for x in pulses)
        tt = np.asarray(t, float)
        if tau is None:  # instantaneous pulses: commanded on-time elapsed by t_i (Eq 17)
            elapsed = np.clip(tt[:, None] - t_on[None, :], 0.0, width[None, :])
            j = elapsed @ (thr[:, None] == np.arange(8)[None, :]).astype(float)
            j = j - j[:1]
        else:
            j = _pulse_impulse(tt, t_on, thr, width, *tau)
    elif on_times is not None:
        j = impulse_from_on_times(np.asarray(on_times, float))
    else:
        raise InputError("thrust estimation needs thruster on-times (on_Z1 ... on_Y4 columns) "
                         "or a pulse log (--pulses)")
    return v, np.asarray(j)


def _fit(u, y, names, per_index, hint=""):
    fit = solve_lstsq(np.asarray(u), np.asarray(y), names, "thrust magnitudes", hint)
    per = np.full(8, np.nan)
    for k, idx in enumerate(per_index):
        per[list(idx)] = fit.estimate[k]
    return ThrustFit(fit.estimate, tuple(names), per, fit.residual_rms, fit.rank, fit.condition,
                     fit.warnings)


def fit_z_thrusters(v, j, q_matrix) -> ThrustFit:
    """``F_Z1 … F_Z4`` (N) from the X, Y rows, Feldman & Lee Eq 19."""
    u, y = system_xy(v, j, q_matrix)
    return _fit(u, y, ("F_Z1", "F_Z2", "F_Z3", "F_Z4"), [(0,), (1,), (2,), (3,)],
                "fire every Z thruster, not always in fixed pairs")


def fit_y_thrusters(v, j, q_matrix) -> ThrustFit:
    """``F_Y1 … F_Y4`` (N) from the Z row, Feldman & Lee Eq 20.

    When Y1 and Y3 (and Y2 and Y4) always fire together ``U_Z`` has rank 2 and this raises
    :class:`~cassini_bayes.errors.UnidentifiableError` naming ``{F_Y1, F_Y3}`` and
    ``{F_Y2, F_Y4}``; use :func:`fit_y_pairs` (Eq 21) or :func:`fit_y_mean` (Eq 22).
    """
    u, y = system_z(v, j, q_matrix)
    return _fit(u, y, ("F_Y1", "F_Y2", "F_Y3", "F_Y4"), [(4,), (5,), (6,), (7,)],
                "the Y thrusters fire in pairs; use fit_y_pairs (Eq 21) or fit_y_mean (Eq 22)")


def fit_y_pairs(v, j, q_matrix) -> ThrustFit:
    """Pair means ``(F_Y1+F_Y3)/2, (F_Y2+F_Y4)/2`` (N), Feldman & Lee Eq 21."""
    u, y = system_zz(v, j, q_matrix)
    return _fit(u, y, ("F_Y13", "F_Y24"), [(4, 6), (5, 7)],
                "only one Y pair fired; use fit_y_mean (Eq 22)")


def fit_y_mean(v, j, q_matrix) -> ThrustFit:
    """Mean Y thrust (N), Feldman & Lee Eq 22."""
    u, y = system_zzz(v, j, q_matrix)
    return _fit(u, y, ("F_Y",), [(4, 5, 6, 7)], "no Y thruster fired")


def fit_mean(v, j, q_matrix) -> ThrustFit:
    """One thrust (N) for all eight thrusters, Feldman & Lee Eq 23."""
    u, y = system_xyz(v, j, q_matrix)
    return _fit(u, y, ("F",), [tuple(range(8))], "no thruster fired")


def ratio_corrected(thrust_plain_n, ratio):
    """Thrust corrected for pulse dynamics: ``F_plain / R`` (Feldman & Lee §V, Table 2).

    ``R`` from :func:`cassini_bayes.physics.pulse.impulse_ratio` or ``mix_ratio``
    (e.g. 0.98 N / 1.3406 ≈ 0.731 N for the FSDS test).
    """
    return np.asarray(thrust_plain_n, float) / np.asarray(ratio, float)

