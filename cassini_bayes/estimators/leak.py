"""Thruster-leak monitor quantities (Lee, §3.2, Eqs 10-11).

The residual momentum ``R(t) = ∫ (I ω̇ + ω × (I ω + H) − T_RWA − T_PMS^f) dt`` (Eq 10) grows when a
thruster leaks. With the wheels' reaction torque ``T_RWA = −Ḣ_RWA`` it integrates to
``R(t) = I Δω + ΔH_RWA + ΔG − Q J(t)``: the left side of Feldman & Lee Eq 17 minus the modelled
thruster angular impulse, for any thruster set. The correction for thruster-to-thruster
variation (Eq 11) and the threshold monitor are Cassini's: Eq 11 pairs the eight thrusters of
Feldman & Lee Eq 16 by name and arm, and ``R_T`` is in Cassini's momentum.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.physics.impulse import (angular_impulse, impulse_lhs, jump_areas,
                                           rate_step_correction)
from cassini_bayes.physics.rate_step_moments import (interval_moments, second_order_correction,
                                                     step_pairs, curvature_correction)

__all__ = ["residual_momentum", "rate_step_columns", "rate_step_units",
           "rate_step_second_order", "leak_torque",
           "momentum_correction", "threshold_monitor", "ThresholdResult", "LEAK_THRESHOLD_NMS",
           "T_LIMIT_CRUISE_S", "ETA", "Z_ARM_M"]

_lhs = jax.jit(impulse_lhs)

LEAK_THRESHOLD_NMS = 50.0  # Lee §3.2: R_T
T_LIMIT_CRUISE_S = 36000.0  # Lee §3.2: T_limit = 10 h in cruise
ETA = 0.05                 # Lee Eq 11: thruster-to-thruster variation at launch
Z_ARM_M = 1.6              # Lee Eq 11: mean moment arm of the Z-facing thrusters, m


def residual_momentum(t_s, omega_rad_s, inertia, h_wheels_body, q_matrix,
                      impulse_ns) -> np.ndarray:
    """Residual momentum ``R(t_i)`` (N m s), (n, 3), Lee Eq 10.

    ``impulse_ns`` (n, m): modelled accumulated thruster impulses (N s, e.g. ``F Δτ``);
    ``q_matrix`` (3, m) moment matrix (m). Other arguments as in
    :func:`cassini_bayes.physics.impulse.impulse_lhs`.
    """
    v = _lhs(np.asarray(t_s, float), np.asarray(omega_rad_s, float), np.asarray(inertia),
                    np.asarray(h_wheels_body, float))
    # Lee Eq 10 with T_RWA = -dH_RWA/dt: R = I dw + dH_RWA + dG - Q J
    return np.asarray(v - angular_impulse(q_matrix, impulse_ns))


_TAIL_TAUS = 40.0   # a pulse's thrust is below e⁻⁴⁰ of its peak this many fall times after it
_jump_areas = jax.jit(jump_areas, static_argnums=(5, 6))
# per wheel-momentum history and body axis a: the correction of a unit area e_a in every
# interval (accumulated)
_unit_corrections = jax.jit(jax.vmap(jax.vmap(
    lambda inertia, e_a, w_m, h_m: rate_step_correction(
        inertia, jnp.broadcast_to(e_a[:, None], w_m.shape), w_m, h_m),
    in_axes=(None, 0, None, None)), in_axes=(None, None, None, 0)))


def interval_means(x: np.ndarray) -> np.ndarray:
    """(..., 3, n): the mean of samples ``i − 1`` and ``i`` of ``x`` (..., n, 3) at ``i`` (the
    first sample's own value at ``i = 0``)."""
    x = np.asarray(x, float)
    mid = np.concatenate([x[..., :1, :], 0.5 * (x[..., 1:, :] + x[..., :-1, :])], -2)
    return np.swapaxes(mid, -1, -2)


def rate_step_units(t_s, omega_rad_s, inertia, h_wheels_body) -> np.ndarray:
    """(..., 3, 3, n) N m s per N m s²: per interval (ending at sample ``i``), what the
    trapezoidal ``ΔG`` misses for a unit area ``Q (F ⊙ ε)`` along body axis ``a`` (``[..., a,
    b, i]``, ``b`` the axis of the miss): the increments of
    :func:`~cassini_bayes.physics.impulse.rate_step_correction`, linear in the area.
    ``h_wheels_body`` (n, 3) N m s, or (B, n, 3) for several wheel-momentum histories at once;
    other arguments as :func:`~cassini_bayes.physics.impulse.impulse_lhs`. ``t_s`` only sets
    the sample count. Affine in the wheel momentum: the difference of two histories' units is
    the units of their difference's momentum term."""
    h = np.asarray(h_wheels_body, float)
    batch = h.reshape((-1,) + h.shape[-2:])
    unit = np.asarray(_unit_corrections(np.asarray(inertia, float), np.eye(3),
                                        interval_means(np.asarray(omega_rad_s, float)),
                                        interval_means(batch)))          # (B, 3a, 3b, n)
    assert unit.shape[-1] == np.size(t_s)
    return np.diff(unit, axis=-1, prepend=0.0).reshape(h.shape[:-2] + unit.shape[1:])


def rate_step_columns(t_s, omega_rad_s, inertia, h_wheels_body, pulses, tau,
                      n_thrusters: int, units: np.ndarray | None = None) -> np.ndarray:
    """(n, 3, M, 3) N m s per N per m: what the trapezoidal ``ΔG`` (Feldman & Lee Eq 15) misses
    across the pulses' rate steps, per newton of thruster ``s`` and per metre of its moment arm
    along body axis ``a`` (``[..., s, a]``), accumulated to each sample: the dense form of
    :func:`~cassini_bayes.physics.impulse.rate_step_correction` for a least-squares design.

    The correction is linear in the thrusts and in the arms, so ``V + Σ_s F_s C[:, :, s] @ q_s``
    is Eq 17's left side with the steps put back (``q_s`` column ``s`` of ``Q``): an estimator
    linear in ``F`` subtracts ``C[:, :, s] @ q_s`` from each thruster's column ``q_s j_s``
    instead of guessing the thrust. ``pulses`` ``(t_on, thruster, width)``; ``tau`` (3,) s the
    time constants of :func:`~cassini_bayes.physics.impulse.jump_areas`; ``units`` the
    :func:`rate_step_units` of the same samples (computed when not given: they do not depend on
    the pulses or ``tau``); other arguments as :func:`~cassini_bayes.physics.impulse.impulse_lhs`.
    The correction's own dependence on the inertia is second order in the inertia's error and
    is taken at ``inertia``.
    """
    t = np.asarray(t_s, float)
    t_on, thr, width = (np.asarray(x) for x in pulses)
    n = t.size
    if n < 2 or t_on.size == 0:
        return np.zeros((n, 3, n_thrusters, 3))
    slot, k = _slots(t, t_on, width, tau)
    eps = np.asarray(_jump_areas(t, t_on, np.asarray(thr, int), width, slot, k, n_thrusters,
                                 tuple(float(x) for x in tau)))                   # (M, n) s²
    if units is None:
        units = rate_step_units(t, omega_rad_s, inertia, h_wheels_body)
    return np.cumsum(np.einsum("sn,abn->nbsa", eps, units), axis=0)               # (n, 3, M, 3)


def _slots(t: np.ndarray, t_on: np.ndarray, width: np.ndarray, tau) -> tuple[np.ndarray, int]:
    """Each pulse's first sample at or after its command, and the samples its thrust lasts."""
    td, _, tf = (float(x) for x in tau)
    k = int(np.ceil((float(np.max(width)) + td + _TAIL_TAUS * tf)
                    / float(np.min(np.diff(t))))) + 1
    return np.searchsorted(t, t_on, side="left"), k


_BUCKET = 128
"""Pulses, samples and pulse pairs are padded to multiples of this (padding adds nothing): events
and stretches of similar size share one compiled program."""


@jax.jit
def _second_order(inertia, q_f, m, pairs, d_omega, d_h, dt, omega_mid, h_mid):
    return (second_order_correction(inertia, q_f, m, pairs, d_omega, d_h, dt)
            + curvature_correction(inertia, q_f, m, d_omega, d_h, dt, omega_mid, h_mid))


def _bucket(n: int) -> int:
    return max(1, -(-n // _BUCKET)) * _BUCKET


def rate_step_second_order(t_s, omega_rad_s, inertia, h_wheels_body, pulses, tau,
                           q_f) -> np.ndarray:
    """(n, 3) N m s: what the trapezoidal ``ΔG`` (Feldman & Lee Eq 15) and
    :func:`rate_step_columns` miss at second order across the pulses' rate steps, accumulated to
    each sample (:func:`~cassini_bayes.physics.rate_step_moments.second_order_correction` and
    :func:`~cassini_bayes.physics.rate_step_moments.curvature_correction`); add it to
    Eq 17's left side.

    Evaluated at the thrusts ``q_f = Q diag(F)`` (3, M) N m and the time constants ``tau`` (3,)
    s given, as a known offset: the term is quadratic in the thrusts, which a linear
    least-squares design cannot carry, and a thrust error ``δ`` changes it by a fraction ``~δ``
    of a term that is already second order. ``pulses`` ``(t_on, thruster, width)``; other
    arguments as :func:`~cassini_bayes.physics.impulse.impulse_lhs`. Its trapezoid-of-two-lines
    part needs no pulse: it is carried on every interval, as the thrust likelihood carries it."""
    t = np.asarray(t_s, float)
    q_f = np.asarray(q_f, float)
    n, n_thr = t.size, q_f.shape[1]
    if n < 2:
        return np.zeros((n, 3))
    t_on, thr, width = (np.asarray(x) for x in pulses)
    size = _bucket(n)
    m, p = np.zeros((n_thr, n)), np.zeros((n_thr, n_thr, n))
    if t_on.size:
        pad = _bucket(t_on.size) - t_on.size          # width 0 after the end: no impulse
        t_on = np.r_[t_on.astype(float), np.full(pad, t[-1] + 1.0)]
        thr, width = np.r_[thr.astype(int), np.zeros(pad, int)], np.r_[width.astype(float),
                                                                         np.zeros(pad)]
        slot, k = _slots(t, t_on, width, tau)
        m, p = interval_moments(t, t_on, thr, width, slot, k, n_thr,
                                tuple(float(x) for x in tau))
    pairs = step_pairs(p, _bucket(int(np.count_nonzero(p))))

    def change(x):
        x = np.asarray(x, float)
        return np.pad(np.diff(x, axis=0, prepend=x[:1]).T, ((0, 0), (0, size - n)))

    def mean(x):
        return np.pad(interval_means(x), ((0, 0), (0, size - n)))

    c = _second_order(np.asarray(inertia, float), q_f, np.pad(m, ((0, 0), (0, size - n))), pairs,
                      change(omega_rad_s), change(h_wheels_body),
                      np.pad(np.diff(t, prepend=t[0]), (0, size - n)),
                      mean(omega_rad_s), mean(h_wheels_body))
    return np.cumsum(np.asarray(c)[:, :n], axis=1).T


def leak_torque(q_matrix, thruster: int, leak_fraction: float, thrust_n: float = 1.0) -> np.ndarray:
    """Torque (N m), (3,), of a thruster leaking ``leak_fraction`` of its thrust ``thrust_n``.

    Column ``thruster`` of ``Q`` (Feldman & Lee Eq 16) scaled: a 10 % Z1 leak at 1 N gives
    (−0.158, +0.1234, 0) N m; Lee §3.2 prints −0.158 and +0.124.
    """
    return leak_fraction * thrust_n * np.asarray(q_matrix, float)[:, thruster]


def momentum_correction(delta_j_ns, eta: float = ETA, arm_m: float = Z_ARM_M) -> np.ndarray:
    """Correction ``R^corr`` (N m s), (3,), for thruster-to-thruster variation, Lee Eq 11.

    ``delta_j_ns`` (8,) impulses (N s) accumulated by ``Z1 … Y4`` over the last sample time.
    X: ``2 η · 1.6 · |ΔJ_Z3 + ΔJ_Z4 − ΔJ_Z1 − ΔJ_Z2|`` exactly as printed. The paper computes
    Y and Z "similarly"; here Y pairs the Z thrusters by the sign of their Y arm
    (``|ΔJ_Z1 + ΔJ_Z4 − ΔJ_Z2 − ΔJ_Z3|``) and Z pairs the Y thrusters by the sign of their Z arm
    (``|ΔJ_Y2 + ΔJ_Y4 − ΔJ_Y1 − ΔJ_Y3|``), both with the same factor ``2 η · arm_m`` (our reading).
    """
    dj = np.asarray(delta_j_ns, float)
    z1, z2, z3, z4, y1, y2, y3, y4 = (dj[..., k] for k in range(8))
    # Lee Eq 11: dJ_x = |dJ_Z3 + dJ_Z4 - dJ_Z1 - dJ_Z2|, R_x^corr = 2 eta 1.6 dJ_x
    dj_x = np.abs(z3 + z4 - z1 - z2)
    dj_y = np.abs(z1 + z4 - z2 - z3)
    dj_z = np.abs(y2 + y4 - y1 - y3)
    return 2.0 * eta * arm_m * np.stack([dj_x, dj_y, dj_z], -1)


@dataclass(frozen=True)
class ThresholdResult:
    """Lee's monitor over a stretch: ``detection_time_s`` (first trigger with
    ``T_trigger ≤ T_limit``, ``None``: none), its ``axis`` (0..2), the thruster whose torque
    column best matches the polarities of ``R`` then (``None``: none), and the times of the
    triggers that were dismissed (``T_trigger > T_limit``) or acted on."""

    detection_time_s: float | None
    axis: int | None
    thruster: int | None
    triggers_s: tuple[float, ...]
    dismissed_s: tuple[float, ...]


def threshold_monitor(t_s, residual_nms, impulse_ns, q_matrix, *,
                      r_t_nms: float = LEAK_THRESHOLD_NMS, t_limit_s: float = T_LIMIT_CRUISE_S,
                      eta: float = ETA, arm_m: float = Z_ARM_M) -> ThresholdResult:
    """Lee's threshold test (§3.2, Eqs 10-11) on a residual ``R`` (n, 3) N m s.

    From the last reset, the check is ``|R_i − R_i(reset)| − C_i ≥ r_t_nms`` with ``C`` the
    accumulated Eq 11 correction (:func:`momentum_correction` of each sample's impulses
    ``impulse_ns`` (n, 8) N s). The paper "adds" ``R^corr`` to ``R``; as ``R^corr ≥ 0`` bounds the
    momentum thruster-to-thruster variation may have built up, we read it as a margin on
    ``|R_i|`` (our reading). A trigger within ``t_limit_s`` of the reset is a leak (the first is
    the detection); a later one is dismissed as slow accumulation. Both reset ``R`` and ``C``.
    The leaking thruster is the column of ``q_matrix`` (3, 8) closest in direction to ``R`` since
    the reset ("the polarities of R_i reveal the identity of the leaky thruster").
    """
    t = np.asarray(t_s, float)
    r = np.asarray(residual_nms, float)
    corr = np.cumsum(momentum_correction(np.diff(np.asarray(impulse_ns, float), axis=0,
                                                 prepend=0.0), eta, arm_m), axis=0)
    q = np.asarray(q_matrix, float)
    q_unit = q / np.linalg.norm(q, axis=0)
    start, triggers, dismissed = 0, [], []
    detection = axis = thruster = None
    while start < t.size:
        excess = np.abs(r[start:] - r[start]) - (corr[start:] - corr[start]) - r_t_nms
        hit = np.nonzero(np.any(excess >= 0.0, axis=1))[0]
        if hit.size == 0:
            break
        i = start + int(hit[0])
        if t[i] - t[start] <= t_limit_s:
            triggers.append(float(t[i]))
            if detection is None:
                d = r[i] - r[start]
                detection, axis = float(t[i]), int(np.argmax(excess[hit[0]]))
                thruster = int(np.argmax(q_unit.T @ (d / np.linalg.norm(d))))
        else:
            dismissed.append(float(t[i]))
        start = i
        if i == t.size - 1:
            break
    return ThresholdResult(detection, axis, thruster, tuple(triggers), tuple(dismissed))
