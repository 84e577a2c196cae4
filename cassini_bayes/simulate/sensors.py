"""Sensor models: what telemetry reports of the true state (pure JAX, keyed).

* gyro (IRU): white noise on each body-rate sample, rad/s, and optionally a constant bias ``b``
  (rad/s) and scale-factor error ``s`` per axis: ``ω_meas = (1 + s) ω + b + noise``;
* attitude (star tracker / attitude estimate): a small random rotation per sample,
  ``q_meas = small_rotation_quat(δθ) ⊗ q``, ``δθ ~ N(0, σ²)`` per axis, rad;
* wheel tachometers: white noise (rpm) and quantization to ``tach_quantum_rpm``;
* time tags: each sample's recorded time is its true time plus white noise of sd
  ``time_tag_jitter_s`` (s), ``t_rec = t + σ_t ε``; the values are those at the true time;
* thruster on-time counters: the commanded on-time accumulated up to each sample. The counters
  tick at 10 Hz (0.1 s resolution); scenarios sample on multiples of 0.1 s and pulses start on the
  1/8 s command grid, so the reported counters are the exact commanded on-times at the sample.

Sampling itself (the telemetry period) is done by the integrator (one sample every
``sample_period_s``). All functions take the key first.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
from jax import Array

from cassini_bayes.frames import quat_multiply, quat_normalize, small_rotation_quat

__all__ = ["NoiseParams", "measure", "time_tags"]

RPM_PER_RAD_S = 60.0 / (2.0 * jnp.pi)


class NoiseParams(NamedTuple):
    """Noise levels as (traceable) scalars; see :class:`cassini_bayes.simulate.scenario.Noise`."""

    gyro_rad_s: Array
    star_tracker_rad: Array
    tach_quantum_rpm: Array
    tach_noise_rpm: Array
    gyro_bias_rad_s: Array | float = 0.0       # (3,) constant gyro bias, rad/s
    gyro_scale_factor: Array | float = 0.0     # (3,) gyro scale-factor error (fraction)
    time_tag_jitter_s: Array | float = 0.0     # sd of each sample's time-tag error, s


def measure(key: Array, q: Array, omega: Array, wheel_rates: Array, noise: NoiseParams):
    """Noisy samples ``(q, ω, ρ)`` of true ``q`` (n, 4), ``ω`` (n, 3) rad/s, ``ρ`` (n, k) rad/s.

    Returns wheel rates in rad/s (after quantization in rpm, as the tachometers count).
    """
    k_g, k_s, k_t = jax.random.split(key, 3)
    scale = jnp.broadcast_to(jnp.asarray(noise.gyro_scale_factor, omega.dtype), (3,))
    bias = jnp.broadcast_to(jnp.asarray(noise.gyro_bias_rad_s, omega.dtype), (3,))
    w_meas = ((1.0 + scale[None, :]) * omega + bias[None, :]
              + noise.gyro_rad_s * jax.random.normal(k_g, omega.shape, omega.dtype))
    dth = noise.star_tracker_rad * jax.random.normal(k_s, q.shape[:-1] + (3,), q.dtype)
    q_meas = quat_normalize(quat_multiply(small_rotation_quat(dth), q))
    rpm = wheel_rates * RPM_PER_RAD_S
    rpm = rpm + noise.tach_noise_rpm * jax.random.normal(k_t, rpm.shape, rpm.dtype)
    quantum = noise.tach_quantum_rpm
    safe = jnp.where(quantum > 0, quantum, 1.0)
    rpm = jnp.where(quantum > 0, jnp.round(rpm / safe) * safe, rpm)
    return q_meas, w_meas, rpm / RPM_PER_RAD_S


def time_tags(key: Array, t: Array, noise: NoiseParams) -> Array:
    """Recorded sample times ``t + σ_t ε`` (s) of true times ``t`` (n,), ``ε ~ N(0, 1)``.

    The scenario keeps ``σ_t`` below 1/20 of the telemetry period, so the tags stay increasing
    (a swap needs a 14-sigma draw).
    """
    return t + noise.time_tag_jitter_s * jax.random.normal(key, t.shape, t.dtype)
