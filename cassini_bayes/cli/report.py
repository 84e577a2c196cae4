"""``cassini-bayes report DIR``: (re)build ``DIR/report.html`` from ``DIR/posterior.nc``."""

from __future__ import annotations

from pathlib import Path

import typer

ORDER = 40


def report(
    run_dir: Path = typer.Argument(..., help="Run directory holding posterior.nc, summary.json."),
    out: Path = typer.Option(None, "--out", help="Write the page here instead of DIR/report.html."),
) -> None:
    """(Re)build DIR/report.html from DIR/posterior.nc, summary.json and config.toml."""
    import matplotlib

    matplotlib.use("Agg")  # headless: never open a window from the command line
    from cassini_bayes.report import build_report

    path = build_report(run_dir, out=out)
    typer.echo(str(path))


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    """Add ``report`` to the ``cassini-bayes`` command."""
    app.command("report")(report)
