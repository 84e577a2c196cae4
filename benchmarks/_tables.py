"""The registry of benchmarks/docs_tables.py's table kinds, and the readers and cell formats
the kinds share."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path


class Records(tuple):
    """One marker argument: its records' paths (``A+B``: several, pooled) and the seeds it
    selects (``PATH@0-19``; None: every seed)."""

    seeds: range | None = None


Kind = Callable[[list[Records]], str]
KINDS: dict[str, Kind] = {}


def kind(name: str) -> Callable[[Kind], Kind]:
    """Register a table generator under ``name`` (the marker's ``KIND``)."""
    def register(fn: Kind) -> Kind:
        KINDS[name] = fn
        return fn
    return register


def read_json(path: Path) -> dict:
    return json.loads(path.read_text(encoding="utf-8"))


def read_jsonl(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines() if line]


def share_cell(x: float) -> str:
    """A coverage in a per-entry list: 1.0, else two decimals without the leading zero."""
    return "1.0" if x == 1.0 else f"{x:.2f}".removeprefix("0")


def coverage_cell(k: int, n: int) -> str:
    """``k/n = p ± sd``: the binomial sd at p, at the nominal 0.9 where p is 0 or 1."""
    p = k / n
    return f"{k}/{n} = {p:.3f} ± {(p * (1 - p) / n if 0 < p < 1 else 0.09 / n) ** 0.5:.3f}"
