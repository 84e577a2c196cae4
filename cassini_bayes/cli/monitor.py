"""``cassini-bayes monitor leak TELEMETRY [--pulses PULSES] --spacecraft MODEL --out DIR``.

Runs the Bayesian thruster-leak monitor (:mod:`cassini_bayes.inference.leak`) and Lee's threshold
monitor (:func:`cassini_bayes.estimators.leak.threshold_monitor`) over one telemetry stretch and
writes, atomically (:class:`cassini_bayes.rundir.RunDir`), ``DIR/summary.json`` (the posterior
probability of each hypothesis ``none, Z1 … Y4`` at the last sample, the detection time and
thruster of both monitors, the leak fraction and torque), ``DIR/probabilities.csv`` (the
probabilities at every check) and ``DIR/config.toml`` (inputs with their SHA-256, settings,
version). docs/leak.md describes the model.
"""

from __future__ import annotations

import time
from pathlib import Path

import typer
from rich.console import Console

from cassini_bayes import __version__
from cassini_bayes.errors import InputError
from cassini_bayes.rundir import RunDir, check_out, file_record, write_config, write_summary

ORDER = 60


def _positive(value: float, option: str) -> float:
    if not value > 0:
        raise InputError(f"must be positive, got {value}", path=option)
    return value


def run_leak_monitor(telemetry: Path, pulses: Path | None, spacecraft: str, out: Path, *,
                     force: bool = False, prior_leak: float = 0.01, p_detect: float = 0.99,
                     sample_step_s: float = 60.0, check_step_s: float = 60.0,
                     onset_step_s: float = 20.0,
                     eta: float = 0.05, threshold_nms: float = 50.0,
                     t_limit_h: float = 10.0) -> dict:
    """Both monitors on one stretch; writes ``out`` and returns the summary."""
    import numpy as np

    from cassini_bayes._paths import model_path
    from cassini_bayes.estimators.leak import threshold_monitor
    from cassini_bayes.inference.leak import HYPOTHESES, leak_inputs, leak_posterior
    from cassini_bayes.physics.impulse import THRUSTER_NAMES
    from cassini_bayes.spacecraft import load_spacecraft
    from cassini_bayes.telemetry import read_pulses, read_telemetry

    for value, option in ((sample_step_s, "--sample-step"), (check_step_s, "--check-step"),
                          (onset_step_s, "--onset-step"),
                          (threshold_nms, "--threshold"), (t_limit_h, "--t-limit")):
        _positive(value, option)
    if eta < 0:
        raise InputError(f"must not be negative, got {eta}", path="--eta")
    inputs = [telemetry] + ([pulses] if pulses is not None else [])
    check_out(out, force=force, inputs=inputs)
    sc = load_spacecraft(spacecraft)
    tel = read_telemetry(telemetry)
    log = read_pulses(pulses) if pulses is not None else None
    inp = leak_inputs(tel, log, sc)
    post = leak_posterior(inp, prior_leak=prior_leak, eta=eta, sample_step_s=sample_step_s,
                          check_step_s=check_step_s, onset_step_s=onset_step_s,
                          p_detect=p_detect)
    lee = threshold_monitor(inp.t, inp.residual, inp.impulse, inp.q_matrix, r_t_nms=threshold_nms,
                            t_limit_s=t_limit_h * 3600.0, eta=eta)
    summary = {
        "command": "monitor leak", "version": __version__,
        "t_start_s": float(inp.t[0]), "t_end_s": float(inp.t[-1]),
        "bayes": post.summary(),
        "lee": {"detection_time_s": lee.detection_time_s,
                "axis": None if lee.axis is None else "XYZ"[lee.axis],
                "thruster": None if lee.thruster is None else THRUSTER_NAMES[lee.thruster],
                "triggers_s": list(lee.triggers_s), "dismissed_s": list(lee.dismissed_s),
                "threshold_nms": threshold_nms, "t_limit_s": t_limit_h * 3600.0, "eta": eta},
        "residual_end_nms": [float(x) for x in inp.residual[-1]],
    }
    config = {"command": "monitor leak", "version": __version__,
              "inputs": {"telemetry": file_record(telemetry),
                         "spacecraft": file_record(model_path(spacecraft)),
                         **({"pulses": file_record(pulses)} if pulses is not None else {})},
              "settings": {"prior_leak": prior_leak, "p_detect": p_detect,
                           "sample_step_s": sample_step_s,
                           "check_step_s": check_step_s, "onset_step_s": onset_step_s,
                           "eta": eta, "threshold_nms": threshold_nms, "t_limit_h": t_limit_h}}
    with RunDir(out, force=force, inputs=inputs) as rd:
        write_summary(rd.path, summary)
        write_config(rd.path, config)
        table = np.column_stack([post.t_check, post.prob])
        np.savetxt(rd.path / "probabilities.csv", table, delimiter=",", fmt="%.10g",
                   header="t_s," + ",".join(f"p_{h}" for h in HYPOTHESES), comments="")
    return summary


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
        onset_step: float = typer.Option(20.0, "--onset-step",
                                         help="Onset grid spacing, s."),
        eta: float = typer.Option(0.05, "--eta", help="Thruster-to-thruster variation "
                                  "(fraction, Lee Eq 11)."),
        threshold: float = typer.Option(50.0, "--threshold", help="Lee's R_T, N m s."),
        t_limit: float = typer.Option(10.0, "--t-limit", help="Lee's T_limit, hours."),
    ) -> None:
        """Posterior probability of a leak per thruster, beside Lee's threshold monitor."""
        console = Console(stderr=True, highlight=False)
        t0 = time.perf_counter()
        s = run_leak_monitor(telemetry, pulses, spacecraft, out, force=force,
                             prior_leak=prior_leak, p_detect=p_detect,
                             sample_step_s=sample_step, check_step_s=check_step,
                             onset_step_s=onset_step, eta=eta, threshold_nms=threshold,
                             t_limit_h=t_limit)
        b, lee = s["bayes"], s["lee"]
        said = (f"leak in {b['thruster']} at {b['isolation_time_s']:.0f} s"
                if b["thruster"] else "leak, thruster not isolated" if b["detection_time_s"]
                else "no leak")
        console.print(f"[green]✓[/green] P(leak) = {b['p_leak']:.3g}: {said}; Lee: "
                      + (f"{lee['thruster']} at {lee['detection_time_s']:.0f} s"
                         if lee["thruster"] else "no trigger")
                      + f" ({time.perf_counter() - t0:.1f} s) → {out}")
