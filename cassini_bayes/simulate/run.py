"""Run a scenario: closed-loop dynamics + controllers + sensors, one compiled ``lax.scan``.

``simulate(key, scenario) -> SimResult`` gives the truth and the noisy telemetry as the package's
containers; ``simulate_batch(keys, scenario, truth=None)`` runs many replicates as one compiled,
vmapped call and returns raw arrays (:class:`SimArrays` with a leading batch axis). The true
parameters (:class:`TruthParams`: inertia, wheel axes incl. RWA4, thrust, pulse time constants,
external torques) and the noise levels are traced inputs, so simulation-based calibration can vmap
over prior draws without recompiling; only the scenario's shape and its controller settings are
compile-time constants.

Internals: the run is ``n_samples − 1`` telemetry periods, each ``steps_per_sample`` fixed steps
of :func:`cassini_bayes.physics.dynamics.step`. Controllers act once per step (zero-order hold;
the RCS controller on the 1/8 s command grid). Each thruster keeps a ring of its last
:data:`PULSE_RING` pulses; the impulse of a step is the exact integral of the pulse profile over
the step, ``F [g(t+dt − t_on) − g(t − t_on)]`` with ``g`` = :func:`pulse_impulse_until`.
The controllers see the true state (the on-board attitude estimate is taken as perfect; its
errors are far below the star-tracker noise put on the telemetry), while they use the *prior*
model's inertia and thruster sets and the *believed* wheel axes. Sensor noise is added to the samples afterwards,
so the noisy telemetry and the truth come from one trajectory; with time-tag jitter the noisy
telemetry carries the jittered times (``SimArrays.t_meas``), the truth the true ones.

Flexible or slosh mode (:class:`~cassini_bayes.simulate.scenario.FlexMode`): in hybrid
coordinates the mode is a momentum store exactly like a wheel — spin inertia ``|δ|²`` about
``δ/|δ|``, relative rate ``η̇/|δ|`` and absolute momentum ``p = |δ| (η̇ + δ·ω)`` — whose
"motor torque" is its spring and damper, ``ṗ = −|δ| (Ω² η + 2ζΩ η̇)``. It rides in the
integrator as one extra wheel (so ``H_N`` stays exactly conserved), the torque evaluated at
``η + η̇ dt/2`` and ``η`` advanced by the trapezoid rule: a second-order, area-preserving step,
stable for ``Ω dt < 2`` (the scenario asks ``Ω dt ≤ 0.5``). The mode never shows in the wheel
telemetry.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from cassini_bayes._devices import require_x64
from cassini_bayes.physics import dynamics
from cassini_bayes.physics.momentum import inertia_matrix, inertia_vector
from cassini_bayes.physics.pulse import pulse_impulse_until
from cassini_bayes.simulate import controllers as ctl
from cassini_bayes.simulate.scenario import Scenario, check_size
from cassini_bayes.simulate.sensors import NoiseParams, measure, time_tags
from cassini_bayes.spacecraft import tilted_axis
from cassini_bayes.telemetry import PulseLog, Telemetry
from cassini_bayes.units import RPM_TO_RAD_S

__all__ = ["TruthParams", "SimArrays", "SimResult", "truth_params", "noise_params", "simulate",
           "simulate_arrays", "simulate_batch", "pulse_log", "quiet_windows", "PULSE_RING",
           "trace_count", "with_errors"]

PULSE_RING = 6           # pulses remembered per thruster (older tails are < 1e-8 of a pulse)
_TRACES = [0]            # incremented each time the core is traced (compile-once test)
QUIET_TORQUE_KNOWLEDGE = 10.0
"""A wheel is busy (biasing) in :func:`quiet_windows` while its motor torque exceeds this many
times the truth model's ``[torque_knowledge] sd_nm``: more than holding the attitude against the
environment takes (Cassini: 1.5e-4 N m)."""
_IMPULSE_RTOL = 1e-9      # a thruster fires while its impulse grows by this × the run's largest step


def trace_count() -> int:
    """How many times the simulation core has been traced (for recompilation tests)."""
    return _TRACES[0]


class TruthParams(NamedTuple):
    """True parameters of a run (all traceable arrays; SI units).

    inertia : (6,) ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)`` kg m², incl. wheels.
    wheel_axes : (k, 3) true unit spin axes (RWA4 wherever it really is).
    wheel_inertias : (k,) spin inertias, kg m² (0 for a wheel that is off).
    thrust_n : (m,) steady thrust per thruster of the truth model (Cassini: ``Z1 … Y4``), N.
    tau_s : (3,) ``(tau_delay, tau_rise, tau_fall)``, s.
    torque_inertial_nm : (3,) external torque at t = 0, inertial axes, N m.
    torque_body_nm : (3,) constant external torque, body axes, N m.
    torque_inertial_rate_nm_s : (3,) slow linear change of the inertial torque, N m/s
        (``T_N(t) = T_N + Ṫ_N t``, integrated exactly).
    flex_freq_rad_s, flex_damping, flex_coupling : the flexible/slosh mode's ``Ω`` (rad/s), ``ζ``
        and ``δ`` (3,) kg^½ m (zeros, and ignored, when the scenario has no mode).
    """

    inertia: Array
    wheel_axes: Array
    wheel_inertias: Array
    thrust_n: Array
    tau_s: Array
    torque_inertial_nm: Array
    torque_body_nm: Array
    torque_inertial_rate_nm_s: Array
    flex_freq_rad_s: Array
    flex_damping: Array
    flex_coupling: Array


class SimArrays(NamedTuple):
    """Raw simulation output; leading axis = samples (and a batch axis first when batched).

    t : (n,) s. q, omega, wheel_rates : true attitude, body rate (rad/s), wheel rates (rad/s).
    q_meas, omega_meas, wheel_rates_meas : the same through the sensors.
    h_inertial : (n, 3) true total inertial momentum, N m s.
    impulse_inertial : (n, 3) cumulative angular impulse of the body-fixed torques (thrusters and
        body-axis external torque) in inertial axes, N m s.
    impulse_body : (n, 3) the same accumulated in body axes (no rotation), N m s.
    thruster_impulse : (n, m) cumulative impulse of each thruster, N s.
    on_times : (n, m) cumulative commanded on-time, s.
    pointing_error : (n, 3) attitude error w.r.t. the command, rad.
    pulse_units : (n_steps, m) int8 widths (units of 1/8 s) commanded at each step (empty when
        the scenario fires no thrusters).
    t_meas : (n,) recorded (time-tag-jittered) sample times, s; equal to ``t`` without jitter.
    flex_eta : (n,) modal coordinate ``η`` of the flexible/slosh mode, kg^½ m (zeros without).
    """

    t: Array
    q: Array
    omega: Array
    wheel_rates: Array
    q_meas: Array
    omega_meas: Array
    wheel_rates_meas: Array
    h_inertial: Array
    impulse_inertial: Array
    impulse_body: Array
    thruster_impulse: Array
    on_times: Array
    pointing_error: Array
    pulse_units: Array
    t_meas: Array
    flex_eta: Array


@dataclass(frozen=True)
class SimResult:
    """One simulated run as the package's containers (NumPy, SI units).

    truth : noise-free :class:`Telemetry` (on-times included when thrusters can fire).
    telemetry : noisy :class:`Telemetry`, what a calibration sees.
    pulses : :class:`PulseLog` of every commanded pulse, or ``None`` when none fired.
    arrays : the raw :class:`SimArrays` (momentum, impulses, pointing error …).
    params : the :class:`TruthParams` used.
    """

    scenario: Scenario
    truth: Telemetry
    telemetry: Telemetry
    pulses: PulseLog | None
    arrays: SimArrays
    params: TruthParams


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


def truth_params(scenario: Scenario) -> TruthParams:
    """The scenario's true parameters as arrays."""
    sc = scenario.truth
    on = np.array(scenario.wheels_on, float)
    fm = scenario.flex
    return TruthParams(
        inertia=jnp.asarray(inertia_vector(sc.inertia)),
        wheel_axes=jnp.asarray(sc.wheel_axes),
        wheel_inertias=jnp.asarray(sc.wheel_inertias * on),
        thrust_n=jnp.asarray(scenario.thrust_n),
        tau_s=jnp.asarray([sc.pulse.tau_delay, sc.pulse.tau_rise, sc.pulse.tau_fall]),
        torque_inertial_nm=jnp.asarray(scenario.external_torque_inertial_nm),
        torque_body_nm=jnp.asarray(scenario.external_torque_body_nm),
        torque_inertial_rate_nm_s=jnp.asarray(scenario.external_torque_inertial_rate_nm_s),
        flex_freq_rad_s=jnp.asarray(0.0 if fm is None else 2.0 * np.pi * fm.freq_hz),
        flex_damping=jnp.asarray(0.0 if fm is None else fm.damping),
        flex_coupling=jnp.asarray(np.zeros(3) if fm is None else fm.coupling),
    )


def noise_params(scenario: Scenario) -> NoiseParams:
    """The scenario's noise levels as arrays."""
    n = scenario.noise
    return NoiseParams(*(jnp.asarray(float(x)) for x in
                         (n.gyro_rad_s, n.star_tracker_rad, n.tach_quantum_rpm,
                          n.tach_noise_rpm)),
                       gyro_bias_rad_s=jnp.asarray(n.gyro_bias_rad_s, float),
                       gyro_scale_factor=jnp.asarray(n.gyro_scale_factor, float),
                       time_tag_jitter_s=jnp.asarray(float(n.time_tag_jitter_s)))


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


def _controller_arrays(s: Scenario) -> dict[str, Array]:
    on = np.array(s.wheels_on, float)
    believed = np.asarray(s.rwa.believed_axes) * on[:, None]
    limits = _wheel_limits(s)
    return {
        "inertia_ctrl": jnp.asarray(s.prior.inertia),
        "axes_believed": jnp.asarray(believed),
        "axes_pinv": jnp.asarray(np.linalg.pinv(believed.T)),
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


def _plant(truth: TruthParams, cfg: _Config):
    """The true plant — with the flexible/slosh mode as one more wheel when the scenario has one
    (module docstring) — and ``|δ|`` (1.0 without a mode)."""
    inertia = inertia_matrix(truth.inertia)
    if not cfg.flex:
        return dynamics.make_plant(inertia, truth.wheel_axes, truth.wheel_inertias), 1.0
    d = truth.flex_coupling
    dn = jnp.sqrt(jnp.sum(d * d))
    axis = d / jnp.where(dn > 0, dn, 1.0)
    plant = dynamics.make_plant(inertia, jnp.concatenate([truth.wheel_axes, axis[None]], 0),
                                jnp.concatenate([truth.wheel_inertias, (dn * dn)[None]]))
    return plant, dn


def _simulate_core(key, truth: TruthParams, noise: NoiseParams, plan, carr, cfg: _Config):
    _TRACES[0] += 1
    dt = cfg.dt
    k = truth.wheel_axes.shape[0]
    m = carr["q_matrix"].shape[1]        # thrusters of the truth model
    on = jnp.asarray(cfg.on)
    plant, d_norm = _plant(truth, cfg)
    rho0 = jnp.concatenate([carr["rho0"], jnp.zeros(1)]) if cfg.flex else carr["rho0"]
    state0 = dynamics.state_from_rates(carr["q0"], carr["w0"], rho0, plant)
    td, tr, tf = truth.tau_s[0], truth.tau_s[1], truth.tau_s[2]
    w_flex, z_flex = truth.flex_freq_rad_s, truth.flex_damping

    def eta_rate(state, omega):
        # η̇ = |δ| × the mode's "wheel rate" ρ_mode = η̇ / |δ|
        return d_norm * dynamics.wheel_rates(state, plant, omega)[k]

    def one_step(carry, xs):
        state, ring_t, ring_w, ring_g, free_at, cum_on, cum_thr, cum_b, cum_n, eta = carry
        i, row = xs
        t = i * dt
        cmd = row[:10]
        omega = dynamics.body_rate(state, plant)
        rho = dynamics.wheel_rates(state, plant, omega)[:k]
        if cfg.control == "rwa":
            u = ctl.rwa_wheel_torques(state.q, omega, rho, cmd, carr["inertia_ctrl"],
                                      carr["axes_believed"], carr["axes_pinv"],
                                      carr["wheel_j_ctrl"], cfg.kp, cfg.kd)
        else:
            u = ctl.wheel_ramp_torques(rho, row[13 + m:13 + m + k],
                                       row[13 + m + k:13 + m + 2 * k], truth.wheel_inertias,
                                       cfg.wheel_gain)
        if cfg.wheel_limits:
            u = ctl.limit_wheel_torques(u, rho, carr["wheel_rate_max"],
                                        carr["wheel_torque_max"])
        u = jnp.where(on, u, 0.0)
        body_imp = truth.torque_body_nm * dt
        if cfg.thrusters:
            forced = row[10:10 + m]
            units = forced
            if cfg.control == "rcs":
                free = t >= free_at - 1e-9
                auto = ctl.rcs_commands(state.q, omega, cmd, row[10 + m:13 + m], free,
                                        carr["sets"],
                                        cfg.rate_gain_s, cfg.width_gain, cfg.max_units)
                units = jnp.maximum(units, auto)
            fire = units > 0
            width = units * ctl.COMMAND_RESOLUTION_S
            ring_t = jnp.where(fire[:, None], jnp.concatenate(
                [jnp.full((m, 1), t), ring_t[:, :-1]], 1), ring_t)
            ring_w = jnp.where(fire[:, None], jnp.concatenate(
                [width[:, None], ring_w[:, :-1]], 1), ring_w)
            ring_g = jnp.where(fire[:, None], jnp.concatenate(
                [jnp.zeros((m, 1)), ring_g[:, :-1]], 1), ring_g)
            free_at = jnp.where(fire, t + width + cfg.min_off_s, free_at)
            # Exact impulse of each pulse over [t, t + dt] (Feldman & Lee §V profile):
            # g(t + dt − t_on) − g(t − t_on), the second term carried from the previous step.
            # Skipped (exactly: the carried g makes a later difference catch up) while every
            # remembered pulse is over and its tail below e^-40.
            busy = jnp.any(t + dt < ring_t + ring_w + td + 40.0 * tf)

            def pulse_step(ring_g):
                g1 = pulse_impulse_until(t + dt - ring_t, ring_w, td, tr, tf)
                over = jnp.clip(jnp.minimum(t + dt, ring_t + ring_w) - jnp.maximum(t, ring_t),
                                0.0)
                return truth.thrust_n * jnp.sum(g1 - ring_g, axis=1), g1, jnp.sum(over, axis=1)

            def idle(ring_g):
                return jnp.zeros(m), ring_g, jnp.zeros(m)

            j_step, ring_g, on_step = jax.lax.cond(busy, pulse_step, idle, ring_g)  # (m,) N s
            cum_on = cum_on + on_step
            cum_thr = cum_thr + j_step
            body_imp = body_imp + carr["q_matrix"] @ j_step                      # Eq 16
            out_units = units.astype(jnp.int8)
        else:
            out_units = jnp.zeros((m,), jnp.int8)[:0]
        if cfg.leak:
            # stuck-open valve (Lee §3.2): f F_k of thrust, torque f F_k Q[:, k] (Eq 16)
            body_imp = body_imp + carr["q_matrix"] @ (truth.thrust_n * row[-m:] * dt)
        # linear-in-time inertial torque: its mean over the step is its value at mid-step
        t_n = truth.torque_inertial_nm + truth.torque_inertial_rate_nm_s * (t + 0.5 * dt)
        if cfg.flex:
            # The mode's spring and damper, ṗ = −|δ| (Ω² η + 2ζΩ η̇), at η + η̇ dt/2.
            eta_dot = eta_rate(state, omega)
            u_mode = -d_norm * (w_flex * w_flex * (eta + 0.5 * dt * eta_dot)
                                + 2.0 * z_flex * w_flex * eta_dot)
            u = jnp.concatenate([u, u_mode[None]])
        state, imp_n = dynamics.step(state, plant, dt, u, body_imp, t_n)
        if cfg.flex:
            eta = eta + 0.5 * dt * (eta_dot + eta_rate(state, dynamics.body_rate(state, plant)))
        carry = (state, ring_t, ring_w, ring_g, free_at, cum_on, cum_thr, cum_b + body_imp,
                 cum_n + imp_n, eta)
        return carry, out_units

    def one_sample(carry, xs):
        j, rows, cmd_end = xs
        idx = j * cfg.sps + jnp.arange(cfg.sps)
        carry, units = jax.lax.scan(one_step, carry, (idx, rows))
        return carry, (_observe(carry, cmd_end), units)

    def _observe(carry, cmd):
        state = carry[0]
        omega = dynamics.body_rate(state, plant)
        rho = jnp.where(on, dynamics.wheel_rates(state, plant, omega)[:k], jnp.nan)
        err = ctl.attitude_error(state.q, cmd[:4])
        return (state.q, omega, rho, state.h_inertial, carry[8], carry[7], carry[6], carry[5],
                err, carry[9])

    zm = jnp.zeros(m)
    carry0 = (state0, jnp.full((m, PULSE_RING), -1e9), jnp.zeros((m, PULSE_RING)),
              jnp.zeros((m, PULSE_RING)), jnp.full(m, -1.0), zm, zm, jnp.zeros(3), jnp.zeros(3),
              jnp.zeros(()))
    obs0 = _observe(carry0, carr["cmd_samples"][0])
    _, (obs, units) = jax.lax.scan(one_sample, carry0, (jnp.arange(cfg.n_out), plan,
                                                         carr["cmd_samples"][1:]))
    cols = [jnp.concatenate([o0[None], o], 0) for o0, o in zip(obs0, obs)]
    q, omega, rho, h_n, imp_n, imp_b, thr, on_t, err, eta = cols
    q_m, w_m, rho_m = measure(key, q, omega, rho, noise)
    t = jnp.arange(cfg.n_out + 1) * (cfg.sps * dt)
    t_m = time_tags(jax.random.fold_in(key, 1), t, noise)   # own stream: q/ω/ρ noise unchanged
    return SimArrays(t, q, omega, rho, q_m, w_m, rho_m, h_n, imp_n, imp_b, thr, on_t, err,
                     units.reshape(-1, m) if cfg.thrusters else jnp.zeros((0, m), jnp.int8),
                     t_m, eta)


_core_jit = jax.jit(_simulate_core, static_argnames=("cfg",))


def _batch_core(keys, truth, noise, plan, carr, cfg, truth_batched, noise_batched=False):
    # A shared truth stays unbatched: its mass properties are then hoisted out of the vmapped
    # loop, ~10x faster than carrying one copy per replicate.
    axes = 0 if truth_batched else None
    return jax.vmap(_simulate_core, in_axes=(0, axes, 0 if noise_batched else None, None,
                                             None, None))(keys, truth, noise, plan, carr, cfg)


_batch_jit = jax.jit(_batch_core, static_argnames=("cfg", "truth_batched", "noise_batched"))


_PREPARED: dict[int, tuple] = {}   # id(scenario) → (scenario, plan, controller arrays), a few


def _prepared(s: Scenario):
    """Plan and controller arrays of a scenario, cached for the last few scenarios used."""
    hit = _PREPARED.get(id(s))
    if hit is not None and hit[0] is s:
        return hit[1], hit[2]
    check_size(s)  # before the (n_steps, P) plan is allocated
    plan, carr = jnp.asarray(_plan(s)), _controller_arrays(s)
    if len(_PREPARED) >= 8:
        _PREPARED.pop(next(iter(_PREPARED)))
    _PREPARED[id(s)] = (s, plan, carr)
    return plan, carr


def simulate_arrays(key: Array, scenario: Scenario, truth: TruthParams | None = None,
                    noise: NoiseParams | None = None) -> SimArrays:
    """One run as raw arrays (compiled once per scenario shape); ``truth``: the file's."""
    require_x64("simulate")
    truth = truth_params(scenario) if truth is None else truth
    noise = noise_params(scenario) if noise is None else noise
    plan, carr = _prepared(scenario)
    return _core_jit(key, truth, noise, plan, carr, cfg=_config(scenario))


def simulate_batch(keys: Array, scenario: Scenario, truth: TruthParams | None = None,
                   noise: NoiseParams | None = None, *, noise_batched: bool = False) -> SimArrays:
    """Replicates of a scenario as one compiled, vmapped call.

    Parameters
    ----------
    keys : (b,) jax.random keys, one per replicate (sensor noise).
    scenario : the scenario.
    truth : optional :class:`TruthParams` with a leading batch axis (b, ...) to vary the true
        parameters per replicate (e.g. prior draws for SBC); default: the scenario's, shared.
        New draws of the same shape reuse the compiled program (no recompilation).
    noise : optional noise levels and sensor errors, shared; with ``noise_batched`` every field
        has a leading batch axis (b, ...), one set per replicate (e.g. gyro biases drawn for SBC).

    Returns
    -------
    :class:`SimArrays` with a leading batch axis.
    """
    require_x64("simulate")
    batched = truth is not None
    truth = truth_params(scenario) if truth is None else truth
    noise = noise_params(scenario) if noise is None else noise
    plan, carr = _prepared(scenario)
    return _batch_jit(keys, truth, noise, plan, carr, cfg=_config(scenario),
                      truth_batched=batched, noise_batched=noise_batched)


def with_errors(scenario: Scenario, truth: TruthParams, noise: NoiseParams, *,
                wheel_scale: dict | None = None, wheel_tilt_rad: dict | None = None,
                gyro_bias_rad_s=None, gyro_scale_factor=None) -> tuple[TruthParams, NoiseParams]:
    """``truth`` and ``noise`` of one run with the sensor and wheel errors the robust models'
    nuisance parameters describe (:mod:`cassini_bayes.inference.nuisance`), relative to the
    ``[prior]`` model, the reference those parameters are errors of.

    ``wheel_scale`` (wheel name → ``c_k``): that wheel's true spin inertia is ``(1 + c_k) J_k``
    with ``J_k`` the prior model's (zero while the wheel is off); ``wheel_tilt_rad`` (name →
    ``(a_k1, a_k2)``): its true axis is the prior model's tilted along
    :func:`~cassini_bayes.spacecraft.wheel_tilt_basis` (an articulated wheel the scenario has moved
    off its model axis stays where the scenario put it); ``gyro_bias_rad_s`` (3,) and
    ``gyro_scale_factor`` (3,): ``ω_meas = (1 + s) ω + b + noise``. Wheels not named keep the
    scenario's truth. NumPy, one run: the campaigns stack the results over replicates.
    """
    prior = scenario.prior
    on = dict(zip(scenario.wheel_names, scenario.wheels_on))
    axes = np.array(truth.wheel_axes, float)
    inertias = np.array(truth.wheel_inertias, float)
    for name, c in (wheel_scale or {}).items():
        k = scenario.wheel_names.index(name)
        inertias[k] = prior.wheel(name).inertia * (1.0 + float(c)) * float(on[name])
    for name, tilt in (wheel_tilt_rad or {}).items():
        k, w = scenario.wheel_names.index(name), prior.wheel(name)
        if not w.articulated or np.allclose(axes[k], w.axis):
            axes[k] = tilted_axis(w.axis, tilt)
    truth = truth._replace(wheel_axes=jnp.asarray(axes), wheel_inertias=jnp.asarray(inertias))
    if gyro_bias_rad_s is not None:
        noise = noise._replace(gyro_bias_rad_s=jnp.asarray(gyro_bias_rad_s, float))
    if gyro_scale_factor is not None:
        noise = noise._replace(gyro_scale_factor=jnp.asarray(gyro_scale_factor, float))
    return truth, noise


def _telemetry(s: Scenario, t, q, w, rho, on_times, source) -> Telemetry:
    return Telemetry(t=np.asarray(t), q=np.asarray(q), omega=np.asarray(w),
                     wheel_rates=np.asarray(rho), wheel_names=s.wheel_names,
                     on_times=np.asarray(on_times) if s.uses_thrusters else None, source=source,
                     thruster_names=s.truth.thruster_names)


def pulse_log(arrays: SimArrays, scenario: Scenario) -> PulseLog | None:
    """The commanded pulses of one run (``None`` when none fired)."""
    units = np.asarray(arrays.pulse_units)
    if units.size == 0 or not units.any():
        return None
    step, thr = np.nonzero(units)
    order = np.lexsort((thr, step))
    step, thr = step[order], thr[order]
    return PulseLog(t_on=step * scenario.dt_s, thruster=thr.astype(int),
                    width=units[step, thr].astype(float) * ctl.COMMAND_RESOLUTION_S,
                    source=f"<simulated {scenario.name}>",
                    thruster_names=scenario.truth.thruster_names)


def simulate(key: Array, scenario: Scenario, truth: TruthParams | None = None) -> SimResult:
    """Simulate a scenario: the truth beside the noisy telemetry and the pulse log.

    Parameters
    ----------
    key : jax.random key for the sensor noise.
    scenario : a loaded :class:`Scenario`.
    truth : optional override of the true parameters.
    """
    params = truth_params(scenario) if truth is None else truth
    arr = jax.tree_util.tree_map(np.asarray, simulate_arrays(key, scenario, params))
    src = f"<simulated {scenario.name}>"
    tel_truth = _telemetry(scenario, arr.t, arr.q, arr.omega, arr.wheel_rates, arr.on_times, src)
    tel = _telemetry(scenario, arr.t_meas, arr.q_meas, arr.omega_meas, arr.wheel_rates_meas,
                     arr.on_times, src)
    return SimResult(scenario, tel_truth, tel, pulse_log(arr, scenario), arr, params)


def quiet_windows(result: SimResult, settle_s: float = 120.0,
                  min_length_s: float = 120.0) -> list[tuple[float, float]]:
    """Quiet windows ``[(t0, t1), …]`` of a run: no slew commanded, no wheel biasing (wheel
    torques below :data:`QUIET_TORQUE_KNOWLEDGE` × the model's external-torque knowledge), no
    thruster impulse, at least ``settle_s`` after any of them, and at least ``min_length_s``
    long. Computed from the truth."""
    a, s = result.arrays, result.scenario
    t = np.asarray(a.t)
    active = np.zeros(t.size, bool)
    for sl in s.slews:
        active |= (t >= sl.t_start_s) & (t <= sl.t_end_s)
    j = np.asarray(result.params.wheel_inertias)
    rho = np.nan_to_num(np.asarray(a.wheel_rates))
    torque = np.abs(np.diff(rho, axis=0)) * j / np.diff(t)[:, None]
    busy = np.any(torque > QUIET_TORQUE_KNOWLEDGE * s.truth.knowledge.torque_sd_nm, axis=1)
    step = np.abs(np.diff(np.asarray(a.thruster_impulse), axis=0))
    imp = np.any(step > _IMPULSE_RTOL * step.max(initial=0.0), axis=1)
    active[1:] |= busy | imp
    active[:-1] |= busy | imp
    # grow the activity by the settling time
    last = np.where(active, t, -np.inf)
    last = np.maximum.accumulate(last)
    quiet = ~active & (t - last > settle_s)
    out = []
    i = 0
    while i < t.size:
        if quiet[i]:
            k = i
            while k + 1 < t.size and quiet[k + 1]:
                k += 1
            if t[k] - t[i] >= min_length_s:
                out.append((float(t[i]), float(t[k])))
            i = k + 1
        else:
            i += 1
    return out
