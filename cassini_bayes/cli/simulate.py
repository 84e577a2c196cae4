"""``cassini-bayes simulate SCENARIO.toml --out DIR [--seed N] [--force]``.

Writes ``DIR/telemetry.csv`` (noisy telemetry, docs/design.md §4.1), ``DIR/pulses.csv`` (when
thrusters fired) and ``DIR/truth.json`` (every true parameter, the noise levels, the quiet windows
and the noise-free momentum check), atomically: everything is written into a temporary directory
beside ``DIR`` and renamed at the end, so a half-written run never appears under the final name. An
existing ``DIR`` is refused unless ``--force`` (and then only one this package wrote,
:func:`cassini_bayes.rundir.check_out`).
"""

from __future__ import annotations

import time
from pathlib import Path

import typer
from cassini_bayes.cli._console import escape, stderr_console

from cassini_bayes._paths import text_file
from cassini_bayes.cli._options import check_seed, seed_option
from cassini_bayes.rundir import check_out

ORDER = 20


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    @app.command("simulate")
    def simulate_cmd(
        scenario: Path = typer.Argument(..., help="Scenario TOML, or a shipped scenario's name "
                                      "(slews_post_probe; experiments/scenarios/)."),
        out: Path = typer.Option(..., "--out", help="Output directory (written atomically)."),
        seed: int | None = seed_option(None, "Seed of the sensor noise (default: the "
                                       "scenario's)."),
        force: bool = typer.Option(False, "--force", help="Replace --out if it is a directory "
                                   "cassini-bayes wrote."),
    ) -> None:
        """Simulate a scenario: telemetry.csv, pulses.csv (if thrusters fire), truth.json."""
        console = stderr_console()
        from cassini_bayes.api import simulate_scenario
        from cassini_bayes.simulate import load_scenario
        from cassini_bayes.simulate.scenario import scenario_path

        scenario = scenario_path(scenario)  # a file, or a shipped scenario's bare name
        text_file(scenario, "scenario")  # a binary file: one line
        check_out(out, force=force, inputs=[scenario])

        sc = load_scenario(scenario)
        seed_ = check_seed(sc.seed, str(scenario)) if seed is None else seed
        t0 = time.perf_counter()
        with console.status(f"simulating {sc.name}: {sc.n_steps} steps of {sc.dt_s} s, "
                            f"{sc.n_samples} samples (compiling on first use)…"):
            sim = simulate_scenario(sc, seed=seed_)
            sim.save(out, force=force)
        n_p = 0 if sim.pulses is None else sim.pulses.t_on.size
        console.print(f"[green]✓[/green] {escape(sc.name)}: {sc.n_samples} samples, {n_p} pulses, "
                      f"{time.perf_counter() - t0:.1f} s → {escape(str(out))}")
