"""Validation of telemetry arrays, shared by the readers and by in-memory telemetry (the rules:
:mod:`cassini_bayes.telemetry.limits`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cassini_bayes.errors import InputError
from cassini_bayes.telemetry._layout import _Q_COLS, _W_COLS, _on_cols
from cassini_bayes.telemetry._tables import _fail_nonfinite, _fail_out_of_range, _row_ref
from cassini_bayes.telemetry._types import Telemetry
from cassini_bayes.telemetry.limits import (
    _EXACT_NORM,
    _MIN_SWEEP_RAD,
    _RATE_RATIO_MAX,
    MIN_SAMPLE_SPACING_S,
    OMEGA_ABS_MAX,
    OMEGA_MAX,
    QUAT_NORM_TOL,
    RAD_S_SUSPECT_MAX,
    TIME_ABS_MAX,
    WHEEL_RPM_MAX,
)
from cassini_bayes.units import RPM_TO_RAD_S


def _check_time(t: np.ndarray, path: str, col: str = "t") -> None:
    _fail_out_of_range(t, col, TIME_ABS_MAX, "s", path, None, "317 years")
    dt = np.diff(t)
    bad = ~(dt > 0)
    if np.any(bad):
        i = int(np.argmax(bad))
        kind = "repeats" if dt[i] == 0 else "goes back from"
        raise InputError(f"column '{col}' is not strictly increasing: {_row_ref(i + 1, t)} "
                         f"{kind} data row {i + 1} (t = {t[i]:.10g} s); sort the rows and drop "
                         "duplicate samples", path=path)
    close = dt < MIN_SAMPLE_SPACING_S
    if np.any(close):
        i = int(np.argmax(close))
        raise InputError(f"column '{col}': {_row_ref(i + 1, t)} is only {dt[i]:.3g} s after data "
                         f"row {i + 1}; samples must be at least {MIN_SAMPLE_SPACING_S:g} s apart "
                         "— check the time unit (seconds) or drop the duplicate", path=path)


def _quat_continuous(q: np.ndarray) -> np.ndarray:
    """NumPy twin of :func:`cassini_bayes.frames.quat_continuous` (same rule, no JAX dispatch).

    Flips the sign of ``q`` after every row whose dot product with the previous row is negative,
    so consecutive quaternions agree in sign; ``A(q)`` is unchanged row by row.
    """
    flips = np.concatenate([[False], np.sum(q[1:] * q[:-1], axis=1) < 0])
    sign = np.where(np.cumsum(flips) % 2 == 1, -1.0, 1.0)
    return q * sign[:, None]


def _turn_angle(q: np.ndarray, q0: np.ndarray) -> np.ndarray:
    """Rotation angle (rad) from attitude ``q0`` to each row of ``q``; 0 for ``q = ±q0``.

    ``4 atan2(|q − s q0|, |q + s q0|)`` with ``s = sign(q·q0)``: accurate for tiny angles, where
    the ``2 acos(|q·q0|)`` of :func:`cassini_bayes.frames.quat_error_angle` loses digits.
    """
    s = np.where(q @ q0 < 0, -1.0, 1.0)[:, None]
    return 4.0 * np.arctan2(np.linalg.norm(q - s * q0, axis=1),
                            np.linalg.norm(q + s * q0, axis=1))


def _check_quaternions(q: np.ndarray, t: np.ndarray, path: str) -> np.ndarray:
    """Renormalise near-unit rows, reject the rest, remove sign flips."""
    for j, c in enumerate(_Q_COLS):  # before the norm, which would overflow
        _fail_out_of_range(q[:, j], c, 2.0, "", path, t, "a unit quaternion's components are "
                           "at most 1; check the column order and scaling")
    norm = np.linalg.norm(q, axis=1)
    dev = np.abs(norm - 1.0)
    if np.any(dev > QUAT_NORM_TOL):
        i = int(np.argmax(dev > QUAT_NORM_TOL))
        raise InputError(f"columns q1..q4, {_row_ref(i, t)}: quaternion norm {norm[i]:.6g} is "
                         f"not 1 (tolerance {QUAT_NORM_TOL:g}); q must be a unit quaternion, "
                         "scalar last (q4) — check the column order and scaling", path=path)
    fix = dev > _EXACT_NORM
    if np.any(fix):
        q = q.copy()
        q[fix] = q[fix] / norm[fix, None]
    return _quat_continuous(q)


def _check_omega_units(t: np.ndarray, q: np.ndarray, w: np.ndarray, path: str) -> None:
    mag = np.linalg.norm(w, axis=1)
    if np.any(mag > OMEGA_MAX):
        i = int(np.argmax(mag > OMEGA_MAX))
        raise InputError(f"columns wx wy wz, {_row_ref(i, t)}: |ω| = {mag[i]:.4g} is absurd for "
                         f"a spacecraft (> {OMEGA_MAX:g} rad/s); body rates must be in rad/s — "
                         "divide deg/s by 57.2958 or mrad/s by 1000", path=path)
    if len(t) < 3:
        return
    # The first time the attitude has turned by `turn` from row 0, compare the angle with the
    # body-rate integral. Rate noise enters as a random walk (not a sum of |noise|), so correct
    # rad/s data gives a ratio near 1; °/s gives 57 and mrad/s 1000.
    excursion = _turn_angle(q, q[0])
    if np.max(excursion) < _MIN_SWEEP_RAD:
        return
    turn = min(0.1, float(np.max(excursion)))
    k = int(np.argmax(excursion >= turn))
    steps = 0.5 * (w[1:k + 1] + w[:k]) * np.diff(t[:k + 1])[:, None]
    integral = float(np.linalg.norm(np.sum(steps, axis=0)))
    ratio = integral / excursion[k]
    if ratio > _RATE_RATIO_MAX:
        guess = "deg/s (divide by 57.2958)" if ratio < 300 else "mrad/s (divide by 1000)"
        if ratio >= 300:   # the same factor when t is in ms: say so, with the step it implies
            guess += (f", or the time column t is in milliseconds (median step "
                      f"{float(np.median(np.diff(t))):.4g} s; the format wants seconds)")
        raise InputError(f"columns wx wy wz: by {_row_ref(k, t)} the body rates integrate to "
                         f"{ratio:.3g}x the rotation the quaternions show ({excursion[k]:.3g} "
                         f"rad); they look like {guess}; body rates must be in rad/s", path=path)


def _check_wheel_units(col: str, rpm: np.ndarray, path: str) -> None:
    a = np.abs(rpm[np.isfinite(rpm)])
    if a.size == 0:
        return
    if np.median(a) >= 1.0 and np.max(a) <= RAD_S_SUSPECT_MAX:
        raise InputError(f"column '{col}' looks like rad/s (max |value| {np.max(a):.3g}); wheel "
                         "rates must be in rpm — multiply by 60/(2*pi) (for a wheel that really "
                         "idles below 12 rpm: --no-unit-check, check_units=False)", path=path)


def _check_on_times(on: np.ndarray, t: np.ndarray, cols: Sequence[str], path: str) -> None:
    for k, col in enumerate(cols):
        x = on[:, k]
        d = np.diff(x)
        if np.any(d < 0):
            i = int(np.argmax(d < 0)) + 1
            raise InputError(f"column '{col}', {_row_ref(i, t)}: cumulative on-time decreases "
                             f"({x[i - 1]:.6g} → {x[i]:.6g} s); on_* columns are cumulative "
                             "seconds of on-time — check the column", path=path)
        too_fast = d > 2.0 * np.diff(t) + 0.1  # slack for on-times quantised in telemetry
        if np.any(too_fast):
            i = int(np.argmax(too_fast)) + 1
            raise InputError(f"column '{col}', {_row_ref(i, t)}: on-time grows by {d[i - 1]:.6g} s "
                             f"in {t[i] - t[i - 1]:.6g} s of time; on_* must be cumulative "
                             "seconds (not ms, not counts)", path=path)


def validate_telemetry(tel: Telemetry, *, check_units: bool = True) -> Telemetry:
    """Check an in-memory :class:`Telemetry` with the file rules; return it cleaned.

    Shapes must agree (``n`` rows everywhere), values must be finite (NaN only for a wheel that is
    off for the whole record), time strictly increasing; quaternions are renormalised within
    :data:`QUAT_NORM_TOL` and made sign-continuous.

    Returns
    -------
    Telemetry
        The same data as float64 NumPy arrays, ``q`` renormalised and sign-continuous.
    """
    path = tel.source
    t = np.asarray(tel.t, dtype=float)
    q = np.asarray(tel.q, dtype=float)
    w = np.asarray(tel.omega, dtype=float)
    r = np.asarray(tel.wheel_rates, dtype=float)
    on = None if tel.on_times is None else np.asarray(tel.on_times, dtype=float)
    n = t.shape[0] if t.ndim == 1 else -1
    expect = {"t": (t, (n,)), "q": (q, (n, 4)), "omega": (w, (n, 3)),
              "wheel_rates": (r, (n, len(tel.wheel_names)))}
    if on is not None:
        expect["on_times"] = (on, (n, len(tel.thruster_names)))
    for name, (x, shape) in expect.items():
        if n < 0 or x.shape != shape:
            raise InputError(f"mismatched lengths: '{name}' has shape {x.shape}, expected {shape} "
                             f"(t has {t.shape}); every series needs one row per sample",
                             path=path)
    if n < 2:
        raise InputError(f"only {n} sample(s); telemetry needs at least two rows", path=path)
    _fail_nonfinite(t, "t", path, None)
    _check_time(t, path)
    for j, c in enumerate(_Q_COLS):
        _fail_nonfinite(q[:, j], c, path, t)
    for j, c in enumerate(_W_COLS):
        _fail_nonfinite(w[:, j], c, path, t)
        _fail_out_of_range(w[:, j], c, OMEGA_ABS_MAX, "rad/s", path, t,
                           "body rates are rad/s; no controlled spacecraft turns faster")
    for j, name in enumerate(tel.wheel_names):
        x = r[:, j]
        if np.any(np.isnan(x)) and not np.all(np.isnan(x)):
            _fail_nonfinite(x, name.lower(), path, t,
                            fix="a wheel that is off must be empty in every row; where it "
                                "dropped out, remove those rows or split the file there (fit "
                                "inertia takes several files)")
        if np.any(np.isinf(x)):
            _fail_nonfinite(x, name.lower(), path, t)
        _fail_out_of_range(x / RPM_TO_RAD_S, name.lower(), WHEEL_RPM_MAX, "rpm", path, t,
                           "5x Cassini's ~2000 rpm wheels")
        if check_units:
            _check_wheel_units(name.lower(), x / RPM_TO_RAD_S, path)
    if on is not None:
        on_cols = _on_cols(tel.thruster_names)
        for k, c in enumerate(on_cols):
            _fail_nonfinite(on[:, k], c, path, t)
            _fail_out_of_range(on[:, k], c, TIME_ABS_MAX, "s", path, t, "317 years")
        _check_on_times(on, t, on_cols, path)
    q = _check_quaternions(q, t, path)
    if check_units:
        _check_omega_units(t, q, w, path)
    return Telemetry(t, q, w, r, tuple(tel.wheel_names), on, path, tuple(tel.thruster_names))
