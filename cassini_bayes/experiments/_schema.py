"""Experiment files (``experiments/NAME.toml``): a kind and overrides of some of its settings::

    kind = "impulse_ratio"
    title = "Impulse ratio R of the thruster pulses (Feldman & Lee §V)"
    [settings]
    grid_points = 61

Every key is checked: an unknown top-level key, an unknown setting or a setting of the wrong type is
an :class:`~cassini_bayes.errors.InputError` naming the file and the key. ``--quick`` applies the
kind's ``quick`` overrides on top of the file (small sizes for tests).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cassini_bayes._paths import EXPERIMENTS_DIR, input_path
from cassini_bayes._toml import TomlTable, check_keys, read_toml
from cassini_bayes.errors import InputError
from cassini_bayes.experiments._registry import ExperimentKind, registered_kinds

_TOP_KEYS = {"kind", "title", "description", "settings", "run"}
_RUN_KEYS = {"name", "seed", "quick", "version"}


@dataclass(frozen=True)
class Experiment:
    """A validated experiment file.

    Attributes
    ----------
    name : the file's stem (the run's sub-directory under ``reproduce``).
    kind : the registered kind.
    title, description : for the report.
    settings : the file's settings merged over the kind's defaults (before ``--quick``).
    source : the file path (for messages).
    seed : the ``[run] seed`` of a re-run ``config.toml``, else ``None``.
    """

    name: str
    kind: ExperimentKind
    title: str
    description: str
    settings: Mapping[str, Any]
    source: str
    seed: int | None = None

    def resolved_settings(self, quick: bool = False) -> dict[str, Any]:
        """Settings to run with: ``--quick`` overrides applied on top of the file's."""
        s = dict(self.settings)
        if quick:
            s.update(self.kind.quick)
        return s


def _type_name(v: Any) -> str:
    return {bool: "true/false", int: "an integer", float: "a number", str: "a string",
            list: "a list", dict: "a table"}.get(type(v), type(v).__name__)


def _check_value(key: str, value: Any, default: Any, choices: tuple | None, src: str) -> Any:
    where = f"settings.{key}"
    if isinstance(default, bool):
        ok = isinstance(value, bool)
    elif isinstance(default, int):
        ok = isinstance(value, int) and not isinstance(value, bool)
    elif isinstance(default, float):
        ok = isinstance(value, (int, float)) and not isinstance(value, bool)
        if ok:
            value = float(value)
            if not math.isfinite(value):
                raise InputError(f"'{where}' must be finite, got {value}", path=src)
    elif isinstance(default, str):
        ok = isinstance(value, str)
    elif isinstance(default, list):
        ok = isinstance(value, list)
        if ok and default:
            proto = default[0]
            value = [_check_value(f"{key}[{i}]", v, proto, None, src) for i, v in enumerate(value)]
            if len(default) and len(value) == 0:
                raise InputError(f"'{where}' must not be empty", path=src)
    elif isinstance(default, dict):  # a sub-table: known keys only, defaults filled in
        ok = isinstance(value, dict)
        if ok:
            check_keys(value, set(default), f"{where}.", src)
            value = {k: _check_value(f"{key}.{k}", value[k], d, None, src) if k in value else d
                     for k, d in default.items()}
    else:  # pragma: no cover - kinds only use TOML types
        ok = True
    if not ok:
        raise InputError(f"'{where}' must be {_type_name(default)}, got {value!r}", path=src)
    if choices is not None and value not in choices:
        raise InputError(f"'{where}' must be one of {', '.join(map(repr, choices))}, got {value!r}",
                         path=src)
    return value


def experiment_from_dict(d: Mapping[str, Any], src: str = "<experiment>",
                         name: str | None = None) -> Experiment:
    """Validate an experiment table (the TOML schema as a dict) into an :class:`Experiment`."""
    if "command" in d and "kind" not in d:
        raise InputError(f"the config.toml of a '{d['command']}' run, not an experiment file; "
                         "re-run a fit with its own command and options (config.toml records "
                         "them), or give an experiments/*.toml file", path=src)
    top = TomlTable(dict(d), "", src, _TOP_KEYS)
    kinds = registered_kinds()
    if "kind" not in d:
        raise InputError(f"missing required key 'kind'; one of: {', '.join(sorted(kinds))}",
                         path=src)
    kind_name = d["kind"]
    if kind_name not in kinds:
        raise InputError(f"unknown experiment kind {kind_name!r}; registered kinds: "
                         f"{', '.join(sorted(kinds))}", path=src)
    kind = kinds[kind_name]
    settings_in = top.sub("settings", set(kind.defaults), note=f" for kind {kind_name!r}").table
    settings = dict(kind.defaults)
    for key, value in settings_in.items():
        settings[key] = _check_value(key, value, kind.defaults[key], kind.choices.get(key), src)
    run = top.sub("run", _RUN_KEYS)
    seed = run.table.get("seed")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int) or seed < 0):
        raise run.err("seed", f"must be a non-negative integer, got {seed!r}")
    title = top.string("title", kind.description or kind_name)
    description = top.string("description", "")
    return Experiment(name=run.string("name", "") or name or Path(src).stem, kind=kind,
                      title=title, description=description, settings=settings, source=src,
                      seed=seed)


def load_experiment(path: str | os.PathLike) -> Experiment:
    """Load and validate ``experiments/NAME.toml`` (``InputError`` naming the file and key)."""
    p = Path(path)
    if p.is_dir() and (p / "config.toml").exists():  # re-run a run directory
        p = p / "config.toml"
    else:   # a file, or a shipped experiment's bare name
        p = input_path(path, "experiment", EXPERIMENTS_DIR)
    d = read_toml(p, "experiment", "experiments/")
    name = p.parent.name if p.name == "config.toml" else p.stem
    return experiment_from_dict(d, str(p), name=name)
