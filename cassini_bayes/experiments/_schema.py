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
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cassini_bayes._paths import EXPERIMENTS_DIR, input_path, not_utf8
from cassini_bayes.errors import InputError
from cassini_bayes.experiments._registry import ExperimentKind, registered_kinds

_TOP_KEYS = ("kind", "title", "description", "settings", "run")
_RUN_KEYS = ("name", "seed", "quick", "version")


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
            for k in value:
                if k not in default:
                    raise InputError(f"unknown key '{where}.{k}'; allowed: "
                                     f"{', '.join(sorted(default))}", path=src)
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
    for key in d:
        if key not in _TOP_KEYS:
            raise InputError(f"unknown key '{key}'; allowed: {', '.join(_TOP_KEYS)}", path=src)
    kinds = registered_kinds()
    if "kind" not in d:
        raise InputError(f"missing required key 'kind'; one of: {', '.join(sorted(kinds))}",
                         path=src)
    kind_name = d["kind"]
    if kind_name not in kinds:
        raise InputError(f"unknown experiment kind {kind_name!r}; registered kinds: "
                         f"{', '.join(sorted(kinds))}", path=src)
    kind = kinds[kind_name]
    settings_in = d.get("settings", {})
    if not isinstance(settings_in, dict):
        raise InputError("'settings' must be a table ([settings])", path=src)
    settings = dict(kind.defaults)
    for key, value in settings_in.items():
        if key not in kind.defaults:
            raise InputError(f"unknown key 'settings.{key}' for kind {kind_name!r}; allowed: "
                             f"{', '.join(sorted(kind.defaults))}", path=src)
        settings[key] = _check_value(key, value, kind.defaults[key], kind.choices.get(key), src)
    run = d.get("run", {})
    if not isinstance(run, dict):
        raise InputError("'run' must be a table ([run])", path=src)
    for key in run:
        if key not in _RUN_KEYS:
            raise InputError(f"unknown key 'run.{key}'; allowed: {', '.join(_RUN_KEYS)}", path=src)
    seed = run.get("seed")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int) or seed < 0):
        raise InputError(f"'run.seed' must be a non-negative integer, got {seed!r}", path=src)
    for key in ("title", "description"):
        if key in d and not isinstance(d[key], str):
            raise InputError(f"'{key}' must be a string", path=src)
    if "name" in run and not isinstance(run["name"], str):
        raise InputError("'run.name' must be a string", path=src)
    return Experiment(name=run.get("name") or name or Path(src).stem, kind=kind,
                      title=d.get("title", kind.description or kind_name),
                      description=d.get("description", ""), settings=settings, source=src,
                      seed=seed)


def load_experiment(path: str | os.PathLike) -> Experiment:
    """Load and validate ``experiments/NAME.toml`` (``InputError`` naming the file and key)."""
    p = Path(path)
    if p.is_dir() and (p / "config.toml").exists():  # re-run a run directory
        p = p / "config.toml"
    else:   # a file, or a shipped experiment's bare name
        p = input_path(path, "experiment", EXPERIMENTS_DIR)
    try:
        d = tomllib.loads(p.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as e:
        raise InputError(f"not valid TOML: {e}", path=str(p)) from None
    except UnicodeDecodeError:
        raise InputError(not_utf8(p, "experiment TOML"), path=str(p)) from None
    name = p.parent.name if p.name == "config.toml" else p.stem
    return experiment_from_dict(d, str(p), name=name)
