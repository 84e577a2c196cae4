"""Attitude controllers of the scenarios: the RWA PD controller and the RCS dead-band controller.

* :func:`slew_profile` / :func:`command_profile` — commanded attitude, rate and acceleration of a
  sequence of eigen-axis slews with trapezoidal rate profiles (the "profiled slew commands" of the
  Attitude Commander, Feldman & Lee (2006) §III, Fig. 6), evaluated in NumPy once per scenario.
* :func:`rwa_wheel_torques` — the reaction-wheel attitude controller of Feldman & Lee §III: a
  decoupled three-axis PD controller with rate and acceleration feed-forward and the gyroscopic
  term ``ω × (I ω + H_RWA)``; the commanded momentum rate is mapped to wheel motor torques with the
  wheel axes the controller *believes* (Brown (2012) §III.C: RWA4 believed at RWA1 while it is
  elsewhere). It uses the controller's inertia (the prediction), not the truth.
* :func:`rcs_commands` — the RCS dead-band controller: per-axis phase-plane switching
  ``s = θ + τ_r (ω − ω_cmd)`` against the dead-band, pulses of 125 ms and up at the 1/8 s command
  resolution, firing for each axis and sign the thruster set :func:`thruster_sets` chose from the
  model's geometry (on Cassini the pairs of Feldman & Lee §II/§V: Z-facing thrusters for X and Y,
  ``{Y2, Y4}`` for +Z, ``{Y1, Y3}`` for −Z).

All JAX functions are pure and traceable; units SI (rad, rad/s, N m, s).
"""

from __future__ import annotations

from itertools import combinations
from typing import TYPE_CHECKING

import numpy as np
import jax.numpy as jnp
from jax import Array

from cassini_bayes.errors import InputError
from cassini_bayes.frames import quat_conjugate, quat_multiply, quat_to_rotvec

if TYPE_CHECKING:
    from cassini_bayes.spacecraft import Spacecraft

__all__ = [
    "COMMAND_RESOLUTION_S",
    "MIN_PULSE_S",
    "SET_SIZE_MAX",
    "thruster_sets",
    "slew_profile",
    "command_profile",
    "attitude_error",
    "rwa_wheel_torques",
    "rcs_commands",
    "wheel_ramp_torques",
    "limit_wheel_torques",
]

COMMAND_RESOLUTION_S = 0.125  # thruster and articulation command resolution (Brown §I: 1/8 s)
MIN_PULSE_S = 0.125           # smallest RCS pulse (Feldman & Lee §V: 125-ms pulses)

SET_SIZE_MAX = 4              # most thrusters fired together for one axis and sign
_OFF_AXIS_MAX = 0.5           # a set's off-axis torque is at most this × its on-axis torque
_USABLE_MIN = 0.05            # each thruster's on-axis torque at least this × the strongest one's
_FORCE_FREE = 0.1             # a couple: net force at most this × the set's summed thrust
_SEARCH_MAX = 32              # most thrusters of one branch the exhaustive search takes


def thruster_sets(sc: Spacecraft) -> np.ndarray:
    """(3, 2, m) 0/1 masks of the thrusters the RCS controller fires: ``[axis, 0]`` for + torque
    about that body axis, ``[axis, 1]`` for − torque; chosen from the model's geometry.

    Search over every set of up to :data:`SET_SIZE_MAX` thrusters of the first branch listed
    (the others are backups), torque ``τ = Σ F_s Q_s`` (Feldman & Lee Eq 16) and net force
    ``f = Σ F_s d_s`` at the model's nominal thrusts. A set is usable for an axis and sign when
    each of its thrusters turns the spacecraft that way by at least 5 % of the strongest
    thruster's torque (no passengers) and its off-axis torque ``|τ_off| ≤ 0.5 τ_on``. Score
    ``τ_on − |τ_off| − σ_e |f|`` (``σ_e`` the centre-of-mass knowledge: the torque the net force may
    add); ties go to the smaller net force, then to fewer thrusters, then to the thrusters listed
    first. An axis whose best sets both ways are force-free couples (``|f| ≤ 10 %`` of the summed
    thrust) keeps those thrusters; the other axes choose among the remaining thrusters when those
    give a usable set: Cassini's Y-facing couples turn about Z, its Z-facing thrusters about X and Y
    (Feldman & Lee §II). Raises :class:`InputError` naming the model and the axis when no set is
    usable.
    """
    m = len(sc.thrusters)
    branches = [t.branch for t in sc.thrusters]
    idx = np.array([k for k in range(m) if branches[k] == branches[0]], int)
    if idx.size > _SEARCH_MAX:
        raise InputError(f"the RCS controller searches thruster sets among at most {_SEARCH_MAX} "
                         f"thrusters of one branch; the spacecraft model {sc.name!r} has "
                         f"{idx.size} in branch {branches[0]!r}: split them into branches")
    force = sc.thrust_per_thruster[idx]
    torque = sc.moment_matrix[:, idx] * force            # (3, n) N m per thruster
    push = np.stack([sc.thrusters[k].direction for k in idx], 1) * force   # (3, n) N
    scale = float(np.max(np.linalg.norm(torque, axis=0), initial=0.0))
    arm = np.stack([sc.thrusters[k].position for k in idx]) - sc.com_m
    if not scale > 1e-9 * float(np.max(np.linalg.norm(arm, axis=1) * force, initial=0.0)):
        scale = np.inf                                  # every force through the centre of mass
    subsets = [c for r in range(1, min(SET_SIZE_MAX, idx.size) + 1)
               for c in combinations(range(idx.size), r)]
    best: dict[tuple[int, int], list] = {}
    for c in subsets:
        tau, f = torque[:, c].sum(1), push[:, c].sum(1)
        f_norm, thrust = float(np.linalg.norm(f)), float(force[list(c)].sum())
        for ax in range(3):
            for j, sign in enumerate((1.0, -1.0)):
                on = sign * tau[ax]
                off = float(np.linalg.norm(np.delete(tau, ax)))
                if not (np.min(sign * torque[ax, c]) >= _USABLE_MIN * scale
                        and off <= _OFF_AXIS_MAX * on):
                    continue
                score = on - off - sc.com_sd_m * f_norm
                key = (-round(score / scale, 9), round(f_norm / thrust, 9), len(c), c)
                best.setdefault((ax, j), []).append((key, c, f_norm <= _FORCE_FREE * thrust))
    masks = np.zeros((3, 2, m))
    for ax in range(3):
        for j in range(2):
            if (ax, j) not in best:
                raise InputError(f"the RCS controller cannot turn the spacecraft model "
                                 f"{sc.name!r} about {'+-'[j]}{'XYZ'[ax]}: no set of up to "
                                 f"{SET_SIZE_MAX} of its thrusters gives torque mostly about "
                                 "that axis; check the thrusters' positions and directions")
            best[ax, j].sort(key=lambda e: e[0])
    coupled = [ax for ax in range(3) if best[ax, 0][0][2] and best[ax, 1][0][2]]
    couples = {k for ax in coupled for j in range(2) for k in best[ax, j][0][1]}
    for (ax, j), cands in best.items():
        chosen = cands[0][1]
        if ax not in coupled:
            free = [c for _, c, _ in cands if not couples.intersection(c)]
            chosen = free[0] if free else chosen
        masks[ax, j, idx[list(chosen)]] = 1.0
    return masks


def slew_profile(t_s, t0_s: float, angle_rad: float, rate_rad_s: float, accel_rad_s2: float):
    """Trapezoidal (or triangular) rate profile of one slew; returns ``(θ, θ̇, θ̈)`` at ``t_s``.

    Accelerates at ``accel`` to at most ``rate``, coasts, decelerates to rest after ``|angle|``.
    """
    t = np.asarray(t_s, float) - t0_s
    sgn = np.sign(angle_rad)
    big = abs(angle_rad)
    ta = rate_rad_s / accel_rad_s2
    if accel_rad_s2 * ta * ta >= big:          # triangular: never reaches the rate limit
        ta = np.sqrt(big / accel_rad_s2)
        tc = 0.0
    else:
        tc = (big - accel_rad_s2 * ta * ta) / rate_rad_s
    wpk = accel_rad_s2 * ta
    t1, t2, t3 = ta, ta + tc, 2 * ta + tc
    th = np.select(
        [t <= 0, t <= t1, t <= t2, t <= t3],
        [0.0, 0.5 * accel_rad_s2 * t**2, 0.5 * accel_rad_s2 * ta**2 + wpk * (t - t1),
         big - 0.5 * accel_rad_s2 * (t3 - t) ** 2], big)
    w = np.select([t <= 0, t <= t1, t <= t2, t <= t3],
                  [0.0, accel_rad_s2 * t, wpk, accel_rad_s2 * (t3 - t)], 0.0)
    a = np.select([t <= 0, t < t1, t < t2, t < t3], [0.0, accel_rad_s2, 0.0, -accel_rad_s2], 0.0)
    return sgn * th, sgn * w, sgn * a


def slew_duration(angle_rad: float, rate_rad_s: float, accel_rad_s2: float) -> float:
    """Duration (s) of the profile of :func:`slew_profile`."""
    big = abs(angle_rad)
    ta = rate_rad_s / accel_rad_s2
    if accel_rad_s2 * ta * ta >= big:
        return 2.0 * np.sqrt(big / accel_rad_s2)
    return 2 * ta + (big - accel_rad_s2 * ta * ta) / rate_rad_s


def command_profile(t_s: np.ndarray, q0, slews) -> np.ndarray:
    """Commanded ``[q (4), ω (3), α (3)]`` at times ``t_s`` for sequential body-axis slews.

    ``slews`` is a sequence of ``(t_start_s, axis, angle_rad, rate_rad_s, accel_rad_s2)``; slew
    ``j`` turns the commanded frame about its own body axis ``axis`` (unit), so
    ``q_cmd(t) = Π_j rotvec_to_quat(axis_j θ_j(t)) ⊗ q0`` with later slews multiplied on the left.
    Returns an array (n, 10).
    """
    from cassini_bayes.frames import rotvec_to_quat  # local: NumPy in, NumPy out

    t = np.asarray(t_s, float)
    q = np.broadcast_to(np.asarray(q0, float), (t.size, 4)).copy()
    w = np.zeros((t.size, 3))
    a = np.zeros((t.size, 3))
    for t0, axis, ang, rate, acc in slews:
        e = np.asarray(axis, float)
        th, dth, ddth = slew_profile(t, t0, ang, rate, acc)
        q = np.asarray(quat_multiply(rotvec_to_quat(th[:, None] * e), q))
        w += dth[:, None] * e
        a += ddth[:, None] * e
    return np.concatenate([q, w, a], axis=1)


def attitude_error(q: Array, q_cmd: Array) -> Array:
    """Rotation vector (rad, body axes) of the body relative to the commanded frame.

    ``q = δq ⊗ q_cmd``; ``θ = rotvec(δq)``; positive θ means the body has turned by θ past the
    command, so the controllers push back along −θ.
    """
    return quat_to_rotvec(quat_multiply(q, quat_conjugate(q_cmd)))


def rwa_wheel_torques(q: Array, omega: Array, wheel_rates: Array, cmd: Array, inertia_ctrl: Array,
                      axes_believed: Array, axes_pinv: Array, wheel_j: Array, kp: float,
                      kd: float) -> Array:
    """Wheel motor torques (k,) N m of the RWA attitude controller (Feldman & Lee 2006 §III).

    Desired acceleration ``ω̇_d = α_cmd − K_p θ − K_d (ω − ω_cmd)`` (decoupled PD with
    acceleration and rate feed-forward, Fig. 6); control torque
    ``I ω̇_d + ω × (I ω + H_RWA)`` (Feldman & Lee §III, with the controller's ``I``); the wheels
    must absorb it, ``Ḣ_w = −(I ω̇_d + ω × (I ω + H_RWA))``, mapped to motor torques with the
    pseudo-inverse of the *believed* axes (zero rows for wheels that are off).
    """
    theta = attitude_error(q, cmd[:4])
    w_cmd, a_cmd = cmd[4:7], cmd[7:10]
    wdot = a_cmd - kp * theta - kd * (omega - w_cmd)
    h_rwa = (wheel_j * wheel_rates) @ axes_believed
    # Feldman & Lee (2006) §III: T_c = I dω/dt + ω × (I ω + H_RWA)
    t_c = inertia_ctrl @ wdot + jnp.cross(omega, inertia_ctrl @ omega + h_rwa)
    return -(axes_pinv @ t_c)


def wheel_ramp_torques(wheel_rates: Array, target_rad_s: Array, torque_max_nm: Array,
                       wheel_j: Array, gain_per_s: float) -> Array:
    """Motor torques (k,) N m that bias wheels towards target rates (RWA biasing under RCS).

    ``u = clip(g J (ρ_target − ρ), ±u_max)``: constant torque ``u_max`` until close, then an
    exponential approach with time constant ``1/g``. A wheel with ``u_max = 0`` coasts.
    """
    u = gain_per_s * wheel_j * (target_rad_s - wheel_rates)
    return jnp.clip(u, -torque_max_nm, torque_max_nm)


def limit_wheel_torques(u: Array, wheel_rates: Array, rate_max_rad_s: Array,
                        torque_max_nm: Array) -> Array:
    """Motor torques (k,) N m within the wheels' limits: each clipped to ``±torque_max_nm``, and
    zero where a wheel at its rate limit ``rate_max_rad_s`` would be driven faster (the motor
    drive's speed limit). ``inf`` is no limit."""
    u = jnp.clip(u, -torque_max_nm, torque_max_nm)
    return jnp.where((jnp.abs(wheel_rates) >= rate_max_rad_s) & (u * wheel_rates > 0), 0.0, u)


def rcs_commands(q: Array, omega: Array, cmd: Array, deadband_rad: Array,
                 free: Array, sets: Array, rate_gain_s: float, width_gain_s_per_rad: float,
                 max_units: int) -> Array:
    """Pulse widths in units of 1/8 s (m,) commanded now by the RCS dead-band controller.

    Per axis ``s = θ + τ_r (ω − ω_cmd)``; beyond ``+db`` the set for negative torque fires, beyond
    ``−db`` the set for positive torque (``sets``: :func:`thruster_sets`), with width
    ``0.125 s + k_w (|s| − db)`` rounded down to the 1/8 s resolution and limited to
    ``max_units``. An axis fires only when every thruster of its set is free (its previous pulse
    done and the minimum off-time past, ``free``); a thruster asked for by two axes gets the
    longer width.
    """
    theta = attitude_error(q, cmd[:4])
    s = theta + rate_gain_s * (omega - cmd[4:7])
    excess = jnp.abs(s) - deadband_rad
    units = jnp.clip(1 + jnp.floor(width_gain_s_per_rad * jnp.maximum(excess, 0.0)
                                   / COMMAND_RESOLUTION_S), 1, max_units)
    want_pos = s < -deadband_rad            # error negative → push positive
    want_neg = s > deadband_rad
    # (3, 2, m) masks; choose the set per axis
    sel = jnp.where(want_pos[:, None], sets[:, 0], 0.0) + jnp.where(want_neg[:, None],
                                                                     sets[:, 1], 0.0)
    ok = jnp.all(jnp.where(sel > 0, free[None, :], True), axis=1)        # (3,)
    per_axis = sel * (units * ok)[:, None]                               # (3, 8)
    return jnp.max(per_axis, axis=0)
