"""``cassini-bayes fit health EVENTS... --spacecraft MODEL --out DIR`` and
``cassini-bayes simulate-health CAMPAIGN.toml --out DIR``.

``fit health`` pools many wheel-biasing events into the exact change-point posterior of each
thrust channel (:func:`cassini_bayes.api.fit_health`; docs/health.md) and writes, atomically,
``DIR/summary.json`` (change probability and date, per channel ``P(down)`` at the last event,
the ``adequacy`` verdict), ``DIR/report.html``,
``DIR/health.csv`` (per event), ``DIR/thrust_bands.csv``, ``DIR/health.png`` and
``DIR/config.toml``. EVENTS are ``events.csv`` files (columns ``date_days, telemetry, pulses``)
or folders holding one. ``simulate-health`` writes such a folder from a campaign TOML.
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
    @groups["fit"].command("health")
    def health_cmd(
        events: list[Path] = typer.Argument(..., help="events.csv files or folders holding "
                                            "one (columns date_days, telemetry, pulses)."),
        spacecraft: str = typer.Option(..., "--spacecraft", help="Spacecraft model TOML."),
        out: Path = typer.Option(..., "--out", help="Output directory (written atomically)."),
        force: bool = typer.Option(False, "--force", help="Replace --out if it is a directory "
                                   "cassini-bayes wrote."),
        fraction: float = typer.Option(0.05, "--fraction", min=1e-6, max=0.999,
                                       help="Loss asked about: P(thrust more than this "
                                            "fraction below its first calibration)."),
        p_change: float = typer.Option(0.1, "--p-change", min=1e-9, max=1 - 1e-9,
                                       help="Prior probability of a change over the events."),
        p_channel: float = typer.Option(0.5, "--p-channel", min=1e-9, max=1 - 1e-9,
                                        help="Prior probability that a channel steps at it."),
        step_sd: float = typer.Option(0.1, "--step-sd", min=1e-6, max=2.0,
                                      help="Prior sd of a step (log ratio)."),
        strict: bool = STRICT_ADEQUACY,
    ) -> None:
        """Thruster health over many biasing events: P(each thruster down) and since when."""
        from cassini_bayes.api._health import fit_health, read_event_list

        console = stderr_console()
        files = read_event_list(events)
        check_out(out, force=force, inputs=[f[1] for f in files] + [f[2] for f in files])
        t0 = time.perf_counter()
        with console.status(f"summarising {len(files)} events…"):
            res = fit_health(events, spacecraft, fraction=fraction, p_change=p_change,
                             p_channel=p_channel, step_sd=step_sd)
            res.save(out, force=force)
        s = res.summary()
        for line in s.get("warnings", []):
            console.print(f"[yellow]warning:[/yellow] {escape(line)}")
        lo, hi = s["change_date_days"]["interval_90"]
        mark = "[green]✓[/green]" if not failed_checks(s) else "[red]✗[/red]"
        worst = max(s["channels"], key=lambda c: s["channels"][c]["p_down_last"])
        console.print(f"{mark} {s['n_events']} events: P(change) = {s['p_change']:.3f}"
                      f" (90 % date [{lo:.0f}, {hi:.0f}] d), P(a channel > {fraction:.0%} down) "
                      f"= {s['p_down_last']['any']:.3f} (most: {escape(worst)} "
                      f"{s['channels'][worst]['p_down_last']:.3f}){verdict_text(s)}, "
                      f"{time.perf_counter() - t0:.1f} s → {escape(str(out))}")
        enforce_adequacy(s, out, strict=strict, what="the spacecraft model does not fit the "
                         "events", hint="check the spacecraft model's epoch (its inertia) and "
                         "the event named")

    @app.command("simulate-health")
    def simulate_health_cmd(
        campaign: Path = typer.Argument(..., help="Campaign TOML (health_degradation, "
                                        "health_control, …)."),
        out: Path = typer.Option(..., "--out", help="Output directory (written atomically)."),
        seed: int | None = seed_option(None, "Seed of the campaign (default: the file's)."),
        force: bool = typer.Option(False, "--force", help="Replace --out if it is a directory "
                                   "cassini-bayes wrote."),
    ) -> None:
        """Simulate a thruster-health campaign: one folder per event and events.csv."""
        from cassini_bayes.api._health import simulate_health_campaign

        console = stderr_console()
        check_out(out, force=force, inputs=[campaign])
        t0 = time.perf_counter()
        with console.status("simulating the campaign's events (compiling on first use)…"):
            path = simulate_health_campaign(str(campaign), out, seed=seed, force=force)
        console.print(f"[green]✓[/green] {escape(path.name)}: {time.perf_counter() - t0:.1f} s "
                      f"→ {escape(str(out))}")
