"""Reading the project's TOML files with one-line errors."""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from cassini_bayes._paths import not_utf8
from cassini_bayes.errors import InputError, with_article

MAX_TOML_BYTES = 1_000_000
"""Largest accepted model or scenario file (1 MB; the shipped ones are under 10 kB)."""
UNIT_TOL = 1e-6
"""How far from 1 the norm of a unit vector in a file may be."""


def read_toml(path: Path, what: str, where: str) -> dict[str, Any]:
    """Parse ``path``; a missing, unreadable or oversized file or bad TOML is an
    :class:`InputError` naming it.

    ``what`` names the kind of file ("spacecraft model"), ``where`` the folder of shipped ones.
    """
    if not path.exists():
        raise InputError(f"{what} not found: {path} (give a path to a .toml file or a name "
                         f"from {where})")
    if not path.is_file():
        raise InputError(f"is not a file, expected {with_article(what)} .toml file", path=str(path))
    if path.stat().st_size > MAX_TOML_BYTES:
        raise InputError(f"is {path.stat().st_size} bytes, more than {with_article(what)} file "
                         f"can be ({MAX_TOML_BYTES} bytes); check the path", path=str(path))
    try:
        text = path.read_text(encoding="utf-8-sig")   # a byte-order mark is dropped, as in CSV
    except UnicodeDecodeError:
        raise InputError(not_utf8(path, f"{what} TOML"), path=str(path)) from None
    except OSError as e:
        raise InputError(f"cannot be read ({e.strerror}); check the path and its permissions",
                         path=str(path)) from None
    return parse_toml(text, str(path))


def parse_toml(text: str, source: str) -> dict[str, Any]:
    """``text`` parsed as TOML; bad TOML is a one-line :class:`InputError` naming ``source``
    (the file the text came from)."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise InputError(f"not valid TOML: {e}", path=source) from None


def toml_value(raw: str) -> Any:
    """``raw`` read as one TOML value (``300``, ``1.2``, ``false``, ``"cone"``), else the text
    itself (stripped): what a ``KEY=VALUE`` option on the command line means."""
    try:
        return tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        return raw.strip()


def is_numbers(v: Any) -> bool:
    """True for a flat list, tuple or 1-D array of real numbers (not booleans, not strings): what
    a TOML array of numbers, or the same built in code, may be."""
    if isinstance(v, np.ndarray):
        return v.ndim == 1 and v.dtype.kind in "iuf"
    return isinstance(v, (list, tuple)) and all(
        isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool)
        for x in v)


def check_keys(table: dict[str, Any], allowed: set[str], where: str, src: str,
               note: str = "") -> None:
    """Raise naming the first key of ``table`` (prefixed ``where``, followed by ``note``) not in
    ``allowed``, and the allowed ones."""
    for key in table:
        if key not in allowed:
            raise InputError(f"unknown key '{where}{key}'{note}; allowed: "
                             f"{', '.join(sorted(allowed))}", path=src)


class TomlTable:
    """Typed, key-checked access to one TOML table; every error names the file and the key.

    ``where`` is the table's dotted prefix (``"truth."``, ``"slew[2]."``, ``""`` at the top);
    ``allowed`` its keys (any other is an error); ``number_max`` the largest magnitude a number
    may have unless a reader gives its own bound (sub-tables inherit it).
    """

    def __init__(self, table: Any, where: str, src: str, allowed: set[str], *,
                 number_max: float = np.inf, note: str = ""):
        if not isinstance(table, dict):
            raise InputError(f"'{where.rstrip('.')}' must be a table", path=src)
        self.table, self.where, self.src = table, where, src
        self.number_max = number_max
        check_keys(table, allowed, where, src, note)

    def err(self, key: str, msg: str) -> InputError:
        """An :class:`InputError` ``'table.key' msg`` naming the file."""
        return InputError(f"'{self.where}{key}' {msg}", path=self.src)

    def has(self, key: str) -> bool:
        return key in self.table

    def _missing(self, key: str) -> InputError:
        return InputError(f"missing required key '{self.where}{key}'", path=self.src)

    def _finite(self, key: str) -> float:
        v = self.table[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
            raise self.err(key, f"must be a finite number, got {v!r}")
        return float(v)

    def num(self, key: str, default: float | None = None, *, positive: bool = False,
            nonneg: bool = False, hi: float | None = None) -> float:
        """A finite number of magnitude at most ``hi`` (else ``number_max``); ``default`` when
        the key is absent (``None``: required)."""
        if key not in self.table:
            if default is None:
                raise self._missing(key)
            return float(default)
        v = self._finite(key)
        bound = self.number_max if hi is None else hi
        if abs(v) > bound:
            raise self.err(key, f"= {v:g} is beyond the physical limit {bound:g} in magnitude; "
                                "check the value and its unit (docs/limits.md)")
        if positive and v <= 0:
            raise self.err(key, f"must be positive, got {v}")
        if nonneg and v < 0:
            raise self.err(key, f"must not be negative, got {v}")
        return v

    def in_range(self, key: str, default: float | None = None, *, lo: float,
                 hi: float | None = None, unit: str = "", open_lo: bool = True) -> float:
        """A finite number in the physical range ``(lo, hi]`` (``[lo, hi]`` with
        ``open_lo=False``; no upper end when ``hi`` is ``None``) of ``unit``."""
        if key not in self.table:
            if default is None:
                raise self._missing(key)
            return float(default)
        v = self._finite(key)
        below = v <= lo if open_lo else v < lo
        if below or (hi is not None and v > hi):
            rng = f"{'(' if open_lo else '['}{lo:g}, {hi:g}]" if hi is not None else f"> {lo:g}"
            sign = " (it must be positive)" if lo == 0 and v <= 0 else ""
            raise self.err(key, f"= {v:g} {unit} is outside the physical range {rng} {unit}{sign}; "
                                "check the value and its unit (docs/limits.md)")
        return v

    def vec(self, key: str, n: int = 3, default: Any = None, *, unit: bool = False,
            nonneg: bool = False, hi: float | None = None) -> np.ndarray:
        """A list of ``n`` finite numbers, each of magnitude at most ``hi`` (else
        ``number_max``); ``unit``: of norm 1 within 1e-6."""
        if key not in self.table:
            if default is None:
                raise self._missing(key)
            return np.asarray(default, float)
        v = self.table[key]
        if not is_numbers(v):
            raise self.err(key, f"must be a list of {n} numbers, got {v!r}")
        a = np.asarray(v, float)
        if a.shape != (n,) or not np.all(np.isfinite(a)):
            raise self.err(key, f"must be a list of {n} finite numbers, got {v!r}")
        bound = self.number_max if hi is None else hi
        if np.any(np.abs(a) > bound):
            raise self.err(key, f"has an entry beyond the physical limit {bound:g} in magnitude, "
                                f"got {v!r}; check the values and their unit (docs/limits.md)")
        if unit and abs(np.linalg.norm(a) - 1.0) > UNIT_TOL:
            raise self.err(key, f"must be a unit vector (|v| = {np.linalg.norm(a):.6f}); "
                                "normalise it")
        if nonneg and np.any(a < 0):
            raise self.err(key, f"must not have negative entries, got {v!r}")
        return a

    def string(self, key: str, default: str | None = None) -> str:
        """A string; ``default`` when the key is absent (``None``: required)."""
        if key not in self.table:
            if default is None:
                raise self._missing(key)
            return default
        v = self.table[key]
        if not isinstance(v, str):
            raise self.err(key, f"must be a string (in quotes), got {v!r}")
        return v

    def flag(self, key: str, default: bool) -> bool:
        """``true`` or ``false``; ``default`` when the key is absent."""
        v = self.table.get(key, default)
        if not isinstance(v, bool):
            raise self.err(key, f"must be true or false, got {v!r}")
        return v

    def interval(self, key: str, default: tuple[float, float], hi: float,
                 unit: str = "s") -> tuple[float, float]:
        """``[low, high]`` with ``0 < low < high <= hi`` (``unit``)."""
        v = self.table.get(key, list(default))
        if not (is_numbers(v) and len(v) == 2) or not 0 < v[0] < v[1] <= hi:
            raise self.err(key, f"must be [low, high] with 0 < low < high <= {hi:g} ({unit}), "
                                f"got {v!r}")
        return float(v[0]), float(v[1])

    def sub(self, key: str, allowed: set[str], required: bool = False,
            note: str = "") -> TomlTable:
        """The sub-table ``[where.key]`` (empty when absent and not ``required``); ``note``
        follows the key in the message of an unknown one."""
        name = f"{self.where}{key}"
        if key not in self.table:
            if required:
                raise InputError(f"missing required section [{name}]", path=self.src)
            return TomlTable({}, name + ".", self.src, allowed, number_max=self.number_max)
        v = self.table[key]
        if not isinstance(v, dict):
            raise self.err(key, f"must be a table [{name}], got {v!r}; write it as a [{name}] "
                                "section")
        return TomlTable(v, name + ".", self.src, allowed, number_max=self.number_max, note=note)

    def items(self, key: str, allowed: set[str], per: str = "entry") -> list[TomlTable]:
        """The tables of the array ``[[where.key]]``, one per ``per`` (none when absent)."""
        v = self.table.get(key, [])
        if not isinstance(v, list) or not all(isinstance(x, dict) for x in v):
            raise self.err(key, f"must be an array of tables, one [[{self.where}{key}]] section "
                                f"per {per}")
        return [TomlTable(x, f"{self.where}{key}[{i}].", self.src, allowed,
                          number_max=self.number_max) for i, x in enumerate(v)]
