"""Check 3: the pulse log vs the telemetry's own ``on_*`` columns.
"""

from __future__ import annotations

import warnings

import numpy as np

from cassini_bayes.errors import InputError
from cassini_bayes.telemetry import (
    PulseLog,
    PulseSpanWarning,
    Telemetry,
    check_pulses_in_span,
    cumulative_on_times,
)


def _derived_on_times(tel: Telemetry, log: PulseLog) -> np.ndarray:
    """Cumulative on-times the pulse log implies at the telemetry samples (warnings silenced:
    the readers and the fits report the pulses outside the span)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PulseSpanWarning)
        return cumulative_on_times(check_pulses_in_span(log, tel), tel.t)


def check_pulses_match_on_times(tel: Telemetry, log: PulseLog) -> None:
    """Refuse a pulse log that disagrees with the telemetry's own ``on_*`` columns.

    Per thruster, the log's cumulative on-time at the samples
    (:func:`cassini_bayes.telemetry.cumulative_on_times`) must match the column at every sample
    to within the longest single pulse (the longest width in the log, or the largest step of
    the column between two samples): a counter may book a pulse straddling a sample on either
    side of it, or in steps of its own resolution. No-op without ``on_*`` columns.
    """
    if tel.on_times is None:
        return
    if tuple(log.thruster_names) != tuple(tel.thruster_names):
        raise InputError(f"its thrusters ({', '.join(log.thruster_names)}) are not the on_* "
                         f"columns' of {tel.source} ({', '.join(tel.thruster_names)}); read both "
                         "with the same spacecraft model", path=log.source)
    derived = _derived_on_times(tel, log)
    col_all = np.asarray(tel.on_times, float)
    t = np.asarray(tel.t, float)
    for k, name in enumerate(tel.thruster_names):
        col, der = col_all[:, k] - col_all[0, k], derived[:, k]
        widths = log.width[log.thruster == k]
        slack = max(float(widths.max()) if widths.size else 0.0, float(np.diff(col).max())) + 1e-6
        diff = np.abs(der - col)
        if diff.max() <= slack:
            continue
        total_c, total_d = float(col[-1]), float(der[-1])
        i = int(np.argmax(diff))
        pct = (f"{100 * (total_d - total_c) / total_c:+.0f} %" if total_c > 0
               else "the column never fires")
        raise InputError(f"pulse log widths disagree with on_{name} of {tel.source} by {pct}: "
                         f"the log gives {total_d:.6g} s of {name} on-time, the column "
                         f"{total_c:.6g} s (largest difference {diff[i]:.3g} s at t = "
                         f"{t[i]:.10g} s); check the width unit (s) and that the log belongs to "
                         "this telemetry", path=log.source)
