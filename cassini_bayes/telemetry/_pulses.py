"""Pulse logs: validation, reading and writing, the telemetry span, cumulative on-times.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from cassini_bayes.errors import InputError, as_path
from cassini_bayes.telemetry._files import _write_frame
from cassini_bayes.telemetry._layout import _PULSE_COLS, _names_of
from cassini_bayes.telemetry._tables import (
    _fail_nonfinite,
    _fail_out_of_range,
    _map_header,
    _read_table,
    _to_float,
)
from cassini_bayes.telemetry._types import PulseLog, Telemetry
from cassini_bayes.telemetry.limits import PULSE_WIDTH_MAX, TIME_ABS_MAX


class PulseSpanWarning(UserWarning):
    """Pulses outside the telemetry span were dropped, or one is on at the first or last sample."""


class PulseAtStartWarning(PulseSpanWarning):
    """A pulse is on at the first sample: only what it does after that sample is used."""


class PulsesDroppedWarning(PulseSpanWarning):
    """Pulses of the log act entirely outside the telemetry span: they are left out."""



if TYPE_CHECKING:
    from cassini_bayes.spacecraft import Spacecraft


def validate_pulses(log: PulseLog) -> PulseLog:
    """Check a :class:`PulseLog`: lengths, finite values, width > 0, per-thruster order, overlap.

    Returns the log sorted by ``t_on`` (stable), as NumPy arrays.
    """
    path = log.source
    t_on = np.asarray(log.t_on, dtype=float)
    thr = np.asarray(log.thruster)
    width = np.asarray(log.width, dtype=float)
    if not (t_on.ndim == thr.ndim == width.ndim == 1 and len(t_on) == len(thr) == len(width)):
        raise InputError(f"mismatched lengths: t_on {t_on.shape}, thruster {thr.shape}, width "
                         f"{width.shape}; one entry per pulse", path=path)
    names = tuple(log.thruster_names)
    if thr.size and (not np.issubdtype(thr.dtype, np.integer)
                     or thr.min() < 0 or thr.max() >= len(names)):
        raise InputError(f"thruster indices must be integers 0..{len(names) - 1} "
                         f"({', '.join(names) or 'the model has no thrusters'})", path=path)
    thr = thr.astype(int)
    _fail_nonfinite(t_on, "t_on", path, None)
    _fail_nonfinite(width, "width", path, None)
    _fail_out_of_range(t_on, "t_on", TIME_ABS_MAX, "s", path, None, "317 years")
    _fail_out_of_range(width, "width", PULSE_WIDTH_MAX, "s", path, None,
                       "an hour; Cassini's RCS pulses are below a second")
    if np.any(width <= 0):
        i = int(np.argmax(width <= 0))
        raise InputError(f"column 'width', data row {i + 1} (t_on = {t_on[i]:.10g} s): width "
                         f"{width[i]:.6g} s must be positive; drop the row", path=path)
    for k, name in enumerate(names):
        rows = np.flatnonzero(thr == k)
        if rows.size < 2:
            continue
        t, w = t_on[rows], width[rows]
        d = np.diff(t)
        if np.any(d <= 0):
            i = int(np.argmax(d <= 0))
            raise InputError(f"thruster {name}: t_on is not increasing — data row {rows[i + 1] + 1}"
                             f" (t_on = {t[i + 1]:.10g} s) follows data row {rows[i] + 1} "
                             f"(t_on = {t[i]:.10g} s); sort the log by time, one pulse per "
                             "command", path=path)
        ov = t[:-1] + w[:-1] > t[1:]
        if np.any(ov):
            i = int(np.argmax(ov))
            fix = (f"the widths look like milliseconds (median {np.median(width):.4g}): the "
                   "format wants seconds" if float(np.median(width)) > 2.0
                   else "merge them into one pulse")
            raise InputError(f"thruster {name}: overlapping pulses — data row {rows[i] + 1} "
                             f"(t_on = {t[i]:.10g} s, width {w[i]:.6g} s) is still on at data row "
                             f"{rows[i + 1] + 1} (t_on = {t[i + 1]:.10g} s); {fix}", path=path)
    order = np.argsort(t_on, kind="stable")
    return PulseLog(t_on[order], thr[order], width[order], path, names)


def read_pulses(path: str | os.PathLike, *, spacecraft: Spacecraft | None = None) -> PulseLog:
    """Read and validate a pulse log: columns ``t_on`` (s), ``thruster`` (a thruster of
    ``spacecraft``; Cassini's ``Z1..Y4`` when ``None``), ``width`` (s).

    Returns
    -------
    PulseLog
        Sorted by ``t_on``; thruster as indices into its ``thruster_names``.
    """
    p = as_path(path, "a pulse-log file")
    name = str(path)
    _, names, whose = _names_of(spacecraft)
    if not names:
        raise InputError(f"a pulse log lists thruster firings, but {whose} has no thrusters; "
                         "give the model of the spacecraft that fired them", path=name)
    header, cells = _read_table(p, "pulse-log", allow_empty=True)
    idx = _map_header(header, _PULSE_COLS, name, "t_on thruster width")
    for c in _PULSE_COLS:
        if c not in idx:
            raise InputError(f"missing column '{c}'; a pulse log needs t_on (s), thruster "
                             f"({' '.join(names)}), width (s)", path=name)
    t_on = _to_float(cells[idx["t_on"]], "t_on", name)
    width = _to_float(cells[idx["width"]], "width", name)
    _fail_nonfinite(t_on, "t_on", name, None, fix="every pulse needs a command time")
    _fail_nonfinite(width, "width", name, None, fix="every pulse needs a width in seconds")
    lookup = {n.lower(): k for k, n in enumerate(names)}
    thr = np.empty(len(t_on), dtype=int)
    for i, c in enumerate(cells[idx["thruster"]]):
        key = "" if c is None else str(c).strip().lower()
        if key not in lookup:
            raise InputError(f"column 'thruster', data row {i + 1} (t_on = {t_on[i]:.10g} s): "
                             f"unknown thruster '{c}'; the thrusters of {whose} are "
                             f"{' '.join(names)}", path=name)
        thr[i] = lookup[key]
    return validate_pulses(PulseLog(t_on, thr, width, name, names))


def write_pulses(path: str | os.PathLike, log: PulseLog, *, force: bool = False) -> None:
    """Write a pulse log (``t_on``, ``thruster`` name, ``width``) atomically, full precision."""
    log = validate_pulses(log)
    cols = {"t_on": log.t_on, "thruster": log.names, "width": log.width}
    _write_frame(Path(path), cols, force)


def check_pulses_in_span(log: PulseLog, tel: Telemetry, *, tail_s: float = 0.0) -> PulseLog:
    """Keep the pulses that can affect the telemetry span ``[t[0], t[-1]]``.

    A pulse acts on the data from its command ``t_on`` to ``t_on + width + tail_s``: ``tail_s`` =
    0 for the commanded on-time (:func:`cumulative_on_times`), the decay of the thrust after the
    command (a few fall time constants) for the thrust fit.

    - A pulse that acts entirely before the first sample or from the last sample on cannot change
      the telemetry: it is dropped with a :class:`PulsesDroppedWarning`.
    - A pulse still on at the last sample is kept with a :class:`PulseSpanWarning`: the data
      see its on-time up to the last sample, which is what :func:`cumulative_on_times` counts.
    - A pulse already acting at the first sample is kept with a :class:`PulseAtStartWarning`
      (one line per pulse, naming it): the data see what it does after the first sample — its
      on-time from that sample (:func:`cumulative_on_times` re-bases to row 0), and in the thrust
      fit, whose cumulative model has a free offset per event, exactly the impulse it delivers
      after ``t[0]`` (what it delivered before is part of the offset).
    """
    t0, t1 = float(tel.t[0]), float(tel.t[-1])
    end = log.t_on + log.width
    at_start = (log.t_on < t0) & (end + tail_s > t0)
    for i in np.flatnonzero(at_start):
        warnings.warn(f"{log.source}: pulse of {log.thruster_names[log.thruster[i]]} at t_on = "
                      f"{log.t_on[i]:.10g} s (width {log.width[i]:.6g} s) is "
                      f"{'on' if end[i] > t0 else 'still decaying'} at the first telemetry "
                      f"sample t = {t0:.10g} s of {tel.source}; only what it does after that "
                      "sample is used", PulseAtStartWarning, stacklevel=2)
    at_end = (log.t_on < t1) & (end > t1)
    if np.any(at_end):
        warnings.warn(f"{log.source}: {int(at_end.sum())} pulse(s) still on at the last sample "
                      f"t = {t1:.10g} s of {tel.source}; their on-time is counted up to it",
                      PulseSpanWarning, stacklevel=2)
    outside = (end + tail_s <= t0) | (log.t_on >= t1)
    if np.any(outside):
        warnings.warn(f"{log.source}: {int(outside.sum())} of {len(outside)} pulses lie outside "
                      f"the telemetry span {t0:.10g}..{t1:.10g} s of {tel.source} and are ignored",
                      PulsesDroppedWarning, stacklevel=2)
        keep = ~outside
        return PulseLog(log.t_on[keep], log.thruster[keep], log.width[keep], log.source,
                        log.thruster_names)
    return log


def pulses_in_span(log: PulseLog, tel: Telemetry, *, tail_s: float = 0.0) -> PulseLog:
    """:func:`check_pulses_in_span` for a fit: of its notes only those about what the fit does
    not see are raised — pulses dropped (:class:`PulsesDroppedWarning`) and pulses on at the
    first sample (:class:`PulseAtStartWarning`); a pulse still on at the last sample is modelled
    up to it and needs no word (``check`` reports it)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        kept = check_pulses_in_span(log, tel, tail_s=tail_s)
    for w in caught:
        if w.category is not PulseSpanWarning:
            warnings.warn(w.message, w.category, stacklevel=2)
    return kept


def cumulative_on_times(pulses: PulseLog, t: np.ndarray) -> np.ndarray:
    """Cumulative commanded on-time of each thruster at times ``t``, since ``t[0]``.

    A pulse of width ``w`` commanded at ``t_on`` contributes ``clip(t − t_on, 0, w)``; the sum is
    re-based so row 0 is zero (docs/design.md §4.1 ``on_*`` columns).

    Parameters
    ----------
    pulses : the pulse log (validated: per thruster sorted and non-overlapping).
    t : (n,) sample times, s.

    Returns
    -------
    (n, m) on-times in s, one column per thruster of ``pulses.thruster_names``.
    """
    pulses = validate_pulses(pulses)
    t = np.asarray(t, dtype=float)
    m = len(pulses.thruster_names)
    out = np.zeros((t.shape[0], m))
    for k in range(m):
        m = pulses.thruster == k
        if not np.any(m):
            continue
        t_on, w = pulses.t_on[m], pulses.width[m]
        done = np.concatenate([[0.0], np.cumsum(w)])  # on-time of pulses 0..j-1, all complete
        j = np.searchsorted(t_on, t, side="right") - 1  # last pulse started at or before t
        started = j >= 0
        jj = np.maximum(j, 0)
        active = np.where(started, np.clip(t - t_on[jj], 0.0, w[jj]), 0.0)
        out[:, k] = np.where(started, done[jj] + active, 0.0)
    return out - out[:1]


def with_on_times(tel: Telemetry, pulses: PulseLog | None) -> Telemetry:
    """The telemetry with ``on_times`` filled from the pulse log when the file had none.

    The pulse log is first checked against the telemetry span (:func:`check_pulses_in_span`:
    may warn with :class:`PulseSpanWarning` or raise :class:`InputError`).
    """
    if tel.on_times is not None or pulses is None:
        return tel
    if tuple(pulses.thruster_names) != tuple(tel.thruster_names):
        raise InputError(f"its thrusters ({', '.join(pulses.thruster_names)}) are not those of "
                         f"the telemetry {tel.source} ({', '.join(tel.thruster_names) or 'none'})"
                         "; read both with the same spacecraft model", path=pulses.source)
    pulses = check_pulses_in_span(pulses, tel)
    return Telemetry(tel.t, tel.q, tel.omega, tel.wheel_rates, tel.wheel_names,
                     cumulative_on_times(pulses, tel.t), tel.source, pulses.thruster_names)
