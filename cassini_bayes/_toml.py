"""Reading the project's TOML files with one-line errors."""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

from cassini_bayes.errors import InputError


def read_toml(path: Path, what: str, where: str) -> dict[str, Any]:
    """Parse ``path``; a missing file or bad TOML is an :class:`InputError` naming it.

    ``what`` names the kind of file ("spacecraft model"), ``where`` the folder of shipped ones.
    """
    if not path.exists():
        raise InputError(f"{what} not found: {path} (give a path to a .toml file or a name "
                         f"from {where})")
    try:
        return tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as e:
        raise InputError(f"not valid TOML: {e}", path=str(path)) from None
