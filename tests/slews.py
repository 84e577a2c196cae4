"""Noisy slew telemetry for the inertia fit, with its truth: the flight inertia of Feldman & Lee
(2006) Eq 8, the initial inertial momentum and a constant inertial torque.

The telemetry is made noise-free by tests/kinematics.py (rest-to-rest slews about Y, X, Y, Z and
a skew axis; wheel rates for which ``H_N = H_0 + T_N (t − t_0)`` holds exactly), then white noise
is added to the body rates, the wheel rates and the attitude.
"""

from __future__ import annotations

import jax
import numpy as np

from cassini_bayes.frames import quat_multiply, rotvec_to_quat
from cassini_bayes.telemetry import Telemetry
from kinematics import slew_segments, wheels_for_conserved_momentum

__all__ = ["H0", "NOISE", "TORQUE", "TRUTH", "make_slews"]

# Feldman & Lee (2006) Eq 8: the flight estimate of 2000-03-15, used as the synthetic truth.
TRUTH = np.array([[8655.2, -144.0, 132.1], [-144.0, 7922.7, 192.1], [132.1, 192.1, 4586.2]])
H0 = np.array([3.0, -2.0, 5.0])          # N m s
TORQUE = np.array([5e-6, -3e-6, 2e-6])   # N m
NOISE = (2e-6, 5e-3, 2e-5)               # rad/s gyro, rad/s wheel rate, rad attitude


def make_slews(key, sc, *, inertia=TRUTH, z_scale=1.0, dt=2.0, dur=300.0, rest=40.0,
               noise=NOISE, h0=H0, torque=TORQUE, source="synthetic") -> Telemetry:
    """Noisy slew telemetry with exact momentum conservation before the noise.

    Slews (rest-to-rest, ``dur`` s each): Y 0.6 rad, X 0.6, Y −0.5, Z ``0.8 z_scale``, skew 0.3.
    """
    segs = [((0, 1, 0), 0.6, dur), ((1, 0, 0), 0.6, dur), ((0, 1, 0), -0.5, dur),
            ((0, 0, 1), 0.8 * z_scale, dur), ((1, 1, 1), 0.3, dur)]
    t, q, w = slew_segments([0.0, 0.0, 0.0, 1.0], segs, dt, rest)
    axes, js = sc.wheel_axes[:3], sc.wheel_inertias[:3]
    rates, _ = wheels_for_conserved_momentum(t, q, w, inertia, h0, axes, js, torque)
    k_w, k_r, k_q = jax.random.split(key, 3)
    n = t.size
    w_n = w + noise[0] * np.asarray(jax.random.normal(k_w, (n, 3)))
    r_n = rates + noise[1] * np.asarray(jax.random.normal(k_r, (n, 3)))
    dq = rotvec_to_quat(noise[2] * np.asarray(jax.random.normal(k_q, (n, 3))))
    q_n = np.asarray(quat_multiply(dq, q))
    wheel = np.full((n, 4), np.nan)
    wheel[:, :3] = r_n
    return Telemetry(t, q_n, w_n, wheel, ("RWA1", "RWA2", "RWA3", "RWA4"), None, source)
