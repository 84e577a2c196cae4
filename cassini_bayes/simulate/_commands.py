"""A scenario as the simulation core's inputs: the compile-time constants (:class:`_Config`),
the per-step command plan and the controllers' arrays."""

from __future__ import annotations

from dataclasses import dataclass

import jax.numpy as jnp
import numpy as np
from jax import Array

from cassini_bayes.simulate import controllers as ctl
from cassini_bayes.simulate.scenario import Scenario
from cassini_bayes.units import RPM_TO_RAD_S


@dataclass(frozen=True)
class _Config:
    """Compile-time constants of a scenario (hashable)."""

    n_out: int
    sps: int
    dt: float
    control: str
    thrusters: bool
    on: tuple[bool, ...]
    kp: float
    kd: float
    rate_gain_s: float
    width_gain: float
    max_units: int
    min_off_s: float
    wheel_gain: float
    flex: bool
    leak: bool
    wheel_limits: bool


def _config(s: Scenario) -> _Config:
    wn, z = s.rwa.bandwidth_rad_s, s.rwa.damping
    return _Config(
        n_out=s.n_samples - 1, sps=s.steps_per_sample, dt=s.dt_s, control=s.control,
        thrusters=s.uses_thrusters, on=s.wheels_on, kp=wn * wn, kd=2 * z * wn,
        rate_gain_s=s.rcs.rate_gain_s, width_gain=s.rcs.width_gain_s_per_rad,
        max_units=int(round(s.rcs.max_pulse_s / ctl.COMMAND_RESOLUTION_S)),
        min_off_s=s.rcs.min_off_s, wheel_gain=s.rcs.wheel_rate_gain_per_s,
        flex=s.flex is not None, leak=s.leak is not None,
        wheel_limits=bool(np.isfinite(_wheel_limits(s)).any()))


def _wheel_limits(s: Scenario) -> np.ndarray:
    """(2, k) the truth model's wheel limits: rate (rad/s) and motor torque (N m); inf: none."""
    return np.array([[w.max_speed_rpm * RPM_TO_RAD_S for w in s.truth.wheels],
                     [w.max_torque_nm for w in s.truth.wheels]], float)


def _plan(s: Scenario) -> np.ndarray:
    """Per-step commands (n_out, sps, P): ``cmd(10)`` then, with thrusters, open-loop pulse units
    (m), dead-bands (3), wheel ramp targets (k) and torque limits (k); last, with a leak, each
    thruster's leak fraction averaged over the step (m)."""
    n = s.n_steps
    t = np.arange(n) * s.dt_s
    slews = [(sl.t_start_s, sl.axis, sl.angle_rad, sl.rate_rad_s, sl.accel_rad_s2)
             for sl in s.slews]
    cols = [ctl.command_profile(t, s.q0, slews)]
    m = len(s.truth.thrusters)
    if s.uses_thrusters:
        k = len(s.wheels_on)
        forced = np.zeros((n, m))
        for p in s.pulses:
            i = int(round(p.t_on_s / s.dt_s))
            if i < n:
                forced[i, p.thruster] = max(forced[i, p.thruster],
                                            round(p.width_s / ctl.COMMAND_RESOLUTION_S))
        db = np.broadcast_to(np.asarray(s.rcs.deadband_rad), (n, 3)).copy()
        for c in s.deadbands:
            db[t >= c.t_s - 1e-9] = c.deadband_rad
        target = np.zeros((n, k))
        tmax = np.zeros((n, k))
        for r in sorted(s.wheel_ramps, key=lambda r: r.t_start_s):
            m = t >= r.t_start_s - 1e-9
            target[m, r.wheel] = r.target_rad_s
            tmax[m, r.wheel] = r.torque_nm
        cols += [forced, db, target, tmax]
    if s.leak is not None:
        leak = np.zeros((n, m))
        # the share of each step after the onset, so the leak impulse is exact
        leak[:, s.leak.thruster] = s.leak.fraction * np.clip(
            (t + s.dt_s - s.leak.t_start_s) / s.dt_s, 0.0, 1.0)
        cols.append(leak)
    plan = np.concatenate(cols, axis=1)
    return plan.reshape(s.n_samples - 1, s.steps_per_sample, -1)


def _sample_commands(s: Scenario) -> np.ndarray:
    """Commanded ``[q, ω, α]`` (n_samples, 10) at the telemetry times (for the pointing error)."""
    slews = [(sl.t_start_s, sl.axis, sl.angle_rad, sl.rate_rad_s, sl.accel_rad_s2)
             for sl in s.slews]
    return ctl.command_profile(np.arange(s.n_samples) * s.sample_period_s, s.q0, slews)


def believed_allocation(s: Scenario, axes) -> dict[str, Array]:
    """The RWA controller's ``axes_believed`` (..., k, 3), the wheels that are off zeroed, and
    their torque allocation ``axes_pinv`` (..., k, 3), the pseudo-inverse of the axes as columns;
    ``axes`` may carry a leading batch axis (one set per replicate)."""
    believed = np.asarray(axes, float) * np.asarray(s.wheels_on, float)[:, None]
    return {"axes_believed": jnp.asarray(believed),
            "axes_pinv": jnp.asarray(np.linalg.pinv(np.swapaxes(believed, -1, -2)))}


def _controller_arrays(s: Scenario) -> dict[str, Array]:
    on = np.array(s.wheels_on, float)
    limits = _wheel_limits(s)
    return {
        "inertia_ctrl": jnp.asarray(s.prior.inertia),
        **believed_allocation(s, s.rwa.believed_axes),
        "wheel_j_ctrl": jnp.asarray(s.prior.wheel_inertias * on),
        "q_matrix": jnp.asarray(s.truth.moment_matrix),
        "sets": jnp.asarray(ctl.thruster_sets(s.prior) if s.control == "rcs"
                            else np.zeros((3, 2, len(s.truth.thrusters)))),
        "wheel_rate_max": jnp.asarray(limits[0]),
        "wheel_torque_max": jnp.asarray(limits[1]),
        "q0": jnp.asarray(s.q0),
        "w0": jnp.asarray(s.rates0_rad_s),
        "rho0": jnp.asarray(s.wheel0_rad_s),
        "cmd_samples": jnp.asarray(_sample_commands(s)),
    }
