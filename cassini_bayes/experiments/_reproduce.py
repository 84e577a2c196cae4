"""``reproduce``: every experiment file whose kind is registered, and one summary page.

Data-driven: every ``experiments/*.toml`` is loaded; those whose ``kind`` is registered run, in
the order of the kinds' ``order`` then the file name, each into ``OUT/<name>/``; files of kinds not
(yet) registered are listed as skipped. ``OUT/report.html`` puts, for every row of
:data:`~cassini_bayes.analysis.paper_facts.PAPER_FACTS` some experiment computed, the paper's value
beside ours with its verdict, and links to each experiment's own report. The whole directory is
written atomically.
"""

from __future__ import annotations

import os
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from cassini_bayes import __version__
from cassini_bayes._devices import jax_entry
from cassini_bayes._paths import EXPERIMENTS_DIR
from cassini_bayes._toml import read_toml
from cassini_bayes.analysis.paper_facts import PAPER_FACTS
from cassini_bayes.errors import InputError
from cassini_bayes.experiments._registry import registered_kinds
from cassini_bayes.experiments._run import RunRecord, experiment_key, run_into
from cassini_bayes.experiments._schema import Experiment, experiment_from_dict
from cassini_bayes.files import json_text

__all__ = ["ExperimentStatus", "ReproduceResult", "discover_experiments", "reproduce"]


@dataclass(frozen=True)
class ExperimentStatus:
    """One experiment of a ``reproduce`` run: its record, or the one-line error it failed with."""

    experiment: Experiment
    record: RunRecord | None
    error: str | None = None


@dataclass(frozen=True)
class ReproduceResult:
    """What ``reproduce`` did.

    Attributes
    ----------
    out : the output directory.
    statuses : every experiment run, in order.
    skipped : (file, reason) of experiment files not run (kind not registered).
    elapsed_s : wall time, s.
    """

    out: Path
    statuses: tuple[ExperimentStatus, ...]
    skipped: tuple[tuple[str, str], ...] = ()
    elapsed_s: float = 0.0
    failed: tuple[str, ...] = field(default=())

    @property
    def checks_failed(self) -> int:
        return sum(c.passed is False for s in self.statuses if s.record
                   for c in s.record.output.checks)


def discover_experiments(directory: str | os.PathLike = EXPERIMENTS_DIR,
                         ) -> tuple[list[Experiment], list[tuple[str, str]]]:
    """Experiment files of ``directory`` whose kind is registered (validated, in run order).

    Returns ``(experiments, skipped)``; ``skipped`` lists ``(file, reason)`` for files whose kind is
    not registered. A file of a registered kind with a bad key raises :class:`InputError`.
    """
    directory = Path(directory)
    if not directory.is_dir():
        raise InputError(f"experiments directory not found: {directory}")
    kinds = registered_kinds()
    found, skipped = [], []
    for p in sorted(directory.glob("*.toml")):
        d = read_toml(p, "experiment file", "experiments/")
        kind = d.get("kind")
        if kind not in kinds:
            skipped.append((str(p), f"kind {kind!r} is not registered"))
            continue
        found.append(experiment_from_dict(d, str(p)))
    names = [e.name for e in found]
    if len(set(names)) != len(names):  # pragma: no cover - file stems are unique in a directory
        raise InputError(f"duplicate experiment names in {directory}: {names}")
    found.sort(key=lambda e: (e.kind.order, e.name))
    return found, skipped


Event = Callable[[str, int, int, str], None]


@jax_entry
def reproduce(out: str | os.PathLike, *, seed: int = 0, quick: bool = False, force: bool = False,
              experiments_dir: str | os.PathLike = EXPERIMENTS_DIR,
              on_event: Event | None = None) -> ReproduceResult:
    """Run every registered experiment of ``experiments_dir`` into ``out`` and write the summary.

    Parameters
    ----------
    out : output directory (refused when it exists, unless ``force``).
    seed : master seed; each experiment's key is ``fold_in(key(seed), hash(name))``.
    quick : small settings (tests).
    force : replace an existing ``out`` once the new one is complete.
    experiments_dir : where the ``*.toml`` files are.
    on_event : ``on_event(event, index, total, message)`` with events ``"start"``, ``"progress"``,
        ``"done"``, ``"failed"`` (for a progress display).

    An experiment that raises is recorded as failed (its one-line error on the page) and the others
    still run.
    """
    from cassini_bayes.rundir import RunDir

    out = Path(out)
    run_dir = RunDir(out, force=force, inputs=[experiments_dir])   # a bad out: before any work
    experiments, skipped = discover_experiments(experiments_dir)
    emit = on_event or (lambda *a: None)
    t0 = time.perf_counter()
    statuses = []
    with run_dir as rd:
        tmp = rd.path
        n = len(experiments)
        for i, exp in enumerate(experiments):
            emit("start", i, n, exp.name)
            sub = tmp / exp.name
            sub.mkdir()
            try:
                rec = run_into(exp, sub, seed=seed, quick=quick, key=experiment_key(seed, exp.name),
                               progress=lambda f, m="", i=i: emit("progress", i, n, m))
                rec = RunRecord(rec.experiment, out / exp.name, rec.output, rec.settings, seed,
                                quick, rec.elapsed_s)
                statuses.append(ExperimentStatus(exp, rec))
                emit("done", i, n, exp.name)
            except Exception as e:  # noqa: BLE001 - one failing experiment must not stop the rest
                msg = " ".join(f"{type(e).__name__}: {e}".split())
                (sub / "error.txt").write_text(traceback.format_exc())
                statuses.append(ExperimentStatus(exp, None, msg))
                emit("failed", i, n, f"{exp.name}: {msg}")
        elapsed = time.perf_counter() - t0
        result = ReproduceResult(out, tuple(statuses), tuple(skipped), elapsed,
                                 tuple(s.experiment.name for s in statuses if s.error))
        _write_summary(tmp, result, seed, quick)
    return result


def _write_summary(tmp: Path, result: ReproduceResult, seed: int, quick: bool) -> None:
    from cassini_bayes.experiments._page import reproduce_page

    rows = []
    for s in result.statuses:
        for c in (s.record.output.checks if s.record else ()):
            rows.append({"experiment": s.experiment.name, **c.to_dict()})
    summary = {
        "version": __version__, "seed": seed, "quick": quick,
        "elapsed_s": round(result.elapsed_s, 3),
        "experiments": [{"name": s.experiment.name, "kind": s.experiment.kind.name,
                         "title": s.experiment.title, "ok": s.error is None, "error": s.error,
                         "elapsed_s": round(s.record.elapsed_s, 3) if s.record else None,
                         "report": f"{s.experiment.name}/report.html"} for s in result.statuses],
        "skipped": [{"file": f, "reason": r} for f, r in result.skipped],
        "checks": rows,
        "uncovered_facts": sorted({f.id for f in PAPER_FACTS} - {r["fact_id"] for r in rows}),
    }
    (tmp / "results.json").write_text(json_text(summary))
    (tmp / "report.html").write_text(reproduce_page(result, seed, quick), encoding="utf-8")
