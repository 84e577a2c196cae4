"""``cassini-bayes budget --inertia RUN --thrust RUN --rwa4 RUN --out DIR``.

Budgets whose inputs are posteriors (:mod:`cassini_bayes.analysis.posterior_budgets`): the draws of
the given fits' ``posterior.nc`` propagated through each budget line, every line a credible interval
with its attribution to the calibrated parameters, beside the papers' numbers (docs/budgets.md).
Writes, atomically (:class:`cassini_bayes.rundir.RunDir`), ``DIR/summary.json``,
``DIR/budget.csv``, ``DIR/report.html`` and ``DIR/config.toml``. Any of the three runs may be left
out; at least one is needed.
"""

from __future__ import annotations

import time
from pathlib import Path

import typer
from rich.console import Console

from cassini_bayes import __version__
from cassini_bayes.cli._options import seed_option
from cassini_bayes.errors import InputError
from cassini_bayes.rundir import RunDir, check_out, file_record, write_config, write_summary

ORDER = 45


def run_budget(out: Path, *, inertia: Path | None = None, thrust: Path | None = None,
               rwa4: Path | None = None, seed: int = 0, n_draws: int = 4000,
               force: bool = False) -> dict:
    """Read the runs, propagate, write ``out``; returns the summary."""
    import jax

    from cassini_bayes.analysis.posterior_budgets import (
        budget_csv,
        budget_table,
        load_posterior,
        posterior_budget,
    )
    from cassini_bayes.report.html import html_page, paragraph, section, table

    runs = {"inertia": inertia, "thrust": thrust, "rwa4": rwa4}
    if all(v is None for v in runs.values()):
        raise InputError("give at least one run directory: --inertia RUN, --thrust RUN or "
                         "--rwa4 RUN")
    if n_draws < 10:
        raise InputError(f"must be at least 10, got {n_draws}", path="--draws")
    given = {k: v for k, v in runs.items() if v is not None}
    check_out(out, force=force, inputs=list(given.values()))
    post = {k: load_posterior(v, k, option=f"--{k}") for k, v in given.items()}
    budget = posterior_budget(jax.random.key(seed), n_draws=n_draws, **post)
    summary = {"command": "budget", "version": __version__, "seed": seed,
               **budget.to_dict()}
    config = {"command": "budget", "version": __version__, "seed": seed,
              "inputs": {k: {"run": str(v), "posterior": file_record(v / "posterior.nc")}
                         for k, v in given.items()},
              "settings": {"n_draws": n_draws, "level": budget.level}}
    columns, rows = budget_table(budget)
    page = html_page("Budgets from posteriors", [
        section("Budget lines", [
            paragraph("Each line propagated from the posterior draws of the runs below: median "
                      "and 90 % credible interval, beside the paper's number; lines without a "
                      "calibrated input keep the paper's value. Attribution: the share of the "
                      "line's posterior variance each parameter causes when it alone varies "
                      "(the others at their posterior medians); docs/budgets.md.", note=True),
            table(list(columns), [list(r) for r in rows], left=3)]),
        section("Inputs", paragraph("; ".join(f"{k}: {v}" for k, v in given.items())))])
    with RunDir(out, force=force, inputs=list(given.values())) as rd:
        write_summary(rd.path, summary)
        write_config(rd.path, config)
        (rd.path / "budget.csv").write_text(budget_csv(budget))
        (rd.path / "report.html").write_text(page, encoding="utf-8")
    return summary


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    """Add ``budget`` to the ``cassini-bayes`` command."""

    @app.command("budget")
    def budget_cmd(
        out: Path = typer.Option(..., "--out", help="Output directory (written atomically)."),
        inertia: Path | None = typer.Option(None, "--inertia", help="Run directory of an "
                                            "inertia fit."),
        thrust: Path | None = typer.Option(None, "--thrust", help="Run directory of a thrust "
                                           "fit (mean thrust F)."),
        rwa4: Path | None = typer.Option(None, "--rwa4", help="Run directory of an RWA4 fit."),
        draws: int = typer.Option(4000, "--draws", help="Joint draws propagated."),
        seed: int = seed_option(0, "Seed of the resampling of the runs' draws."),
        force: bool = typer.Option(False, "--force", help="Replace --out if it is a directory "
                                   "cassini-bayes wrote."),
    ) -> None:
        """Budgets from posteriors: each line a credible interval with its attribution."""
        console = Console(stderr=True, highlight=False)
        t0 = time.perf_counter()
        s = run_budget(out, inertia=inertia, thrust=thrust, rwa4=rwa4, seed=seed,
                       n_draws=draws, force=force)
        console.print(f"[green]✓[/green] {len(s['rows'])} budget lines from "
                      f"{', '.join(s['sources'])} ({time.perf_counter() - t0:.1f} s) → {out}")
        typer.echo(str(out / "report.html"))
