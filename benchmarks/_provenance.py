"""Provenance of a benchmark's records: a manifest beside them (command, commit, versions,
machine, options, dates), and a refusal to append records made with other options.

The one manifest writer of the benchmarks: every benchmark that writes records calls
:func:`start` before its first record, so each record under ``docs/`` can be traced to the run
that made it (``tests/test_evidence.py`` checks that each has a manifest)."""

from __future__ import annotations

import datetime as _dt
import importlib.util
import json
import os
import platform
import subprocess
import sys
from importlib import metadata
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _commit() -> str | None:
    try:
        out = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True,
                             text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain",
                                "--untracked-files=no"], capture_output=True, text=True,
                               check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None
    return out + ("+uncommitted" if dirty else "")


def cpu_name() -> str:
    """The CPU's model name (/proc/cpuinfo; the platform's processor string elsewhere)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def manifest_path(records: Path) -> Path:
    """``records.manifest.json`` beside a records file; ``manifest.json`` inside a run directory
    (a folder whose files are one run's records)."""
    if records.is_dir():
        return records / "manifest.json"
    return records.with_name(records.name + ".manifest.json")


def start(records: Path, options: dict, argv: list[str] | None = None, *,
          replace: bool = False) -> dict:
    """Write (or, on a resumed run, extend) the manifest of ``records``; exit with a one-line
    message if the records were made with other ``options``.

    ``replace``: the caller rewrites the records whole, so the manifest starts afresh (one run)
    rather than extending the old one. ``options`` are stored as JSON (paths as strings)."""
    records = Path(records)
    options = json.loads(json.dumps(options, default=str))
    path = manifest_path(records)
    now = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
    run = {"command": " ".join([Path(sys.argv[0]).name, *(sys.argv[1:] if argv is None
                                                          else argv)]),
           "commit": _commit(), "started": now,
           "versions": {p: metadata.version(p) for p in ("cassini-bayes", "jax", "numpyro")},
           "package": getattr(importlib.util.find_spec("cassini_bayes"), "origin", None),
           "machine": f"{cpu_name()}, {os.cpu_count()} cores", "load_average": os.getloadavg()[0]}
    if path.exists() and not replace:
        man = json.loads(path.read_text())
        if man.get("options") != options:
            sys.exit(f"{records}: made with other options ({path}); use another --out")
        man["runs"].append(run)
    else:
        if not replace and records.is_file() and records.stat().st_size:
            sys.exit(f"{records}: records without a manifest; use another --out")
        man = {"records": "." if records.is_dir() else records.name, "options": options,
               "runs": [run]}
    write_json(path, man)
    return man


def write_json(path: Path, obj) -> None:
    """``obj`` as indented JSON at ``path``, atomically (a temporary beside it, then renamed)."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(obj, indent=1) + "\n")
    os.replace(tmp, path)
