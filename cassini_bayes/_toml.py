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
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise InputError(f"not valid TOML: {e}", path=str(path)) from None


def is_numbers(v: Any) -> bool:
    """True for a flat list, tuple or 1-D array of real numbers (not booleans, not strings): what
    a TOML array of numbers, or the same built in code, may be."""
    if isinstance(v, np.ndarray):
        return v.ndim == 1 and v.dtype.kind in "iuf"
    return isinstance(v, (list, tuple)) and all(
        isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool)
        for x in v)
