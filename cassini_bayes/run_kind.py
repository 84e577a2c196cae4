"""Which fit wrote a run directory, read from its ``summary.json`` (no heavy imports: the
inference layer checks an ``--inertia-posterior`` with it)."""

from __future__ import annotations

import json
import os
from pathlib import Path

__all__ = ["run_kind"]


def run_kind(path: str | os.PathLike) -> str | None:
    """The ``kind`` a fit run directory's ``summary.json`` records (``"inertia"``, ``"thrust"``,
    ``"rwa4"``), or None when there is none to read."""
    try:
        kind = json.loads((Path(path) / "summary.json").read_text(encoding="utf-8")).get("kind")
    except (OSError, ValueError, AttributeError):
        return None
    return kind if isinstance(kind, str) else None
