"""Budgets whose inputs are posteriors: :func:`budget` (docs/budgets.md).

The draws of the given fits' ``posterior.nc`` propagated through each budget line
(:mod:`cassini_bayes.analysis.posterior_budgets`), every line a credible interval with its
attribution to the calibrated parameters, beside the papers' numbers; what
``cassini-bayes budget`` computes.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from cassini_bayes import __version__
from cassini_bayes._devices import jax_entry
from cassini_bayes.errors import InputError, spelled
from cassini_bayes.names import a_kind

__all__ = ["BudgetResult", "budget"]


@dataclass(frozen=True)
class BudgetResult:
    """The propagated ``budget``
    (:class:`~cassini_bayes.analysis.posterior_budgets.PosteriorBudget`), its ``summary``
    (``summary.json``) and ``config`` (``config.toml``) dicts and the inputs ``runs`` (by kind:
    run directories or fit results, :class:`~cassini_bayes.api.FitResult`)."""

    budget: object
    summary: dict
    config: dict
    runs: dict

    def save(self, out: str | os.PathLike, *, force: bool = False) -> Path:
        """Write ``summary.json``, ``config.toml``, ``budget.csv`` and ``report.html`` into
        ``out`` atomically; returns it. ``force`` replaces only a directory cassini-bayes
        wrote."""
        from cassini_bayes.analysis.posterior_budgets import budget_csv, budget_table
        from cassini_bayes.report.html import (bullet_list, html_page, paragraph, section,
                                               table)
        from cassini_bayes.rundir import RunDir, write_config, write_summary

        columns, rows = budget_table(self.budget)
        warns = self.summary.get("warnings") or []
        header = (f'<div class="warnings"><strong>Warnings</strong>{bullet_list(warns)}</div>'
                  if warns else "")
        page = html_page("Budgets from posteriors", [
            section("Budget lines", [
                paragraph("Each line propagated from the posterior draws of the runs below: "
                          "median and 90 % credible interval, beside the paper's number; lines "
                          "without a calibrated input keep the paper's value. Attribution: the "
                          "share of the line's posterior variance each parameter causes when it "
                          "alone varies (the others at their posterior medians); "
                          "docs/budgets.md.", note=True),
                table(list(columns), [list(r) for r in rows], left=3)]),
            section("Inputs", paragraph("; ".join(f"{k}: {v}" for k, v in self.runs.items())))],
            header=header)
        inputs = [r for r in self.runs.values() if isinstance(r, Path)]
        with RunDir(out, force=force, inputs=inputs) as rd:
            write_summary(rd.path, self.summary)
            write_config(rd.path, self.config)
            (rd.path / "budget.csv").write_text(budget_csv(self.budget))
            (rd.path / "report.html").write_text(page, encoding="utf-8")
        return rd.final


def _run_record(run, name: str) -> dict | None:
    """A budget input's ``summary.json`` or ``config.toml`` (``name``) as a dict: a
    :class:`~cassini_bayes.api.FitResult`'s own, else read from its run directory (``None``
    when missing or unreadable)."""
    import json
    import tomllib

    if not isinstance(run, Path):
        return run.summary() if name == "summary.json" else run.config
    try:
        text = (run / name).read_text(encoding="utf-8")
        record = json.loads(text) if name.endswith(".json") else tomllib.loads(text)
    except (OSError, UnicodeDecodeError, ValueError):
        return None
    return record if isinstance(record, dict) else None


def _mixed_models(runs: dict) -> list[str]:
    """A warning when the runs were fitted with different spacecraft models (their
    ``config.toml``): their parameters then describe different spacecraft or epochs."""
    names = {}
    for kind, run in runs.items():
        cfg = _run_record(run, "config.toml")
        if cfg is None:
            continue
        name = (cfg.get("spacecraft") or {}).get("name")
        if isinstance(name, str):
            names[kind] = name
    if len(set(names.values())) < 2:
        return []
    return ["the runs were fitted with different spacecraft models ("
            + ", ".join(f"{k}: {v}" for k, v in names.items()) + "): the budget combines "
            "parameters of different spacecraft or epochs; give runs of one model"]


def _unreliable_inputs(runs: dict) -> list[str]:
    """A warning per input run whose own ``summary.json`` says it did not converge or failed its
    adequacy checks: the budget inherits what is wrong with its draws."""
    out = []
    for kind, run in runs.items():
        summary = _run_record(run, "summary.json")
        if summary is None:
            continue
        diag = summary.get("diagnostics") or {}
        if diag.get("converged") is False:
            def num(key: str, spec: str) -> str:
                x = diag.get(key)
                return format(x, spec) if isinstance(x, (int, float)) else "?"

            out.append(f"the {kind} run {run} did not converge (max R-hat "
                       f"{num('max_r_hat', '.4f')}, min bulk ESS {num('min_ess_bulk', '.0f')}, "
                       f"{num('divergences', 'd')} divergences): its lines rest on draws that "
                       "may not represent its posterior; re-fit it with more draws")
        adequacy = summary.get("adequacy") or {}
        if adequacy.get("ok") is False:
            failed = [k for k, c in (adequacy.get("checks") or {}).items()
                      if isinstance(c, dict) and c.get("ok") is False]
            out.append(f"the {kind} run {run} failed its adequacy checks ({', '.join(failed)}): "
                       "its model may not fit its data")
    return out


@jax_entry
def budget(*, inertia=None, thrust=None, rwa4=None, seed: int = 0,
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

    from cassini_bayes.analysis.posterior_budgets import (load_posterior, posterior_budget,
                                                          posterior_from_idata)
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
    if not given:
        raise InputError("give at least one run directory: "
                         + ", ".join(spelled(f"--{k} RUN", k) for k in runs))
    check_seed(seed)
    n_draws = number("n_draws", n_draws, lo=10, hi=MAX_DRAWS, integer=True,
                     where=spelled("--draws", "n_draws"))
    post = {k: (load_posterior(v, k, option=spelled(f"--{k}", k)) if isinstance(v, Path) else
                posterior_from_idata(v.idata, k, f"{k}={v}",
                                     (v.config.get("options") or {}).get("method")))
            for k, v in given.items()}
    result = posterior_budget(jax.random.key(seed), n_draws=n_draws, **post)
    summary = {"command": "budget", "version": __version__, "seed": seed, **result.to_dict(),
               "warnings": _mixed_models(given) + _unreliable_inputs(given)}
    config = {"command": "budget", "version": __version__, "seed": seed,
              "inputs": {k: ({"run": str(v), "posterior": file_record(v / "posterior.nc")}
                             if isinstance(v, Path) else  # an unsaved fit: how to redo it
                             {"command": v.config["command"], "seed": v.config["seed"],
                              "inputs": v.config["inputs"]})
                         for k, v in given.items()},
              "settings": {"n_draws": n_draws, "level": result.level}}
    return BudgetResult(result, summary, config, given)
