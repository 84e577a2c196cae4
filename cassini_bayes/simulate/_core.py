"""The simulation core: one compiled ``lax.scan`` of closed-loop dynamics, controllers and
sensors over a run (:func:`_simulate_core`), and its vmapped batch.

Internals: the run is ``n_samples − 1`` telemetry periods, each ``steps_per_sample`` fixed steps
of :func:`cassini_bayes.physics.dynamics.step`. Controllers act once per step (zero-order hold;
the RCS controller on the 1/8 s command grid). Each thruster keeps a ring of its last
:data:`PULSE_RING` pulses; the impulse of a step is the exact integral of the pulse profile over
the step, ``F [g(t+dt − t_on) − g(t − t_on)]`` with ``g`` = :func:`pulse_impulse_until`.
The controllers see the true state (the on-board attitude estimate is taken as perfect; its
errors are far below the star-tracker noise put on the telemetry), while they use the *prior*
model's inertia and thruster sets and the *believed* wheel axes. Sensor noise is added to the
samples afterwards, so the noisy telemetry and the truth come from one trajectory; with
time-tag jitter the noisy telemetry carries the jittered times (``SimArrays.t_meas``), the truth
the true ones.

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

import jax
import jax.numpy as jnp

from cassini_bayes.physics import dynamics
from cassini_bayes.physics.momentum import inertia_matrix
from cassini_bayes.physics.pulse import pulse_impulse_until
from cassini_bayes.simulate import controllers as ctl
from cassini_bayes.simulate._arrays import SimArrays, TruthParams
from cassini_bayes.simulate._commands import _Config
from cassini_bayes.simulate.sensors import NoiseParams, measure, time_tags

PULSE_RING = 6           # pulses remembered per thruster (older tails are < 1e-8 of a pulse)
_TRACES = [0]            # incremented each time the core is traced (compile-once test)


def trace_count() -> int:
    """How many times the simulation core has been traced (for recompilation tests)."""
    return _TRACES[0]


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


def _wheel_torques(q, omega, rho, row, truth: TruthParams, carr, cfg: _Config, on):
    """The wheel motor torques of one step, N m: the RWA attitude controller's (``control =
    "rwa"``) or the commanded wheel ramps', clipped by the wheel limits when the scenario has
    them; zero for a wheel that is off."""
    k, m = truth.wheel_axes.shape[0], carr["q_matrix"].shape[1]
    if cfg.control == "rwa":
        u = ctl.rwa_wheel_torques(q, omega, rho, row[:10], carr["inertia_ctrl"],
                                  carr["axes_believed"], carr["axes_pinv"],
                                  carr["wheel_j_ctrl"], cfg.kp, cfg.kd)
    else:
        u = ctl.wheel_ramp_torques(rho, row[13 + m:13 + m + k],
                                   row[13 + m + k:13 + m + 2 * k], truth.wheel_inertias,
                                   cfg.wheel_gain)
    if cfg.wheel_limits:
        u = ctl.limit_wheel_torques(u, rho, carr["wheel_rate_max"], carr["wheel_torque_max"])
    return jnp.where(on, u, 0.0)


def _thruster_step(t, q, omega, row, rings, truth: TruthParams, carr, cfg: _Config):
    """The thrusters over the step from ``t``: the commanded pulses (with ``control = "rcs"``
    also the RCS controller's) enter each thruster's ring of its last :data:`PULSE_RING` pulses.
    Returns the impulse (m,) N s of each thruster over the step and to its middle, its on-time
    (m,) s over the step, its command units (int8) and the rings ``(ring_t, ring_w, ring_g,
    free_at)`` after it."""
    ring_t, ring_w, ring_g, free_at = rings
    dt, m = cfg.dt, carr["q_matrix"].shape[1]
    td, tr, tf = truth.tau_s[0], truth.tau_s[1], truth.tau_s[2]
    forced = row[10:10 + m]
    units = forced
    if cfg.control == "rcs":
        free = t >= free_at - 1e-9
        auto = ctl.rcs_commands(q, omega, row[:10], row[10 + m:13 + m], free, carr["sets"],
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
        g_half = pulse_impulse_until(t + 0.5 * dt - ring_t, ring_w, td, tr, tf)
        over = jnp.clip(jnp.minimum(t + dt, ring_t + ring_w) - jnp.maximum(t, ring_t), 0.0)
        return (truth.thrust_n * jnp.sum(g1 - ring_g, axis=1),
                truth.thrust_n * jnp.sum(g_half - ring_g, axis=1), g1, jnp.sum(over, axis=1))

    def idle(ring_g):
        return jnp.zeros(m), jnp.zeros(m), ring_g, jnp.zeros(m)

    j_step, j_half, ring_g, on_step = jax.lax.cond(busy, pulse_step, idle, ring_g)  # (m,) N s
    return j_step, j_half, on_step, units.astype(jnp.int8), (ring_t, ring_w, ring_g, free_at)


def _simulate_core(key, truth: TruthParams, noise: NoiseParams, plan, carr, cfg: _Config):
    _TRACES[0] += 1
    dt = cfg.dt
    k = truth.wheel_axes.shape[0]
    m = carr["q_matrix"].shape[1]        # thrusters of the truth model
    on = jnp.asarray(cfg.on)
    plant, d_norm = _plant(truth, cfg)
    rho0 = jnp.concatenate([carr["rho0"], jnp.zeros(1)]) if cfg.flex else carr["rho0"]
    state0 = dynamics.state_from_rates(carr["q0"], carr["w0"], rho0, plant)
    w_flex, z_flex = truth.flex_freq_rad_s, truth.flex_damping

    def eta_rate(state, omega):
        # η̇ = |δ| × the mode's "wheel rate" ρ_mode = η̇ / |δ|
        return d_norm * dynamics.wheel_rates(state, plant, omega)[k]

    def one_step(carry, xs):
        state, ring_t, ring_w, ring_g, free_at, cum_on, cum_thr, cum_b, cum_n, eta = carry
        i, row = xs
        t = i * dt
        omega = dynamics.body_rate(state, plant)
        rho = dynamics.wheel_rates(state, plant, omega)[:k]
        u = _wheel_torques(state.q, omega, rho, row, truth, carr, cfg, on)
        body_imp = truth.torque_body_nm * dt
        if cfg.thrusters:
            j_step, j_half, on_step, units, (ring_t, ring_w, ring_g, free_at) = _thruster_step(
                t, state.q, omega, row, (ring_t, ring_w, ring_g, free_at), truth, carr, cfg)
            cum_on = cum_on + on_step
            cum_thr = cum_thr + j_step
            # the pulses' impulse by mid-step, for the integrator's stages (a pulse's profile
            # is not spread evenly over the step)
            body_half = 0.5 * body_imp + carr["q_matrix"] @ j_half
            body_imp = body_imp + carr["q_matrix"] @ j_step                      # Eq 16
            out_units = units
        else:
            body_half = 0.5 * body_imp
            out_units = jnp.zeros((m,), jnp.int8)[:0]
        if cfg.leak:
            # stuck-open valve (Lee §3.2): f F_k of thrust, torque f F_k Q[:, k] (Eq 16)
            leak_imp = carr["q_matrix"] @ (truth.thrust_n * row[-m:] * dt)
            body_imp = body_imp + leak_imp
            body_half = body_half + 0.5 * leak_imp
        # linear-in-time inertial torque: its mean over the step is its value at mid-step
        t_n = truth.torque_inertial_nm + truth.torque_inertial_rate_nm_s * (t + 0.5 * dt)
        if cfg.flex:
            # The mode's spring and damper, ṗ = −|δ| (Ω² η + 2ζΩ η̇), at η + η̇ dt/2.
            eta_dot = eta_rate(state, omega)
            u_mode = -d_norm * (w_flex * w_flex * (eta + 0.5 * dt * eta_dot)
                                + 2.0 * z_flex * w_flex * eta_dot)
            u = jnp.concatenate([u, u_mode[None]])
        state, imp_n = dynamics.step(state, plant, dt, u, body_imp, t_n, body_half)
        if cfg.flex:
            eta = eta + 0.5 * dt * (eta_dot + eta_rate(state, dynamics.body_rate(state, plant)))
        carry = (state, ring_t, ring_w, ring_g, free_at, cum_on, cum_thr, cum_b + body_imp,
                 cum_n + imp_n, eta)
        return carry, out_units

    def one_sample(carry, xs):
        j, rows, cmd_end = xs
        idx = j * cfg.sps + jnp.arange(cfg.sps)
        carry, units = jax.lax.scan(one_step, carry, (idx, rows))
        return carry, (_observe(carry, cmd_end, plant, on), units)

    zm = jnp.zeros(m)
    carry0 = (state0, jnp.full((m, PULSE_RING), -1e9), jnp.zeros((m, PULSE_RING)),
              jnp.zeros((m, PULSE_RING)), jnp.full(m, -1.0), zm, zm, jnp.zeros(3), jnp.zeros(3),
              jnp.zeros(()))
    obs0 = _observe(carry0, carr["cmd_samples"][0], plant, on)
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


def _observe(carry, cmd, plant, on):
    """One output sample from the integrator's carry: attitude, body and wheel rates (NaN where
    a wheel is off), inertial momentum, the impulses and on-times so far, attitude error, η."""
    state = carry[0]
    omega = dynamics.body_rate(state, plant)
    rho = jnp.where(on, dynamics.wheel_rates(state, plant, omega)[:on.shape[0]], jnp.nan)
    err = ctl.attitude_error(state.q, cmd[:4])
    return (state.q, omega, rho, state.h_inertial, carry[8], carry[7], carry[6], carry[5],
            err, carry[9])


_core_jit = jax.jit(_simulate_core, static_argnames=("cfg",))


def _batch_core(keys, truth, noise, plan, carr, cfg, truth_batched, noise_batched=False,
                carr_batched=()):
    # A shared truth stays unbatched: its mass properties are then hoisted out of the vmapped
    # loop (the speed-up: docs/design.md, benchmarks). ``carr_batched``: the controller arrays
    # given per replicate.
    axes = 0 if truth_batched else None
    carr_axes = {k: 0 if k in carr_batched else None for k in carr}
    return jax.vmap(_simulate_core, in_axes=(0, axes, 0 if noise_batched else None, None,
                                             carr_axes, None))(keys, truth, noise, plan, carr, cfg)


_batch_jit = jax.jit(_batch_core,
                     static_argnames=("cfg", "truth_batched", "noise_batched", "carr_batched"))
