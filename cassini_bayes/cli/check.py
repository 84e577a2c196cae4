"""``cassini-bayes check FILE [--pulses P.csv] [--spacecraft M.toml]``: validate a telemetry file
and say what it holds.

Prints :func:`cassini_bayes.api.check_telemetry`. Exit 0 when the file (and pulse log) pass
every rule of :mod:`cassini_bayes.telemetry` and the physics checks of
:mod:`cassini_bayes.consistency` (attitude vs body rates; pulse log vs the ``on_*`` columns; with
``--spacecraft``, wheel units by momentum conservation); otherwise one line ``error: …`` on
stderr and exit 2 (raised as ``InputError``, printed by :func:`cassini_bayes.cli.main`).
"""

from __future__ import annotations

import math
from pathlib import Path

import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

ORDER = 15


def _print(console: Console, file: Path, pulses: Path | None, c) -> None:
    """Print a :class:`~cassini_bayes.api.TelemetryCheck`."""
    t = c.t
    console.print(f"[bold]{escape(str(file))}[/bold]: valid telemetry")
    console.print(f"  rows       {c.n}")
    console.print(f"  time       {t[0]:.10g} to {t[-1]:.10g} s ({t[-1] - t[0]:.6g} s)")
    console.print(f"  sampling   {c.sampling()}")
    console.print(f"  body rate  max |ω| {c.max_rate_rad_s * 1e3:.4g} mrad/s; attitude turns up "
                  f"to {math.degrees(c.max_turn_rad):.4g}° from the first row")
    console.print("  physics    " + c.physics)
    if c.quanta:
        console.print("  quantised  " + escape("; ".join(r.text() for r in c.quanta)))

    wheels = Table(title="Reaction wheels", title_justify="left")
    for col in ("wheel", "status", "min rpm", "max rpm", "first → last rpm"):
        wheels.add_column(col, justify="left" if col in ("wheel", "status") else "right")
    for w in c.wheels:
        if not w.on:
            wheels.add_row(w.name, "off (no data)", "", "", "")
            continue
        wheels.add_row(w.name, "idle (rms at its noise or ≤ 1 rpm: as off)" if w.idle else "on",
                       f"{w.min_rpm:.2f}", f"{w.max_rpm:.2f}",
                       f"{w.first_rpm:.2f} → {w.last_rpm:.2f}")
    console.print(wheels)

    if c.thruster_source is None and not c.model_thrusters:
        console.print("Thrusters: none in the spacecraft model")
    elif c.thruster_source is None:
        console.print("Thrusters: no on_* columns and no pulse log (thrust fits need --pulses)")
    elif c.thrusters:
        thr = Table(title=f"Thrusters (from {escape(c.thruster_source)})", title_justify="left")
        for col in ("thruster", "pulses", "total on-time s"):
            thr.add_column(col, justify="left" if col == "thruster" else "right")
        for k in c.thrusters:
            thr.add_row(k.name, str(k.pulses), f"{k.on_time_s:.6g}")
        console.print(thr)
    else:
        console.print(f"Thrusters (from {escape(c.thruster_source)}): none fired")

    if c.quiet:
        qt = Table(title=f"Quiet periods ≥ {c.min_quiet_s:g} s", title_justify="left")
        for col in ("#", "t0 s", "t1 s", "duration s"):
            qt.add_column(col, justify="right")
        for i, (a, b) in enumerate(c.quiet, start=1):
            qt.add_row(str(i), f"{a:.10g}", f"{b:.10g}", f"{b - a:.6g}")
        console.print(qt)
        console.print(f"  {len(c.quiet)} quiet period(s), {max(len(c.quiet) - 1, 0)} slew(s) "
                      "between them")
    else:
        console.print(f"Quiet periods: none of at least {c.min_quiet_s:g} s")
    console.print(f"  quiet means |ω| ≤ {c.rate_max_rad_s * 1e3:.3g} mrad/s ({c.rate_rule}, at "
                  f"least 8 noise sd), running wheels within {c.wheel_tol_rpm:g} rpm "
                  f"({c.wheel_tol_rule}, at least 8 noise sd) over 10 s, no thruster firing")
    if c.n_pulses is not None:
        console.print(f"[bold]{escape(str(pulses))}[/bold]: valid pulse log, "
                      f"{c.n_pulses} pulses")
    for note in c.notes:
        console.print(f"[yellow]warning:[/yellow] {escape(note)}")


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    @app.command("check")
    def check(
        file: Path = typer.Argument(..., help="Telemetry file (CSV, or Parquet with pyarrow)."),
        pulses: Path | None = typer.Option(None, "--pulses", help="Pulse log CSV to validate "
                                           "and use for the thruster on-times."),
        min_quiet: float = typer.Option(60.0, "--min-quiet", help="Shortest quiet period, s."),
        rate_max: float | None = typer.Option(
            None, "--rate-max", help="Largest body rate of a quiet sample, rad/s [default: a "
            "third of the file's top rate, at least 8 sd of its gyro noise]."),
        wheel_tol: float | None = typer.Option(
            None, "--wheel-tol", help="Largest wheel-rate change in a quiet stretch, rpm "
            "[default: each wheel's quiet_tol_rpm in the spacecraft model, else 2; at least 8 sd "
            "of each wheel's noise]."),
        spacecraft: str | None = typer.Option(None, "--spacecraft", help="Spacecraft model "
                                              "TOML: also check the wheel units against "
                                              "momentum conservation."),
        no_unit_check: bool = typer.Option(False, "--no-unit-check",
                                           help="Skip the rad/s-vs-rpm and deg/s heuristics "
                                           "(wheels genuinely idling below 12 rpm)."),
    ) -> None:
        """Validate a telemetry file (and pulse log) and summarise what it holds."""
        from cassini_bayes.api import check_telemetry

        c = check_telemetry(file, pulses=pulses, spacecraft=spacecraft, min_quiet_s=min_quiet,
                            rate_max_rad_s=rate_max, wheel_tol_rpm=wheel_tol,
                            check_units=not no_unit_check)
        _print(Console(highlight=False, soft_wrap=True), file, pulses, c)
