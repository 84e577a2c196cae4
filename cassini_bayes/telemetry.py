"""Telemetry and pulse-log containers, readers, writers, validation (docs/design.md §4.1-4.2).

SI inside: wheel rates are rad/s in :class:`Telemetry` (rpm only in files). Every problem with a
file is an :class:`~cassini_bayes.errors.InputError` with one line naming the file, the column
and/or the data row (1-based, header not counted, with its ``t``) and what to do about it.

Validation rules and their tolerances
-------------------------------------
- Columns: ``t q1 q2 q3 q4 wx wy wz`` required; one column per wheel of the spacecraft model,
  named as the wheel in lower case (rpm, optional — absent or entirely empty means the wheel is
  off, NaN inside); ``on_<thruster>`` per thruster of the model (s, optional — when any is
  present, a thruster without a column never fired). Without a model the names are Cassini's
  (``rwa1 … rwa4``, ``on_Z1 … on_Y4``; docs/model_file.md). Header names are matched
  case-insensitively; an unknown or duplicate column is an error (a typo must not silently drop
  data), and a column for a wheel or thruster the model lacks names the model's.
- Values: numbers only; a required cell that is empty, NaN or infinite is an error; a wheel column
  that is empty in some rows but not in others is an error.
- Time: strictly increasing (a duplicate or a step back is an error naming both rows).
- Physical bounds (docs/limits.md), checked whatever ``check_units`` says, so that nothing that
  passes validation can overflow later (differences of ``t``, rate × time products): ``|t| ≤
  TIME_ABS_MAX`` (1e10 s, 317 years: any epoch in seconds, SCLK or J2000, fits) and consecutive
  samples at least ``MIN_SAMPLE_SPACING_S`` (1 µs) apart; wheel rates ``|ρ| ≤ WHEEL_RPM_MAX``
  (10 000 rpm: five times Cassini's ~2000 rpm wheels, which the papers bias to 1800 rpm);
  body rates ``|ω_i| ≤ OMEGA_ABS_MAX`` (5 rad/s, 290 °/s: no spacecraft under attitude control
  turns that fast); quaternion components ``|q_i| ≤ 2`` (before the norm test); cumulative on-times
  ``|on| ≤ TIME_ABS_MAX``; pulse ``|t_on| ≤ TIME_ABS_MAX`` and ``0 < width ≤ PULSE_WIDTH_MAX``
  (3600 s; Cassini's RCS pulses are below a second, its longest RCS burns minutes).
- Size: at most ``MAX_ROWS`` (200 000) data rows per file (telemetry or pulse log) and per fit
  (:func:`read_telemetry_many`). Telemetry CSV is parsed to floats in chunks of rows and the limit
  is checked while reading, so reading takes ~0.35 MB per 1000 rows and a huge file fails fast
  (docs/limits.md).
- Quaternion norm: ``|‖q‖ − 1| ≤ QUAT_NORM_TOL`` (1e-3, telemetry rounding) is accepted and the row
  renormalised; a larger deviation is an error. Rows within 1e-12 of unit norm are left bit-exact.
- Quaternion sign: ``q`` and ``−q`` are the same attitude. Sign flips between consecutive rows are
  accepted and removed with the rule of :func:`cassini_bayes.frames.quat_continuous` (a NumPy
  twin here, tested equal), which only ever changes signs, never the attitude — a genuine
  attitude jump passes through unchanged.
- Wheel units: a wheel column is taken to be rad/s (an error) when the wheel is clearly spinning
  (median ``|value| ≥ 1``) yet never exceeds ``RAD_S_SUSPECT_MAX`` = 12 in magnitude — in rpm that
  would be a wheel idling between 1 and 12 rpm for the whole record, which Cassini avoids (wheels
  are biased to hundreds of rpm, away from zero-crossing friction); in rad/s it is any wheel slower
  than 115 rpm. Wheels at rest (noise about zero) and real rpm data over 0-2000 rpm never trip it.
  ``check_units=False`` turns the unit checks off for genuinely slow wheels.
- Body-rate units: ``|ω| > OMEGA_MAX`` (0.2 rad/s = 11.5 °/s, far above any Cassini slew rate of a
  few mrad/s) is taken to be °/s or mrad/s. And where the attitude turns by more than 0.01 rad,
  the body rate integrated up to the first row where the quaternions have turned by
  ``min(0.1 rad, largest turn)`` must not exceed that angle by more than ten times (°/s gives
  57×, mrad/s 1000×; rate noise adds only a random walk, far below ten times the angle).
- Pulse logs: thruster names of the model (Cassini's ``Z1 … Y4`` without one; case-insensitive);
  ``0 < width ≤ PULSE_WIDTH_MAX``;
  ``t_on`` strictly increasing per thruster and no pulse starting before the previous pulse of
  the same thruster has ended. A header-only pulse log is valid (no pulses). Against a telemetry
  (:func:`check_pulses_in_span`): a pulse entirely outside the telemetry span cannot affect it
  and is dropped with a :class:`PulseSpanWarning`; one still on at the last sample is kept with a
  warning (its on-time counts up to that sample); one already on at the first sample is kept with
  a :class:`PulseAtStartWarning` (its on-time counts from that sample, and the thrust fit models
  exactly what it delivers after it).
"""

from __future__ import annotations

import csv
import itertools
import os
import warnings
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from cassini_bayes.files import atomic_path
from cassini_bayes._paths import input_path, not_utf8
from cassini_bayes.errors import InputError, as_path
from cassini_bayes.names import THRUSTER_NAMES
from cassini_bayes.units import RPM_TO_RAD_S

__all__ = [
    "Telemetry",
    "PulseLog",
    "RPM_TO_RAD_S",
    "WHEEL_NAMES",
    "IDLE_RPM",
    "IDLE_NOISE_SD",
    "THRUSTER_NAMES",
    "QUAT_NORM_TOL",
    "OMEGA_MAX",
    "RAD_S_SUSPECT_MAX",
    "TIME_ABS_MAX",
    "MIN_SAMPLE_SPACING_S",
    "WHEEL_RPM_MAX",
    "OMEGA_ABS_MAX",
    "PULSE_WIDTH_MAX",
    "MAX_ROWS",
    "PulseSpanWarning",
    "read_telemetry",
    "read_telemetry_many",
    "write_telemetry",
    "read_pulses",
    "write_pulses",
    "validate_telemetry",
    "validate_pulses",
    "check_pulses_in_span",
    "pulses_in_span",
    "check_model_names",
    "PulseAtStartWarning",
    "PulsesDroppedWarning",
    "cumulative_on_times",
    "with_on_times",
    "white_noise_sd",
    "RATE_NOISE_FLOORS",
]

WHEEL_NAMES = ("RWA1", "RWA2", "RWA3", "RWA4")
"""Cassini's wheels: the telemetry's wheel columns ``rwa1 … rwa4`` when no model names others."""
IDLE_RPM = 1.0
"""A wheel whose rate's root mean square is at most this (rpm) is idle, as if off: its momentum,
0.16 kg m² × 1 rpm = 0.017 N m s rms, is ~1000× below what a slew exchanges (18–22 N m s);
tachometer noise about 0 rpm (±0.3 rpm) is idle, a wheel through zero speed is not."""
IDLE_NOISE_SD = 3.0
"""… or whose rms rate is at most this many times its own white noise
(:func:`white_noise_sd`): a coarse tachometer's noise about 0 rpm (a CubeSat's hall sensors,
±1 rpm steps) is idle too."""


@dataclass(frozen=True)
class Telemetry:
    """Sampled attitude-control telemetry, SI units.

    Attributes
    ----------
    t : (n,) sample times, s, strictly increasing.
    q : (n, 4) attitude quaternions ``(q1, q2, q3, q4)``, scalar last, inertial → body.
    omega : (n, 3) body rates in body axes, rad/s.
    wheel_rates : (n, k) wheel spin rates about their own axes relative to the body, rad/s;
        a column of NaN is a wheel that is off.
    wheel_names : the k wheel names, matching the spacecraft model's wheels (``RWA1`` …).
    on_times : (n, m) cumulative thruster on-times since the first row, s, in the order of
        ``thruster_names``; ``None`` when the file had none.
    source : where the data came from (a file name), for error messages.
    thruster_names : the m thrusters of ``on_times`` (the model's; Cassini's ``Z1 … Y4``).
    """

    t: np.ndarray
    q: np.ndarray
    omega: np.ndarray
    wheel_rates: np.ndarray
    wheel_names: tuple[str, ...] = WHEEL_NAMES
    on_times: np.ndarray | None = None
    source: str = "<telemetry>"
    thruster_names: tuple[str, ...] = THRUSTER_NAMES

    @property
    def n(self) -> int:
        return int(self.t.shape[0])

    def wheel_rate(self, name: str) -> np.ndarray:
        """Rates (rad/s) of one wheel by name."""
        return self.wheel_rates[:, self.wheel_names.index(name.upper())]

    def active_mask(self) -> np.ndarray:
        """(k,) which wheels carry momentum: finite rates whose root mean square exceeds
        :data:`IDLE_RPM` and :data:`IDLE_NOISE_SD` times their white noise. A wheel written as
        0 rpm (or within tachometer noise of it) all along is as good as off: its momentum is
        below the noise, and a wheel the data cannot see must not get a spin-inertia scale of
        its own (it moved the inertia fit by −2.4 %)."""
        rates = np.asarray(self.wheel_rates, float)
        finite = np.isfinite(rates)
        n = finite.sum(axis=0)
        ms = np.where(finite, rates, 0.0) ** 2
        rms = np.sqrt(ms.sum(axis=0) / np.maximum(n, 1))
        noise = np.array([white_noise_sd(rates[:, j]) for j in range(rates.shape[1])])
        return (n > 0) & (rms > np.maximum(IDLE_RPM * RPM_TO_RAD_S, IDLE_NOISE_SD * noise))

    def active_wheels(self) -> tuple[str, ...]:
        """Names of the wheels that carry momentum (:meth:`active_mask`)."""
        return tuple(n for n, on in zip(self.wheel_names, self.active_mask()) if on)

    def slice(self, t0: float, t1: float) -> "Telemetry":
        """Rows with ``t0 ≤ t ≤ t1``."""
        m = (self.t >= t0) & (self.t <= t1)
        return Telemetry(self.t[m], self.q[m], self.omega[m], self.wheel_rates[m],
                         self.wheel_names, None if self.on_times is None else self.on_times[m],
                         self.source, self.thruster_names)


@dataclass(frozen=True)
class PulseLog:
    """Thruster pulse commands.

    Attributes
    ----------
    t_on : (p,) command times, s.
    thruster : (p,) thruster indices into ``thruster_names``.
    width : (p,) commanded on-times, s.
    thruster_names : the spacecraft model's thrusters (Cassini's ``Z1 … Y4`` by default).
    """

    t_on: np.ndarray
    thruster: np.ndarray
    width: np.ndarray
    source: str = field(default="<pulses>")
    thruster_names: tuple[str, ...] = THRUSTER_NAMES

    @property
    def names(self) -> list[str]:
        return [self.thruster_names[i] for i in self.thruster]


# --------------------------------------------------------------------------------------------
# Tolerances (documented in the module docstring)

QUAT_NORM_TOL = 1e-3
"""Largest accepted ``|‖q‖ − 1|``; such rows are renormalised, larger is an error."""
OMEGA_MAX = 0.2
"""Largest plausible body rate, rad/s (11.5 °/s); above it the column is in the wrong unit."""
RAD_S_SUSPECT_MAX = 12.0
"""A spinning wheel (median ``|value| ≥ 1``) never above this magnitude is read as rad/s."""
TIME_ABS_MAX = 1e10
"""Largest ``|t|``, ``|t_on|`` and ``|on_*|``, s (317 years; SCLK and J2000 seconds fit)."""
MIN_SAMPLE_SPACING_S = 1e-6
"""Smallest time between consecutive telemetry samples, s (1 MHz; telemetry is ~1 Hz)."""
WHEEL_RPM_MAX = 1e4
"""Largest wheel-rate magnitude, rpm (five times Cassini's ~2000 rpm wheels)."""
OMEGA_ABS_MAX = 5.0
"""Largest body-rate component magnitude, rad/s, checked even without the unit heuristics."""
MAX_ROWS = 200_000
"""Most data rows of one telemetry file, and of all the files of one fit together (measured
peak memory: ~0.35 kB per row to read and check, ~4-5 kB per row to prepare an inertia fit, so
~1 GB at the limit; docs/limits.md). 55 h at 1 Hz; longer records: decimate or split."""
_CHUNK_ROWS = 8192  # CSV rows parsed to floats at a time (bounds the text held in memory)
PULSE_WIDTH_MAX = 3600.0
"""Longest accepted pulse width, s (Cassini's RCS pulses are below a second)."""
_EXACT_NORM = 1e-12  # rows this close to unit norm are left bit-exact
_RATE_RATIO_MAX = 10.0  # |∫ω dt| over the quaternion angle turned above this → wrong unit
_MIN_SWEEP_RAD = 0.01  # the ratio test needs the attitude to move at least this much

_Q_COLS = ("q1", "q2", "q3", "q4")
_W_COLS = ("wx", "wy", "wz")
_REQUIRED = ("t",) + _Q_COLS + _W_COLS
_PULSE_COLS = ("t_on", "thruster", "width")


def _on_cols(thruster_names: Sequence[str]) -> tuple[str, ...]:
    """The on-time columns ``on_<name>`` of the thrusters."""
    return tuple(f"on_{n}" for n in thruster_names)


def _names_of(spacecraft) -> tuple[tuple[str, ...], tuple[str, ...], str]:
    """``(wheel names, thruster names, whose)`` of the file layout: the model's, or Cassini's
    (the format's default) when ``spacecraft`` is ``None``."""
    if spacecraft is None:
        return (WHEEL_NAMES, THRUSTER_NAMES,
                "Cassini's layout (the default without a spacecraft model)")
    return (tuple(spacecraft.wheel_names), tuple(spacecraft.thruster_names),
            f"the spacecraft model {spacecraft.name!r}")


def _unknown_column(h: str, wheel_names, thruster_names, whose: str,
                    no_model: bool) -> str:
    """Why header ``h`` is unknown, naming the wheels or thrusters ``whose`` layout expects."""
    give = (", or give the spacecraft model whose wheels and thrusters these are (--spacecraft)"
            if no_model else "")
    if h.lower().startswith("on_"):
        have = " ".join(_on_cols(thruster_names)) or "none: it has no thrusters"
        return (f"column '{h}' is the on-time of no thruster of {whose} (its on_* columns: "
                f"{have}); rename or remove it{give}")
    wheels = " ".join(n.lower() for n in wheel_names)
    return (f"unknown column '{h}': neither a required column ({' '.join(_REQUIRED)}) nor a "
            f"wheel column of {whose} ({wheels}); rename or remove it{give}")


class PulseSpanWarning(UserWarning):
    """Pulses outside the telemetry span were dropped, or one is on at the first or last sample."""


class PulseAtStartWarning(PulseSpanWarning):
    """A pulse is on at the first sample: only what it does after that sample is used."""


class PulsesDroppedWarning(PulseSpanWarning):
    """Pulses of the log act entirely outside the telemetry span: they are left out."""


# --------------------------------------------------------------------------------------------
# Raw tables: header + columns of strings (CSV) or objects (Parquet)


def _check_readable(path: Path, what: str) -> None:
    input_path(path, what, suffix=None)   # the rule of every file argument: exists, not a folder
    if path.stat().st_size == 0:
        raise InputError(f"{what} file is empty; expected a header line and data rows",
                         path=str(path))


def _is_parquet(path: Path) -> bool:
    return path.suffix.lower() in (".parquet", ".pq")


def _require_pyarrow(path: Path) -> None:
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise InputError("Parquet needs pyarrow, which is not installed; "
                         "pip install 'cassini-bayes[parquet]' or use CSV",
                         path=str(path)) from None


def _read_table(path: Path, what: str,
                allow_empty: bool = False) -> tuple[list[str], list[np.ndarray]]:
    """Header names (stripped) and one array of raw cells per column; rows are data rows.

    More than :data:`MAX_ROWS` data rows is an error, found before the rest is read.
    """
    _check_readable(path, what)
    name = str(path)
    if _is_parquet(path):
        _require_pyarrow(path)
        import pandas as pd
        import pyarrow.parquet as pq

        try:
            n = pq.read_metadata(path).num_rows
            if n > MAX_ROWS:
                raise _too_many_rows(n, name, what)
            df = pd.read_parquet(path)
        except InputError:
            raise
        except Exception as e:  # corrupt file: pyarrow's message, on one line
            raise InputError(f"cannot read Parquet ({e}); re-export the file", path=name) from None
        header = [str(c).strip() for c in df.columns]
        cols = [df.iloc[:, j].to_numpy() for j in range(df.shape[1])]
        if df.shape[0] == 0 and not allow_empty:
            raise InputError(f"{what} file has a header but no data rows", path=name)
        return header, cols
    try:
        with open(path, newline="", encoding="utf-8-sig") as f:
            rows = list(itertools.islice((r for r in csv.reader(f) if any(c.strip() for c in r)),
                                         MAX_ROWS + 2))
    except UnicodeDecodeError:
        raise InputError(_not_text(path, what), path=name) from None
    except csv.Error as e:
        raise InputError(f"malformed CSV ({e}); re-export the file", path=name) from None
    if not rows:
        raise InputError(f"{what} file is empty; expected a header line and data rows", path=name)
    header = [c.strip() for c in rows[0]]
    data = rows[1:]
    if len(data) > MAX_ROWS:
        raise _too_many_rows(len(data), name, what)
    if not data and not allow_empty:
        raise InputError(f"{what} file has a header but no data rows", path=name)
    for i, r in enumerate(data, start=1):
        if len(r) != len(header):
            raise InputError(f"data row {i} has {len(r)} fields but the header has "
                             f"{len(header)}; every row needs one value per column "
                             "(leave a cell empty, keep the comma)", path=name)
    cols = [np.array([r[j] for r in data], dtype=object) for j in range(len(header))]
    return header, cols


def _too_many_rows(n: int, path: str, what: str = "telemetry") -> InputError:
    return InputError(f"has more than {MAX_ROWS} data rows ({n} read so far), the limit of one "
                      f"{what} file; decimate it (e.g. keep every k-th row) or split it into "
                      "one file per slew (docs/limits.md)", path=path)


def _read_numeric_csv(path: Path, what: str, known: Sequence[str], expected: str,
                      unknown=None) -> tuple[dict[str, int], list[np.ndarray]]:
    """Header map and one float64 column per header name, parsed in chunks of rows.

    Equivalent to :func:`_read_table` then :func:`_to_float` on every column (same errors, same
    row numbers), but holds at most :data:`_CHUNK_ROWS` rows as text, so memory is ~8 bytes per
    cell; more than :data:`MAX_ROWS` data rows is an error raised while reading.
    """
    _check_readable(path, what)
    name = str(path)
    try:
        with open(path, newline="", encoding="utf-8-sig") as f:
            rows = (r for r in csv.reader(f) if any(c.strip() for c in r))
            first = next(rows, None)
            if first is None:
                raise InputError(f"{what} file is empty; expected a header line and data rows",
                                 path=name)
            header = [c.strip() for c in first]
            idx = _map_header(header, known, name, expected, unknown)
            canon = {j: c for c, j in idx.items()}
            parts: list[list[np.ndarray]] = [[] for _ in header]
            n = 0
            while True:
                chunk = list(itertools.islice(rows, _CHUNK_ROWS))
                if not chunk:
                    break
                for i, r in enumerate(chunk, start=n + 1):
                    if len(r) != len(header):
                        raise InputError(f"data row {i} has {len(r)} fields but the header has "
                                         f"{len(header)}; every row needs one value per column "
                                         "(leave a cell empty, keep the comma)", path=name)
                for j in range(len(header)):
                    cells = np.array([r[j] for r in chunk], dtype=object)
                    parts[j].append(_to_float(cells, canon[j], name, offset=n))
                n += len(chunk)
                if n > MAX_ROWS:
                    raise _too_many_rows(n, name)
    except UnicodeDecodeError:
        raise InputError(_not_text(path, what), path=name) from None
    except csv.Error as e:
        raise InputError(f"malformed CSV ({e}); re-export the file", path=name) from None
    if n == 0:
        raise InputError(f"{what} file has a header but no data rows", path=name)
    return idx, [np.concatenate(p) for p in parts]


def _not_text(path, what: str) -> str:
    """Why a file is not UTF-8 text (:func:`cassini_bayes._paths.not_utf8`)."""
    return not_utf8(path, f"{what} CSV")


def _map_header(header: list[str], known: Sequence[str], path: str,
                expected: str, unknown=None) -> dict[str, int]:
    """Canonical column name → index; unknown and duplicate names are errors (``unknown``:
    the message for an unknown name, a function of it)."""
    canon = {k.lower(): k for k in known}
    out: dict[str, int] = {}
    for j, h in enumerate(header):
        key = canon.get(h.lower())
        if key is None:
            shown = h if h else f"(blank, position {j + 1})"
            sep = next((c for c in ";\t|" if len(header) == 1 and c in h), None)
            if sep is not None:
                raise InputError(f"the header '{shown[:40]}' is one column split by "
                                 f"{sep!r}: the file format separates columns with commas; "
                                 "re-export it as comma-separated CSV", path=path)
            if unknown is not None and h:
                raise InputError(unknown(h), path=path)
            raise InputError(f"unknown column '{shown}'; expected columns are {expected}; "
                             "rename or remove it", path=path)
        if key in out:
            raise InputError(f"duplicate column '{key}' (positions {out[key] + 1} and {j + 1}); "
                             "keep one", path=path)
        out[key] = j
    return out


def _row_ref(i: int, t: np.ndarray | None) -> str:
    """'data row 17 (t = 12.5 s)' for the 0-based index i."""
    if t is not None and i < len(t) and np.isfinite(t[i]):
        return f"data row {i + 1} (t = {t[i]:.10g} s)"
    return f"data row {i + 1}"


def _is_missing(c: object) -> bool:
    """True for the missing-value markers of Parquet columns (None, NaN, pandas.NA, NaT)."""
    import pandas as pd

    try:
        return bool(pd.isna(c))
    except (TypeError, ValueError):
        return False


def _to_float(cells: np.ndarray, col: str, path: str, offset: int = 0) -> np.ndarray:
    """Cells → float64; empty cells → NaN; non-numeric text is an error naming the row
    (``offset`` rows before ``cells[0]``)."""
    if cells.dtype.kind in "iuf":  # a numeric Parquet column
        return cells.astype(float)
    try:  # fast path: every cell a number or blank
        return np.array([c.strip() or "nan" if isinstance(c, str) else c for c in cells],
                        dtype=float)
    except (TypeError, ValueError):
        pass  # find the offending cell below
    out = np.empty(len(cells), dtype=float)
    for i, c in enumerate(cells):
        if c is None or (not isinstance(c, str) and _is_missing(c)):
            out[i] = np.nan
            continue
        if isinstance(c, str):
            c = c.strip()
            if c == "":
                out[i] = np.nan
                continue
        try:
            out[i] = float(c)
        except (TypeError, ValueError):
            raise InputError(f"column '{col}', data row {offset + i + 1}: '{c}' is not a number; "
                             "fix or remove that row", path=path) from None
    return out


def _fail_nonfinite(x: np.ndarray, col: str, path: str, t: np.ndarray | None,
                    fix: str = "fill it in or drop the row") -> None:
    bad = ~np.isfinite(x)
    if np.any(bad):
        i = int(np.argmax(bad))
        what = "is empty or NaN" if np.isnan(x[i]) else "is infinite"
        raise InputError(f"column '{col}', {_row_ref(i, t)} {what}; {fix}", path=path)


def _fail_out_of_range(x: np.ndarray, col: str, limit: float, unit: str, path: str,
                       t: np.ndarray | None, why: str) -> None:
    """Error naming the first row where the finite ``|x|`` exceeds ``limit``."""
    bad = np.abs(x) > limit
    if np.any(bad):
        i = int(np.argmax(bad))
        raise InputError(f"column '{col}', {_row_ref(i, t)}: {x[i]:.6g} {unit} is beyond the "
                         f"physical limit |{col}| <= {limit:g} {unit} ({why}); fix the value, its "
                         "unit or drop the row (docs/limits.md)", path=path)


# --------------------------------------------------------------------------------------------
# Validation of arrays (shared by the readers and by in-memory telemetry)


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


# --------------------------------------------------------------------------------------------
# Telemetry files


def read_telemetry(path: str | os.PathLike, *, check_units: bool = True,
                   spacecraft=None) -> Telemetry:
    """Read and validate a telemetry file (CSV, or Parquet where pyarrow is installed).

    Parameters
    ----------
    path : the file; columns as docs/design.md §4.1 (``t`` s, ``q1..q4``, ``wx wy wz`` rad/s,
        one column per wheel in rpm, optional ``on_<thruster>`` s).
    check_units : run the rad/s-vs-rpm and rad/s-vs-°/s heuristics (see the module docstring).
    spacecraft : the :class:`~cassini_bayes.spacecraft.Spacecraft` whose wheels and thrusters
        name the columns (their names in lower case, ``on_<name>``); ``None``: Cassini's
        (``rwa1..rwa4``, ``on_Z1..on_Y4``).

    Returns
    -------
    Telemetry
        SI units (wheel rates rad/s; NaN for a wheel that is off), ``q`` renormalised and
        sign-continuous, ``on_times`` re-based to 0 at the first row (or ``None``).

    Raises
    ------
    InputError
        One line naming the file, column and/or row, and the fix.
    """
    p = as_path(path, "a telemetry file")
    name = str(path)
    wheel_names, thruster_names, whose = _names_of(spacecraft)
    rwa_cols = tuple(n.lower() for n in wheel_names)
    on_cols = _on_cols(thruster_names)
    known = _REQUIRED + rwa_cols + on_cols
    expected = (f"{' '.join(_REQUIRED)} {' '.join(rwa_cols)} (rpm) {' '.join(on_cols)} (s)"
                if on_cols else f"{' '.join(_REQUIRED)} {' '.join(rwa_cols)} (rpm)")

    def unknown(h: str) -> str:
        return _unknown_column(h, wheel_names, thruster_names, whose, spacecraft is None)

    if _is_parquet(p):
        header, cells = _read_table(p, "telemetry")
        idx = _map_header(header, known, name, expected, unknown)
        canon = {j: c for c, j in idx.items()}
        values = [_to_float(cells[j], canon[j], name) for j in range(len(header))]
    else:
        idx, values = _read_numeric_csv(p, "telemetry", known, expected, unknown)
    for c in _REQUIRED:
        if c not in idx:
            raise InputError(f"missing column '{c}'; a telemetry file needs "
                             f"{' '.join(_REQUIRED)} (and {' '.join(rwa_cols)} in rpm)",
                             path=name)
    cols = {c: values[j] for c, j in idx.items()}
    t = cols["t"]
    _fail_nonfinite(t, "t", name, None, fix="every row needs a time")
    _check_time(t, name)
    n = len(t)
    q = np.stack([cols[c] for c in _Q_COLS], axis=1)
    w = np.stack([cols[c] for c in _W_COLS], axis=1)
    rpm = np.stack([cols.get(c, np.full(n, np.nan)) for c in rwa_cols], axis=1)
    on = None
    if any(c in cols for c in on_cols):
        on = np.stack([cols.get(c, np.zeros(n)) for c in on_cols], axis=1)
        for k, c in enumerate(on_cols):
            _fail_nonfinite(on[:, k], c, name, t)
            _fail_out_of_range(on[:, k], c, TIME_ABS_MAX, "s", name, t, "317 years")
        on = on - on[0]
    tel = Telemetry(t, q, w, rpm * RPM_TO_RAD_S, wheel_names, on, name, thruster_names)
    return validate_telemetry(tel, check_units=check_units)


def check_model_names(tel: Telemetry, spacecraft) -> Telemetry:
    """``tel`` when its wheels are wheels of ``spacecraft`` (a wheel of the model without data
    is off) and its on-times, if any, belong to the model's thrusters; else an InputError naming
    both. Files read with the model pass by construction; this is for in-memory telemetry."""
    model = {n.upper() for n in spacecraft.wheel_names}
    stray = [n for n in tel.wheel_names if n.upper() not in model]
    if stray:
        raise InputError(f"wheel {stray[0]} (column {stray[0].lower()}) is not a wheel of the "
                         f"spacecraft model {spacecraft.name!r}, whose wheels are "
                         f"{', '.join(spacecraft.wheel_names)}; give the model of this "
                         "spacecraft", path=tel.source)
    if tel.on_times is not None and tuple(tel.thruster_names) != tuple(spacecraft.thruster_names):
        have = ", ".join(spacecraft.thruster_names) or "none"
        raise InputError(f"the on-time columns are of thrusters {', '.join(tel.thruster_names)}"
                         f", but the spacecraft model {spacecraft.name!r} has {have}; give the "
                         "model of this spacecraft", path=tel.source)
    return tel


def read_telemetry_many(paths: Iterable[str | os.PathLike], *, check_units: bool = True,
                        spacecraft=None) -> list[Telemetry]:
    """Read several telemetry files (e.g. one per slew; columns named by ``spacecraft`` as in
    :func:`read_telemetry`); errors name the offending file."""
    paths = list(paths)
    if not paths:
        raise InputError("no telemetry files given; pass at least one CSV")
    out, total = [], 0
    for p in paths:
        out.append(read_telemetry(p, check_units=check_units, spacecraft=spacecraft))
        total += out[-1].n
        if total > MAX_ROWS:
            raise InputError(f"the files up to this one hold {total} rows together, more than "
                             f"the limit of {MAX_ROWS} for one fit; decimate them or fit fewer "
                             "files (docs/limits.md)", path=str(p))
    return out


def _atomic_write(path: Path, force: bool, write) -> None:
    """Write with ``write(tmp)`` atomically (:func:`cassini_bayes.files.atomic_path`)."""
    if path.exists() and not force:
        raise InputError("already exists; choose another path or pass force=True to overwrite",
                         path=str(path))
    if not path.parent.exists():
        raise InputError(f"directory '{path.parent}' does not exist; create it first",
                         path=str(path))
    with atomic_path(path) as tmp:
        write(tmp)


def _cell(x: object) -> str:
    """Shortest text that reads back to the same float (Python's repr); NaN → empty cell."""
    if isinstance(x, float):
        return "" if x != x else repr(x)
    return str(x)


def _write_csv(path: Path, columns: dict[str, list]) -> None:
    names = list(columns)
    with open(path, "w", newline="", encoding="utf-8") as f:
        f.write(",".join(names) + "\n")
        for row in zip(*(columns[c] for c in names)):
            f.write(",".join(map(_cell, row)) + "\n")


def _write_frame(path: Path, columns: dict[str, object], force: bool) -> None:
    """Write columns as CSV (repr-precision floats) or Parquet, atomically."""
    if _is_parquet(path):
        _require_pyarrow(path)
        import pandas as pd

        df = pd.DataFrame(columns)
        _atomic_write(path, force, lambda tmp: df.to_parquet(tmp, index=False))
    else:
        lists = {c: (v.tolist() if isinstance(v, np.ndarray) else list(v))
                 for c, v in columns.items()}
        _atomic_write(path, force, lambda tmp: _write_csv(tmp, lists))


def write_telemetry(path: str | os.PathLike, tel: Telemetry, *, force: bool = False) -> None:
    """Write a telemetry file in the §4 format (wheel rates in rpm), atomically.

    Floats are written with Python's shortest round-trip ``repr``, so :func:`read_telemetry`
    returns the same ``t``, ``q``, ``omega`` bit for bit and wheel rates to within one rounding
    of the rpm ↔ rad/s conversion. The data are written as given (sign flips of ``q`` included);
    a wheel that is off (all NaN) is an empty column. ``.parquet`` paths are written as Parquet
    (needs pyarrow).

    Raises
    ------
    InputError
        The file exists and ``force`` is false; or the telemetry fails :func:`validate_telemetry`.
    """
    p = Path(path)
    validate_telemetry(tel, check_units=False)  # errors only: the file gets the data as given
    q = np.asarray(tel.q, dtype=float)
    omega = np.asarray(tel.omega, dtype=float)
    rates = np.asarray(tel.wheel_rates, dtype=float)
    cols: dict[str, object] = {"t": np.asarray(tel.t, dtype=float)}
    for j, c in enumerate(_Q_COLS):
        cols[c] = q[:, j]
    for j, c in enumerate(_W_COLS):
        cols[c] = omega[:, j]
    for j, name in enumerate(tel.wheel_names):
        cols[name.lower()] = rates[:, j] / RPM_TO_RAD_S
    if tel.on_times is not None:
        on = np.asarray(tel.on_times, dtype=float)
        for k, c in enumerate(_on_cols(tel.thruster_names)):
            cols[c] = on[:, k]
    _write_frame(p, cols, force)


# --------------------------------------------------------------------------------------------
# Pulse logs


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


def read_pulses(path: str | os.PathLike, *, spacecraft=None) -> PulseLog:
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


# --------------------------------------------------------------------------------------------
# Noise

_MAD_TO_SD = 1.4826
RATE_NOISE_FLOORS = (1e-9, 1e-7)
"""rad/s: body-rate and wheel-rate noise levels are floored here, so that noise-free synthetic
data keep finite noise priors and thresholds (the noise priors and the input checks)."""


def white_noise_sd(x: np.ndarray, *, differenced: bool = False) -> float:
    """Robust sd of white noise on a smooth signal ``x`` (n, ...) sampled along axis 0: the MAD
    of its second differences (all components pooled, non-finite values left out) ÷ √6.

    The one white-noise estimator of the package (noise priors, input checks). For white noise
    of sd ``σ`` second differences have sd ``√6 σ``; the median absolute deviation (× 1.4826,
    the normal's MAD-to-sd factor) ignores the few samples where the signal itself bends (a
    pulse, a wheel ramp, the slew profile).

    ``differenced``: ``x`` already holds the signal's first differences (e.g. attitude
    increments ``rotvec(q_{t+1} q_t⁻¹)``), so one more difference is taken. 0 when the signal
    has fewer than four samples or no finite difference.
    """
    order = 1 if differenced else 2
    if x.shape[0] < 2 + order or x.size == 0:
        return 0.0
    d = np.diff(x, n=order, axis=0).ravel()
    d = d[np.isfinite(d)]
    if d.size == 0:
        return 0.0
    return float(_MAD_TO_SD * np.median(np.abs(d - np.median(d))) / np.sqrt(6.0))
