"""Check 1b: a constant gyro bias beyond the spacecraft model's ``[gyro]`` knowledge (a warning).
"""

from __future__ import annotations

import warnings
from typing import NamedTuple

import numpy as np

from cassini_bayes.consistency._attitude import _gaps_before, _integrated_rates
from cassini_bayes.consistency._programs import _rotvecs_between
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import Telemetry

# Thresholds (margins measured in docs/input_checks.md)

GYRO_WINDOW_MIN_SAMPLES = 4
"""Shortest window of :func:`gyro_bias_estimate`, samples; longer ones double from it."""
GYRO_MIN_WINDOWS = 8
"""Fewest quiet windows of one length that :func:`gyro_bias_estimate` uses (the standard error
comes from their scatter)."""
GYRO_WINDOW_TURN_RAD = 2e-3
"""Windows whose attitude turns more than this (rad) are left out of the gyro-bias estimate."""
GYRO_BIAS_Z = 5.0
"""A gyro bias is reported beyond this many prior sd and this many standard errors."""


class GyroBiasWarning(UserWarning):
    """The data show a gyro bias beyond the spacecraft model's ``[gyro]`` knowledge."""


class GyroBias(NamedTuple):
    """Constant gyro bias seen in the data: the body rates' integral against the quaternions'
    rotation over quiet windows (:func:`gyro_bias_estimate`).

    Attributes
    ----------
    bias : (3,) rad/s, body axes: what the rates read above the truth.
    se : (3,) rad/s, its standard error from the windows' scatter.
    windows : number of windows used.
    window_s : their length, s.
    """

    bias: np.ndarray
    se: np.ndarray
    windows: int
    window_s: float = 0.0


def _quiet_windows(t: np.ndarray, q: np.ndarray, gaps: np.ndarray,
                   length_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Consecutive gap-free windows ``(a, b)`` of ``length_s`` whose attitude turns by less than
    :data:`GYRO_WINDOW_TURN_RAD` (sample indices)."""
    edges = np.unique(np.searchsorted(t, np.arange(t[0], t[-1], length_s)))
    a, b = edges[:-1], edges[1:]
    keep = (b > a) & (gaps[a] == gaps[b])
    a, b = a[keep], b[keep]
    sign = np.where(np.sum(q[a] * q[b], axis=1) < 0, -1.0, 1.0)[:, None]
    turn = 4.0 * np.arctan2(np.linalg.norm(q[b] - sign * q[a], axis=1),
                            np.linalg.norm(q[b] + sign * q[a], axis=1))
    quiet = turn < GYRO_WINDOW_TURN_RAD
    return a[quiet], b[quiet]


def gyro_bias_estimate(tel: Telemetry) -> GyroBias | None:
    """Least-squares constant gyro bias ``b`` from windows where the attitude hardly turns.

    Per gap-free window ``(a, b)`` whose attitude turns by less than
    :data:`GYRO_WINDOW_TURN_RAD` (so the rotation vector and ``∫ω dt`` differ only by the bias,
    not by non-commuting turns or a rate-scale error): ``∫ω dt − rotvec(q_b q_a⁻¹) = b Δt +
    noise`` per body axis (a gyro reading ``ω + b`` integrates ``b Δt`` more than the attitude
    turns; Brown Eq 2 kinematics). The window length is the file's own: from
    :data:`GYRO_WINDOW_MIN_SAMPLES` median sample steps, doubling, the length whose quiet windows
    (at least :data:`GYRO_MIN_WINDOWS` of them) give the most precise estimate, ``N L²`` largest
    (the attitude noise of each window's ends is fixed, the bias grows with ``L``): long rests
    give long windows, a CubeSat's one-minute rests shorter ones. ``None`` when no length has
    :data:`GYRO_MIN_WINDOWS` quiet windows.
    """
    t = np.asarray(tel.t, float)
    q = np.asarray(tel.q, float)
    if t.size < 4:
        return None
    gaps = _gaps_before(t)
    length = GYRO_WINDOW_MIN_SAMPLES * float(np.median(np.diff(t)))
    best, best_score = None, 0.0
    while GYRO_MIN_WINDOWS * length <= t[-1] - t[0]:
        a, b = _quiet_windows(t, q, gaps, length)
        if a.size >= GYRO_MIN_WINDOWS and a.size * length**2 > best_score:
            best, best_score = (a, b, length), a.size * length**2
        length *= 2.0
    if best is None:
        return None
    a, b, length = best
    integral = _integrated_rates(tel)
    d = integral[b] - integral[a] - np.asarray(_rotvecs_between(q[a], q[b]))
    dt = t[b] - t[a]
    ss = float(dt @ dt)
    bias = dt @ d / ss
    resid = d - dt[:, None] * bias
    se = np.sqrt(np.sum(resid**2, axis=0) / max(dt.size - 1, 1) / ss)
    return GyroBias(bias, se, int(dt.size), length)


def check_gyro_bias(tel: Telemetry, spacecraft: Spacecraft) -> GyroBias | None:
    """Warn when the data show a gyro bias far beyond the model file's ``[gyro]`` knowledge:
    on some axis ``|b| > GYRO_BIAS_Z × bias_sd_rad_s`` and ``> GYRO_BIAS_Z × its standard
    error``. The fits' gyro-bias prior then under-states it, and the RWA4 axis by the RWA method
    can be wrong by more than its cone with every adequacy check passing. Returns the estimate
    (``None``: not enough quiet windows).
    """
    est = gyro_bias_estimate(tel)
    if est is None:
        return None
    sd = spacecraft.knowledge.gyro_bias_sd_rad_s
    big = (np.abs(est.bias) > GYRO_BIAS_Z * sd) & (np.abs(est.bias) > GYRO_BIAS_Z * est.se)
    if np.any(big):
        axes = ", ".join(f"{'xyz'[i]} {est.bias[i]:+.2g}" for i in np.flatnonzero(big))
        worst = float(np.max(np.abs(est.bias)[big]) / sd)
        warnings.warn(f"{tel.source}: columns wx wy wz carry a constant gyro bias of about "
                      f"{axes} rad/s ({worst:.0f}x the [gyro] bias_sd_rad_s = {sd:.2g} of "
                      f"the model {spacecraft.name!r}, seen over {est.windows} quiet "
                      f"{est.window_s:.3g}-s windows): the fits' gyro prior under-states it; "
                      "widen bias_sd_rad_s in the spacecraft model, or remove the bias",
                      GyroBiasWarning, stacklevel=2)
    return est
