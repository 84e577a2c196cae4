"""``cassini-bayes check FILE [--pulses P.csv] [--spacecraft M.toml]``: validate a telemetry file
and say what it holds.

Exit 0 when the file (and pulse log) pass every rule of :mod:`cassini_bayes.telemetry` and the
physics checks of :mod:`cassini_bayes.consistency` (attitude vs body rates; pulse log vs the
``on_*`` columns; with ``--spacecraft``, wheel units by momentum conservation); otherwise one line
``error: …`` on stderr and exit 2 (raised as ``InputError``, printed by
:func:`cassini_bayes.cli.main`).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from cassini_bayes.consistency import MOMENTUM_ALIGN_MIN, check_telemetry_data
from cassini_bayes.spacecraft import load_spacecraft
from cassini_bayes.telemetry import (
    RPM_TO_RAD_S,
    THRUSTER_NAMES,
    PulseSpanWarning,
    _turn_angle,
    read_pulses,
    read_telemetry,
    with_on_times,
)
from cassini_bayes.windows import quiet_periods

ORDER = 15


def _sampling(t: np.ndarray) -> str:
    dt = np.diff(t)
    med = float(np.median(dt))
    text = f"{1.0 / med:.4g} Hz (median step {med:.4g} s"
    if dt.max() > 1.5 * med or dt.min() < 0.5 * med:
        text += f", irregular: {dt.min():.4g} to {dt.max():.4g} s"
    return text + ")"


def _physics_line(attitude, momentum, sc) -> str:
    """What the physics checks of :mod:`cassini_bayes.consistency` established, on one line."""
    if attitude is None:
        text = "q vs ω not checked (the attitude hardly turns)"
    else:
        text = (f"q vs ω consistent (alignment {attitude.alignment[0]:.3f} over "
                f"{attitude.segments} turning stretches, rate scale {attitude.scale:.3f})")
    if sc is None:
        return text + "; wheel units not checked (give --spacecraft)"
    if momentum is None or momentum.alignment < MOMENTUM_ALIGN_MIN:
        return text + "; wheel units not checked (no clean momentum exchange)"
    return (text + f"; wheel rpm confirmed by momentum conservation (scale {momentum.scale:.3f}, "
            "rad/s would give 9.55)")


def _summary(console: Console, file: Path, pulses: Path | None, min_quiet_s: float,
             rate_max: float, wheel_tol_rpm: float, *, check_units: bool = True,
             spacecraft: str | None = None) -> None:
    tel = read_telemetry(file, check_units=check_units)
    log = read_pulses(pulses) if pulses is not None else None
    sc = load_spacecraft(spacecraft) if spacecraft is not None else None
    attitude, momentum = check_telemetry_data(tel, sc, log)
    notes: list[str] = []
    source = "on_* columns"
    if log is not None and tel.on_times is not None:
        notes.append(f"{file} has on_* columns; they are used and {pulses} is only validated")
    elif log is not None:
        source = f"pulse log {pulses}"
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", PulseSpanWarning)
            tel = with_on_times(tel, log)
        notes += [str(w.message) for w in caught if issubclass(w.category, PulseSpanWarning)]
    t = tel.t
    console.print(f"[bold]{escape(str(file))}[/bold]: valid telemetry")
    console.print(f"  rows       {tel.n}")
    console.print(f"  time       {t[0]:.10g} to {t[-1]:.10g} s ({t[-1] - t[0]:.6g} s)")
    console.print(f"  sampling   {_sampling(t)}")
    rate = np.linalg.norm(tel.omega, axis=1)
    turn = _turn_angle(tel.q, tel.q[0])
    console.print(f"  body rate  max |ω| {rate.max() * 1e3:.4g} mrad/s; attitude turns up to "
                  f"{np.degrees(turn.max()):.4g}° from the first row")
    console.print("  physics    " + _physics_line(attitude, momentum, sc))

    wheels = Table(title="Reaction wheels", title_justify="left")
    for col in ("wheel", "status", "min rpm", "max rpm", "first → last rpm"):
        wheels.add_column(col, justify="left" if col in ("wheel", "status") else "right")
    for j, name in enumerate(tel.wheel_names):
        rpm = tel.wheel_rates[:, j] / RPM_TO_RAD_S
        if not np.all(np.isfinite(rpm)):
            wheels.add_row(name, "off (no data)", "", "", "")
            continue
        wheels.add_row(name, "on", f"{rpm.min():.2f}", f"{rpm.max():.2f}",
                       f"{rpm[0]:.2f} → {rpm[-1]:.2f}")
    console.print(wheels)

    if tel.on_times is None:
        console.print("Thrusters: no on_* columns and no pulse log (thrust fits need --pulses)")
    else:
        thr = Table(title=f"Thrusters (from {escape(source)})", title_justify="left")
        for col in ("thruster", "pulses", "total on-time s"):
            thr.add_column(col, justify="left" if col == "thruster" else "right")
        fired = False
        for k, name in enumerate(THRUSTER_NAMES):
            on = tel.on_times[:, k]
            total = float(on[-1] - on[0])
            if total <= 0:
                continue
            fired = True
            if source != "on_* columns":
                count = str(int(np.count_nonzero(log.thruster == k)))
            else:
                count = str(int(np.count_nonzero(np.diff((np.diff(on) > 0).astype(int)) == 1)
                                + (on[1] > on[0])))
            thr.add_row(name, count, f"{total:.6g}")
        if fired:
            console.print(thr)
        else:
            console.print(f"Thrusters (from {escape(source)}): none fired")

    quiet = quiet_periods(tel, min_duration_s=min_quiet_s, rate_max=rate_max,
                          wheel_tol_rpm=wheel_tol_rpm)
    qt = Table(title=f"Quiet periods ≥ {min_quiet_s:g} s", title_justify="left")
    for col in ("#", "t0 s", "t1 s", "duration s"):
        qt.add_column(col, justify="right")
    for i, (a, b) in enumerate(quiet, start=1):
        qt.add_row(str(i), f"{a:.10g}", f"{b:.10g}", f"{b - a:.6g}")
    if quiet:
        console.print(qt)
        console.print(f"  {len(quiet)} quiet period(s), {max(len(quiet) - 1, 0)} slew(s) "
                      "between them")
    else:
        console.print(f"Quiet periods: none of at least {min_quiet_s:g} s")
    console.print(f"  quiet means |ω| ≤ {rate_max * 1e3:g} mrad/s, running wheels within "
                  f"{wheel_tol_rpm:g} rpm over 10 s, no thruster firing")
    if log is not None:
        console.print(f"[bold]{escape(str(pulses))}[/bold]: valid pulse log, "
                      f"{len(log.t_on)} pulses")
    for note in notes:
        console.print(f"[yellow]warning:[/yellow] {escape(note)}")


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    @app.command("check")
    def check(
        file: Path = typer.Argument(..., help="Telemetry file (CSV, or Parquet with pyarrow)."),
        pulses: Path | None = typer.Option(None, "--pulses", help="Pulse log CSV to validate "
                                           "and use for the thruster on-times."),
        min_quiet: float = typer.Option(60.0, "--min-quiet", help="Shortest quiet period, s."),
        rate_max: float = typer.Option(1e-3, "--rate-max",
                                       help="Largest body rate of a quiet sample, rad/s."),
        wheel_tol: float = typer.Option(2.0, "--wheel-tol",
                                        help="Largest wheel-rate change in a quiet stretch, rpm."),
        spacecraft: str | None = typer.Option(None, "--spacecraft", help="Spacecraft model "
                                              "TOML: also check the wheel units against "
                                              "momentum conservation."),
        no_unit_check: bool = typer.Option(False, "--no-unit-check",
                                           help="Skip the rad/s-vs-rpm and deg/s heuristics "
                                           "(wheels genuinely idling below 12 rpm)."),
    ) -> None:
        """Validate a telemetry file (and pulse log) and summarise what it holds."""
        console = Console(highlight=False, soft_wrap=True)
        _summary(console, file, pulses, min_quiet, rate_max, wheel_tol,
                 check_units=not no_unit_check, spacecraft=spacecraft)
