"""The registry of experiment kinds: one library function registered under a name::

    @register("impulse_ratio", defaults={"spacecraft": "fsds", "grid_points": 51},
              quick={"grid_points": 9})
    def impulse_ratio(key, settings, ctx) -> ExperimentOutput: ...
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import jax

from cassini_bayes.experiments._results import ExperimentContext, ExperimentOutput

RunFn = Callable[[jax.Array, Mapping[str, Any], ExperimentContext], ExperimentOutput]


@dataclass(frozen=True)
class ExperimentKind:
    """A registered experiment kind.

    Attributes
    ----------
    name : the ``kind`` experiment files name.
    run : ``run(key, settings, ctx) -> ExperimentOutput``.
    defaults : every setting with its default; the default's type is the setting's type.
    quick : overrides applied under ``--quick``.
    choices : allowed values of string settings.
    order : position in ``reproduce`` (smaller first).
    description : one line for listings.
    """

    name: str
    run: RunFn
    defaults: Mapping[str, Any]
    quick: Mapping[str, Any] = field(default_factory=dict)
    choices: Mapping[str, tuple] = field(default_factory=dict)
    order: int = 100
    description: str = ""


_KINDS: dict[str, ExperimentKind] = {}
_DISCOVERED = False


def register(name: str, *, defaults: Mapping[str, Any], quick: Mapping[str, Any] | None = None,
             choices: Mapping[str, tuple] | None = None, order: int = 100,
             description: str = "") -> Callable[[RunFn], RunFn]:
    """Decorator registering ``run(key, settings, ctx)`` as the experiment kind ``name``."""
    quick = dict(quick or {})
    unknown = set(quick) - set(defaults)
    if unknown:
        raise ValueError(f"quick settings {sorted(unknown)} of kind {name!r} have no default")

    def deco(fn: RunFn) -> RunFn:
        _KINDS[name] = ExperimentKind(name, fn, dict(defaults), quick, dict(choices or {}), order,
                                      description or (fn.__doc__ or "").strip().split("\n")[0])
        return fn

    return deco


def registered_kinds() -> dict[str, ExperimentKind]:
    """All registered kinds, importing every module of :mod:`cassini_bayes.experiments` once."""
    global _DISCOVERED
    if not _DISCOVERED:
        import cassini_bayes.experiments as pkg

        for info in pkgutil.iter_modules(pkg.__path__):
            if not info.name.startswith("_"):
                importlib.import_module(f"{pkg.__name__}.{info.name}")
        _DISCOVERED = True
    return dict(_KINDS)
