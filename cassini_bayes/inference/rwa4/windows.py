"""The Time A / Time B window pairs of the spin-axis calibration (Brown 2012 §III): detected
from the quiet periods or given, and checked.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from cassini_bayes.errors import InputError, spelled
from cassini_bayes.telemetry import RPM_TO_RAD_S, Telemetry
from cassini_bayes.windows import clamp_window

if TYPE_CHECKING:
    from cassini_bayes.spacecraft import Spacecraft

__all__ = ["MIN_SPIN_CHANGE_RPM", "RCS_MIN_QUIET_S", "WHEEL", "Window", "detect_windows"]

MIN_SPIN_CHANGE_RPM = 10.0   # smaller spin changes between A and B cannot calibrate the axis
RCS_MIN_QUIET_S = 30.0
"""Shortest RCS-method Time A / Time B, s: the drift after the spin-up lasts until the widened
dead-band is reached, dead-band × I / (J Δρ), under a minute on a small spacecraft
(docs/model_file.md)."""
WHEEL = "RWA4"               # the wheel solved for by default

Window = tuple[float, float]


def _WINDOWS_HINT() -> str:  # noqa: N802 - a message constant, spelled for the caller
    return spelled("--window-a T0:T1 --window-b T0:T1", "windows=[((A0, A1), (B0, B1))] (s)")


def wheel_name(tel: Telemetry, wheel: str) -> str:
    """The telemetry's spelling of ``wheel``; InputError when it is absent or not running."""
    names = {n.upper(): n for n in tel.wheel_names}
    name = names.get(str(wheel).upper())
    if name is None or name not in tel.active_wheels():
        raise InputError(f"no {wheel} rates (column {str(wheel).lower()}, rpm); the spin-axis "
                         f"calibration needs {wheel} running", path=tel.source)
    return name


def _median_rpm(tel: Telemetry, w: Window, wheel: str) -> float:
    m = (tel.t >= w[0]) & (tel.t <= w[1])
    return float(np.nanmedian(np.asarray(tel.wheel_rate(wheel), float)[m]) / RPM_TO_RAD_S)


def detect_windows(tel: Telemetry, method: str, wheel: str = WHEEL,
                   spacecraft: Spacecraft | None = None) -> list[tuple[Window, Window]]:
    """Time A / Time B window pairs from the quiet periods (:func:`cassini_bayes.windows.
    quiet_periods`; the wheels' tolerances the ``spacecraft`` model's ``quiet_tol_rpm``).

    * RCS: the two consecutive quiet periods across the largest change of ``wheel``'s median
      rate, with no body-rate rule and at least :data:`RCS_MIN_QUIET_S` long: Brown's Time B is
      a free drift at ``J Δρ / I`` (Brown Eq 1: the body rates carry the balance); what makes it
      quiet is the wheels holding their rates and no thruster firing.
    * RWA: the rests paired in order, ``(Q0, Q1), (Q2, Q3), …`` — Brown's "Time A" before and
      "Time B" after the first slew of each slew pair; a rest split by a glitch with no slew
      between its pieces counts once (:func:`cassini_bayes.windows.joined_rests`).

    Raises
    ------
    InputError
        Fewer than two quiet periods; for RCS, no spin change of ``MIN_SPIN_CHANGE_RPM``.
    """
    from cassini_bayes.windows import QUIET_RATE_FRACTION, joined_rests, quiet_periods

    wheel = wheel_name(tel, wheel) if method == "rcs" else wheel

    if method == "rcs":
        quiet = quiet_periods(tel, rate_max=np.inf, min_duration_s=RCS_MIN_QUIET_S,
                              spacecraft=spacecraft)
        rule = f"≥ {RCS_MIN_QUIET_S:g} s"
    else:
        quiet = joined_rests(tel, quiet_periods(tel, spacecraft=spacecraft))
        rule = f"≥ 60 s, |ω| ≤ {QUIET_RATE_FRACTION:.2g} × the file's top rate"
    if len(quiet) < 2:
        raise InputError(f"found {len(quiet)} quiet period(s) ({rule}, wheels steady, no "
                         "thruster firing); the spin-axis calibration needs a Time A and a "
                         "Time B: give them with " + _WINDOWS_HINT(), path=tel.source)
    if method == "rcs":
        rpm = np.array([_median_rpm(tel, w, wheel) for w in quiet])
        jumps = np.abs(np.diff(rpm))
        k = int(np.nanargmax(jumps))
        if not jumps[k] >= MIN_SPIN_CHANGE_RPM:
            raise InputError(f"no {wheel} spin change between quiet periods (largest "
                             f"{jumps[k]:.3g} rpm < {MIN_SPIN_CHANGE_RPM:g} rpm); the RCS method "
                             f"needs {wheel} spun up or down between Time A and Time B",
                             path=tel.source)
        return [(quiet[k], quiet[k + 1])]
    return [(quiet[i], quiet[i + 1]) for i in range(0, len(quiet) - 1, 2)]


def check_windows(tel: Telemetry, pairs, method: str) -> list:
    """The window pairs, ends up to half a sample past the data clamped onto it
    (:func:`~cassini_bayes.windows.clamp_window`, with a warning); one-line InputErrors for
    pairs the calibration cannot use."""
    if not pairs:
        raise InputError("no window pair; give " + _WINDOWS_HINT(),
                         path=tel.source)
    if method == "rcs" and len(pairs) != 1:
        raise InputError(f"the RCS method takes one Time A / Time B pair, got {len(pairs)}",
                         path=tel.source)
    t = np.asarray(tel.t, float)
    pairs = [tuple(clamp_window(w, t, f"{tel.source}: window {w[0]:.10g}:{w[1]:.10g} s")
                   for w in p) for p in pairs]
    windows = [w for p in pairs for w in p]
    for w in windows:
        if np.count_nonzero((t >= w[0]) & (t <= w[1])) < 2:
            raise InputError(f"window {w[0]:.10g}:{w[1]:.10g} s holds fewer than two samples; "
                             "widen it", path=tel.source)
    ws = sorted(windows)
    for a, b in zip(ws[:-1], ws[1:]):
        if b[0] <= a[1]:
            raise InputError(f"windows {a[0]:.10g}:{a[1]:.10g} and {b[0]:.10g}:{b[1]:.10g} s "
                             "overlap; each sample may belong to one window only",
                             path=tel.source)
    if tel.on_times is not None:
        for w in windows:
            m = (t >= w[0]) & (t <= w[1])
            if np.any(np.diff(tel.on_times[m], axis=0) > 0):
                raise InputError(f"thrusters fire inside window {w[0]:.10g}:{w[1]:.10g} s; "
                                 "momentum is not conserved there: choose a quiet window",
                                 path=tel.source)
        for a, b in pairs:   # Brown §III: no firing from the start of Time A to the end of B
            lo, hi = min(a[0], b[0]), max(a[1], b[1])
            m = (t >= lo) & (t <= hi)
            fired = np.flatnonzero(np.any(np.diff(tel.on_times[m], axis=0) > 0, axis=1))
            if fired.size:
                t_fire = float(t[m][fired[0] + 1])
                raise InputError(f"thrusters fire at {t_fire:.10g} s, between Time A "
                                 f"{a[0]:.10g}:{a[1]:.10g} s and Time B {b[0]:.10g}:{b[1]:.10g} s; "
                                 "momentum is not conserved across the pair: give windows "
                                 "with no firing from the start of A to the end of B",
                                 path=tel.source)
    return pairs
