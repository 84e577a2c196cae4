"""Which command wrote a run directory, read from its ``summary.json`` (and ``config.toml``; no
heavy imports: the inference layer checks an ``--inertia-posterior`` with it)."""

from __future__ import annotations

import json
import os
import tomllib
from pathlib import Path

__all__ = ["run_kind", "run_command"]


def _field(path: str | os.PathLike, name: str, key: str) -> str | None:
    """The string ``key`` of the run directory's file ``name`` (JSON or TOML), or None."""
    parse = json.loads if name.endswith(".json") else tomllib.loads
    try:
        value = parse((Path(path) / name).read_text(encoding="utf-8")).get(key)
    except (OSError, UnicodeDecodeError, ValueError, AttributeError):
        return None
    return value if isinstance(value, str) else None


def run_kind(path: str | os.PathLike) -> str | None:
    """The ``kind`` a fit run directory's ``summary.json`` records (``"inertia"``, ``"thrust"``,
    ``"rwa4"``), or None when there is none to read."""
    return _field(path, "summary.json", "kind")


def run_command(path: str | os.PathLike) -> str | None:
    """The command that wrote a run directory (``"fit inertia"``, ``"budget"``, ``"fit health"``
    …): its ``summary.json``'s ``command``, else its ``config.toml``'s; None when neither says."""
    return _field(path, "summary.json", "command") or _field(path, "config.toml", "command")
