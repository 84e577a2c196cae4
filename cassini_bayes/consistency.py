"""Unit and convention checks that use the physics in the data, not magnitude thresholds.

A file can pass every rule of :mod:`cassini_bayes.telemetry` and still be read wrongly: wheel
rates written in rad/s where the format wants rpm, a quaternion written scalar-first or
conjugated, a pulse log that does not belong to the telemetry's own ``on_*`` columns, or data
that cannot identify what a fit asks for. Each such mistake gives a wrong answer, not a crash, so
each is refused here (:class:`~cassini_bayes.errors.InputError`, one line naming the file and the
likely cause) from relations the data must obey whatever the unit of a column:

1. **Attitude vs body rates** (:func:`attitude_rate_agreement`). Consecutive attitudes are tied to
   the gyro rates by the kinematics ``q̇ = ½ Ω(ω) q`` (Brown Eq 2 convention,
   :mod:`cassini_bayes.frames`): the rotation from ``q(t_a)`` to ``q(t_b)`` is the integrated body
   rate. Over stretches where the attitude turns measurably the quaternion rotation vectors are
   compared with ``∫ω dt`` under four readings of the columns (as declared; scalar first;
   conjugated; both) by their alignment (the cosine between the stacked vectors, 1 for a perfect
   fit, near 0 or negative for a wrong reading) and, for the declared reading, their ratio (the
   body-rate unit: 57.3 for °/s).
2. **Wheel units, signs and order vs momentum conservation** (:func:`wheel_momentum_scale`).
   Between thruster firings the inertial momentum ``A(q)ᵀ (I ω + Σ J_k ρ_k g_k)`` changes only
   by the external torque's impulse (Feldman & Lee Eqs 2-3; a constant torque is fitted). With the model's predicted inertia (known to ±10 %) the balance is
   fitted with the wheel momentum times a free scale ``κ``: ``κ ≈ 1`` for rpm as the file
   format wants, ``κ ≈ 60/(2π) = 9.55`` when the wheel columns hold rad/s (the wheel momentum
   read ×0.105). Where slews about several axes separate the wheels, it is fitted again with a free
   momentum vector per wheel (:class:`WheelAxes`): each must lie along its wheel's axis in the
   model (a flipped sign gives the opposite direction, swapped columns another wheel's axis).
3. **Pulse log vs ``on_*`` columns** (:func:`check_pulses_match_on_times`): the cumulative
   on-time the pulse log implies (:func:`cassini_bayes.telemetry.cumulative_on_times`) must match
   the telemetry's own counters.
4. **Quantised rates** (:func:`check_rate_quantisation`, a warning): a body-rate or wheel-rate
   column whose values lie on a lattice ``q k`` with a quantum ``q`` far above the noise
   measured in the column and not small against the column's excursion; its rounding error is
   then no noise the fits model but an error that repeats while the rate holds its value.
5. **Identifiability for the fit asked for** (:func:`check_inertia_excitation`,
   :func:`check_rwa4_method`): an inertia fit needs rotation about more than one body axis; the
   RWA method of the RWA4 calibration needs the wheels that carry the slews (Brown Eq 3).

Thresholds and the margins measured on every scenario in ``experiments/scenarios/`` and on
corrupted copies are in ``docs/input_checks.md``. A check whose statistic is not identifiable
from the data (no rotation, no momentum exchange) says nothing.

The entry points called by the CLI right after reading the inputs are
:func:`check_telemetry_data` (``cassini-bayes check``), :func:`check_inertia_data`,
:func:`check_thrust_data` and :func:`check_rwa4_data`.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import NamedTuple

import jax
import numpy as np

from cassini_bayes.errors import InputError, UnidentifiableError, arg
from cassini_bayes.frames import dcm, quat_conjugate, quat_multiply, quat_to_rotvec
from cassini_bayes.physics.momentum import INERTIA_NAMES, wheel_momentum_body
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import (RPM_TO_RAD_S, PulseLog, PulseSpanWarning,
                                     RATE_NOISE_FLOORS, Telemetry, check_pulses_in_span,
                                     cumulative_on_times, white_noise_sd)

# The checks' JAX work as four programs: called eagerly on NumPy arrays, every frames function
# is a few one-operation programs, each loaded (or compiled) in every process.
_rotvecs_between = jax.jit(lambda qa, qb: quat_to_rotvec(quat_multiply(qb, quat_conjugate(qa))))
_conjugate = jax.jit(quat_conjugate)
_dcm = jax.jit(dcm)
_wheel_momentum_body = jax.jit(wheel_momentum_body)


__all__ = [
    "READINGS",
    "AttitudeAgreement",
    "MomentumScale",
    "WheelAxes",
    "attitude_rate_agreement",
    "check_attitude_rates",
    "GyroBias",
    "GyroBiasWarning",
    "gyro_bias_estimate",
    "check_gyro_bias",
    "RateQuantum",
    "QuantisedRatesWarning",
    "rate_quantum",
    "quantised_rates",
    "check_rate_quantisation",
    "wheel_momentum_scale",
    "check_wheel_units",
    "axis_angle_max_deg",
    "check_pulses_match_on_times",
    "inertia_excitation",
    "check_inertia_excitation",
    "check_rwa4_method",
    "check_telemetry_data",
    "check_inertia_data",
    "check_thrust_data",
    "check_rwa4_data",
]

# ---------------------------------------------------------------------------------------------
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
_SEG_NOISE = 20.0      # a turning stretch turns by this many attitude-noise sd …
_SEG_MIN_RAD = 1e-3    # … and at least this much
_SEG_MAX_RAD = 0.05    # target turn per stretch is capped here (∫ω dt ≈ rotation vector)
_SEG_MAX_SAMPLES = 200  # longest stretch searched, samples

GYRO_WINDOW_MIN_SAMPLES = 4
"""Shortest window of :func:`gyro_bias_estimate`, samples; longer ones double from it."""
GYRO_MIN_WINDOWS = 8
"""Fewest quiet windows of one length that :func:`gyro_bias_estimate` uses (the standard error
comes from their scatter)."""
GYRO_WINDOW_TURN_RAD = 2e-3
"""Windows whose attitude turns more than this (rad) are left out of the gyro-bias estimate."""
GYRO_BIAS_Z = 5.0
"""A gyro bias is reported beyond this many prior sd and this many standard errors."""
QUANTUM_LATTICE_TOL = 1e-3
"""Values lie on a lattice of spacing ``q`` when every difference between two distinct values is
a whole multiple of ``q`` to within this fraction of ``q`` (text round trips and the rpm → rad/s
conversion leave ~1e-12)."""
QUANTUM_NOISE_RATIO = 4.0
"""A rate column's quantum is not hidden in its noise when it is at least this many times the
white-noise sd measured in the column: noise of sd ≥ 0.4 q before the rounding dithers the
quantiser and measures 0.61 q (second differences of ±1, ±2 quanta); below about q/3 it
measures 0 (second differences mostly zero), so the ratio is 1.65 or infinite."""
QUANTUM_EXCURSION_MIN = 5e-4
"""... and it is large against the signal when it is at least this fraction of the column's
excursion (its 0.5–99.5 percentile range): undithered quanta from about this fraction on moved
an inertia fit by two posterior sd (docs/input_checks.md)."""
GAP_FACTOR = 3.0
"""A time step over this many median steps is a data gap: no turning stretch spans one."""
MOMENTUM_ALIGN_MIN = 0.9
"""The wheel-unit check judges ``κ`` only when the balance fits this well (alignment)."""
RAD_S_FACTOR = 1.0 / RPM_TO_RAD_S
"""``κ`` expected when the wheel columns hold rad/s: 60/(2π) = 9.55."""
KAPPA_RANGE = (float(np.sqrt(RPM_TO_RAD_S)), float(1.0 / np.sqrt(RPM_TO_RAD_S)))
"""Accepted wheel-momentum scale ``κ``: the geometric midpoints between 1 (rpm) and 60/(2π)
(rad/s) or its inverse, 0.324 … 3.09; the ±10 % knowledge of the moments moves ``κ`` by 10 %."""
AXES_CONDITION_MIN = 0.1
"""Each wheel's free momentum vector is judged only when the free-axis balance's design is this
well conditioned (smallest/largest singular value, unit columns): 0.29–0.47 on slews (shipped and
open-world), 0.017–0.14 on biasing events (their wheels move together)."""
AXES_ALIGN_MIN = 0.99
"""In a file without thruster firings (no ``on_*`` columns, no pulse log), the free-axis balance
must fit at least this well where separable: 0.9984–1.0000 on 160 open-world and every shipped
slew and RWA-method file (Basilisk's slews 0.9999); one tachometer reporting |rpm| through zero
0.962."""
SWING_MIN_SNR = 100.0
"""... and only where the body and the wheels exchange at least this many times the momentum
noise of one sample (:attr:`WheelAxes.noise_nms`): Cassini's shipped slews swing 18–22 N m s
against ~0.007 N m s of noise (a quiet file's swing is that noise), the ESPA bus 0.39 N m s
against 1.4e-4, the 12U CubeSat 9.5e-3 against 2.9e-5. At 100× the balance's misfit from
noise alone is ~1e-4, far inside :data:`AXES_ALIGN_MIN`."""
UNSIGNED_TOUCH_RPM = 5.0
"""A wheel that stays on one side of zero yet comes within this (rpm) of it is named as possibly
unsigned in :func:`_balance_error`."""
AXIS_ANGLE_MAX_DEG = 30.0
"""Largest accepted angle between a wheel's fitted momentum and its axis in the model: a flipped
sign gives 180°, another wheel's column the angle between the two axes (Cassini's fixed wheels
90°, a pyramid's 70.5°, a CubeSat's skew wheel 54.7° from each body axis). Smaller where the
model's wheels are closer: half the smallest angle between two of its (non-articulated) wheel
lines (:func:`axis_angle_max_deg`), so another wheel's column always lies beyond it."""

EXCITATION_MIN = 1e-3
"""Second-largest over largest eigenvalue of ``Σ ω ωᵀ dt``: below it the slews turn the
spacecraft about one axis only."""
RWA_METHOD_MIN_KNOWN = 2
"""The RWA method (Brown Eq 3) needs this many running wheels besides the one solved for."""
CONTROL_WHEEL_RPM = 10.0
"""A wheel whose rate changes by more than this (rpm) over the record takes part in the control
(a rate: a wheel sized to its spacecraft exchanges hundreds of rpm in a slew, whatever the size)
…"""
CONTROL_NOISE_SD = 10.0
"""… and by more than this many times its own white noise (the range of white noise over
thousands of samples is ~8 sd: a CubeSat's 1-rpm hall sensors)."""


# ---------------------------------------------------------------------------------------------
# 1. Attitude vs body rates


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


class GyroBiasWarning(UserWarning):
    """The data show a gyro bias beyond the spacecraft model's ``[gyro]`` knowledge."""


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


def _turning_segments(q: np.ndarray, t: np.ndarray | None = None) -> list[tuple[int, int]]:
    """Non-overlapping stretches ``(a, b)`` over which the attitude turns by a set angle.

    The angle is ``clip(20 σ_att, 1e-3, 0.05)`` rad (``σ_att`` from :func:`_attitude_noise`),
    reached within :data:`_SEG_MAX_SAMPLES` samples; quiet stretches give none. The rotation angle
    between two quaternions is the same under every reading (``|q_a · q_b|`` is invariant under
    reordering and conjugation), so the stretches are too. Given the times ``t``, no stretch spans
    a data gap (:func:`_gaps_before`): across a gap the trapezoid ``∫ω dt`` is a straight line
    through whatever the spacecraft did, and one such stretch had swayed the whole comparison
    into a "check the rates' unit" refusal.
    """
    n = q.shape[0]
    gaps = _gaps_before(t) if t is not None else np.zeros(n, int)
    target = float(np.clip(_SEG_NOISE * _attitude_noise(q), _SEG_MIN_RAD, _SEG_MAX_RAD))
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
    segs = _turning_segments(q, np.asarray(tel.t, float))
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


class GyroBias(NamedTuple):
    """Constant gyro bias seen in the data: the body rates' integral against the quaternions'
    rotation over quiet windows (:func:`gyro_bias_estimate`).

    Attributes
    ----------
    bias : (3,) rad/s, body axes: what the rates read above the truth.
    se : (3,) rad/s, its standard error from the windows' scatter.
    windows : number of windows used.
    window_s : their length, s.
    """

    bias: np.ndarray
    se: np.ndarray
    windows: int
    window_s: float = 0.0


def _quiet_windows(t: np.ndarray, q: np.ndarray, gaps: np.ndarray,
                   length_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Consecutive gap-free windows ``(a, b)`` of ``length_s`` whose attitude turns by less than
    :data:`GYRO_WINDOW_TURN_RAD` (sample indices)."""
    edges = np.unique(np.searchsorted(t, np.arange(t[0], t[-1], length_s)))
    a, b = edges[:-1], edges[1:]
    keep = (b > a) & (gaps[a] == gaps[b])
    a, b = a[keep], b[keep]
    sign = np.where(np.sum(q[a] * q[b], axis=1) < 0, -1.0, 1.0)[:, None]
    turn = 4.0 * np.arctan2(np.linalg.norm(q[b] - sign * q[a], axis=1),
                            np.linalg.norm(q[b] + sign * q[a], axis=1))
    quiet = turn < GYRO_WINDOW_TURN_RAD
    return a[quiet], b[quiet]


def gyro_bias_estimate(tel: Telemetry) -> GyroBias | None:
    """Least-squares constant gyro bias ``b`` from windows where the attitude hardly turns.

    Per gap-free window ``(a, b)`` whose attitude turns by less than
    :data:`GYRO_WINDOW_TURN_RAD` (so the rotation vector and ``∫ω dt`` differ only by the bias,
    not by non-commuting turns or a rate-scale error): ``∫ω dt − rotvec(q_b q_a⁻¹) = b Δt +
    noise`` per body axis (a gyro reading ``ω + b`` integrates ``b Δt`` more than the attitude
    turns; Brown Eq 2 kinematics). The window length is the file's own: from
    :data:`GYRO_WINDOW_MIN_SAMPLES` median sample steps, doubling, the length whose quiet windows
    (at least :data:`GYRO_MIN_WINDOWS` of them) give the most precise estimate, ``N L²`` largest
    (the attitude noise of each window's ends is fixed, the bias grows with ``L``): long rests
    give long windows, a CubeSat's one-minute rests shorter ones. ``None`` when no length has
    :data:`GYRO_MIN_WINDOWS` quiet windows.
    """
    t = np.asarray(tel.t, float)
    q = np.asarray(tel.q, float)
    if t.size < 4:
        return None
    gaps = _gaps_before(t)
    length = GYRO_WINDOW_MIN_SAMPLES * float(np.median(np.diff(t)))
    best, best_score = None, 0.0
    while GYRO_MIN_WINDOWS * length <= t[-1] - t[0]:
        a, b = _quiet_windows(t, q, gaps, length)
        if a.size >= GYRO_MIN_WINDOWS and a.size * length**2 > best_score:
            best, best_score = (a, b, length), a.size * length**2
        length *= 2.0
    if best is None:
        return None
    a, b, length = best
    integral = _integrated_rates(tel)
    d = integral[b] - integral[a] - np.asarray(_rotvecs_between(q[a], q[b]))
    dt = t[b] - t[a]
    ss = float(dt @ dt)
    bias = dt @ d / ss
    resid = d - dt[:, None] * bias
    se = np.sqrt(np.sum(resid**2, axis=0) / max(dt.size - 1, 1) / ss)
    return GyroBias(bias, se, int(dt.size), length)


def check_gyro_bias(tel: Telemetry, spacecraft: Spacecraft) -> GyroBias | None:
    """Warn when the data show a gyro bias far beyond the model file's ``[gyro]`` knowledge:
    on some axis ``|b| > GYRO_BIAS_Z × bias_sd_rad_s`` and ``> GYRO_BIAS_Z × its standard
    error``. The fits' gyro-bias prior then under-states it, and the RWA4 axis by the RWA method
    can be wrong by more than its cone with every adequacy check passing (a 2e-5 rad/s bias:
    0.71° off against a 0.18° cone). Returns the estimate (``None``: not enough quiet windows).
    """
    est = gyro_bias_estimate(tel)
    if est is None:
        return None
    sd = spacecraft.knowledge.gyro_bias_sd_rad_s
    big = (np.abs(est.bias) > GYRO_BIAS_Z * sd) & (np.abs(est.bias) > GYRO_BIAS_Z * est.se)
    if np.any(big):
        axes = ", ".join(f"{'xyz'[i]} {est.bias[i]:+.2g}" for i in np.flatnonzero(big))
        worst = float(np.max(np.abs(est.bias)[big]) / sd)
        warnings.warn(f"{tel.source}: columns wx wy wz carry a constant gyro bias of about "
                      f"{axes} rad/s ({worst:.0f}x the [gyro] bias_sd_rad_s = {sd:.2g} of "
                      f"the model {spacecraft.name!r}, seen over {est.windows} quiet "
                      f"{est.window_s:.3g}-s windows): the fits' gyro prior under-states it; "
                      "widen bias_sd_rad_s in the spacecraft model, or remove the bias",
                      GyroBiasWarning, stacklevel=2)
    return est


class QuantisedRatesWarning(UserWarning):
    """Body or wheel rates quantised coarsely against their noise and their excursion."""


class RateQuantum(NamedTuple):
    """A rate column on a lattice: ``column`` (``wx`` … ``rwa4``), its ``quantum``, the white-noise
    sd measured in it (``noise``) and its ``excursion`` (0.5–99.5 percentile range, the whole
    range where that is 0), all rad/s;
    ``large``: the quantum is at least :data:`QUANTUM_NOISE_RATIO` × the noise and
    :data:`QUANTUM_EXCURSION_MIN` × the excursion."""

    column: str
    quantum: float
    noise: float
    excursion: float

    @property
    def large(self) -> bool:
        return (self.quantum >= QUANTUM_NOISE_RATIO * self.noise
                and self.quantum >= QUANTUM_EXCURSION_MIN * self.excursion)

    def text(self) -> str:
        """``rwa1 1 rpm (its measured noise 0, 0.088 % of its excursion)``: the quantum in the
        column's file unit, the noise measured in it in quanta, the quantum against the
        excursion."""
        unit, scale = (("rpm", 1.0 / RPM_TO_RAD_S) if self.column.startswith("rwa")
                       else ("rad/s", 1.0))
        return (f"{self.column} {self.quantum * scale:.3g} {unit} (its measured noise "
                f"{self.noise / self.quantum:.2g} quanta, {100 * self.quantum / self.excursion:.2g}"
                " % of its excursion)")


def rate_quantum(x: np.ndarray) -> float | None:
    """The spacing ``q`` of the lattice the finite values of ``x`` lie on: the smallest gap
    between distinct values, when every gap is a whole multiple of it (to
    :data:`QUANTUM_LATTICE_TOL`); ``None`` when the values are not on a lattice or all equal."""
    u = np.unique(np.asarray(x, float)[np.isfinite(x)])
    if u.size < 2:
        return None
    gaps = np.diff(u)
    q = float(gaps.min())
    k = gaps / q
    return q if float(np.max(np.abs(k - np.round(k)))) <= QUANTUM_LATTICE_TOL else None


def quantised_rates(tel: Telemetry) -> tuple[RateQuantum, ...]:
    """Every body-rate column and every active wheel's column (rad/s) that lies on a lattice."""
    cols = [(name, np.asarray(tel.omega[:, i], float)) for i, name in enumerate(("wx", "wy", "wz"))]
    cols += [(name.lower(), np.asarray(tel.wheel_rate(name), float))
             for name in tel.active_wheels()]
    out = []
    for name, x in cols:
        q = rate_quantum(x)
        if q is None:
            continue
        finite = x[np.isfinite(x)]
        lo, hi = np.percentile(finite, [0.5, 99.5])
        excursion = float(hi - lo) if hi > lo else float(np.ptp(finite))
        out.append(RateQuantum(name, q, white_noise_sd(x), excursion))
    return tuple(out)


def check_rate_quantisation(tel: Telemetry) -> tuple[RateQuantum, ...]:
    """Warn (:class:`QuantisedRatesWarning`) when a rate column is quantised coarsely: its
    quantum is at least :data:`QUANTUM_NOISE_RATIO` × the noise measured in it (the rounding is
    not dithered by noise, so its error repeats while the rate holds its value instead of being
    the white noise the fits model) and at least :data:`QUANTUM_EXCURSION_MIN` × its excursion
    (large against the signal). A warning, not a refusal: the file holds no finer rates, and the
    fits' estimates move by up to several posterior sd (docs/input_checks.md). Returns every
    quantised column."""
    found = quantised_rates(tel)
    large = [r for r in found if r.large]
    if large:
        warnings.warn(f"{tel.source}: rates on a coarse lattice: "
                      + "; ".join(r.text() for r in large)
                      + ": with no noise to dither the rounding, its error repeats while a rate "
                      "holds its value, which the fits do not model, so their estimates can move "
                      "by several posterior sd; give the rates at finer resolution if there are "
                      "any",
                      QuantisedRatesWarning, stacklevel=2)
    return found


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
    integrated rate (°/s or mrad/s body rates). Returns the agreement (``None``: not identifiable, no check).
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


# ---------------------------------------------------------------------------------------------
# 2. Wheel units vs momentum conservation


class WheelAxes(NamedTuple):
    """Fit of the momentum balance with each known wheel's momentum a free body vector ``w_k``.

    Attributes
    ----------
    alignment : cosine between the fitted and the measured body-momentum changes (1 = perfect).
    conditioning : smallest over largest singular value of the balance's design (the wheels'
        columns and the external torque's), its columns scaled to unit length: near 0 when the wheels' rates move together (a biasing event, a
        slew about one axis) and the vectors cannot be told apart; 0.3–0.5 for slews about
        three axes.
    vectors : per known wheel, ``w_k / J_k`` (body frame, per rpm-read rad/s): the model's axis
        ``g_k`` for a correct file, within the inertia's ±10 %; ``−g_k`` for a column with its
        sign flipped, ``g_j`` for a column holding wheel ``j``'s rates, ``9.55 g_k`` for rad/s.
    swing_nms : largest de-meaned body momentum ``|A(q)ᵀ I_pred ω|``, N m s: how much momentum
        the wheels and the body exchange (Cassini's slews: 18–22; gyro noise alone: ~0.01).
    noise_nms : the momentum noise of one sample, N m s: ``√((λ_max σ_ω)² + Σ_k (J_k σ_k)²)``
        with ``λ_max`` the predicted inertia's largest moment and ``σ_ω``, ``σ_k`` the white
        noise of the body rates and of each running wheel's rates
        (:func:`cassini_bayes.telemetry.white_noise_sd`, floored at
        :data:`cassini_bayes.telemetry.RATE_NOISE_FLOORS`).
    """

    alignment: float
    conditioning: float
    vectors: dict[str, np.ndarray]
    swing_nms: float = 0.0
    noise_nms: float = 0.0

    @property
    def judged(self) -> bool:
        """Whether the vectors are determined well enough to judge each wheel on its own."""
        return (self.conditioning >= AXES_CONDITION_MIN
                and self.alignment >= MOMENTUM_ALIGN_MIN)

    def angle_deg(self, name: str, axis) -> float:
        """Angle between wheel ``name``'s fitted vector and ``axis``, degrees."""
        w = self.vectors[name]
        cos = float(w @ np.asarray(axis, float)) / (np.linalg.norm(w) * np.linalg.norm(axis))
        return float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))

    def scale(self, name: str) -> float:
        """``|w_k| / J_k``: 1 for rpm (within the inertia's ±10 %), 9.55 for rad/s."""
        return float(np.linalg.norm(self.vectors[name]))


class MomentumScale(NamedTuple):
    """Fit of the momentum balance with the wheel momentum scaled by ``κ`` (1 for a correct file).

    Attributes
    ----------
    scale : ``κ``, the factor on the wheel momentum that balances the body momentum of the
        model's predicted inertia: 1 (within the ±10 % knowledge of the inertia) for rpm,
        60/(2π) = 9.55 when the wheel columns hold rad/s.
    alignment : cosine between the fitted and the measured body-momentum changes (1 = perfect).
    stretches : number of stretches between thruster firings used.
    axes : the same balance with a free momentum vector per known wheel (:class:`WheelAxes`);
        ``None`` when no known wheel runs or the balance cannot be formed.
    """

    scale: float
    alignment: float
    stretches: int
    axes: WheelAxes | None = None


def _quiet_labels(on_times: np.ndarray | None, n: int) -> np.ndarray:
    """Label of the firing-free stretch of every sample; ``-1`` next to a firing.

    An interval in which any cumulative on-time grows carries a thruster impulse (and its
    rise/fall tail into the next interval): both intervals split the record.
    """
    if on_times is None:
        return np.zeros(n, int)
    fired = np.any(np.diff(on_times, axis=0) > 0, axis=1)
    cut = fired | np.concatenate([[False], fired[:-1]])
    labels = np.concatenate([[0], np.cumsum(cut)])
    bad = np.zeros(n, bool)
    bad[1:] |= cut
    bad[:-1] |= cut
    return np.where(bad, -1, labels)


class _Balance(NamedTuple):
    """The de-meaned momentum balance of :func:`wheel_momentum_scale` (inertial frame)."""

    body: np.ndarray                # (n, 3) A(q)ᵀ I_pred ω, each stretch de-meaned
    known: list[str]                # the known wheels running
    known_cols: list[np.ndarray]    # per known wheel, (n, 3, 3): −ρ_k A(q)ᵀ e_j, de-meaned
    free: list[str]                 # the articulated wheels running
    free_cols: list[np.ndarray]     # per free wheel, its three columns
    torque_cols: list[np.ndarray]   # a constant inertial torque's three columns: (t − t̄_s) e_j
    stretches: int
    noise_nms: float                # momentum noise of one sample (WheelAxes.noise_nms)


def _balance(tel: Telemetry, spacecraft: Spacecraft, on_times: np.ndarray | None,
             free_wheels: Sequence[str]) -> _Balance | None:
    """The balance's pieces per firing-free stretch, or ``None`` (no wheel, no stretch)."""
    names = tel.active_wheels()
    free_upper = {n.upper() for n in free_wheels}
    free = [n for n in names if n.upper() in free_upper]
    known = [n for n in names if n not in free]
    if not names:
        return None
    on = tel.on_times if on_times is None else on_times
    labels = _quiet_labels(on, tel.n)
    ids, counts = np.unique(labels[labels >= 0], return_counts=True)
    good = ids[counts >= 3]
    keep = np.isin(labels, good)
    if not np.any(keep):
        return None
    a_t = np.swapaxes(np.asarray(_dcm(np.asarray(tel.q, float))), -1, -2)[keep]  # body → inertial
    body = np.einsum("nij,jk,nk->ni", a_t, np.asarray(spacecraft.inertia, float),
                     np.asarray(tel.omega, float)[keep])
    known_cols = [-np.asarray(tel.wheel_rate(n), float)[keep][:, None, None] * a_t
                  for n in known]
    free_cols = [-np.asarray(tel.wheel_rate(f), float)[keep][:, None] * a_t[:, :, j]
                 for f in free for j in range(3)]
    t_keep = np.asarray(tel.t, float)[keep] - float(tel.t[0])
    torque_cols = [t_keep[:, None] * np.eye(3)[j] for j in range(3)]
    lab = labels[keep]
    for s in good:
        m = lab == s
        for x in [body, *known_cols, *free_cols, *torque_cols]:
            x[m] -= x[m].mean(0)
    s_w, s_r = RATE_NOISE_FLOORS
    i_max = float(np.linalg.eigvalsh(np.asarray(spacecraft.inertia, float))[-1])
    noise = (i_max * max(white_noise_sd(np.asarray(tel.omega, float)[keep]), s_w)) ** 2
    for n in names:
        rate = np.asarray(tel.wheel_rate(n), float)[keep]
        noise += (spacecraft.wheel(n).inertia * max(white_noise_sd(rate), s_r)) ** 2
    return _Balance(body, known, known_cols, free, free_cols, torque_cols, len(good),
                    float(np.sqrt(noise)))


def _solve(design: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, float] | None:
    """Least squares of the balance: coefficients and alignment, ``None`` if not identifiable."""
    tt = float(target @ target)
    if tt <= 0 or np.linalg.matrix_rank(design) < design.shape[1]:
        return None
    theta = np.linalg.lstsq(design, target, rcond=None)[0]
    fitted = design @ theta
    align = float(target @ fitted / np.sqrt(tt * (fitted @ fitted))) if fitted.any() else 0.0
    return theta, align


def _wheel_axes(bal: _Balance, spacecraft: Spacecraft) -> WheelAxes | None:
    """:class:`WheelAxes` of the balance: one free body vector ``w_k`` per known wheel."""
    if not bal.known:
        return None
    cols = [c[:, :, j] for c in bal.known_cols for j in range(3)] + bal.free_cols
    cols += bal.torque_cols
    design = np.stack([c.ravel() for c in cols], 1)
    solved = _solve(design, bal.body.ravel())
    if solved is None:
        return None
    theta, align = solved
    norms = np.linalg.norm(design, axis=0)
    sv = np.linalg.svd(design / np.where(norms > 0, norms, 1.0), compute_uv=False)
    js = [spacecraft.wheel(n).inertia for n in bal.known]
    vectors = {n: theta[3 * k: 3 * k + 3] / js[k] for k, n in enumerate(bal.known)}
    swing = float(np.max(np.linalg.norm(bal.body, axis=1)))
    return WheelAxes(align, float(sv[-1] / sv[0]), vectors, swing, bal.noise_nms)


def wheel_momentum_scale(tel: Telemetry, spacecraft: Spacecraft,
                         on_times: np.ndarray | None = None,
                         free_wheels: Sequence[str] | None = None) -> MomentumScale | None:
    """Least-squares wheel-momentum scale ``κ`` of the momentum balance (Feldman & Lee Eqs 2-3).

    Per firing-free stretch ``s`` (thruster firings from ``on_times``, default the telemetry's)

        ``A(q_t)ᵀ (I_pred ω_t + κ Σ_known J_k ρ_k,t g_k + ρ_f,t w) = H_s + T t``

    with ``I_pred`` the model's predicted tensor and the known wheels' axes and spin inertias
    from the model, and ``T`` a constant inertial external torque over the whole file (its
    impulse over a long record is a sizeable part of what a small spacecraft's slews exchange:
    the ESPA bus's 2e-5 N m over 22 minutes against 0.38 N m s). Each articulated wheel (``free_wheels``, default the model's
    ``articulated`` wheels: Cassini's RWA4, whose axis is what the RWA4 calibration measures,
    Brown §III) enters with a free momentum vector ``w`` (``J_f u_f`` for rpm data); with no other
    wheel running ``κ`` is the median of ``|w_f| / J_f``. Subtracting each stretch's mean
    removes ``H_s``. The same balance with a free vector ``w_k`` for every known wheel in place
    of ``κ J_k g_k`` is :attr:`MomentumScale.axes`. ``None`` when no wheel runs, no stretch has
    three samples, or nothing varies.
    """
    free_wheels = spacecraft.articulated_wheels if free_wheels is None else free_wheels
    bal = _balance(tel, spacecraft, on_times, free_wheels)
    if bal is None:
        return None
    cols = list(bal.free_cols) + bal.torque_cols
    if bal.known:
        axes = np.stack([spacecraft.wheel(n).axis for n in bal.known])
        js = np.array([spacecraft.wheel(n).inertia for n in bal.known])
        momentum = np.einsum("wnij,wj,w->ni", np.stack(bal.known_cols), axes, js)
        cols.insert(0, momentum)
    solved = _solve(np.stack([c.ravel() for c in cols], 1), bal.body.ravel())
    if solved is None:
        return None
    theta, align = solved
    if bal.known:
        scale = float(theta[0])
    else:     # the free wheels alone: their momenta's sizes
        scale = float(np.median([np.linalg.norm(theta[3 * k:3 * k + 3])
                                 / spacecraft.wheel(f).inertia for k, f in enumerate(bal.free)]))
    return MomentumScale(scale, align, bal.stretches, _wheel_axes(bal, spacecraft))


def _unit_error(cols: str, scale: float, what: str, tel: Telemetry) -> InputError:
    """The wheel-unit refusal for ``cols`` whose momentum needs ``scale`` × the rpm reading."""
    if scale > 0 and abs(np.log(scale / RAD_S_FACTOR)) < np.log(2.0):
        return InputError(f"{cols}: wheel rates look like rad/s, the file format wants rpm; "
                          f"multiply by 60/(2*pi) ({what})", path=tel.source)
    return InputError(f"{cols}: {what}; check that the wheel rates are rpm, the body rates "
                      "rad/s, and that the spacecraft model matches the spacecraft",
                      path=tel.source)


def axis_angle_max_deg(spacecraft: Spacecraft) -> float:
    """Largest accepted angle (degrees) between a wheel's fitted momentum and its model axis:
    :data:`AXIS_ANGLE_MAX_DEG`, or half the smallest angle between the lines of two of the
    model's wheels whose axes are trusted (articulated wheels left out) when that is smaller."""
    axes = [w.axis for w in spacecraft.wheels if not w.articulated]
    half = [0.5 * float(np.degrees(np.arccos(min(abs(float(a @ b)), 1.0))))
            for i, a in enumerate(axes) for b in axes[i + 1:]]
    return min([AXIS_ANGLE_MAX_DEG, *half])


def _axis_error(name: str, axes: WheelAxes, spacecraft: Spacecraft,
                tel: Telemetry) -> InputError:
    """The refusal for a wheel whose momentum does not lie along its axis in the model."""
    limit = axis_angle_max_deg(spacecraft)
    col = name.lower()
    angle = axes.angle_deg(name, spacecraft.wheel(name).axis)
    head = (f"column {col}: momentum is conserved only with {col}'s momentum {angle:.0f}° from "
            f"{name}'s axis in the model {spacecraft.name!r} (free-axis balance alignment "
            f"{axes.alignment:.3f})")
    if angle > 180.0 - limit:
        return InputError(f"{head}: its sign looks flipped; negate the column, or correct the "
                          "wheel's axis in the spacecraft model", path=tel.source)
    for other in spacecraft.wheels:
        if other.name == name:
            continue
        off = axes.angle_deg(name, other.axis)
        if min(off, 180.0 - off) < limit:
            flipped = " with the sign flipped" if off > 90.0 else ""
            return InputError(f"{head}, {min(off, 180.0 - off):.0f}° from {other.name}'s: it "
                              f"looks like {other.name}'s rates{flipped}; check the column "
                              "order", path=tel.source)
    return InputError(f"{head}; check the column order, the wheels' signs and the model's wheel "
                      "axes", path=tel.source)


def _balance_error(tel: Telemetry, axes: WheelAxes) -> InputError:
    """The refusal for a file without thruster firings whose momentum does not balance even with
    a free axis per wheel; names the wheels that touch zero without crossing it (unsigned)."""
    unsigned = []
    for name in axes.vectors:
        rpm = np.asarray(tel.wheel_rate(name), float) / RPM_TO_RAD_S
        rpm = rpm[np.isfinite(rpm)]
        for x in (rpm, -rpm):     # never below zero (or above it), yet reaching it
            if x.min() >= 0.0 and x.min() < UNSIGNED_TOUCH_RPM < x.max():
                unsigned.append(f"{name.lower()} stays on one side of 0 rpm yet reaches "
                                f"{x.min():.2g} rpm")
    hint = (f" ({'; '.join(unsigned)}: a tachometer that reports speed without direction?)"
            if unsigned else "")
    cols = " ".join(n.lower() for n in axes.vectors)
    return InputError(f"columns {cols}: with no thruster firing in the file, the wheels' momenta "
                      "do not balance the body's even with a free axis per wheel (alignment "
                      f"{axes.alignment:.4f}; correct files ≥ 0.998){hint}; check the wheel "
                      "columns' signs through zero speed and their units, or give the thruster "
                      "firings (--pulses, or on_* columns) if any fired", path=tel.source)


def check_wheel_units(tel: Telemetry, spacecraft: Spacecraft,
                      on_times: np.ndarray | None = None) -> MomentumScale | None:
    """Refuse wheel columns whose unit, sign or order breaks momentum conservation.

    When the balance of :func:`wheel_momentum_scale` fits (alignment ≥
    :data:`MOMENTUM_ALIGN_MIN`) yet needs a wheel-momentum scale ``κ`` outside
    :data:`KAPPA_RANGE`, raise :class:`InputError`: ``κ`` near 60/(2π) means the wheel columns
    hold rad/s. Then, where the free-axis balance (:class:`WheelAxes`) determines each known
    wheel's momentum on its own (:attr:`WheelAxes.judged`), refuse a wheel whose momentum lies
    more than :func:`axis_angle_max_deg` from its axis in the model (a flipped sign, another
    wheel's column) or whose scale is outside :data:`KAPPA_RANGE` (that column in rad/s). In a
    file without thruster firings (no ``on_times``, no ``on_*`` columns) where the vectors are
    separable and the body swings by :data:`SWING_MIN_SNR` times the momentum noise, refuse a
    free-axis balance below
    :data:`AXES_ALIGN_MIN` (:func:`_balance_error`: unsigned tachometers, mixed units).
    Otherwise (including a balance that does not fit: momentum exchange with unlogged thruster
    firings, or none at all) say nothing. Returns the fit.
    """
    fit = wheel_momentum_scale(tel, spacecraft, on_times)
    if fit is None:
        return fit
    lo, hi = KAPPA_RANGE
    if fit.alignment >= MOMENTUM_ALIGN_MIN and not lo <= fit.scale <= hi:
        cols = "columns " + " ".join(n.lower() for n in tel.active_wheels())
        raise _unit_error(cols, fit.scale, (
            f"momentum is conserved only with the wheel momentum {fit.scale:.3g}x what the "
            f"columns say in rpm with the model {spacecraft.name!r} (alignment "
            f"{fit.alignment:.3f}; rpm gives 1, rad/s {RAD_S_FACTOR:.3g})"), tel)
    axes = fit.axes
    if axes is None:
        return fit
    if (on_times is None and tel.on_times is None and axes.conditioning >= AXES_CONDITION_MIN
            and axes.swing_nms >= SWING_MIN_SNR * axes.noise_nms
            and axes.alignment < AXES_ALIGN_MIN):
        raise _balance_error(tel, axes)
    if not axes.judged:
        return fit
    angle_max = axis_angle_max_deg(spacecraft)
    for name in axes.vectors:
        if axes.angle_deg(name, spacecraft.wheel(name).axis) > angle_max:
            raise _axis_error(name, axes, spacecraft, tel)
    for name in axes.vectors:
        if not lo <= axes.scale(name) <= hi:
            scale, j = axes.scale(name), spacecraft.wheel(name).inertia
            raise _unit_error(f"column {name.lower()}", scale, (
                f"momentum is conserved only with {name}'s momentum {scale:.3g}x what the "
                f"column says in rpm with the model {spacecraft.name!r} (free-axis balance "
                f"alignment {axes.alignment:.3f}; rpm gives 1, rad/s {RAD_S_FACTOR:.3g}); or "
                f"the model's {name} spin inertia {j:.4g} kg m^2 is "
                f"{max(scale, 1 / scale):.3g}x too {'small' if scale > 1 else 'large'}"), tel)
    return fit


# ---------------------------------------------------------------------------------------------
# 3. Pulse log vs on_* columns


def _derived_on_times(tel: Telemetry, log: PulseLog) -> np.ndarray:
    """Cumulative on-times the pulse log implies at the telemetry samples (warnings silenced:
    the readers and the fits report the pulses outside the span)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PulseSpanWarning)
        return cumulative_on_times(check_pulses_in_span(log, tel), tel.t)


def check_pulses_match_on_times(tel: Telemetry, log: PulseLog) -> None:
    """Refuse a pulse log that disagrees with the telemetry's own ``on_*`` columns.

    Per thruster, the log's cumulative on-time at the samples
    (:func:`cassini_bayes.telemetry.cumulative_on_times`) must match the column at every sample
    to within the longest single pulse (the longest width in the log, or the largest step of
    the column between two samples): a counter may book a pulse straddling a sample on either
    side of it, or in steps of its own resolution. No-op without ``on_*`` columns.
    """
    if tel.on_times is None:
        return
    if tuple(log.thruster_names) != tuple(tel.thruster_names):
        raise InputError(f"its thrusters ({', '.join(log.thruster_names)}) are not the on_* "
                         f"columns' of {tel.source} ({', '.join(tel.thruster_names)}); read both "
                         "with the same spacecraft model", path=log.source)
    derived = _derived_on_times(tel, log)
    col_all = np.asarray(tel.on_times, float)
    t = np.asarray(tel.t, float)
    for k, name in enumerate(tel.thruster_names):
        col, der = col_all[:, k] - col_all[0, k], derived[:, k]
        widths = log.width[log.thruster == k]
        slack = max(float(widths.max()) if widths.size else 0.0, float(np.diff(col).max())) + 1e-6
        diff = np.abs(der - col)
        if diff.max() <= slack:
            continue
        total_c, total_d = float(col[-1]), float(der[-1])
        i = int(np.argmax(diff))
        pct = (f"{100 * (total_d - total_c) / total_c:+.0f} %" if total_c > 0
               else "the column never fires")
        raise InputError(f"pulse log widths disagree with on_{name} of {tel.source} by {pct}: "
                         f"the log gives {total_d:.6g} s of {name} on-time, the column "
                         f"{total_c:.6g} s (largest difference {diff[i]:.3g} s at t = "
                         f"{t[i]:.10g} s); check the width unit (s) and that the log belongs to "
                         "this telemetry", path=log.source)


# ---------------------------------------------------------------------------------------------
# 4. Identifiability for the fit asked for


def inertia_excitation(tels: Sequence[Telemetry]) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues (ascending, rad² s) and eigenvectors of ``Σ ω ωᵀ dt`` over all files.

    The momentum balance sees the inertia only through ``I ω`` (Feldman & Lee Eq 10): rotation
    about a single unit axis ``e`` determines ``I e`` (three of the six entries' combinations)
    and nothing else.
    """
    m = np.zeros((3, 3))
    for tel in tels:
        w = np.asarray(tel.omega, float)
        dt = np.gradient(np.asarray(tel.t, float)) if tel.n > 1 else np.ones(tel.n)
        m += np.einsum("n,ni,nj->ij", dt, w, w)
    return np.linalg.eigh(m)


def check_inertia_excitation(tels: Sequence[Telemetry]) -> None:
    """Raise :class:`UnidentifiableError` when the slews turn the spacecraft about one axis only.

    The ratio of the second-largest to the largest eigenvalue of :func:`inertia_excitation`
    below :data:`EXCITATION_MIN` means all rotation is about one axis ``e``; only ``I e`` is
    learnable (the posterior of the rest is the prior, and the sampler does not converge on
    that ridge). A weak second or third axis is the inertia fit's own "weakly identified"
    warning.
    """
    vals, vecs = inertia_excitation(tels)
    if not vals[-1] > 0 or vals[1] / vals[-1] >= EXCITATION_MIN:
        return
    e = vecs[:, -1] * np.sign(vecs[np.argmax(np.abs(vecs[:, -1])), -1])
    src = ", ".join(t.source for t in tels)
    axis = int(np.argmax(np.abs(e)))
    if abs(e[axis]) > 0.99:
        learn = {0: ("Ixx", "Ixy", "Ixz"), 1: ("Ixy", "Iyy", "Iyz"), 2: ("Ixz", "Iyz", "Izz")}[axis]
        lost = [n for n in INERTIA_NAMES if n not in learn]
        about = f"body {'XYZ'[axis]}"
        what = (f"{', '.join(lost)} cannot be learned from them (only {', '.join(learn)})")
    else:
        about = f"the body axis [{e[0]:.2f}, {e[1]:.2f}, {e[2]:.2f}]"
        what = "only the three combinations I·e of the six entries can be learned"
    raise UnidentifiableError(f"{src}: the slews turn the spacecraft about {about} only "
                              f"(second axis {vals[1] / vals[-1]:.1e} of the first in Σ ω ωᵀ dt); "
                              f"{what}; add slews about other axes")


def check_rwa4_method(tel: Telemetry, method: str, wheel: str = "RWA4") -> None:
    """Refuse data that the chosen RWA4 method cannot use.

    * ``rwa`` (Brown Eq 3): the slews are carried by the other wheels, whose momentum is known;
      with fewer than :data:`RWA_METHOD_MIN_KNOWN` of them running the data hold no RWA slew
      pairs (RCS-controlled drift).
    * ``rcs`` (Brown Eq 1): under RCS control the body drift takes up the wheel's momentum and
      the thrusters hold the attitude. When at least :data:`RWA_METHOD_MIN_KNOWN` other wheels
      run and change by more than :data:`CONTROL_WHEEL_RPM` (and :data:`CONTROL_NOISE_SD` ×
      their white noise) while no thruster fires (``on_*``
      columns flat or absent), the wheels carry the attitude control: RWA-controlled data.
    """
    others = [n for n in tel.active_wheels() if n.upper() != wheel.upper()]
    if method == "rwa" and len(others) < RWA_METHOD_MIN_KNOWN:
        running = ", ".join(tel.active_wheels()) or "none"
        raise InputError(f"{arg('method', 'rwa')} needs RWA slew pairs, carried by at least "
                         f"{RWA_METHOD_MIN_KNOWN} wheels besides {wheel} (Brown Eq 3), but the "
                         f"wheels running are {running}: this looks like RCS-controlled data; "
                         f"use {arg('method', 'rcs')}", path=tel.source)
    if method != "rcs" or len(others) < RWA_METHOD_MIN_KNOWN:
        return
    fired = tel.on_times is not None and bool(np.any(np.diff(tel.on_times, axis=0) > 0))
    span = {n: float(np.ptp(tel.wheel_rate(n))) / RPM_TO_RAD_S for n in others}
    noise = {n: white_noise_sd(np.asarray(tel.wheel_rate(n), float)) / RPM_TO_RAD_S
             for n in others}
    varying = [n for n, v in span.items()
               if v > max(CONTROL_WHEEL_RPM, CONTROL_NOISE_SD * noise[n])]
    if not fired and len(varying) >= RWA_METHOD_MIN_KNOWN:
        spans = ", ".join(f"{n} {span[n]:.0f} rpm" for n in varying)
        raise InputError(f"{arg('method', 'rcs')} needs RCS-controlled data (Brown Eq 1: the "
                         "body drifts, thrusters fire), but no thruster fires and the other "
                         f"wheels carry the control (they change by {spans}): these are "
                         "RWA-controlled "
                         f"slews; use {arg('method', 'rwa')}", path=tel.source)


# ---------------------------------------------------------------------------------------------
# Entry points (one per command)


def check_telemetry_data(tel: Telemetry, spacecraft: Spacecraft | None = None,
                         pulses: PulseLog | None = None
                         ) -> tuple[AttitudeAgreement | None, MomentumScale | None]:
    """Every physics check one telemetry file (and its pulse log) allows: attitude vs rates,
    quantised rates (a warning), pulse log vs ``on_*`` columns, and with a spacecraft model the
    wheel units and the gyro bias (a warning).

    Returns the attitude agreement and the momentum fit (``None`` where not identifiable or,
    for the momentum, without a spacecraft model), for a summary.
    """
    attitude = check_attitude_rates(tel)
    check_rate_quantisation(tel)
    on = tel.on_times
    if pulses is not None:
        check_pulses_match_on_times(tel, pulses)
        if on is None:
            on = _derived_on_times(tel, pulses)
    momentum = check_wheel_units(tel, spacecraft, on) if spacecraft is not None else None
    if spacecraft is not None:
        check_gyro_bias(tel, spacecraft)
    return attitude, momentum


def check_inertia_data(tels: Sequence[Telemetry], spacecraft: Spacecraft) -> None:
    """Checks before ``fit inertia``: each file's attitude, rates and wheel units; then that the
    slews excite more than one axis."""
    for tel in tels:
        check_telemetry_data(tel, spacecraft)
    check_inertia_excitation(tels)


def check_thrust_data(events: Sequence[tuple[Telemetry, PulseLog]],
                      spacecraft: Spacecraft) -> None:
    """Checks before ``fit thrust``: per event, attitude and rates, pulse log vs ``on_*``
    columns, and wheel units (stretches between the logged firings)."""
    for tel, log in events:
        check_telemetry_data(tel, spacecraft, log)


def check_rwa4_data(tel: Telemetry, spacecraft: Spacecraft, method: str) -> None:
    """Checks before ``fit rwa4``: attitude, rates and wheel units, and that ``method`` suits
    how the data were controlled."""
    check_telemetry_data(tel, spacecraft)
    check_rwa4_method(tel, method)
