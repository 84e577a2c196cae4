"""Impulse model of Feldman & Lee (2006) Eqs 14-23 (pure JAX).

Integrating Euler's equation with wheels (Eq 14) from the first telemetry row ``t_0`` to ``t_i``
gives (Eqs 15, 17)

    V(t_i) = I Δω(t_i) + ΔH_RWA(t_i) + ΔG(t_i) = Q J(t_i),

with ``Δω(t_i) = ω(t_i) − ω(t_0)``, ``ΔH_RWA`` the change of the wheel momentum in body axes,
``ΔG(t_i) = ∫ ω × (I ω + H_RWA) dt`` (the gyroscopic impulse), ``Q`` the moment matrix of Eq 16 and
``J(t_i)`` the (8,) accumulated thruster impulses. The paper takes ``J_s = F_s Δτ_s`` (cumulative
on-time, Eq 17); :func:`impulse_from_pulses` gives the actual impulse of a pulse log under the
pulse response of :mod:`cassini_bayes.physics.pulse` instead. The stacked regressions of Eqs 19-23
are built by :func:`system_xy`, :func:`system_z`, :func:`system_zz`, :func:`system_zzz` and
:func:`system_xyz` from ``V`` and the per-newton impulses ``j`` (N s per N of thrust, i.e. s).

Everything here is pure JAX (jit/vmap/grad friendly): the NumPyro thrust model calls
:func:`impulse_from_pulses` with traced time constants.

Thruster geometry: ``Q`` (3, m) comes from the spacecraft model
(:attr:`cassini_bayes.spacecraft.Spacecraft.moment_matrix`, column ``s`` = ``(r_s − e) × d_s``);
Cassini's eight thrusters ``Z1 … Y4`` are the expansion of Eq 16's lever arms
(:func:`cassini_bayes.spacecraft.eq16_thrusters`). The regressions of Eqs 19-22 assume that
layout (``Z1..Z4`` first, then ``Y1..Y4``); everything else takes any number of thrusters.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jax import Array

from cassini_bayes.names import THRUSTER_NAMES
from cassini_bayes.physics.momentum import inertia_matrix
from cassini_bayes.physics.pulse import pulse_impulse_area, pulse_impulse_until
from cassini_bayes.physics.quadrature import cumulative_trapezoid

__all__ = [
    "THRUSTER_NAMES",
    "delta_omega",
    "delta_wheel_momentum",
    "gyroscopic_impulse",
    "jump_areas",
    "rate_step_correction",
    "impulse_lhs",
    "impulse_lhs_basis",
    "impulse_from_on_times",
    "impulse_from_pulses",
    "angular_impulse",
    "system_xy",
    "system_z",
    "system_zz",
    "system_zzz",
    "system_xyz",
]


def _per_thruster(thrust_n, m: int) -> Array:
    """Thrust (N) as a (1, m) row: a scalar applies to all ``m`` thrusters."""
    return jnp.broadcast_to(jnp.asarray(thrust_n, dtype=float), (m,))[None, :]


def delta_omega(omega_rad_s: Array) -> Array:
    """``Δω(t_i) = ω(t_i) − ω(t_0)`` (rad/s), (n, 3); Feldman & Lee Eq 15."""
    w = jnp.asarray(omega_rad_s)
    return w - w[:1]


def delta_wheel_momentum(h_wheels_body: Array) -> Array:
    """``ΔH_RWA(t_i) = H_RWA(t_i) − H_RWA(t_0)`` (N m s, body axes), (n, 3); Feldman & Lee Eq 15."""
    h = jnp.asarray(h_wheels_body)
    return h - h[:1]


def gyroscopic_impulse(t_s: Array, omega_rad_s: Array, inertia: Array,
                       h_wheels_body: Array) -> Array:
    """``ΔG(t_i) = ∫_{t_0}^{t_i} ω × (I ω + H_RWA) dt`` (N m s), (n, 3); Feldman & Lee Eq 15.

    Cumulative trapezoidal rule on the telemetry samples (second order in the sample interval;
    exact when the integrand is piecewise linear between samples). At Cassini's slow body rates
    (mrad/s) the term is small, so the trapezoid's ``O(Δt²)`` error is far below the noise.
    """
    t = jnp.asarray(t_s)
    w = jnp.asarray(omega_rad_s)
    h_body = jnp.einsum("ij,nj->ni", jnp.asarray(inertia), w) + jnp.asarray(h_wheels_body)
    return cumulative_trapezoid(jnp.cross(w, h_body), t)


def jump_areas(t: Array, t_on: Array, thruster: Array, width: Array, slot: Array, k: int,
               n_thrusters: int, tau) -> Array:
    """(M, n) s²: per thruster, ``∫ j dt − Δt (j(t_{i−1}) + j(t_i)) / 2`` over the interval
    ending at sample ``i`` (0 at ``i = 0``) of the samples ``t`` (n,) s, ``j`` the impulse per
    newton of the pulses commanded at ``t_on`` (m,) s on ``thruster`` (m,) (indices into the
    ``n_thrusters``) with widths ``width`` (m,) s; ``slot`` (m,) is each pulse's first sample at
    or after its command (``n``: none), and its thrust has ended ``k`` samples after it. Time
    constants ``tau`` (3,) s.

    A pulse steps the body rate between two samples; the trapezoidal ``ΔG`` (Feldman & Lee
    Eq 15) treats the rate as linear across the interval, and misses ``∫ δω dt`` by ``I⁻¹ Q (F ⊙
    ε)``, ``ε`` this area (:func:`rate_step_correction`). It is ``j_∞ (t_mid − t_c)`` for a pulse
    that lands inside one interval, ``t_c`` its thrust's centroid.
    """
    t = jnp.asarray(t)
    n = t.shape[0]
    rows = jnp.asarray(slot)[:, None] + jnp.arange(-1, k)[None, :]        # (m, k + 1)
    valid = (rows >= 0) & (rows < n)
    dt = t[jnp.clip(rows, 0, n - 1)] - jnp.asarray(t_on)[:, None]
    w = jnp.asarray(width)[:, None]
    j = pulse_impulse_until(dt, w, *tau)
    area = pulse_impulse_area(dt, w, *tau)
    eps = (area[:, 1:] - area[:, :-1]) - 0.5 * (dt[:, 1:] - dt[:, :-1]) * (j[:, 1:] + j[:, :-1])
    ok = valid[:, 1:] & valid[:, :-1]
    at = jnp.where(ok, jnp.asarray(thruster)[:, None] * n + rows[:, 1:], n_thrusters * n)
    return jnp.zeros(n_thrusters * n).at[at].add(eps, mode="drop").reshape(n_thrusters, n)


def rate_step_correction(inertia: Array, area: Array, omega_mid: Array, h_mid: Array) -> Array:
    """(3, n) N m s: what the trapezoidal ``ΔG`` (Feldman & Lee Eq 15, :func:`gyroscopic_impulse`)
    misses across the pulses' rate steps, accumulated to each sample; add it to ``V``.

    ``area = Q (F ⊙ ε)`` (3, n) N m s², ``ε`` the thrusters' :func:`jump_areas`: the thrusters'
    part of the rate, ``δω = I⁻¹ Q (F ⊙ j(t))``, is integrated by the trapezoid with the error
    ``δθ = I⁻¹ area`` per interval; to first order in it the integrand ``ω × (I ω + H)`` then
    misses ``δθ × (I ω_m + H_m) + ω_m × I δθ``, ``ω_m`` (3, n) rad/s and ``H_m`` (3, n) N m s
    the interval's mean rate and wheel momentum (exact for one step). Where the wheels hold
    newton-metre-seconds and a pulse steps the rate by mrad/s, it is as large as the sample noise
    per pulse, and it accumulates over an event.
    """
    d_theta = jnp.linalg.inv(inertia) @ area    # one 3×3 inverse: cheaper to differentiate
    h_m = inertia @ omega_mid + h_mid
    step = jnp.cross(d_theta, h_m, axis=0) + jnp.cross(omega_mid, area, axis=0)
    return jnp.cumsum(step, 1)


def impulse_lhs(t_s: Array, omega_rad_s: Array, inertia: Array, h_wheels_body: Array) -> Array:
    """Left side ``V(t_i) = I Δω + ΔH_RWA + ΔG`` (N m s), (n, 3); Feldman & Lee Eq 17.

    ``t_s`` (n,) s; ``omega_rad_s`` (n, 3) body rates; ``inertia`` (3, 3) kg m²;
    ``h_wheels_body`` (n, 3) wheel momentum in body axes (N m s).
    """
    i_dw = jnp.einsum("ij,nj->ni", jnp.asarray(inertia), delta_omega(omega_rad_s))
    # Feldman & Lee Eq 17 (left side)
    return (i_dw + delta_wheel_momentum(h_wheels_body)
            + gyroscopic_impulse(t_s, omega_rad_s, inertia, h_wheels_body))


def impulse_lhs_basis(t_s: Array, omega_rad_s: Array, h_wheels_body: Array) -> Array:
    """(7, n, 3) N m s arrays with ``V(t_i) = basis[0] + Σ_k π_k basis[1 + k]`` exactly.

    ``V`` (:func:`impulse_lhs`, Feldman & Lee Eq 17 left side) is linear in the inertia: ``I Δω``
    and ``ΔG = ∫ ω × (I ω + H_RWA) dt`` both are. ``basis[0]`` is ``V`` at ``I = 0`` (the wheels'
    part), ``basis[1 + k]`` its derivative in ``π_k``, ``π = (Ixx, Iyy, Izz, Ixy, Ixz, Iyz)``
    (kg m², :func:`~cassini_bayes.physics.momentum.inertia_matrix`). A model that samples the
    inertia computes these once per data set and ``V`` as one small product per density
    evaluation, instead of the cross products and cumulative sums of ``ΔG``.
    """
    w, h = jnp.asarray(omega_rad_s), jnp.asarray(h_wheels_body)
    v0 = impulse_lhs(t_s, w, jnp.zeros((3, 3), w.dtype), h)
    per_pi = jax.jacfwd(lambda pi: impulse_lhs(t_s, w, inertia_matrix(pi), jnp.zeros_like(h)))(
        jnp.zeros(6, w.dtype))                                            # (n, 3, 6)
    return jnp.concatenate([v0[None], jnp.moveaxis(per_pi, -1, 0)], 0)


def impulse_from_on_times(on_times_s: Array, thrust_n=1.0) -> Array:
    """Accumulated impulse ``J_s = F_s Δτ_s`` (N s), (n, m); Feldman & Lee Eq 17's assumption.

    ``on_times_s`` (n, m) cumulative on-times (s), counted from the first row (the first row is
    subtracted, so any offset is harmless); ``thrust_n`` scalar or (m,) steady thrust (N). With
    the default ``thrust_n = 1`` the result is the per-newton impulse ``Δτ`` (s).
    """
    tau = jnp.asarray(on_times_s)
    # Feldman & Lee Eq 17: int T_PMS dt = Q [F_1 dtau_1, ..., F_m dtau_m]
    return (tau - tau[:1]) * _per_thruster(thrust_n, tau.shape[-1])


def impulse_from_pulses(t_s: Array, t_on_s: Array, thruster: Array, width_s: Array,
                        tau_delay_s, tau_rise_s, tau_fall_s, thrust_n=1.0,
                        n_thrusters: int = 8) -> Array:
    """Accumulated actual impulse per thruster from a pulse log (N s), (n, m).

    Each pulse ``p`` (command time ``t_on_s[p]``, thruster index ``thruster[p]`` in
    ``0..n_thrusters − 1``,
    commanded width ``width_s[p]``) contributes
    :func:`~cassini_bayes.physics.pulse.pulse_impulse_until` ``(t − t_on, width, τd, τr, τf)``,
    the impulse it has actually delivered by time ``t`` (pulse response of Feldman & Lee §V, the
    correction the paper applies to Eq 17 through the ratio ``R``). The result is counted from
    the first telemetry time ``t_s[0]``, like ``Δω`` and ``ΔH_RWA``. Time constants in s may be
    traced (differentiable); ``thrust_n`` scalar or (m,) N (default 1: per-newton impulse, s);
    ``m = n_thrusters`` (Cassini's eight by default).
    Memory is ``O(n × pulses)``.
    """
    t = jnp.asarray(t_s)
    dt = t[:, None] - jnp.asarray(t_on_s)[None, :]
    w = jnp.asarray(width_s)[None, :]
    per_pulse = pulse_impulse_until(dt, w, tau_delay_s, tau_rise_s, tau_fall_s)
    one_hot = (jnp.asarray(thruster)[:, None]
               == jnp.arange(n_thrusters)[None, :]).astype(per_pulse.dtype)
    j = per_pulse @ one_hot
    return (j - j[:1]) * _per_thruster(thrust_n, n_thrusters)


def angular_impulse(q_matrix: Array, impulse_ns: Array) -> Array:
    """Thruster angular impulse ``Q J(t_i)`` (N m s), (n, 3); right side of Feldman & Lee Eq 17."""
    return jnp.einsum("ks,ns->nk", jnp.asarray(q_matrix), jnp.asarray(impulse_ns))


def system_xy(v: Array, j: Array, q_matrix: Array):
    """``U_XY`` (2N, 4) and ``V_XY`` (2N,) of Feldman & Lee Eq 19, unknowns ``F_Z1 … F_Z4``.

    ``v`` (N, 3) left side :func:`impulse_lhs`; ``j`` (N, 8) per-newton impulses (s).
    As in Eq 18 the Y thrusters are left out of the X row: their X torques cancel when they fire
    in the pairs {Y1, Y3}, {Y2, Y4} with equal impulse.
    """
    q = jnp.asarray(q_matrix)
    # Feldman & Lee Eq 18-19: rows [Q_1s dtau_s ; Q_2s dtau_s], s = Z1..Z4
    u = jnp.asarray(j)[:, None, :4] * q[None, :2, :4]
    return u.reshape(-1, 4), jnp.asarray(v)[:, :2].reshape(-1)


def system_z(v: Array, j: Array, q_matrix: Array):
    """``U_Z`` (N, 4) and ``V_Z`` (N,) of Feldman & Lee Eq 20, unknowns ``F_Y1 … F_Y4``.

    Rank 2 when Y1/Y3 and Y2/Y4 always fire in pairs (the paper's remark after Eq 20).
    """
    q = jnp.asarray(q_matrix)
    # Feldman & Lee Eq 20: U_Z[i, s] = Q_3s dtau_s(t_i), s = Y1..Y4
    return jnp.asarray(j)[:, 4:] * q[None, 2, 4:], jnp.asarray(v)[:, 2]


def system_zz(v: Array, j: Array, q_matrix: Array):
    """``U_ZZ`` (N, 2) and ``V_Z`` of Feldman & Lee Eq 21: unknowns the pair means
    ``((F_Y1 + F_Y3)/2, (F_Y2 + F_Y4)/2)``."""
    u, vz = system_z(v, j, q_matrix)
    # Feldman & Lee Eq 21: columns Q35 dtau5 + Q37 dtau7, Q36 dtau6 + Q38 dtau8
    return jnp.stack([u[:, 0] + u[:, 2], u[:, 1] + u[:, 3]], -1), vz


def system_zzz(v: Array, j: Array, q_matrix: Array):
    """``U_ZZZ`` (N, 1) and ``V_Z`` of Feldman & Lee Eq 22: unknown the mean Y thrust."""
    u, vz = system_z(v, j, q_matrix)
    # Feldman & Lee Eq 22
    return jnp.sum(u, -1, keepdims=True), vz


def system_xyz(v: Array, j: Array, q_matrix: Array):
    """``U_XYZ`` (3N, 1) and ``V_XYZ`` (3N,) of Feldman & Lee Eq 23: one thrust for all eight.

    ``U_XYZ`` stacks ``Q J(t_i)`` per newton: every thruster's torque on every axis.
    """
    # Feldman & Lee Eq 23: rows sum_s Q_ks dtau_s(t_i), k = X, Y, Z
    return angular_impulse(q_matrix, j).reshape(-1, 1), jnp.asarray(v).reshape(-1)
