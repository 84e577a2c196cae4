"""``cassini-bayes monitor leak TELEMETRY [--pulses PULSES] --spacecraft MODEL --out DIR``.

Runs :func:`cassini_bayes.api.monitor_leak` (the Bayesian thruster-leak monitor and Lee's
threshold monitor over one telemetry stretch) and writes, atomically, ``DIR/summary.json`` (the
posterior probability of each hypothesis, ``none`` and each of the model's thrusters, at the last
sample, the detection time and thruster of both monitors — Lee's where the thrusters are
Cassini's Eq 16 layout — the leak fraction and torque), ``DIR/probabilities.csv`` (the
probabilities at every check), ``DIR/report.html`` (the adequacy verdict and both monitors)
and ``DIR/config.toml`` (inputs with their SHA-256, settings, version); ``summary.json`` carries
the ``adequacy`` verdict and ``--strict`` exits 3 when it failed. docs/leak.md describes the
model.
"""

from __future__ import annotations

import time
from pathlib import Path

import typer
from cassini_bayes.cli._console import escape, stderr_console

from cassini_bayes.cli._verdict import (STRICT_ADEQUACY, enforce_adequacy, failed_checks,
                                        verdict_text)
from cassini_bayes.rundir import check_out

ORDER = 60


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    monitor = typer.Typer(help="On-line monitors: thruster leak.", no_args_is_help=True)
    app.add_typer(monitor, name="monitor")

    @monitor.command("leak")
    def leak_cmd(
        telemetry: Path = typer.Argument(..., help="Telemetry file (CSV, or Parquet)."),
        pulses: Path | None = typer.Option(None, "--pulses", help="Pulse log CSV (else the "
                                           "telemetry's on-times times the model thrust)."),
        spacecraft: str = typer.Option(..., "--spacecraft", help="Spacecraft model TOML."),
        out: Path = typer.Option(..., "--out", help="Output directory (written atomically)."),
        force: bool = typer.Option(False, "--force", help="Replace --out if it is a directory "
                                   "cassini-bayes wrote."),
        prior_leak: float = typer.Option(0.01, "--prior-leak", min=1e-12, max=0.5,
                                         help="Prior probability of a leak in the stretch."),
        p_detect: float = typer.Option(0.99, "--p-detect", min=0.5, max=1 - 1e-12,
                                       help="Alarm when P(leak) reaches this."),
        sample_step: float = typer.Option(60.0, "--sample-step",
                                          help="Spacing of the residual samples used, s."),
        check_step: float = typer.Option(60.0, "--check-step", help="Seconds between checks."),
        eta: float = typer.Option(0.05, "--eta", help="Thruster-to-thruster variation "
                                  "(fraction, Lee Eq 11)."),
        threshold: float = typer.Option(50.0, "--threshold", help="Lee's R_T, N m s."),
        t_limit: float = typer.Option(10.0, "--t-limit", help="Lee's T_limit, hours."),
        strict: bool = STRICT_ADEQUACY,
    ) -> None:
        """Posterior probability of a leak per thruster, beside Lee's threshold monitor (Cassini's
        thruster layout only)."""
        console = stderr_console()
        t0 = time.perf_counter()
        from cassini_bayes.api import monitor_leak

        check_out(out, force=force, inputs=[telemetry] + ([pulses] if pulses else []))
        res = monitor_leak(telemetry, spacecraft, pulses=pulses, prior_leak=prior_leak,
                           p_detect=p_detect, sample_step_s=sample_step,
                           check_step_s=check_step, eta=eta,
                           threshold_nms=threshold, t_limit_h=t_limit)
        res.save(out, force=force)
        s = res.summary()
        b, lee = s["bayes"], s["lee"]
        for line in s.get("warnings", []):
            console.print(f"[yellow]warning:[/yellow] {escape(line)}")
        said = (f"leak in {b['thruster']} at {b['isolation_time_s']:.0f} s"
                if b["thruster"] else "leak, thruster not isolated" if b["detection_time_s"]
                else "no leak")
        mark = "[green]✓[/green]" if not failed_checks(s) else "[red]✗[/red]"
        lee_said = ("not run (Cassini's thruster layout only)" if not lee["applies"]
                    else f"{lee['thruster']} at {lee['detection_time_s']:.0f} s"
                    if lee["thruster"] else "no trigger")
        console.print(f"{mark} P(leak) = {b['p_leak']:.3g}: {said}; Lee: {lee_said}"
                      + f"{verdict_text(s)} (run took "
                      f"{time.perf_counter() - t0:.1f} s) → {escape(str(out))}")
        enforce_adequacy(s, out, strict=strict, what="the monitor's model does not "
                         "fit the stretch", hint="check the spacecraft model (its inertia, "
                         "thrust and torque knowledge) and the pulse log")
