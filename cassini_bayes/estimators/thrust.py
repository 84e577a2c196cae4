"""Thruster magnitude from wheel-biasing events by least squares (Feldman & Lee 2006 §V).

The integrated Euler equation ``V(t_i) = Q J(t_i)`` (Eq 17, :mod:`cassini_bayes.physics.impulse`)
is linear in the thrusts. The paper stacks it four ways:

* :func:`fit_z_thrusters` — ``F_Z1 … F_Z4`` from the X, Y rows (Eq 19);
* :func:`fit_y_thrusters` — ``F_Y1 … F_Y4`` from the Z row (Eq 20); rank 2 when {Y1, Y3} and
  {Y2, Y4} fire in pairs, and then it raises, naming the pairs;
* :func:`fit_y_pairs` — the pair means ``(F_Y1+F_Y3)/2, (F_Y2+F_Y4)/2`` (Eq 21);
* :func:`fit_y_mean` — the mean Y thrust (Eq 22);
* :func:`fit_mean` — one thrust for all eight (Eq 23).

Eqs 19-22 assume Cassini's eight thrusters in the layout of Eq 16 (``Z1..Z4`` first, then
``Y1..Y4``). For any other layout, :func:`fit_per_thruster` stacks all three rows of Eq 17 with one
unknown per thruster that fired (Eq 17 with ``J_s = F_s j_s``): each thruster whose own direction
lies in the row space of the stacked design gets its thrust, and combinations given by the caller
(the Bayesian fit's identified combinations) get theirs when they lie in it; the rest are not
estimated.

Each takes ``v`` (N, 3), the left side ``I Δω + ΔH_RWA + ΔG`` (N m s), and ``j`` (N, 8), the
accumulated impulse per newton of thrust (s) — either the cumulative on-times ``Δτ`` (the paper's
Eq 17) or, with the pulse-dynamics correction, the actual per-newton impulse of the pulse log
under given time constants. :func:`regression_inputs` builds both from telemetry. The paper's
other correction, dividing the plain estimate by the impulse ratio ``R`` (Table 2), is
:func:`ratio_corrected`.
"""

from __future__ import annotations

from typing import NamedTuple, Sequence

import jax
import numpy as np

from cassini_bayes.errors import InputError
from cassini_bayes.estimators.lstsq import solve_lstsq
from cassini_bayes.physics.impulse import (impulse_from_on_times,
                                           impulse_from_pulses, impulse_lhs, system_xy,
                                           system_xyz, system_z, system_zz, system_zzz)

__all__ = ["ThrustFit", "regression_inputs", "fit_z_thrusters", "fit_y_thrusters", "fit_y_pairs",
           "fit_y_mean", "fit_mean", "fit_per_thruster", "combination_label", "ratio_corrected"]


_lhs = jax.jit(impulse_lhs)
_pulse_impulse = jax.jit(impulse_from_pulses, static_argnames="n_thrusters")


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
                      tau=None, n_thrusters: int = 8):
    """``(v, j)`` for the thrust regressions from telemetry.

    Parameters
    ----------
    t : (n,) s. omega : (n, 3) rad/s. h_wheels_body : (n, 3) N m s. inertia : (3, 3) kg m².
    on_times : (n, M) cumulative on-times (s): ``j = Δτ`` (Feldman & Lee Eq 17).
    n_thrusters : M, the spacecraft's thrusters (pulse-log indices run over them).
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
            j = elapsed @ (thr[:, None] == np.arange(n_thrusters)[None, :]).astype(float)
            j = j - j[:1]
        else:
            j = _pulse_impulse(tt, t_on, thr, width, *tau, n_thrusters=n_thrusters)
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


def combination_label(weights, names: Sequence[str]) -> str:
    """``"0.5 F[Y1] + 0.5 F[Y3]"``: a combination's weights as text (3 significant digits)."""
    out = ""
    for w, n in zip(weights, names):
        if not w:
            continue
        term = f"{abs(w):.3g} F[{n}]"
        out += (term if w > 0 else f"-{term}") if not out else (
            f" + {term}" if w > 0 else f" - {term}")
    return out


def fit_per_thruster(v, j, q_matrix, names, combinations=None) -> ThrustFit:
    """One thrust per thruster (N) from all three rows of Feldman & Lee Eq 17, any layout.

    ``v`` (N, 3) N m s and ``j`` (N, M) s as for the other regressions, ``q_matrix`` (3, M) m,
    ``names`` (M,) the thrusters' names, ``combinations`` (C, M) optional weights of thrust
    combinations. The unknowns are the thrusters that fired; the stacked design
    ``U[(i, k), s] = Q_ks j_s(t_i)`` is solved by its pseudo-inverse (relative singular-value
    cut :data:`~cassini_bayes.estimators.lstsq.RANK_RTOL`, columns scaled to unit length). A
    thruster is estimated (``F[<name>]``) when its unit vector lies in the design's row space
    (to 1e-6), a combination (``F_combination[<label>]``) when its weights do; the others
    are named in ``warnings``. Raises :class:`~cassini_bayes.errors.UnidentifiableError` when
    nothing is estimable (no thruster fired)."""
    from cassini_bayes.errors import UnidentifiableError
    from cassini_bayes.estimators.lstsq import RANK_RTOL

    j = np.asarray(j, float)
    v = np.asarray(v, float)
    q = np.asarray(q_matrix, float)
    m = q.shape[1]
    u = (j[:, None, :] * q[None, :, :]).reshape(-1, m)                 # Feldman & Lee Eq 17
    y = v.reshape(-1)
    if not (np.all(np.isfinite(u)) and np.all(np.isfinite(y))):
        raise InputError("the least-squares system for the thrusts has NaN/inf entries; "
                         "remove the bad rows from the input")
    scale = np.linalg.norm(u, axis=0)
    fired = scale > 0
    if not fired.any():
        raise UnidentifiableError("no thruster fired: no thrust can be estimated")
    a = u[:, fired] / scale[fired]
    uu, sv, vt = np.linalg.svd(a, full_matrices=False)
    rank = int(np.sum(sv > RANK_RTOL * sv[0]))
    x = vt[:rank].T @ ((uu[:, :rank].T @ y) / sv[:rank])
    f = np.full(m, np.nan)
    f[fired] = x / scale[fired]                                          # minimum-norm solution
    row = vt[:rank]                                                      # row space, scaled units
    residual = y - u[:, fired] @ f[fired]

    def estimable(w):
        ws = np.asarray(w, float)[fired] / scale[fired]             # the weights in scaled units
        n = np.linalg.norm(ws)
        return n > 0 and not np.any(np.asarray(w, float)[~fired]) and (
            np.linalg.norm(ws - row.T @ (row @ ws)) <= 1e-6 * n)

    est, labels, per, notes = [], [], np.full(m, np.nan), []
    for s in range(m):
        w = np.eye(m)[s]
        if fired[s] and estimable(w):
            est.append(f[s])
            labels.append(f"F[{names[s]}]")
            per[s] = f[s]
    missing = [names[s] for s in range(m) if fired[s] and np.isnan(per[s])]
    for w in (np.zeros((0, m)) if combinations is None else np.asarray(combinations, float)):
        label = combination_label(w, names)
        if estimable(w):
            est.append(float(np.nansum(w * np.where(np.isnan(f), 0.0, f))))
            labels.append(f"F_combination[{label}]")
        else:
            notes.append(f"combination {label} is not estimable by least squares")
    if missing:
        notes.append(f"thrusters {', '.join(missing)} fire only in combinations the data cannot "
                     "separate; their thrusts are not estimated one by one")
    cond = float(sv[0] / sv[rank - 1]) if rank else float("inf")
    return ThrustFit(np.asarray(est, float), tuple(labels), per,
                     float(np.sqrt(np.mean(residual**2))), rank, cond, tuple(notes))


def ratio_corrected(thrust_plain_n, ratio):
    """Thrust corrected for pulse dynamics: ``F_plain / R`` (Feldman & Lee §V, Table 2).

    ``R`` from :func:`cassini_bayes.physics.pulse.impulse_ratio` or ``mix_ratio``
    (e.g. 0.98 N / 1.3406 ≈ 0.731 N for the FSDS test).
    """
    return np.asarray(thrust_plain_n, float) / np.asarray(ratio, float)

