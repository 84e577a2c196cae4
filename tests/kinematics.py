"""Noise-free rigid-body + wheel telemetry from known truth, for exact-recovery tests.

Every generator here makes telemetry in which the paper's conservation laws hold to rounding:

* :func:`slew_segments` — attitude and body rate for a sequence of rest-to-rest rotations, each
  about a fixed body axis (then ``q(t) = rot(θ(t) n) q0`` is the exact solution of the
  kinematics for ``ω = θ̇ n``), separated by quiescent rests;
* :func:`wheels_for_conserved_momentum` — wheel rates that keep the inertial momentum
  ``H_N(t) = H_0 + T_N (t − t_0)`` exactly: ``H_w = A(q) H_N(t) − I ω``, solved for three wheels;
* :func:`free_drift` — a body drifting freely (no control) while one wheel changes speed,
  integrated by RK4 with ``ω = I⁻¹ (A(q) H_N − H_w)`` evaluated at the recorded ``q``;
* :func:`biasing_wheel_momentum` — wheel momentum for which the trapezoidal impulse balance of
  Feldman & Lee Eq 17 holds exactly for a given thruster angular impulse.
"""

from __future__ import annotations

import numpy as np



def slew_segments(q0, segments, dt: float, rest_s: float):
    """``t`` (n,), ``q`` (n, 4), ``omega`` (n, 3) for rest-to-rest slews about fixed body axes.

    ``segments``: sequence of ``(axis (3,), angle_rad, duration_s)``; the angle profile is
    ``θ(τ) = Θ (τ/T − sin(2πτ/T)/(2π))`` so ``ω = Θ/T (1 − cos(2πτ/T)) n`` starts and ends at 0.
    A rest of ``rest_s`` precedes each segment and follows the last.
    """
    ts, qs, ws = [], [], []
    q_start = np.asarray(q0, float)
    t0 = 0.0
    for axis, angle, dur in list(segments) + [(None, 0.0, 0.0)]:
        tr = np.arange(0.0, rest_s, dt)
        ts.append(t0 + tr)
        qs.append(np.tile(q_start, (tr.size, 1)))
        ws.append(np.zeros((tr.size, 3)))
        t0 += tr.size * dt
        if axis is None:
            break
        n = np.asarray(axis, float) / np.linalg.norm(axis)
        tau = np.arange(0.0, dur, dt)
        theta = angle * (tau / dur - np.sin(2 * np.pi * tau / dur) / (2 * np.pi))
        rate = angle / dur * (1 - np.cos(2 * np.pi * tau / dur))
        rot = rotvec_to_quat_np(theta[:, None] * n)
        qs.append(qmul_np(rot, np.broadcast_to(q_start, rot.shape)))
        ws.append(rate[:, None] * n)
        ts.append(t0 + tau)
        t0 += tau.size * dt
        q_start = qmul_np(rotvec_to_quat_np(angle * n), q_start)
    return np.concatenate(ts), np.concatenate(qs), np.concatenate(ws)


def wheels_for_conserved_momentum(t, q, omega, inertia, h0_inertial, wheel_axes, wheel_inertias,
                                  torque_inertial=(0.0, 0.0, 0.0)):
    """Wheel rates (n, 3) rad/s about ``wheel_axes`` (3, 3) keeping ``H_N = H_0 + T_N (t − t_0)``.

    Returns ``(rates, h_wheels_body)``.
    """
    t = np.asarray(t, float)
    h_n = np.asarray(h0_inertial, float) + np.outer(t - t[0], np.asarray(torque_inertial, float))
    a = dcm_np(q)
    h_w = np.einsum("nij,nj->ni", a, h_n) - omega @ np.asarray(inertia).T
    g = np.asarray(wheel_axes, float)
    # h_w = (rho * J) @ G  ->  rho = h_w G^-1 / J
    rates = np.linalg.solve(g.T, h_w.T).T / np.asarray(wheel_inertias, float)
    return rates, h_w


def dcm_np(q):
    """NumPy copy of :func:`cassini_bayes.frames.dcm` (batched; fast, no JAX compilation)."""
    q = np.asarray(q, float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    v, s = q[..., :3], q[..., 3]
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    o = np.zeros_like(x)
    vx = np.stack([np.stack([o, -z, y], -1), np.stack([z, o, -x], -1),
                   np.stack([-y, x, o], -1)], -2)
    return (((s * s - np.sum(v * v, -1))[..., None, None] * np.eye(3)
             + 2 * v[..., :, None] * v[..., None, :]) - 2 * s[..., None, None] * vx)


def qmul_np(a, b):
    """NumPy copy of :func:`cassini_bayes.frames.quat_multiply` (batched)."""
    av, a4, bv, b4 = a[..., :3], a[..., 3:], b[..., :3], b[..., 3:]
    return np.concatenate([a4 * bv + b4 * av - np.cross(av, bv),
                           a4 * b4 - np.sum(av * bv, -1, keepdims=True)], -1)


def rotvec_to_quat_np(theta):
    """NumPy copy of :func:`cassini_bayes.frames.rotvec_to_quat` (batched)."""
    theta = np.asarray(theta, float)
    ang = np.linalg.norm(theta, axis=-1, keepdims=True)
    safe = np.where(ang > 0, ang, 1.0)
    sinc = np.where(ang > 0, np.sin(0.5 * ang) / safe, 0.5)
    return np.concatenate([theta * sinc, np.cos(0.5 * ang)], -1)


def free_drift(q0, t, inertia, h_inertial, h_wheel_body_fn):
    """RK4 attitude of a free body with wheel momentum ``h_wheel_body_fn(t)`` (N m s, body).

    ``ω(t, q) = I⁻¹ (A(q) H_N − H_w(t))``; returns ``q`` (n, 4) and ``omega`` (n, 3), the rate
    evaluated at each recorded ``q`` so that momentum is conserved exactly per sample.
    """
    inv = np.linalg.inv(np.asarray(inertia, float))
    hn = np.asarray(h_inertial, float)

    def rate(tt, q):
        return inv @ (dcm_np(q) @ hn - h_wheel_body_fn(tt))

    def qdot(tt, q):
        w = rate(tt, q)
        return 0.5 * qmul_np(np.concatenate([w, [0.0]]), q)

    qs = [np.asarray(q0, float)]
    for i in range(len(t) - 1):
        h = t[i + 1] - t[i]
        q = qs[-1]
        k1 = qdot(t[i], q)
        k2 = qdot(t[i] + h / 2, q + h / 2 * k1)
        k3 = qdot(t[i] + h / 2, q + h / 2 * k2)
        k4 = qdot(t[i] + h, q + h * k3)
        qn = q + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        qs.append(qn / np.linalg.norm(qn))
    q = np.stack(qs)
    omega = np.stack([rate(tt, qq) for tt, qq in zip(t, q)])
    return q, omega


def biasing_wheel_momentum(t, omega, inertia, angular_impulse_nms, h0_body):
    """Wheel momentum (n, 3) N m s with ``I Δω + ΔH + ΔG_trapezoid = angular_impulse`` exactly.

    Solves the trapezoidal balance of Feldman & Lee Eq 17 step by step:
    ``(1 + Δt/2 [ω_i×]) h_i = P_i − I (ω_i − ω_0) + h_0 − G_{i−1} − Δt/2 (f_{i−1} + ω_i × I ω_i)``.
    """
    t = np.asarray(t, float)
    w = np.asarray(omega, float)
    i_m = np.asarray(inertia, float)
    p = np.asarray(angular_impulse_nms, float)
    h = np.zeros_like(w)
    h[0] = h0_body
    g = np.zeros(3)
    f_prev = np.cross(w[0], i_m @ w[0] + h[0])
    for i in range(1, len(t)):
        dt = t[i] - t[i - 1]
        wx = np.array([[0, -w[i, 2], w[i, 1]], [w[i, 2], 0, -w[i, 0]], [-w[i, 1], w[i, 0], 0]])
        rhs = (p[i] - i_m @ (w[i] - w[0]) + h[0] - g
               - 0.5 * dt * (f_prev + np.cross(w[i], i_m @ w[i])))
        h[i] = np.linalg.solve(np.eye(3) + 0.5 * dt * wx, rhs)
        f_i = np.cross(w[i], i_m @ w[i] + h[i])
        g = g + 0.5 * dt * (f_prev + f_i)
        f_prev = f_i
    return h
