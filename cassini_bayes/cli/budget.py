"""``cassini-bayes budget --inertia RUN --thrust RUN --rwa4 RUN --out DIR``.

Runs :func:`cassini_bayes.api.budget`: budgets whose inputs are posteriors, the draws of the given
fits' ``posterior.nc`` propagated through each budget line, every line a credible interval with
its attribution to the calibrated parameters, beside the papers' numbers (docs/budgets.md).
Writes, atomically, ``DIR/summary.json`` (with the ``adequacy`` verdict on the input runs;
``--strict`` exits 3 when it failed),
``DIR/budget.csv``, ``DIR/report.html`` and ``DIR/config.toml``. Any of the three runs may be left
out; at least one is needed.
"""

from __future__ import annotations

import time
from pathlib import Path

import typer
from cassini_bayes.cli._console import escape, stderr_console

from cassini_bayes.cli._options import seed_option
from cassini_bayes.cli._verdict import (STRICT_ADEQUACY, enforce_adequacy, failed_checks,
                                        verdict_text)
from cassini_bayes.rundir import check_out

ORDER = 45


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
        strict: bool = STRICT_ADEQUACY,
    ) -> None:
        """Budgets from posteriors: each line a credible interval with its attribution."""
        console = stderr_console()
        t0 = time.perf_counter()
        from cassini_bayes.api import budget

        check_out(out, force=force, inputs=[p for p in (inertia, thrust, rwa4) if p])
        res = budget(inertia=inertia, thrust=thrust, rwa4=rwa4, seed=seed, n_draws=draws)
        res.save(out, force=force)
        s = res.summary()
        for line in s["warnings"]:
            console.print(f"[yellow]warning:[/yellow] {escape(line)}")
        mark = "[green]✓[/green]" if not failed_checks(s) else "[red]✗[/red]"
        console.print(f"{mark} {len(s['rows'])} budget lines from "
                      f"{escape(', '.join(s['sources']))}{verdict_text(s)} "
                      f"({time.perf_counter() - t0:.1f} s) → {escape(str(out))}")
        typer.echo(str(out / "report.html"))
        enforce_adequacy(s, out, strict=strict, what="the input runs are not fit to be "
                         "combined", hint="re-fit the runs named, or give runs of one "
                         "spacecraft model and epoch")
