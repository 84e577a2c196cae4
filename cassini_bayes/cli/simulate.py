"""``cassini-bayes simulate SCENARIO.toml --out DIR [--seed N] [--force]``.

Writes ``DIR/telemetry.csv`` (noisy telemetry, docs/design.md §4.1), ``DIR/pulses.csv`` (when
thrusters fired) and ``DIR/truth.json`` (every true parameter, the noise levels, the quiet windows
and the noise-free momentum check), atomically: everything is written into a temporary directory
beside ``DIR`` and renamed at the end, so a half-written run never appears under the final name. An
existing ``DIR`` is refused unless ``--force`` (and then only one this package wrote,
:func:`cassini_bayes.rundir.check_out`).
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import jax
import numpy as np
import typer
from rich.console import Console

from cassini_bayes import __version__
from cassini_bayes._paths import text_file
from cassini_bayes.cli._options import check_seed, seed_option
from cassini_bayes.estimators.leak import leak_torque
from cassini_bayes.physics.impulse import THRUSTER_NAMES, moment_matrix
from cassini_bayes.physics.momentum import INERTIA_NAMES
from cassini_bayes.rundir import RunDir, check_out
from cassini_bayes.simulate import SimResult, load_scenario, quiet_windows, simulate
from cassini_bayes.telemetry import write_pulses, write_telemetry

ORDER = 20


def truth_document(result: SimResult, seed: int) -> dict:
    """Everything true about a simulated run, as plain JSON-able data (SI units)."""
    s, p, a = result.scenario, result.params, result.arrays
    h = np.asarray(a.h_inertial)
    drift = float(np.max(np.linalg.norm(h - h[0] - np.asarray(a.impulse_inertial), axis=1))
                  / max(np.linalg.norm(h[0]), 1e-300))
    windows = [{"name": w.name, "t0_s": w.t0_s, "t1_s": w.t1_s, "source": "scenario"}
               for w in s.windows]
    windows += [{"name": f"quiet{i}", "t0_s": t0, "t1_s": t1, "source": "detected"}
                for i, (t0, t1) in enumerate(quiet_windows(result))]
    inertia = dict(zip(INERTIA_NAMES, map(float, np.asarray(p.inertia))))
    return {
        "scenario": s.name,
        "scenario_file": s.source,
        "description": s.description,
        "seed": seed,
        "version": __version__,
        "truth_model": s.truth_model_path,
        "prior_model": s.prior_model_path,
        "inertia_kgm2": inertia,
        "wheels": [{"name": n, "on": bool(on), "axis": [float(x) for x in ax],
                    "inertia_kgm2": float(j),
                    "inertia_error_frac": s.wheel_inertia_scale * (1.0 + e) - 1.0}
                   for n, on, ax, j, e in zip(
                       s.wheel_names, s.wheels_on, s.truth.wheel_axes, s.truth.wheel_inertias,
                       s.wheel_inertia_errors or np.zeros(len(s.wheels_on)))],
        "wheel_inertia_scale": s.wheel_inertia_scale,
        "wheel_inertia_errors": list(s.wheel_inertia_errors),
        "rwa4_axis": ([float(x) for x in s.truth.wheel("RWA4").axis]
                      if "RWA4" in s.wheel_names else None),
        "believed_axes": [list(a) for a in s.rwa.believed_axes],
        "thrust_n": dict(zip(THRUSTER_NAMES, map(float, np.asarray(p.thrust_n)))),
        "tau_delay_s": float(p.tau_s[0]),
        "tau_rise_s": float(p.tau_s[1]),
        "tau_fall_s": float(p.tau_s[2]),
        "external_torque_inertial_nm": [float(x) for x in np.asarray(p.torque_inertial_nm)],
        "external_torque_body_nm": [float(x) for x in np.asarray(p.torque_body_nm)],
        "external_torque_inertial_rate_nm_s": [float(x) for x in
                                               np.asarray(p.torque_inertial_rate_nm_s)],
        "noise": {"gyro_rad_s": s.noise.gyro_rad_s, "star_tracker_rad": s.noise.star_tracker_rad,
                  "tach_noise_rpm": s.noise.tach_noise_rpm,
                  "tach_quantum_rpm": s.noise.tach_quantum_rpm,
                  "gyro_bias_rad_s": list(s.noise.gyro_bias_rad_s),
                  "gyro_scale_factor": list(s.noise.gyro_scale_factor),
                  "time_tag_jitter_s": s.noise.time_tag_jitter_s,
                  "on_time_resolution_s": 0.1},
        "flex_mode": (None if s.flex is None else
                      {"freq_hz": s.flex.freq_hz, "damping": s.flex.damping,
                       "coupling_kg05_m": [float(x) for x in s.flex.coupling]}),
        "run": {"duration_s": s.duration_s, "dt_s": s.dt_s,
                "sample_period_s": s.sample_period_s, "control": s.control},
        "quiet_windows": windows,
        "h_inertial_start_nms": [float(x) for x in h[0]],
        "h_inertial_end_nms": [float(x) for x in h[-1]],
        "thruster_impulse_ns": dict(zip(THRUSTER_NAMES,
                                        map(float, np.asarray(a.thruster_impulse)[-1]))),
        "momentum_balance_rel_error": drift,
        "max_pointing_error_rad": float(np.max(np.linalg.norm(a.pointing_error, axis=1))),
        "n_pulses": 0 if result.pulses is None else int(result.pulses.t_on.size),
        "leak": _leak_document(result),
    }


def _leak_document(result: SimResult) -> dict | None:
    """The scenario's leak and its true torque ``f F_k Q[:, k]`` (N m), or ``None``."""
    s, lk = result.scenario, result.scenario.leak
    if lk is None:
        return None
    th = s.truth.thrusters
    q = np.asarray(moment_matrix(th.Lx, th.Ly, th.Lzy, th.Lzz, th.com))
    thrust = float(np.asarray(result.params.thrust_n)[lk.thruster])
    return {"thruster": THRUSTER_NAMES[lk.thruster], "fraction": lk.fraction,
            "t_start_s": lk.t_start_s, "thrust_n": thrust,
            "torque_nm": [float(x) for x in leak_torque(q, lk.thruster, lk.fraction, thrust)]}


def write_run(result: SimResult, out: Path, seed: int, force: bool = False) -> None:
    """Write a simulated run into ``out`` atomically (:class:`cassini_bayes.rundir.RunDir`)."""
    with RunDir(out, force=force) as rd:
        write_telemetry(rd.path / "telemetry.csv", result.telemetry)
        if result.pulses is not None:
            write_pulses(rd.path / "pulses.csv", result.pulses)
        (rd.path / "truth.json").write_text(json.dumps(truth_document(result, seed), indent=2)
                                            + "\n")


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    @app.command("simulate")
    def simulate_cmd(
        scenario: Path = typer.Argument(..., help="Scenario TOML (experiments/scenarios/…)."),
        out: Path = typer.Option(..., "--out", help="Output directory (written atomically)."),
        seed: int | None = seed_option(None, "Seed of the sensor noise (default: the "
                                       "scenario's)."),
        force: bool = typer.Option(False, "--force", help="Replace --out if it is a directory "
                                   "cassini-bayes wrote."),
    ) -> None:
        """Simulate a scenario: telemetry.csv, pulses.csv (if thrusters fire), truth.json."""
        console = Console(stderr=True, highlight=False)
        text_file(scenario, "scenario")  # a directory or a binary file: one line
        check_out(out, force=force, inputs=[scenario])
        sc = load_scenario(scenario)
        seed_ = check_seed(sc.seed, str(scenario)) if seed is None else seed
        t0 = time.perf_counter()
        with console.status(f"simulating {sc.name}: {sc.n_steps} steps of {sc.dt_s} s, "
                            f"{sc.n_samples} samples (compiling on first use)…"):
            result = simulate(jax.random.key(seed_), sc)
            write_run(result, out, seed_, force)
        n_p = 0 if result.pulses is None else result.pulses.t_on.size
        console.print(f"[green]✓[/green] {sc.name}: {sc.n_samples} samples, {n_p} pulses, "
                      f"{time.perf_counter() - t0:.1f} s → {out}")
