"""Check 1: attitude vs body rates (the quaternion columns' reading and the body-rate unit).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from cassini_bayes.consistency._programs import _conjugate, _rotvecs_between
from cassini_bayes.errors import InputError
from cassini_bayes.telemetry import RATE_NOISE_FLOORS, Telemetry, white_noise_sd

# Thresholds (margins measured in docs/input_checks.md)

READINGS = ("as declared", "scalar-first", "conjugated", "scalar-first and conjugated")
"""The four readings of the q1..q4 columns that the attitude check compares."""
ALIGN_GOOD = 0.9
"""A reading whose alignment with the body rates is at least this fits."""
MISFIT_RATIO = 5.0
"""Another reading fits clearly better when the declared one's misfit ``1 − alignment`` is at
least this many times its misfit."""
ALIGN_BAD = 0.5
"""With no other reading fitting, the declared one is refused when its alignment is below this
(body rates and attitude inconsistent)."""
RATE_SCALE_RANGE = (0.5, 2.0)
"""Accepted ratio of the attitude's rotation to the integrated body rate (1 for rad/s)."""
MIN_SEGMENTS = 5
"""Fewer turning stretches than this: the attitude check is not identifiable and is skipped."""
STILL_RATES_RAD = 0.2
"""With the attitude (nearly) still, the body rates may integrate to at most this rotation
(rad, 11.5°) before the two are called inconsistent: gyro noise and bias stay far below it (a
1e-6 rad/s bias turns 0.036 rad in ten hours)."""
STILL_RATIO = 0.1
"""… "nearly still": the quaternions turn by less than this fraction of that integrated
rotation."""
SEG_NOISE_SD = 20.0
"""A turning stretch turns by this many sd of the file's own noise: of its attitude, and of one
sample's integrated body rate (``σ_ω × dt``): relative to the file, so a spacecraft flown slower
with sensors to match is cut into the same stretches."""
_SEG_MAX_RAD = 0.05    # target turn per stretch is capped here (∫ω dt ≈ rotation vector)
_SEG_MAX_SAMPLES = 200  # longest stretch searched, samples
GAP_FACTOR = 3.0
"""A time step over this many median steps is a data gap: no turning stretch spans one."""


class AttitudeAgreement(NamedTuple):
    """How well each reading of the quaternion columns agrees with the body rates.

    Attributes
    ----------
    alignment : (4,) cosine between the stacked quaternion rotation vectors and ``∫ω dt``, one
        per reading of :data:`READINGS`.
    scale : ratio of the declared reading's rotation to ``∫ω dt`` (1 for rad/s, 0.0175 for °/s).
    segments : number of turning stretches used.
    turn_rad : total rotation over them, rad.
    """

    alignment: np.ndarray
    scale: float
    segments: int
    turn_rad: float


def _reading(q: np.ndarray, k: int) -> np.ndarray:
    """The quaternion (scalar last, inertial → body) under reading ``k`` of :data:`READINGS`."""
    if k in (1, 3):  # columns hold (q4, q1, q2, q3)
        q = np.roll(q, -1, axis=1)
    if k in (2, 3):  # body → inertial: the inverse rotation
        q = np.asarray(_conjugate(q))
    return q


def _attitude_noise(q: np.ndarray) -> float:
    """Attitude noise sd per axis (rad) from second differences of the per-step rotations.

    ``θ_k = rotvec(q_{k+1} q_k⁻¹)`` carries ``n_{k+1} − n_k`` of the attitude noise; its
    difference ``n_{k+2} − 2 n_{k+1} + n_k`` has variance ``6 σ²`` per axis, while smooth motion
    cancels. The median absolute deviation keeps slew starts and stops from inflating it.
    """
    if q.shape[0] < 4:
        return 0.0
    step = np.asarray(_rotvecs_between(q[:-1], q[1:]))
    d = np.diff(step, axis=0)
    return float(1.4826 * np.median(np.abs(d - np.median(d, axis=0))) / np.sqrt(6.0))


def _gaps_before(t: np.ndarray) -> np.ndarray:
    """(n,) number of data gaps (steps over :data:`GAP_FACTOR` × the median step) before each
    sample: a stretch ``(a, b)`` spans a gap when the counts at ``a`` and ``b`` differ."""
    dt = np.diff(np.asarray(t, float))
    if dt.size == 0:
        return np.zeros(len(t), int)
    gap = dt > GAP_FACTOR * float(np.median(dt))
    return np.concatenate([[0], np.cumsum(gap)])


def _segment_turn(q: np.ndarray, t: np.ndarray | None = None,
                  omega: np.ndarray | None = None) -> float:
    """The turn of a stretch, rad: :data:`SEG_NOISE_SD` × the larger of the attitude noise
    (:func:`_attitude_noise`) and one median step's integrated body-rate noise (``σ_ω`` floored
    at ``RATE_NOISE_FLOORS[0]`` for noise-free data), at most :data:`_SEG_MAX_RAD`."""
    step_rad = 0.0
    if t is not None and len(t) > 1:
        sd = max(white_noise_sd(omega) if omega is not None else 0.0, RATE_NOISE_FLOORS[0])
        step_rad = sd * float(np.median(np.diff(np.asarray(t, float))))
    return float(min(SEG_NOISE_SD * max(_attitude_noise(q), step_rad), _SEG_MAX_RAD))


def _turning_segments(q: np.ndarray, t: np.ndarray | None = None,
                      omega: np.ndarray | None = None) -> list[tuple[int, int]]:
    """Non-overlapping stretches ``(a, b)`` over which the attitude turns by a set angle.

    The angle is :func:`_segment_turn`'s (given the times ``t`` and body rates ``omega``),
    reached within :data:`_SEG_MAX_SAMPLES` samples; quiet stretches give none. The rotation angle
    between two quaternions is the same under every reading (``|q_a · q_b|`` is invariant under
    reordering and conjugation), so the stretches are too. Given the times ``t``, no stretch spans
    a data gap (:func:`_gaps_before`): across a gap the trapezoid ``∫ω dt`` is a straight line
    through whatever the spacecraft did, and one such stretch had swayed the whole comparison
    into a "check the rates' unit" refusal.
    """
    n = q.shape[0]
    gaps = _gaps_before(t) if t is not None else np.zeros(n, int)
    target = _segment_turn(q, t, omega)
    lmax = min(_SEG_MAX_SAMPLES, n - 1)
    reach = np.full(n, -1)
    for lag in range(lmax, 0, -1):  # smallest lag wins
        # the rotation angle of telemetry._turn_angle, for every pair lag samples apart
        sign = np.where(np.sum(q[lag:] * q[:-lag], axis=1) < 0, -1.0, 1.0)[:, None]
        ang = 4.0 * np.arctan2(np.linalg.norm(q[lag:] - sign * q[:-lag], axis=1),
                               np.linalg.norm(q[lag:] + sign * q[:-lag], axis=1))
        hit = np.flatnonzero((ang >= target) & (gaps[lag:] == gaps[:-lag]))
        reach[hit] = hit + lag
    out, a = [], 0
    while a < n - 1:
        if reach[a] > a:
            out.append((a, int(reach[a])))
            a = int(reach[a])
        else:
            a += 1
    return out


def _integrated_rates(tel: Telemetry) -> np.ndarray:
    """(n, 3) rad: the trapezoid integral ``∫ω dt`` of the body rates from the first sample,
    nothing added across a data gap (:func:`_gaps_before`: what the rates did there is unknown)."""
    t = np.asarray(tel.t, float)
    w = np.asarray(tel.omega, float)
    step = 0.5 * (w[1:] + w[:-1]) * np.diff(t)[:, None]
    step[np.diff(_gaps_before(t)) > 0] = 0.0
    return np.concatenate([np.zeros((1, 3)), np.cumsum(step, axis=0)])


def attitude_rate_agreement(tel: Telemetry) -> AttitudeAgreement | None:
    """Compare the quaternions' rotation with the integrated body rates, per reading.

    Per stretch ``(a, b)`` of :func:`_turning_segments`: the rotation vector
    ``rotvec(q_b q_a⁻¹)`` (:mod:`cassini_bayes.frames`: ``q(t + dt) = rotvec_to_quat(ω dt) q(t)``)
    and the trapezoid integral ``∫ω dt`` (equal to it up to the small non-commuting part of a
    ≤ 0.05 rad turn). ``None`` when fewer than :data:`MIN_SEGMENTS` stretches turn (not
    identifiable).
    """
    q = np.asarray(tel.q, float)
    if q.shape[0] < 4:
        return None
    segs = _turning_segments(q, np.asarray(tel.t, float), np.asarray(tel.omega, float))
    if len(segs) < MIN_SEGMENTS:
        return None
    a_idx = np.array([s[0] for s in segs])
    b_idx = np.array([s[1] for s in segs])
    steps = _integrated_rates(tel)
    g = steps[b_idx] - steps[a_idx]
    rots = [np.asarray(_rotvecs_between(qk[a_idx], qk[b_idx]))
            for qk in (_reading(q, k) for k in range(len(READINGS)))]
    gg = float(np.sum(g * g))
    rr = float(np.sum(rots[0] ** 2))  # the same for every reading (angles are invariant)
    if not (gg > 0 and rr > 0):
        return None
    align = np.array([float(np.sum(r * g)) / np.sqrt(rr * gg) for r in rots])
    scale = float(np.sum(rots[0] * g)) / gg
    turn = float(np.sum(np.linalg.norm(rots[0], axis=1)))
    return AttitudeAgreement(align, scale, len(segs), turn)


def _check_still_attitude(tel: Telemetry) -> None:
    """Where the attitude hardly turns (too little for :func:`attitude_rate_agreement`), the
    body rates must not integrate to a turn either: refuse a file whose rates show slews of
    more than :data:`STILL_RATES_RAD` while its quaternions turn by less than
    :data:`STILL_RATIO` of that (stale or constant attitude columns, rates of another file)."""
    from cassini_bayes.telemetry import _turn_angle

    q = np.asarray(tel.q, float)
    if q.shape[0] < 2:
        return
    rates_turn = float(np.linalg.norm(_integrated_rates(tel), axis=1).max())
    q_turn = float(_turn_angle(q, q[0]).max())
    if rates_turn > STILL_RATES_RAD and q_turn < STILL_RATIO * rates_turn:
        raise InputError(f"columns q1..q4 and wx wy wz: the body rates integrate to a turn of "
                         f"{np.degrees(rates_turn):.3g}° but the quaternions turn by at most "
                         f"{np.degrees(q_turn):.3g}°: the attitude columns look stale or "
                         "constant, or the rates belong to another file", path=tel.source)


def check_attitude_rates(tel: Telemetry) -> AttitudeAgreement | None:
    """Refuse a quaternion convention or body-rate unit that the kinematics contradict.

    Raises :class:`InputError` when another reading of q1..q4 fits (alignment ≥
    :data:`ALIGN_GOOD`) with a misfit ``1 − alignment`` at least :data:`MISFIT_RATIO` times
    smaller than the declared reading's (naming that reading, or every such reading when the
    rotation, e.g. about a single axis from the identity, cannot tell them apart); when no
    reading fits and the declared one aligns by less than :data:`ALIGN_BAD` (rates and attitude
    inconsistent); or when the declared reading fits but the rotation is not about 1× the
    integrated rate (°/s or mrad/s body rates). Returns the agreement (``None``: not
    identifiable, no check).
    """
    ag = attitude_rate_agreement(tel)
    if ag is None:
        _check_still_attitude(tel)
        return None
    src = tel.source
    c = ag.alignment
    stats = (f"alignment of the quaternions' rotation with ∫ω dt over {ag.segments} turning "
             f"stretches: {c[0]:.2f} as written")
    fits = [k for k in range(1, len(READINGS))
            if c[k] >= ALIGN_GOOD and 1.0 - c[0] >= MISFIT_RATIO * (1.0 - c[k])]
    if len(fits) == 1:
        k = fits[0]
        cause = {
            1: "the quaternion looks scalar-first (q4 first); write q1 q2 q3 (vector part) "
               "first and the scalar q4 last",
            2: "the quaternion looks conjugated (body → inertial); the format wants "
               "inertial → body: negate q1 q2 q3",
            3: "the quaternion looks scalar-first and conjugated (body → inertial); write "
               "the vector part first, negated, and the scalar q4 last",
        }[k]
        raise InputError(f"columns q1..q4: {cause} ({stats}, {c[k]:.2f} {READINGS[k]})",
                         path=src)
    if fits:  # rotation about too few axes to tell these readings apart
        alts = " or ".join(f"{READINGS[k]} ({c[k]:.2f})" for k in fits)
        raise InputError(f"columns q1..q4: the quaternion does not follow the format's "
                         f"convention but fits the body rates read as {alts} ({stats}); the "
                         "format wants q1 q2 q3 (vector part) first, the scalar q4 last, "
                         "inertial → body", path=src)
    if c[0] < ALIGN_BAD:
        raise InputError(f"columns q1..q4 and wx wy wz: body rates and attitude are inconsistent "
                         f"({stats}, at most {c[1:].max():.2f} read otherwise: scalar-first or "
                         "conjugated); check that wx wy wz are rad/s in body axes and q is "
                         "inertial → body, scalar last", path=src)
    lo, hi = RATE_SCALE_RANGE
    if not lo <= ag.scale <= hi:
        ratio = 1.0 / ag.scale if ag.scale > 0 else np.inf
        if 30.0 < ratio < 100.0:
            guess = "they look like deg/s: divide by 57.2958"
        elif 300.0 < ratio < 3000.0:
            step = float(np.median(np.diff(np.asarray(tel.t, float))))
            guess = ("they look like mrad/s: divide by 1000; or the time column t is in "
                     f"milliseconds (median step {step:.4g} s): the format wants seconds")
        else:
            guess = "check their unit"
        raise InputError(f"columns wx wy wz: the body rates integrate to {ratio:.3g}x the "
                         f"rotation the quaternions show; {guess} (body rates must be rad/s)",
                         path=src)
    return ag
