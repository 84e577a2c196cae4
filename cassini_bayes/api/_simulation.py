"""Synthetic telemetry from a scenario: :func:`simulate_scenario`, what ``cassini-bayes simulate``
runs."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cassini_bayes import __version__
from cassini_bayes._devices import jax_entry
from cassini_bayes.estimators.leak import leak_torque
from cassini_bayes.physics.momentum import INERTIA_NAMES
from cassini_bayes.simulate import Scenario, SimResult, quiet_windows
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import PulseLog, Telemetry

__all__ = ["Simulation", "simulate_scenario", "truth_document"]


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
        "thrust_n": dict(zip(s.truth.thruster_names, map(float, np.asarray(p.thrust_n)))),
        # the thrust fit's com_x, com_y, com_z: the true centre of mass minus the prior model's
        "center_of_mass_offset_m": ([float(x) for x in s.truth.com_m - s.prior.com_m]
                                    if s.truth.thrusters else None),
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
        "thruster_impulse_ns": dict(zip(s.truth.thruster_names,
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
    q = s.truth.moment_matrix
    thrust = float(np.asarray(result.params.thrust_n)[lk.thruster])
    return {"thruster": s.truth.thruster_names[lk.thruster], "fraction": lk.fraction,
            "t_start_s": lk.t_start_s, "thrust_n": thrust,
            "torque_nm": [float(x) for x in leak_torque(q, lk.thruster, lk.fraction, thrust)]}


@dataclass(frozen=True)
class Simulation:
    """One simulated run and the seed of its noise.

    Attributes
    ----------
    result : the simulator's :class:`~cassini_bayes.simulate.SimResult` (noise-free truth,
        noisy telemetry, pulse log, raw arrays, true parameters).
    seed : seed of the ``jax.random`` key the run was simulated with.
    """

    result: SimResult
    seed: int

    @property
    def telemetry(self) -> Telemetry:
        """The noisy telemetry, what a calibration sees."""
        return self.result.telemetry

    @property
    def pulses(self) -> PulseLog | None:
        """Every commanded thruster pulse, or ``None`` when none fired."""
        return self.result.pulses

    @property
    def prior(self) -> Spacecraft:
        """The scenario's ``[prior]`` spacecraft model, where a calibration of this run starts
        (its predicted inertia and stated uncertainties, its believed wheels and thrusters)."""
        return self.result.scenario.prior

    def truth(self) -> dict:
        """Everything true about the run (``truth.json``; SI units)."""
        return truth_document(self.result, self.seed)

    def save(self, out: str | os.PathLike, *, force: bool = False) -> Path:
        """Write ``telemetry.csv``, ``pulses.csv`` (when thrusters fired) and ``truth.json`` into
        the directory ``out`` atomically; returns it. ``force=True`` replaces only a directory
        cassini-bayes wrote."""
        from cassini_bayes.rundir import RunDir
        from cassini_bayes.telemetry import write_pulses, write_telemetry

        with RunDir(out, force=force) as rd:
            write_telemetry(rd.path / "telemetry.csv", self.telemetry)
            if self.pulses is not None:
                write_pulses(rd.path / "pulses.csv", self.pulses)
            (rd.path / "truth.json").write_text(json.dumps(self.truth(), indent=2) + "\n")
        return rd.final


@jax_entry
def simulate_scenario(scenario: Scenario | str | os.PathLike, *,
                      seed: int | None = None) -> Simulation:
    """Simulate a scenario: the telemetry, pulse log and truth ``cassini-bayes simulate`` writes.

    Parameters
    ----------
    scenario : a :class:`~cassini_bayes.simulate.Scenario`, a scenario TOML path or the name of
        a shipped one (``"slews_post_probe"``, ``"fsds_biasing"``, ``"rwa4_rcs"`` …).
    seed : seed of the sensor noise (0 .. 2**63 - 1); default the scenario's own.
    """
    import jax

    from cassini_bayes.api._inputs import check_seed
    from cassini_bayes.simulate import load_scenario
    from cassini_bayes.simulate import simulate as run_scenario

    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    seed = check_seed(sc.seed if seed is None else seed)
    return Simulation(run_scenario(jax.random.key(seed), sc), seed)
