"""``cassini-bayes experiment experiments/NAME.toml --out DIR``: run one experiment."""

from __future__ import annotations

from pathlib import Path

import typer

from cassini_bayes.cli._options import check_seed, seed_option

ORDER = 50


def experiment(
    file: Path = typer.Argument(..., help="Experiment file (experiments/NAME.toml, or a shipped "
                                          "experiment's bare NAME), or a run directory's "
                                          "config.toml to re-run it."),
    out: Path = typer.Option(..., "--out", help="Run directory to write (must not exist)."),
    seed: int = seed_option(None, "Seed of the run's jax.random key (default: the file's "
                                  "\\[run] seed, else 0)."),
    force: bool = typer.Option(False, "--force", help="Replace --out if it is a run directory "
                               "cassini-bayes wrote."),
    quick: bool = typer.Option(False, "--quick", help="Small settings (for tests and previews)."),
) -> None:
    """Run one experiment: DIR/results.json, DIR/report.html, DIR/config.toml, DIR/figures/."""
    import matplotlib

    matplotlib.use("Agg")  # headless
    from cassini_bayes.cli._console import escape, stderr_console

    from cassini_bayes._paths import EXPERIMENTS_DIR, input_path, text_file
    from cassini_bayes.experiments import load_experiment, run_experiment
    from cassini_bayes.rundir import check_out

    file = input_path(file, "experiment", EXPERIMENTS_DIR)  # or a shipped one's bare name
    text_file(file, "experiment")  # a binary file: one line
    check_out(out, force=force, inputs=[file])
    exp = load_experiment(file)
    if seed is None and exp.seed is not None:
        check_seed(exp.seed, str(file))
    console = stderr_console()
    with console.status(f"running {exp.name} ({exp.kind.name})"):
        rec = run_experiment(exp, out, seed=seed, quick=quick, force=force)
    checks = rec.output.checks
    n_fail = sum(c.passed is False for c in checks)
    n_pass = sum(c.passed is True for c in checks)
    console.print(f"{escape(exp.name)}: {n_pass} pass, {n_fail} fail against the papers "
                  f"({rec.elapsed_s:.2f} s)")
    typer.echo(str(rec.path / "report.html"))


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    """Add ``experiment`` to the ``cassini-bayes`` command."""
    app.command("experiment")(experiment)
