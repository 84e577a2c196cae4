"""What the planners share: their inputs (model file, limits, comparison), their argument
checks, their warnings and the run directory they write."""

from __future__ import annotations

import os
import sys
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from cassini_bayes import __version__
from cassini_bayes.errors import InputError, arg

if TYPE_CHECKING:
    from cassini_bayes.simulate import Scenario

PathArg = str | os.PathLike
"""A file path or a shipped file's name."""

__all__ = ["PathArg", "model_reference", "spacecraft_path", "write_dir", "PlannedRun",
           "PlannerInputs", "planner_inputs", "load_baseline", "check_positive", "counts_of",
           "progress_printer", "limits_exceeded", "emit_warnings", "plan_header",
           "inputs_config"]


def model_reference(path: Path) -> str:
    """How a written scenario names a model file: ``models/NAME.toml`` for a shipped one (found
    from any directory), else its absolute path."""
    from cassini_bayes._paths import DATA_DIR

    p = path.resolve()
    try:
        return p.relative_to(Path(DATA_DIR).resolve()).as_posix()
    except ValueError:
        return str(p)


def spacecraft_path(spacecraft: Any) -> Path:
    """The model file a plan names: a path or a shipped model's name (not a loaded model)."""
    from cassini_bayes._paths import model_path
    from cassini_bayes.spacecraft import Spacecraft

    if isinstance(spacecraft, Spacecraft) or not isinstance(spacecraft, (str, os.PathLike)) \
            or not str(spacecraft):
        raise InputError(f"{arg('spacecraft')}: a plan is written as a scenario that names its "
                         "model file: give a model .toml path or a shipped model's name "
                         "(e.g. 'cassini_post_prm')")
    return model_path(spacecraft)


def write_dir(out: PathArg, *, force: bool, files: Mapping[str, str | bytes], summary: dict,
               config: dict, inputs: Sequence[Any] = ()) -> Path:
    """Write a planning run directory atomically: the text ``files`` and summary/config."""
    from cassini_bayes.rundir import RunDir, write_config, write_summary

    with RunDir(out, force=force, inputs=inputs) as rd:
        for name, text in files.items():
            target = rd.path / name
            if isinstance(text, bytes):
                target.write_bytes(text)
            else:
                target.write_text(text, encoding="utf-8")
        write_summary(rd.path, summary)
        write_config(rd.path, config)
    return rd.final


class PlannerInputs(NamedTuple):
    """A planner's model file, its reference in the written scenario, the limits and the
    limits' base scenario, and the files read (for the run directory)."""

    sc_file: Path
    ref: str
    lim: Any
    base: Any
    inputs: list[Path]


def planner_inputs(spacecraft: PathArg, limits: PathArg, *, slews: bool = True) -> PlannerInputs:
    """Resolve a planner's model file and load its limits (``slews``: limits on slews too)."""
    from cassini_bayes.plan.limits import load_limits

    sc_file = spacecraft_path(spacecraft)
    ref = model_reference(sc_file)
    lim, base = load_limits(limits, ref, slews=slews)
    return PlannerInputs(sc_file, ref, lim, base, [sc_file, Path(lim.source)])


def load_baseline(baseline: PathArg | None, inputs: list[Path]) -> Scenario | None:
    """The comparison scenario (path or shipped name), its file added to ``inputs``; ``None``
    without one."""
    from cassini_bayes.simulate import load_scenario
    from cassini_bayes.simulate.scenario import scenario_path

    if baseline is None:
        return None
    bp = scenario_path(baseline)
    bl = load_scenario(bp)
    inputs.append(bp)
    return bl


def check_positive(name: str, value: Any, what: str) -> None:
    """``value`` must be ``None`` or a finite positive number; else an error asking for
    ``what``."""
    if value is not None and (isinstance(value, bool) or not isinstance(value, (int, float))
                              or not np.isfinite(value) or value <= 0):
        raise InputError(f"{arg(name, value)}: give {what}")


def counts_of(name: str, value: Any, lo: int, hi: int, what: str) -> Sequence[int] | None:
    """The counts to search (an int or a list of them, each from ``lo`` to ``hi``); ``None``
    for the planner's default; else an error asking for ``what``."""
    if value is None:
        return None
    counts = [value] if isinstance(value, int) and not isinstance(value, bool) else value
    if not isinstance(counts, (list, tuple)) or not counts or any(
            isinstance(n, bool) or not isinstance(n, int) or not lo <= n <= hi for n in counts):
        raise InputError(f"{arg(name, value)}: give {what}")
    return counts


def progress_printer(progress: bool) -> Callable[[str], None] | None:
    """A printer of the search's steps on stderr, or ``None``."""
    if not progress:
        return None
    return lambda m: print(m, file=sys.stderr, flush=True)


def limits_exceeded(usage: Mapping[str, float]) -> list[str]:
    """The warning of a plan that exceeds limits on its simulated telemetry (none if not)."""
    bad = {k: v for k, v in usage.items() if v > 1.0}
    if not bad:
        return []
    return ["the plan exceeds limits on its simulated telemetry: " + ", ".join(
        f"{k} {v:.3f} of the limit" for k, v in bad.items())]


def emit_warnings(warns: Sequence[str]) -> None:
    """Each of a planner's warnings as a :class:`UserWarning` at the planner's caller."""
    for w in warns:
        warnings.warn(w, stacklevel=3)


def plan_header(command: str, calibration: str, pi: PlannerInputs) -> dict[str, Any]:
    """The first keys of a planner's ``summary.json``."""
    return {"kind": "plan", "command": command, "calibration": calibration,
            "version": __version__, "spacecraft": pi.ref, "limits_file": pi.lim.source,
            "limits": pi.lim.to_dict()}


def inputs_config(pi: PlannerInputs, bl: Scenario | None) -> dict[str, Any]:
    """The ``[inputs]`` of a planner's ``config.toml``."""
    return {"spacecraft": str(pi.sc_file), "limits": pi.lim.source,
            "baseline": None if bl is None else bl.source}


@dataclass(frozen=True)
class PlannedRun:
    """What a planner returns: the plan, its ``config.toml`` and ``summary.json``, and the run
    directory ``save`` writes (a subclass gives the report and the scenario's header)."""

    plan: Any
    config: dict
    _summary: dict = field(repr=False)
    _inputs: tuple[Path, ...] = field(default=(), repr=False)

    @property
    def scenario(self) -> dict:
        """The plan as a scenario dict (``scenario.toml``)."""
        return self.plan.scenario

    @property
    def warnings(self) -> list[str]:
        """Lines on what the plan cannot reach or does not respect."""
        return list(self._summary["warnings"])

    def summary(self) -> dict:
        """``summary.json`` (a copy)."""
        import copy

        return copy.deepcopy(self._summary)

    def scenario_toml(self) -> str:
        """The plan as scenario TOML text (the subclass's header above it)."""
        raise NotImplementedError

    def _report(self) -> str:
        raise NotImplementedError

    def save(self, out: str | os.PathLike, *, force: bool = False) -> Path:
        """Write ``scenario.toml`` (the plan), ``summary.json``, ``config.toml`` and
        ``report.html`` (the manoeuvre against time, the limits as lines, the prediction beside
        the comparison's) into ``out``, atomically."""
        files = {"scenario.toml": self.scenario_toml(), "report.html": self._report()}
        if self.plan.baseline_scenario is not None:
            import tomli_w

            files["papers_scenario.toml"] = tomli_w.dumps(self.plan.baseline_scenario)
        return write_dir(out, force=force, files=files, summary=self._summary,
                          config=self.config, inputs=self._inputs)
