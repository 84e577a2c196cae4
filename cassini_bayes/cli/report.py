"""``cassini-bayes report DIR``: (re)build ``DIR/report.html`` from ``DIR/posterior.nc``.

``--out PAGE`` writes the page elsewhere: its missing folders are created; an existing directory,
or a file of the run directory other than ``report.html``, is refused.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import typer

ORDER = 40


def report(
    run_dir: Path = typer.Argument(..., help="Run directory holding posterior.nc, summary.json."),
    out: Path = typer.Option(None, "--out", help="Write the page here instead of "
                             "DIR/report.html (missing folders are created)."),
) -> None:
    """(Re)build DIR/report.html from DIR/posterior.nc, summary.json and config.toml."""
    import matplotlib

    matplotlib.use("Agg")  # headless: never open a window from the command line
    from cassini_bayes.report import build_report

    created = None if out is None else _prepare_page(Path(out), Path(run_dir))
    try:
        path = build_report(run_dir, out=out)
    except BaseException:
        if created is not None:  # leave no empty folders behind
            shutil.rmtree(created, ignore_errors=True)
        raise
    typer.echo(str(path))


def _prepare_page(out: Path, run_dir: Path) -> Path | None:
    """Refuse a bad ``--out`` page before any work; create its missing folders and return the
    first one created (None if none)."""
    from cassini_bayes.errors import InputError
    from cassini_bayes.rundir import check_writable

    page = out.expanduser().resolve()
    if page.is_dir():
        raise InputError("is a directory; give the path of the .html page to write",
                         path=str(out))
    run = run_dir.expanduser().resolve()
    if page.parent == run and page.exists() and page.name != "report.html":
        raise InputError(f"is a file of the run directory {run_dir}; the report may only replace "
                         "report.html there: choose another --out", path=str(out))
    check_writable(page.parent, str(out))
    created = next((a for a in reversed(page.parents) if not a.exists()), None)
    page.parent.mkdir(parents=True, exist_ok=True)
    return created


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    """Add ``report`` to the ``cassini-bayes`` command."""
    app.command("report")(report)
