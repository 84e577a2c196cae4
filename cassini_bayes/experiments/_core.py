"""Experiment kinds, experiment files and run directories.

An *experiment kind* is one library function registered under a name::

    @register("impulse_ratio", defaults={"spacecraft": "fsds", "grid_points": 51},
              quick={"grid_points": 9})
    def impulse_ratio(key, settings, ctx) -> ExperimentOutput: ...

An *experiment file* (``experiments/NAME.toml``) names a kind and overrides some of its settings::

    kind = "impulse_ratio"
    title = "Impulse ratio R of the thruster pulses (Feldman & Lee §V)"
    [settings]
    grid_points = 61

Every key is checked: an unknown top-level key, an unknown setting or a setting of the wrong type is
an :class:`~cassini_bayes.errors.InputError` naming the file and the key. ``--quick`` applies the
kind's ``quick`` overrides on top of the file (small sizes for tests).

:func:`run_experiment` runs one into a run directory, atomically (a temporary directory beside the
target, renamed into place when complete): ``results.json`` (settings, the kind's JSON summary, the
checks against the papers), ``report.html`` (self-contained), ``config.toml`` (the resolved file,
re-runnable as it is) and ``figures/*.png``.
"""

from __future__ import annotations

import importlib
import math
import os
import pkgutil
import time
import tomllib
import zlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import jax

from cassini_bayes import __version__
from cassini_bayes._devices import jax_entry
from cassini_bayes._paths import EXPERIMENTS_DIR, input_path, not_utf8
from cassini_bayes.analysis.paper_facts import fact
from cassini_bayes.diagnostics import ESS_BULK_MIN, R_HAT_MAX, Diagnostics
from cassini_bayes.errors import InputError
from cassini_bayes.files import json_text, toml_text

__all__ = [
    "Check",
    "FigureOut",
    "Table",
    "ExperimentOutput",
    "ExperimentContext",
    "ExperimentKind",
    "Experiment",
    "RunRecord",
    "register",
    "registered_kinds",
    "check_fact",
    "convergence_check",
    "coverage_check",
    "png",
    "load_experiment",
    "experiment_from_dict",
    "run_experiment",
    "run_into",
    "write_run",
    "experiment_key",
]


# --- what an experiment returns --------------------------------------------------------------


@dataclass(frozen=True)
class Check:
    """Our number for one row of the papers' facts (or a check of our own).

    Attributes
    ----------
    label : what was computed, in words.
    ours : our value (in ``unit``).
    unit : unit of ``ours``.
    fact_id : id of the :data:`~cassini_bayes.analysis.paper_facts.PAPER_FACTS` row it
        reproduces, or ``None`` for a check with no printed counterpart.
    paper : the paper's value as printed ("" when none).
    passed : ``True``/``False`` against the paper (printed precision or budget); ``None`` when
        there is nothing to pass (a reference row).
    decimals : decimals to show ``ours`` with.
    note : how the comparison was made, one line.
    """

    label: str
    ours: float
    unit: str = ""
    fact_id: str | None = None
    paper: str = ""
    passed: bool | None = None
    decimals: int = 4
    note: str = ""

    @property
    def ours_text(self) -> str:
        return f"{self.ours:.{self.decimals}f} {self.unit}".strip()

    def to_dict(self) -> dict[str, Any]:
        return {"label": self.label, "ours": self.ours, "unit": self.unit,
                "fact_id": self.fact_id, "paper": self.paper, "passed": self.passed,
                "note": self.note}


def convergence_check(what: str, diagnostics: Diagnostics, quick: bool = False) -> Check:
    """A check row saying whether a fit's sampler converged (the rule of
    :mod:`cassini_bayes.diagnostics`). Under ``--quick`` the runs are too short to judge: the
    row is shown but not counted (``passed=None``)."""
    d = diagnostics
    note = (f"min bulk ESS {d.min_ess_bulk:.0f}, {d.divergences} divergences "
            f"(R-hat ≤ {R_HAT_MAX}, ESS ≥ {ESS_BULK_MIN:g}, no divergences)")
    if quick:
        note += "; --quick: too few draws to judge, not counted"
    return Check(f"{what}: sampler converged", float(d.max_r_hat), "max R-hat", decimals=3,
                 passed=None if quick else bool(d.converged), note=note)


def coverage_check(label: str, covered: int, total: int, nominal: float = 0.90) -> Check:
    """A check row: do posterior intervals of nominal level ``nominal`` cover the truth at that
    rate? ``covered`` of ``total`` intervals contain the truth; the row passes when an exact
    two-sided binomial test does not reject ``p = nominal`` at the 5 % level (a calibrated
    posterior fails 5 % of the time with independent intervals). The note gives the binomial
    standard error."""
    from scipy.stats import binomtest

    if total <= 0:
        return Check(label, float("nan"), "%", passed=None, note="no intervals")
    rate = covered / total
    p_value = float(binomtest(covered, total, nominal).pvalue)
    se = (nominal * (1.0 - nominal) / total) ** 0.5
    return Check(label, 100.0 * rate, "%", decimals=0, passed=p_value >= 0.05,
                 note=f"{covered} of {total}; nominal {100 * nominal:g} % ± {100 * se:.0f} % "
                      f"(binomial sd); exact binomial p = {p_value:.2f} (fails below 0.05)")


def check_fact(fact_id: str, ours: float, *, label: str | None = None, note: str = "",
               decimals: int | None = None) -> Check:
    """A :class:`Check` of ``ours`` against the paper-facts row ``fact_id``.

    Passes when ``ours`` matches at the printed precision (value rows) or is within the bound
    (budget rows); shown with two more decimals than the paper prints unless ``decimals`` is given.
    """
    f = fact(fact_id)
    shown = decimals if decimals is not None else (f.decimals or 0) + 2
    return Check(label=label or f.description, ours=float(ours), unit=f.unit, fact_id=f.id,
                 paper=f.printed, passed=f.passes(ours), decimals=shown, note=note)


@dataclass(frozen=True)
class FigureOut:
    """A rendered figure: file stem ``name``, PNG bytes and a caption."""

    name: str
    png: bytes
    caption: str = ""


@dataclass(frozen=True)
class Table:
    """A small table for the report (cells already formatted as text)."""

    title: str
    columns: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    note: str = ""

    def to_dict(self) -> dict[str, Any]:
        return {"title": self.title, "columns": list(self.columns),
                "rows": [list(r) for r in self.rows], "note": self.note}


@dataclass(frozen=True)
class ExperimentOutput:
    """What an experiment kind returns; the framework writes it to the run directory.

    Attributes
    ----------
    summary : JSON-able results (units in the key names).
    checks : our numbers against the papers'.
    figures : rendered figures.
    tables : extra tables for the report.
    notes : paragraphs for the report (method, distributions used, caveats).
    links : (label, path relative to the run directory) of files or sub-runs written by the kind.
    """

    summary: Mapping[str, Any]
    checks: tuple[Check, ...] = ()
    figures: tuple[FigureOut, ...] = ()
    tables: tuple[Table, ...] = ()
    notes: tuple[str, ...] = ()
    links: tuple[tuple[str, str], ...] = ()


@dataclass(frozen=True)
class ExperimentContext:
    """What a kind may use besides its key and settings.

    Attributes
    ----------
    workdir : the (temporary) run directory being written; a kind may write sub-runs into it and
        list them in :attr:`ExperimentOutput.links`.
    quick : whether ``--quick`` was asked for.
    source : the experiment file, for error messages.
    progress : ``progress(fraction, message)`` reports progress within the experiment.
    """

    workdir: Path
    quick: bool = False
    source: str = "<experiment>"
    progress: Callable[[float, str], None] = lambda fraction, message="": None

    def error(self, message: str) -> InputError:
        """An :class:`InputError` naming the experiment file."""
        return InputError(message, path=self.source)


def png(fig, dpi: int = 90) -> bytes:
    """Render a matplotlib ``Figure`` to PNG bytes (palette-quantised like the run reports)."""
    from cassini_bayes.report.figures import png_bytes

    return png_bytes(fig, dpi=dpi)


# --- registry ----------------------------------------------------------------------------------

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


# --- experiment files ----------------------------------------------------------------------------

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


# --- running --------------------------------------------------------------------------------


def experiment_key(seed: int, name: str | None = None) -> jax.Array:
    """The experiment's key: ``jax.random.key(seed)``, folded with a stable hash of ``name``.

    Folding by name (not by position) keeps each experiment's draws the same when others are added.
    """
    key = jax.random.key(int(seed))
    if name is not None:
        key = jax.random.fold_in(key, zlib.crc32(name.encode()) & 0x7FFFFFFF)
    return key


@dataclass(frozen=True)
class RunRecord:
    """A finished experiment run: where it is, what it returned, how long it took (s)."""

    experiment: Experiment
    path: Path
    output: ExperimentOutput
    settings: Mapping[str, Any]
    seed: int
    quick: bool
    elapsed_s: float


def _config_dict(exp: Experiment, settings: Mapping[str, Any], seed: int, quick: bool) -> dict:
    d: dict[str, Any] = {"kind": exp.kind.name, "title": exp.title}
    if exp.description:
        d["description"] = exp.description
    d["settings"] = dict(settings)
    d["run"] = {"name": exp.name, "seed": int(seed), "quick": bool(quick), "version": __version__}
    return d


def write_run(exp: Experiment, workdir: Path, output: ExperimentOutput,
              settings: Mapping[str, Any], seed: int, quick: bool, elapsed_s: float) -> None:
    """Write ``results.json``, ``config.toml``, ``figures/*.png``, ``report.html`` into ``workdir``."""
    from cassini_bayes.experiments._page import experiment_page

    fig_dir = workdir / "figures"
    fig_dir.mkdir(exist_ok=True)
    for f in output.figures:
        (fig_dir / f"{f.name}.png").write_bytes(f.png)
    results = {
        "name": exp.name, "kind": exp.kind.name, "title": exp.title, "seed": int(seed),
        "quick": bool(quick), "version": __version__, "elapsed_s": round(elapsed_s, 3),
        "settings": dict(settings),
        "results": output.summary,
        "checks": [c.to_dict() for c in output.checks],
        "all_passed": all(c.passed is not False for c in output.checks),
        "figures": [{"name": f.name, "path": f"figures/{f.name}.png", "caption": f.caption}
                    for f in output.figures],
        "tables": [t.to_dict() for t in output.tables],
        "links": [{"label": label, "path": path} for label, path in output.links],
    }
    (workdir / "results.json").write_text(json_text(results))
    (workdir / "config.toml").write_text(toml_text(_config_dict(exp, settings, seed, quick)))
    (workdir / "report.html").write_text(
        experiment_page(exp, output, settings, seed, quick, elapsed_s), encoding="utf-8")


def run_into(exp: Experiment, workdir: Path, *, seed: int = 0, quick: bool = False,
             key: jax.Array | None = None,
             progress: Callable[[float, str], None] | None = None) -> RunRecord:
    """Run ``exp`` and write its files into the existing directory ``workdir`` (not atomic)."""
    settings = exp.resolved_settings(quick)
    ctx = ExperimentContext(workdir=workdir, quick=quick, source=exp.source,
                            progress=progress or (lambda fraction, message="": None))
    t0 = time.perf_counter()
    try:
        output = exp.kind.run(experiment_key(seed, exp.name) if key is None else key, settings,
                              ctx)
    except InputError as e:  # name the experiment file in every user error raised while running
        raise InputError(str(e), path=exp.source) from None
    elapsed = time.perf_counter() - t0
    write_run(exp, workdir, output, settings, seed, quick, elapsed)
    return RunRecord(exp, workdir, output, settings, seed, quick, elapsed)


@jax_entry
def run_experiment(exp: Experiment | str | os.PathLike, out: str | os.PathLike, *,
                   seed: int | None = None, quick: bool = False, force: bool = False,
                   progress: Callable[[float, str], None] | None = None) -> RunRecord:
    """Run an experiment into the run directory ``out``, atomically.

    Parameters
    ----------
    exp : an :class:`Experiment` or the path of its TOML file.
    out : the run directory; refused when it exists unless ``force``.
    seed : the run's seed (turned into a key once, here); default the file's ``[run] seed`` or 0.
    quick : apply the kind's small ``quick`` settings.
    force : replace an existing ``out`` (only once the new run is complete).
    progress : ``progress(fraction, message)`` callback.
    """
    if not isinstance(exp, Experiment):
        exp = load_experiment(exp)
    from cassini_bayes.rundir import RunDir

    out = Path(out)
    seed = seed if seed is not None else (exp.seed if exp.seed is not None else 0)
    with RunDir(out, force=force) as rd:     # (refuses a bad out before any work)
        record = run_into(exp, rd.path, seed=seed, quick=quick, progress=progress)
    return RunRecord(exp, out, record.output, record.settings, seed, quick, record.elapsed_s)
