"""``cassini-bayes reproduce --out DIR``: every paper reproduction, one report."""

from __future__ import annotations

from pathlib import Path

import typer

from cassini_bayes.cli._options import seed_option

ORDER = 5


def reproduce(
    out: Path = typer.Option(..., "--out", help="Directory to write (must not exist)."),
    seed: int = seed_option(0, "Master seed; each experiment folds in its name."),
    quick: bool = typer.Option(False, "--quick", help="Small settings (tests, previews)."),
    force: bool = typer.Option(False, "--force", help="Replace --out if it is a directory "
                               "cassini-bayes wrote."),
    experiments_dir: Path = typer.Option(None, "--experiments", hidden=True,
                                         help="Directory of experiment files (default: the "
                                              "shipped experiments/)."),
) -> None:
    """Run every experiment in experiments/ and write DIR/report.html: the papers beside ours."""
    import matplotlib

    matplotlib.use("Agg")  # headless
    from cassini_bayes.cli._console import escape, stderr_console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    from cassini_bayes._paths import EXPERIMENTS_DIR
    from cassini_bayes.experiments import discover_experiments
    from cassini_bayes.experiments import reproduce as run_all
    from cassini_bayes.rundir import check_out

    experiments_dir = experiments_dir or EXPERIMENTS_DIR
    check_out(out, force=force, inputs=[experiments_dir])  # before any progress is drawn
    discover_experiments(experiments_dir)
    console = stderr_console()
    columns = (TextColumn("[bold]{task.description}"), BarColumn(),
               TextColumn("{task.completed}/{task.total}"), TimeElapsedColumn())
    with Progress(*columns, console=console, transient=False) as progress:
        task = progress.add_task("reproduce", total=None)

        def on_event(event: str, i: int, n: int, message: str) -> None:
            if event == "start":
                progress.update(task, total=n, description=f"{message}")
            elif event == "progress" and message:
                progress.update(task, description=message)
            elif event == "done":
                progress.update(task, advance=1, description=f"{message} done")
            elif event == "failed":
                progress.update(task, advance=1)
                progress.console.print(f"[red]failed[/red] {escape(message)}")

        result = run_all(out, seed=seed, quick=quick, force=force,
                         experiments_dir=experiments_dir, on_event=on_event)
    for f, reason in result.skipped:
        console.print(f"skipped {escape(Path(f).name)}: {escape(reason)}")
    n_fail = result.checks_failed
    console.print(f"{len(result.statuses)} experiments in {result.elapsed_s:.1f} s; "
                  f"{n_fail} check(s) outside the papers' values or budgets")
    typer.echo(str(result.out / "report.html"))
    if result.failed:
        console.print(f"[red]error:[/red] experiment(s) failed: {escape(', '.join(result.failed))} "
                      f"(see {escape(str(result.out / 'report.html'))})")
        raise typer.Exit(1)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    """Add ``reproduce`` to the ``cassini-bayes`` command."""
    app.command("reproduce")(reproduce)
