"""Budgets whose inputs are posteriors: :func:`budget` (docs/budgets.md).

The draws of the given fits' ``posterior.nc`` propagated through each budget line
(:mod:`cassini_bayes.analysis.posterior_budgets`), every line a credible interval with its
attribution to the calibrated parameters, beside the papers' numbers; what
``cassini-bayes budget`` computes.
"""

from __future__ import annotations

import copy
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from cassini_bayes import __version__
from cassini_bayes._devices import jax_entry
from cassini_bayes.errors import InputError, spelled
from cassini_bayes.names import a_kind

if TYPE_CHECKING:
    from cassini_bayes.analysis.posterior_budgets import PosteriorBudget
    from cassini_bayes.api._inputs import FitArg

__all__ = ["BudgetResult", "budget"]


@dataclass(frozen=True)
class BudgetResult:
    """The propagated ``budget``
    (:class:`~cassini_bayes.analysis.posterior_budgets.PosteriorBudget`), its ``summary``
    (``summary.json``) and ``config`` (``config.toml``) dicts and the inputs ``runs`` (by kind:
    run directories or fit results, :class:`~cassini_bayes.api.FitResult`)."""

    budget: PosteriorBudget
    _summary: dict[str, Any] = field(repr=False)
    config: dict[str, Any]
    runs: dict[str, Any]

    def summary(self) -> dict:
        """``summary.json`` as a dict (a copy; the same protocol as :meth:`FitResult.summary`)."""
        return copy.deepcopy(self._summary)

    def save(self, out: str | os.PathLike, *, force: bool = False) -> Path:
        """Write ``summary.json`` (with the ``adequacy`` verdict of
        :func:`~cassini_bayes.analysis.budget_adequacy.budget_adequacy`), ``config.toml``,
        ``budget.csv`` and ``report.html`` (the answer first, the adequacy verdict) into ``out``
        atomically; returns it. ``force`` replaces only a directory cassini-bayes wrote."""
        from cassini_bayes.analysis.posterior_budgets import budget_csv
        from cassini_bayes.report.budget import budget_report_html
        from cassini_bayes.rundir import RunDir, write_config, write_summary

        page = budget_report_html(self)
        inputs = [r for r in self.runs.values() if isinstance(r, Path)]
        with RunDir(out, force=force, inputs=inputs) as rd:
            write_summary(rd.path, self._summary)
            write_config(rd.path, self.config)
            (rd.path / "budget.csv").write_text(budget_csv(self.budget))
            (rd.path / "report.html").write_text(page, encoding="utf-8")
        return rd.final


def _axis_wheel(run: FitArg) -> str:
    """The wheel a spin-axis fit (a FitResult or a run directory) calibrated: its summary's
    ``wheel`` block; RWA4 for a summary written before the block existed (or none to read)."""
    import json

    from cassini_bayes.api._result import FitResult

    if isinstance(run, FitResult):
        summary = run.summary()
    else:
        path = Path(run) / "summary.json"
        try:
            summary = json.loads(path.read_text(encoding="utf-8")) if path.is_file() else {}
        except (OSError, ValueError):
            summary = {}     # load_posterior's own checks name what is wrong with the run
    wheel = summary.get("wheel") if isinstance(summary, dict) else None
    return str(wheel.get("name") or "RWA4") if isinstance(wheel, dict) else "RWA4"


@jax_entry
def budget(*, inertia: FitArg | None = None, thrust: FitArg | None = None,
           rwa4: FitArg | None = None, seed: int = 0,
           n_draws: int = 4000) -> BudgetResult:
    """Budget lines from the posteriors of fit run directories (any of the three; at least one).

    Parameters
    ----------
    inertia, thrust, rwa4 : an inertia, a thrust (mean thrust ``F``) and an RWA4 fit: its
        :class:`~cassini_bayes.api.FitResult` or its run directory (``posterior.nc`` in each).
    seed : seed of the resampling of the runs' draws to a common number.
    n_draws : joint draws propagated (≥ 10).
    """
    import jax

    from cassini_bayes.analysis.budget_adequacy import budget_adequacy
    from cassini_bayes.analysis.posterior_budgets import (
        load_posterior,
        posterior_budget,
        posterior_from_idata,
    )
    from cassini_bayes.api._inputs import MAX_DRAWS, check_seed, number
    from cassini_bayes.api._result import FitResult
    from cassini_bayes.rundir import file_record

    runs = {"inertia": inertia, "thrust": thrust, "rwa4": rwa4}
    given: dict = {}
    for k, v in runs.items():
        if v is None:
            continue
        if isinstance(v, FitResult):
            if v.kind != k:   # (a thrust fit carries inertia draws: never take those)
                raise InputError(f"{spelled(f'--{k}', k)}: {a_kind(v.kind)} fit; give "
                                 f"{a_kind(k)} fit's FitResult or run directory")
            given[k] = v
        elif isinstance(v, (str, os.PathLike)):
            given[k] = Path(v)
        else:
            raise InputError(f"{spelled(f'--{k}', k)}: give a FitResult or a run directory, "
                             f"not {type(v).__name__}")
    if "rwa4" in given and _axis_wheel(given["rwa4"]) != "RWA4":
        raise InputError(f"{spelled('--rwa4', 'rwa4')}: a spin-axis fit of "
                         f"{_axis_wheel(given['rwa4'])}; the budget's axis line is Cassini's "
                         "RWA4 (Lee's pointing budget): give an RWA4 fit")
    if not given:
        raise InputError("give at least one run directory: "
                         + ", ".join(spelled(f"--{k} RUN", k) for k in runs))
    check_seed(seed)
    n_draws = int(number("n_draws", n_draws, lo=10, hi=MAX_DRAWS, integer=True,
                         where=spelled("--draws", "n_draws")))
    post = {k: (load_posterior(v, k, option=spelled(f"--{k}", k)) if isinstance(v, Path) else
                posterior_from_idata(v.idata, k, f"{k}={v}",
                                     (v.config.get("options") or {}).get("method")))
            for k, v in given.items()}
    result = posterior_budget(jax.random.key(seed), n_draws=n_draws, inertia=post.get("inertia"),
                              thrust=post.get("thrust"), rwa4=post.get("rwa4"))
    adequacy = budget_adequacy(given)
    summary = {"command": "budget", "version": __version__, "seed": seed, **result.to_dict(),
               "adequacy": adequacy.to_dict(), "warnings": adequacy.warnings()}
    config = {"command": "budget", "version": __version__, "seed": seed,
              "inputs": {k: ({"run": str(v), "posterior": file_record(v / "posterior.nc")}
                             if isinstance(v, Path) else  # an unsaved fit: how to redo it
                             {"command": v.config["command"], "seed": v.config["seed"],
                              "inputs": v.config["inputs"]})
                         for k, v in given.items()},
              "settings": {"n_draws": n_draws, "level": result.level}}
    return BudgetResult(result, summary, config, given)
