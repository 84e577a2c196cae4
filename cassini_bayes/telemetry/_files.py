"""Telemetry files: reading (CSV, Parquet), model column names, writing atomically.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from cassini_bayes.errors import InputError, as_path
from cassini_bayes.files import atomic_path
from cassini_bayes.telemetry import limits
from cassini_bayes.telemetry._layout import (
    _Q_COLS,
    _REQUIRED,
    _W_COLS,
    _names_of,
    _on_cols,
    _unknown_column,
)
from cassini_bayes.telemetry._tables import (
    _fail_nonfinite,
    _fail_out_of_range,
    _is_parquet,
    _map_header,
    _read_numeric_csv,
    _read_table,
    _require_pyarrow,
    _to_float,
)
from cassini_bayes.telemetry._types import Telemetry
from cassini_bayes.telemetry._validate import _check_time, validate_telemetry
from cassini_bayes.telemetry.limits import TIME_ABS_MAX
from cassini_bayes.units import RPM_TO_RAD_S

if TYPE_CHECKING:
    from cassini_bayes.spacecraft import Spacecraft


def read_telemetry(path: str | os.PathLike, *, check_units: bool = True,
                   spacecraft: Spacecraft | None = None) -> Telemetry:
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
                        spacecraft: Spacecraft | None = None) -> list[Telemetry]:
    """Read several telemetry files (e.g. one per slew; columns named by ``spacecraft`` as in
    :func:`read_telemetry`); errors name the offending file."""
    paths = list(paths)
    if not paths:
        raise InputError("no telemetry files given; pass at least one CSV")
    out, total = [], 0
    for p in paths:
        out.append(read_telemetry(p, check_units=check_units, spacecraft=spacecraft))
        total += out[-1].n
        if total > limits.MAX_ROWS:
            raise InputError(f"the files up to this one hold {total} rows together, more than "
                             f"the limit of {limits.MAX_ROWS} for one fit; decimate them or fit "
                             "fewer files (docs/limits.md)", path=str(p))
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
        return "" if math.isnan(x) else repr(x)
    return str(x)


def _write_csv(path: Path, columns: dict[str, list]) -> None:
    names = list(columns)
    with open(path, "w", newline="", encoding="utf-8") as f:
        f.write(",".join(names) + "\n")
        f.writelines(",".join(map(_cell, row)) + "\n" for row in zip(*(columns[c] for c in names)))


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
