"""The second-order part of the trapezoidal ``ΔG`` across the pulses' rate steps.

Feldman & Lee Eq 15's gyroscopic impulse ``ΔG = ∫ ω × (I ω + H) dt`` is summed by the trapezoid
on the telemetry samples (:func:`~cassini_bayes.physics.impulse.gyroscopic_impulse`), and
:func:`~cassini_bayes.physics.impulse.rate_step_correction` adds what it misses to first order in
the thrusters' deviation ``δω = I⁻¹ Q (F ⊙ e(t))`` from the rate's linear interpolation. Over an
interval of length ``Δ`` with ``ω``'s and ``H``'s changes ``Δω``, ``ΔH`` and ``s = (t − t₀)/Δ``,
the exact integral less those two is

    −(Δ/6) Δω × (I Δω + ΔH)                       (the trapezoid on a product of two lines)
    + μ × (I Δω + ΔH) + Δω × I μ,   μ = ∫ δω (s − ½) dt
    + ∫ δω × I δω dt,

the smooth rate's own curvature left out. The first line is the data's; ``μ`` and the last line
need each thruster's ``e_k(t)`` (its impulse per newton less that impulse's linear interpolation
across the interval), through the moments ``m_k = ∫ e_k (s − ½) dt`` and ``P_kl = ∫ e_k e_l dt``
(:func:`interval_moments`). A pulse steps the rate by ``b/I``; these terms grow as ``b² / I`` and
``b ΔH``, so they vanish against the sample noise on a large spacecraft and not on a small one
whose wheels change by a fraction of a newton-metre-second per sample.

Euler's equation bends the rate inside each interval away from the line the samples draw:
``I ω̈ = −(ω̇ × L + ω × L̇)`` with ``L = I ω + H``, to first order in the bend. Integrated twice
over the interval, the bend of the samples' secant (``ω̇ = Δω/Δ``, ``L̇ = (I Δω + ΔH)/Δ``) is
``κ_s = (Δ²/12) I⁻¹ (Δω × L_m + ω_m × (I Δω + ΔH))`` and the body's answer to the steps'
deviation ``δω`` is ``κ_μ = I⁻¹ (Δ μ × L_m + ω_m × I Δ μ)`` (rad; ``ω_m``, ``L_m`` the
interval's means), and ``ΔG`` misses ``κ × L_m + ω_m × I κ``, ``κ = κ_s + κ_μ``
(:func:`curvature_correction`). It grows as ``b L² / I²``: negligible on a large spacecraft, and
as large as the gyro noise per interval on a small bus whose wheels hold newton-metre-seconds
and whose dead-band pulses fire every second, where ``κ_μ`` accumulates over an event (``κ_s``
largely cancels from one interval to the next).
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from jax import Array

from typing import NamedTuple

from cassini_bayes.physics.pulse import pulse_impulse_until

__all__ = ["StepPairs", "interval_moments", "second_order_correction", "step_pairs",
           "curvature_correction"]

SUBSTEPS = 64
"""Simpson panels per interval for the moments: a pulse's rise and fall (tens of ms) against a
sample interval of up to seconds."""


def _simpson_weights(n: int) -> np.ndarray:
    w = np.ones(n + 1)
    w[1:-1:2], w[2:-1:2] = 4.0, 2.0
    return w / (3.0 * n)


def interval_moments(t, t_on, thruster, width, slot, k: int, n_thrusters: int,
                     tau) -> tuple[np.ndarray, np.ndarray]:
    """``(m, P)``: per thruster and interval ending at sample ``i`` (0 at ``i = 0``), ``m`` (M, n)
    s² and ``P`` (M, M, n) s³ (module docstring) of the pulses commanded at ``t_on`` (p,) s on
    ``thruster`` (p,) with widths ``width`` (p,) s, ``slot`` (p,) their first sample at or after
    the command (``n``: none; width 0: padding), each over its ``k`` transient intervals and the
    one before, at the time constants ``tau`` (3,) s; Simpson's rule on :data:`SUBSTEPS`
    panels."""
    t = np.asarray(t, float)
    n = t.size
    slot = np.asarray(slot)
    ends = slot[:, None] + np.arange(0, k)[None, :]                       # (p, k) interval ends
    ok = (ends >= 1) & (ends < n) & (np.asarray(width) > 0)[:, None]
    e1 = np.clip(ends, 1, n - 1)
    t0, t1 = t[e1 - 1], t[e1]
    s = np.linspace(0.0, 1.0, SUBSTEPS + 1)
    times = t0[..., None] + (t1 - t0)[..., None] * s                     # (p, k, G)
    rel = times - np.asarray(t_on, float)[:, None, None]
    j = np.asarray(pulse_impulse_until(jnp.asarray(rel), jnp.asarray(width)[:, None, None],
                                       *tau))
    e = j - (j[..., :1] + (j[..., -1:] - j[..., :1]) * s)                  # less its line
    e = np.where(ok[..., None], e, 0.0)
    sums = np.zeros((n_thrusters, n, s.size))
    np.add.at(sums, (np.broadcast_to(np.asarray(thruster)[:, None], ends.shape)[ok], e1[ok]),
              e[ok])
    dt = np.r_[0.0, np.diff(t)]
    w = _simpson_weights(SUBSTEPS)
    m = np.einsum("kng,g->kn", sums, w * (s - 0.5)) * dt
    p = np.einsum("kng,lng,g->kln", sums, sums, w) * dt
    return m, p


class StepPairs(NamedTuple):
    """The non-zero products ``P_kl`` of :func:`interval_moments`: thrusters ``k``, ``l`` (r,)
    firing in the interval ending at sample ``at`` (r,), ``value`` (r,) s³ (padding: 0)."""

    k: Array
    l: Array  # noqa: E741 - the second thruster index of P_kl
    at: Array
    value: Array


def step_pairs(p: np.ndarray, size: int | None = None) -> StepPairs:
    """:class:`StepPairs` of ``p`` (M, M, n), padded with zeros to ``size`` entries (default:
    as many as are non-zero, at least one): thrusters fire in few intervals and few together."""
    k, l_, at = np.nonzero(p)
    size = max(1, k.size) if size is None else size
    pad = size - k.size
    return StepPairs(np.r_[k, np.zeros(pad, int)], np.r_[l_, np.zeros(pad, int)],
                     np.r_[at, np.zeros(pad, int)], np.r_[p[k, l_, at], np.zeros(pad)])


def second_order_correction(inertia: Array, q_f: Array, m: Array, pairs: StepPairs,
                            d_omega: Array, d_h: Array, dt: Array) -> Array:
    """(3, n) N m s per interval (not accumulated): what the trapezoidal ``ΔG`` and
    :func:`~cassini_bayes.physics.impulse.rate_step_correction` miss at second order (module
    docstring). ``q_f = Q diag(F)`` (3, M) N m; ``m`` (M, n) and ``pairs`` from
    :func:`interval_moments` and :func:`step_pairs`; ``d_omega`` (3, n) rad/s, ``d_h`` (3, n)
    N m s the samples' changes over each interval; ``dt`` (n,) s its length."""
    i_inv = jnp.linalg.inv(inertia)
    mu = i_inv @ (q_f @ m)                                                 # (3, n) rad
    b = inertia @ d_omega + d_h
    trap = -(jnp.asarray(dt)[None, :] / 6.0) * jnp.cross(d_omega, b, axis=0)
    first = jnp.cross(mu, b, axis=0) + jnp.cross(d_omega, inertia @ mu, axis=0)
    a = (i_inv @ q_f)[:, pairs.k]                                          # (3, r)
    pair = jnp.cross(a, q_f[:, pairs.l], axis=0) * pairs.value[None, :]
    return trap + first + jnp.zeros_like(trap).at[:, pairs.at].add(pair)


def curvature_correction(inertia: Array, q_f: Array, m: Array, d_omega: Array, d_h: Array,
                         dt: Array, omega_mid: Array, h_mid: Array) -> Array:
    """(3, n) N m s per interval (not accumulated): what the trapezoidal ``ΔG`` misses through
    the rate's bend inside each interval by Euler's equation (module docstring). ``q_f``, ``m``,
    ``d_omega``, ``d_h`` and ``dt`` as :func:`second_order_correction`; ``omega_mid`` (3, n)
    rad/s and ``h_mid`` (3, n) N m s the interval's mean rate and wheel momentum."""
    i_mat = jnp.asarray(inertia)
    i_inv = jnp.linalg.inv(i_mat)
    w_m, d_omega, dt = jnp.asarray(omega_mid), jnp.asarray(d_omega), jnp.asarray(dt)[None, :]
    big_l = i_mat @ w_m + jnp.asarray(h_mid)                               # (3, n) N m s
    secant = (dt**2 / 12.0) * (jnp.cross(d_omega, big_l, axis=0)
                               + jnp.cross(w_m, i_mat @ d_omega + d_h, axis=0))
    k = dt * (i_inv @ (q_f @ m))                                           # Δ μ (3, n) rad s
    kappa = i_inv @ (secant + jnp.cross(k, big_l, axis=0) + jnp.cross(w_m, i_mat @ k, axis=0))
    # Feldman & Lee Eq 15: the bend's change of ∫ ω × (I ω + H) dt, to first order in κ
    return jnp.cross(kappa, big_l, axis=0) + jnp.cross(w_m, i_mat @ kappa, axis=0)
