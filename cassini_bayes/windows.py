"""Quiet periods, slews between them, and ``T0:T1`` window arguments.

A *quiet period* is a stretch of telemetry where the spacecraft is quiescent: the body rate is
small, every wheel that is on holds its rate, and no thruster fires. The papers anchor their
estimates on such stretches — Feldman & Lee's momentum model on the quiescent samples before and
after each RWA slew, Brown's RWA4 calibration on "Time A" / "Time B" windows (Brown §III-IV) —
and ``cassini-bayes check`` lists them. Everything here is NumPy on the arrays of a
:class:`~cassini_bayes.telemetry.Telemetry` (SI units).

Detection (per sample, then runs of at least ``min_duration_s``): with a centred moving window
of ``smooth_s`` seconds (converted to samples with the median sample spacing; at least a
sample's two neighbours, however coarse the sampling),

- ``max |ω| ≤ rate_max`` (rad/s) over the window; by default a third of the file's top rate
  (:data:`QUIET_RATE_FRACTION`): quiet is relative to the spacecraft's own slews, not to one
  spacecraft's rates,
- ``max ρ − min ρ ≤ wheel_tol_rpm`` for each wheel that is on (NaN wheels are ignored); by
  default the spacecraft model's ``[[wheel]] quiet_tol_rpm`` of that wheel
  (:func:`quiet_wheel_tol_rpm`; :data:`QUIET_WHEEL_TOL_RPM` without a model),
- no cumulative thruster on-time grows within the window (when the telemetry has on-times).

Both tolerances are at least :data:`QUIET_NOISE_SD` times the white noise of the file's own
body rates and of each wheel's rates (:func:`cassini_bayes.telemetry.white_noise_sd`): a MEMS
gyro or a CubeSat's 1-rpm hall sensors are quiet at rest however coarse their noise.

The window makes a single noisy sample or a thruster pulse exclude its neighbourhood too, so a
quiet period never starts in the middle of a wheel ramp or a pulse's thrust tail.
"""

from __future__ import annotations

import re
import warnings
from typing import TYPE_CHECKING

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from cassini_bayes.errors import InputError
from cassini_bayes.spacecraft import QUIET_WHEEL_TOL_RPM
from cassini_bayes.telemetry import RPM_TO_RAD_S, Telemetry, white_noise_sd

if TYPE_CHECKING:
    from cassini_bayes.spacecraft import Spacecraft

__all__ = ["quiet_mask", "quiet_periods", "quiet_rate_max", "quiet_wheel_tol_rpm", "top_rate",
           "QUIET_RATE_FRACTION", "QUIET_NOISE_SD", "QUIET_WHEEL_TOL_RPM", "slew_windows",
           "joined_rests",
           "split_slews", "parse_window", "clamp_window", "WindowClampWarning"]

Window = tuple[float, float]

QUIET_RATE_FRACTION = 1.0 / 3.0
"""A quiet sample's body rate is at most this fraction of the file's top rate (:func:`top_rate`):
a slew coasting at its top rate with the wheels steady is not a rest. On Cassini's slews it gives
the papers' 1 mrad/s (docs/model_file.md)."""

QUIET_NOISE_SD = 8.0
"""The quiet tolerances are at least this many white-noise sds of the file's own rates: the range
of a window's worth of white noise (10-40 samples) is ~4 sd, beyond 8 sd less than once in 10⁵
windows (7.4 sd at 1e-4 for 41 samples)."""


def _moving_range(x: np.ndarray, half: int) -> np.ndarray:
    """``max − min`` of ``x`` over samples ``i − half … i + half`` (edges padded), per column."""
    if half == 0:
        return np.zeros_like(x)
    padded = np.pad(x, [(half, half)] + [(0, 0)] * (x.ndim - 1), mode="edge")
    view = sliding_window_view(padded, 2 * half + 1, axis=0)
    return view.max(axis=-1) - view.min(axis=-1)


def top_rate(rate: np.ndarray, half: int) -> float:
    """The file's top body rate, rad/s: the largest moving median of ``|ω|`` over samples
    ``i − half … i + half`` (a slew's coast rate; a lone spike or gap sample does not count)."""
    if half == 0 or rate.size == 0:
        return float(np.max(rate, initial=0.0))
    return float(np.max(_moving_median(rate, half)))


def _moving_median(x: np.ndarray, half: int) -> np.ndarray:
    """Median of ``x`` over samples ``i − half … i + half`` (edges padded)."""
    padded = np.pad(x, (half, half), mode="edge")
    return np.median(sliding_window_view(padded, 2 * half + 1), axis=-1)


def _moving_max(x: np.ndarray, half: int) -> np.ndarray:
    if half == 0:
        return x
    padded = np.pad(x, (half, half), mode="edge")
    return sliding_window_view(padded, 2 * half + 1).max(axis=-1)


def _half(t: np.ndarray, smooth_s: float) -> int:
    """Half the moving window in samples: at least the neighbours, however coarse the sampling
    (at 0.1 Hz half a 10-s window rounds to no sample, and a window of one sample sees no wheel
    ramp)."""
    dt = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    return max(1, int(round(0.5 * smooth_s / dt))) if dt > 0 else 1


def quiet_rate_max(tel: Telemetry, rate_max: float | None = None,
                   smooth_s: float = 10.0) -> float:
    """The body-rate bound of a quiet sample that :func:`quiet_mask` applies, rad/s:
    ``rate_max`` (default :data:`QUIET_RATE_FRACTION` × :func:`top_rate`), at least
    :data:`QUIET_NOISE_SD` × the rates' white noise."""
    t = np.asarray(tel.t, dtype=float)
    omega = np.asarray(tel.omega, dtype=float)
    if rate_max is None:
        rate_max = QUIET_RATE_FRACTION * top_rate(np.linalg.norm(omega, axis=1), _half(t, smooth_s))
    return float(max(rate_max, QUIET_NOISE_SD * white_noise_sd(omega)))


def quiet_wheel_tol_rpm(tel: Telemetry, wheel_tol_rpm: float | None = None,
                        spacecraft: Spacecraft | None = None) -> np.ndarray:
    """(k,) the largest change of each telemetry wheel's rate within a quiet window, rpm, before
    its noise floor: ``wheel_tol_rpm`` when given, else the spacecraft model's ``[[wheel]]
    quiet_tol_rpm`` of that wheel, else :data:`QUIET_WHEEL_TOL_RPM` (no model, or a wheel the
    model lacks)."""
    if wheel_tol_rpm is not None:
        return np.full(len(tel.wheel_names), float(wheel_tol_rpm))
    model = {} if spacecraft is None else {w.name: w.quiet_tol_rpm for w in spacecraft.wheels}
    return np.array([model.get(n.upper(), QUIET_WHEEL_TOL_RPM) for n in tel.wheel_names])


def quiet_mask(
    tel: Telemetry,
    *,
    rate_max: float | None = None,
    wheel_tol_rpm: float | None = None,
    smooth_s: float = 10.0,
    spacecraft: Spacecraft | None = None,
) -> np.ndarray:
    """Boolean (n,) mask of quiescent samples (criteria in the module docstring).

    Parameters
    ----------
    tel : the telemetry.
    rate_max : largest body-rate magnitude of a quiet sample, rad/s (at least
        :data:`QUIET_NOISE_SD` × the rates' white noise); default :data:`QUIET_RATE_FRACTION` ×
        the file's top rate (:func:`top_rate`), which excludes slews in progress whatever the
        spacecraft's slew rates; ``inf``: no rate rule (a free drift is quiet, as Brown's
        RCS-method Time B needs).
    wheel_tol_rpm : largest change of any running wheel's rate within the window, rpm (at least
        :data:`QUIET_NOISE_SD` × that wheel's white noise); default each wheel's
        (:func:`quiet_wheel_tol_rpm`).
    smooth_s : width of the centred moving window, s.
    spacecraft : the model whose ``[[wheel]] quiet_tol_rpm`` give the wheels' default
        tolerances.
    """
    t = np.asarray(tel.t, dtype=float)
    n = t.shape[0]
    if n < 2:
        return np.zeros(n, dtype=bool)
    half = _half(t, smooth_s)
    rate = np.linalg.norm(np.asarray(tel.omega, dtype=float), axis=1)
    quiet = _moving_max(rate, half) <= quiet_rate_max(tel, rate_max, smooth_s)
    rates = np.asarray(tel.wheel_rates, dtype=float)
    running = np.all(np.isfinite(rates), axis=0)
    if np.any(running):
        spread_rpm = _moving_range(rates[:, running], half) / RPM_TO_RAD_S
        noise_rpm = np.array([white_noise_sd(rates[:, j]) for j in np.flatnonzero(running)])
        given = quiet_wheel_tol_rpm(tel, wheel_tol_rpm, spacecraft)[running]
        tol = np.maximum(given, QUIET_NOISE_SD * noise_rpm / RPM_TO_RAD_S)
        quiet &= np.all(spread_rpm <= tol, axis=1)
    if tel.on_times is not None:
        # a sample is loud when on-time grows into or out of it, or anywhere in its window
        growth = np.zeros(n, dtype=bool)
        step = np.any(np.diff(np.asarray(tel.on_times, dtype=float), axis=0) > 0, axis=1)
        growth[1:] |= step
        growth[:-1] |= step
        quiet &= ~(_moving_max(growth.astype(float), half) > 0)
    return quiet


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Inclusive index ranges of the runs of True in ``mask``."""
    m = np.concatenate([[False], mask, [False]]).astype(np.int8)
    d = np.diff(m)
    starts = np.flatnonzero(d == 1)
    ends = np.flatnonzero(d == -1) - 1
    return list(zip(starts.tolist(), ends.tolist()))


def quiet_periods(
    tel: Telemetry,
    *,
    min_duration_s: float = 60.0,
    rate_max: float | None = None,
    wheel_tol_rpm: float | None = None,
    smooth_s: float = 10.0,
    spacecraft: Spacecraft | None = None,
) -> list[Window]:
    """Quiet periods of at least ``min_duration_s`` seconds, as ``(t0, t1)`` sample times, s.

    See :func:`quiet_mask` for the criteria; returned in time order, non-overlapping.
    """
    mask = quiet_mask(tel, rate_max=rate_max, wheel_tol_rpm=wheel_tol_rpm, smooth_s=smooth_s,
                      spacecraft=spacecraft)
    t = np.asarray(tel.t, dtype=float)
    return [(float(t[a]), float(t[b])) for a, b in _runs(mask)
            if t[b] - t[a] >= min_duration_s]


def slew_windows(quiet: list[Window]) -> list[Window]:
    """The gaps between consecutive quiet periods: ``(end of quiet i, start of quiet i+1)``."""
    return [(a[1], b[0]) for a, b in zip(quiet[:-1], quiet[1:])]


def joined_rests(tel: Telemetry, quiet: list[Window], *, rate_max: float | None = None,
                 smooth_s: float = 10.0) -> list[Window]:
    """``quiet`` with each rest that a glitch split in two made one again, as its longest piece.

    Consecutive periods belong to one rest when the gap between them holds no slew: the body
    rate's moving median over ``smooth_s`` never exceeds the quiet bound
    (:func:`quiet_rate_max`). A wheel-rate step or a gyro spike then cannot put a pairing of
    rests out of step; the longest piece is kept because the gap's samples failed a quiet rule.
    """
    if len(quiet) < 2:
        return list(quiet)
    t = np.asarray(tel.t, dtype=float)
    half = _half(t, smooth_s)
    median = _moving_median(np.linalg.norm(np.asarray(tel.omega, dtype=float), axis=1), half)
    bound = quiet_rate_max(tel, rate_max, smooth_s)
    rests = [[quiet[0]]]
    for a, b in zip(quiet[:-1], quiet[1:]):
        gap = (t > a[1]) & (t < b[0])
        if np.any(median[gap] > bound):
            rests.append([b])
        else:
            rests[-1].append(b)
    return [max(pieces, key=lambda w: w[1] - w[0]) for pieces in rests]


def split_slews(
    tel: Telemetry,
    quiet: list[Window] | None = None,
    *,
    margin_s: float | None = 30.0,
    **criteria: float,
) -> list[Telemetry]:
    """Cut the telemetry into slews, each with quiescent samples on both sides.

    Segment ``i`` runs from ``margin_s`` seconds before the end of quiet period ``i`` to
    ``margin_s`` seconds after the start of quiet period ``i+1`` (clipped to the quiet periods;
    ``margin_s=None`` keeps the whole quiet periods), so a momentum model can anchor on quiescent
    samples before and after the slew (Feldman & Lee §III).

    Parameters
    ----------
    tel : the telemetry.
    quiet : quiet periods; detected with ``criteria`` (see :func:`quiet_periods`) when omitted.
    margin_s : quiescent seconds kept on each side, s.
    """
    if quiet is None:
        quiet = quiet_periods(tel, **criteria)
    out = []
    for a, b in zip(quiet[:-1], quiet[1:]):
        t0 = a[0] if margin_s is None else max(a[0], a[1] - margin_s)
        t1 = b[1] if margin_s is None else min(b[1], b[0] + margin_s)
        out.append(tel.slice(t0, t1))
    return out


_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_WINDOW = re.compile(rf"^\s*({_NUM})?\s*:\s*({_NUM})?\s*$")


def parse_window(text: str, t: np.ndarray | None = None, *, option: str = "window") -> Window:
    """Parse ``"T0:T1"`` (seconds) into ``(t0, t1)``.

    ``T0`` or ``T1`` may be left out (``":600"``, ``"1200:"``) when ``t`` is given: the data's
    first or last time is used. With ``t`` the window must lie within ``[t[0], t[-1]]`` and hold
    at least two samples; an end at most half a median sample period past the data (a rounded
    time, a jittered first or last sample) is clamped onto it with a :class:`WindowClampWarning`
    (:func:`clamp_window`).

    Raises
    ------
    InputError
        Bad syntax, ``T0 ≥ T1``, or a window outside the data; the message names ``option``.
    """
    m = _WINDOW.match(str(text))
    if m is None:
        raise InputError(f"--{option} '{text}': expected T0:T1 in seconds, e.g. 120:540")
    a, b = m.group(1), m.group(2)
    if (a is None or b is None) and t is None:
        raise InputError(f"--{option} '{text}': give both ends, T0:T1 in seconds")
    if t is not None:
        t = np.asarray(t, dtype=float)
        lo, hi = float(t[0]), float(t[-1])
    t0 = float(a) if a is not None else lo
    t1 = float(b) if b is not None else hi
    if not t0 < t1:
        raise InputError(f"--{option} '{text}': start {t0:g} s is not before end {t1:g} s; "
                         "write T0:T1 with T0 < T1")
    if t is not None:
        t0, t1 = clamp_window((t0, t1), t, f"--{option} '{text}'")
        inside = int(np.count_nonzero((t >= t0) & (t <= t1)))
        if inside < 2:
            raise InputError(f"--{option} '{text}' holds {inside} sample(s); widen it to at least "
                             "two samples")
    return (t0, t1)


class WindowClampWarning(UserWarning):
    """A window end a fraction of a sample past the data was moved onto the data's end."""


def clamp_window(window: Window, t: np.ndarray, what: str) -> Window:
    """``window`` with an end at most half a median sample period outside ``[t[0], t[-1]]``
    moved onto the data, with one :class:`WindowClampWarning` naming ``what`` and both windows.

    Raises :class:`InputError` (naming ``what``) when an end lies further out.
    """
    t = np.asarray(t, dtype=float)
    lo, hi = float(t[0]), float(t[-1])
    slack = 0.5 * float(np.median(np.diff(t))) if t.size > 1 else 0.0
    t0, t1 = float(window[0]), float(window[1])
    if t0 < lo - slack or t1 > hi + slack:
        raise InputError(f"{what} lies outside the data ({lo:.10g} to {hi:.10g} s); choose a "
                         "window inside the telemetry")
    new = (max(t0, lo), min(t1, hi))
    if new != (t0, t1):
        warnings.warn(f"{what}: window {t0:.10g}:{t1:.10g} s reaches past the data ({lo:.10g} to "
                      f"{hi:.10g} s) by less than half a sample period; clamped to "
                      f"{new[0]:.10g}:{new[1]:.10g} s", WindowClampWarning, stacklevel=3)
    return new
