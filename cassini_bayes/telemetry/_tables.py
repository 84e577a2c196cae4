"""Raw tables: a CSV's or Parquet file's header and columns, parsed to floats with one-line
errors naming the file, column and data row.
"""

from __future__ import annotations

import csv
import itertools
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from cassini_bayes._paths import input_path, not_utf8
from cassini_bayes.errors import InputError
from cassini_bayes.telemetry import limits


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
            if n > limits.MAX_ROWS:
                raise _too_many_rows(n, name, what)
            df = pd.read_parquet(path)
        except InputError:
            raise
        except Exception as e:  # noqa: BLE001  (corrupt file: pyarrow's message, on one line)
            raise InputError(f"cannot read Parquet ({e}); re-export the file", path=name) from None
        header = [str(c).strip() for c in df.columns]
        cols = [df.iloc[:, j].to_numpy() for j in range(df.shape[1])]
        if df.shape[0] == 0 and not allow_empty:
            raise InputError(f"{what} file has a header but no data rows", path=name)
        return header, cols
    try:
        with open(path, newline="", encoding="utf-8-sig") as f:
            rows = list(itertools.islice((r for r in csv.reader(f) if any(c.strip() for c in r)),
                                         limits.MAX_ROWS + 2))
    except UnicodeDecodeError:
        raise InputError(_not_text(path, what), path=name) from None
    except csv.Error as e:
        raise InputError(f"malformed CSV ({e}); re-export the file", path=name) from None
    if not rows:
        raise InputError(f"{what} file is empty; expected a header line and data rows", path=name)
    header = [c.strip() for c in rows[0]]
    data = rows[1:]
    if len(data) > limits.MAX_ROWS:
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
    return InputError(f"has more than {limits.MAX_ROWS} data rows ({n} read so far), the "
                      f"limit of one {what} file; decimate it (e.g. keep every k-th row) or split "
                      "it into one file per slew (docs/limits.md)", path=path)


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
                chunk = list(itertools.islice(rows, limits._CHUNK_ROWS))
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
                if n > limits.MAX_ROWS:
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
