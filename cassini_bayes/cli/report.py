"""``cassini-bayes report DIR``: (re)build ``DIR/report.html`` from ``DIR/posterior.nc``.

``--out PAGE`` writes the page elsewhere: its missing folders are created; an existing directory
is refused, and so is an existing file unless ``--force`` is given and the file is a page
cassini-bayes wrote (the run directory's own ``report.html`` is always rebuilt).
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
    force: bool = typer.Option(False, "--force", help="Replace an existing --out page that "
                               "cassini-bayes wrote (never any other file)."),
) -> None:
    """(Re)build DIR/report.html from DIR/posterior.nc, summary.json and config.toml."""
    import matplotlib

    matplotlib.use("Agg")  # headless: never open a window from the command line
    from cassini_bayes.report import build_report

    created = None if out is None else _prepare_page(Path(out), Path(run_dir), force)
    try:
        path = build_report(run_dir, out=out)
    except BaseException:
        if created is not None:  # leave no empty folders behind
            shutil.rmtree(created, ignore_errors=True)
        raise
    typer.echo(str(path))


def _prepare_page(out: Path, run_dir: Path, force: bool) -> Path | None:
    """Refuse a bad ``--out`` page before any work; create its missing folders and return the
    first one created (None if none)."""
    from cassini_bayes.errors import InputError
    from cassini_bayes.report.html import written_by_package
    from cassini_bayes.rundir import check_writable

    page = out.expanduser().resolve()
    if page.is_dir():
        raise InputError("is a directory; give the path of the .html page to write",
                         path=str(out))
    run = run_dir.expanduser().resolve()
    own_report = page == run / "report.html"
    if page.exists() and not own_report:
        if not written_by_package(page):
            raise InputError("exists and is not a page cassini-bayes wrote; choose another "
                             "--out (nothing else is ever overwritten)", path=str(out))
        if not force:
            raise InputError("exists; add --force to replace it", path=str(out))
    check_writable(page.parent, str(out))
    created = next((a for a in reversed(page.parents) if not a.exists()), None)
    page.parent.mkdir(parents=True, exist_ok=True)
    return created


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    """Add ``report`` to the ``cassini-bayes`` command."""
    app.command("report")(report)
