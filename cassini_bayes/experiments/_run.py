""":func:`run_experiment` runs one experiment into a run directory, atomically (a temporary
directory beside the target, renamed into place when complete): ``results.json`` (settings, the
kind's JSON summary, the checks against the papers), ``report.html`` (self-contained),
``config.toml`` (the resolved file, re-runnable as it is) and ``figures/*.png``.
"""

from __future__ import annotations

import os
import time
import zlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import jax

from cassini_bayes import __version__
from cassini_bayes._devices import jax_entry
from cassini_bayes.errors import InputError
from cassini_bayes.experiments._results import ExperimentContext, ExperimentOutput
from cassini_bayes.experiments._schema import Experiment, load_experiment
from cassini_bayes.files import json_text


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
    """Write ``results.json``, ``config.toml``, ``figures/*.png`` and ``report.html`` into
    ``workdir`` (the caller's :class:`~cassini_bayes.rundir.RunDir` makes it atomic).

    An experiment's run directory is not a fit's: its numbers are ``results.json`` (checks,
    tables, figures beside the summary) and it holds no posterior, so it shares only
    ``config.toml``'s writer with :func:`cassini_bayes.api.write_run` and the SBC run's."""
    from cassini_bayes.experiments._page import experiment_page
    from cassini_bayes.rundir import write_config

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
    write_config(workdir, _config_dict(exp, settings, seed, quick))
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
