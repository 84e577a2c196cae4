"""The leak monitor's inputs and result types, and the residual it reads (Lee Eq 10).

The residual momentum, the modelled impulse of each thruster and the prior constants of the
model in :mod:`cassini_bayes.inference.leak`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cassini_bayes.errors import InputError
from cassini_bayes.estimators.baseline import wheel_momentum
from cassini_bayes.estimators.leak import (rate_step_columns, rate_step_second_order,
                                           residual_momentum)
from cassini_bayes.physics.impulse import THRUSTER_NAMES, impulse_from_on_times
from cassini_bayes.physics.pulse import pulse_impulse_until
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import RATE_NOISE_FLOORS, PulseLog, Telemetry, pulses_in_span

HYPOTHESES = ("none",) + THRUSTER_NAMES
"""Cassini's hypotheses (the Eq 16 layout); a run's own are :attr:`LeakInputs.hypotheses`:
``none`` and the model's thruster names."""
FRACTION_SCALES = 10.0 ** np.arange(-4.0, 0.01, 0.5)
"""Scales of the half-normal mixture prior on the leak fraction (fractions of the thrust)."""
TORQUE_SCALES = ((1.0, 0.9), (10.0, 0.1))
"""The external torque's prior: ``(multiple of the model file's sd, weight)`` of each normal
component of its scale mixture (a contaminated normal)."""
OFFSET_SD_NMS = 10.0
"""Prior sd of the residual's offset ``r_0`` per axis, N m s, of inputs built without a
spacecraft model (:class:`LeakInputs`' default; Cassini's scale): :func:`leak_inputs` takes the
model's wheel momentum capacity instead (wide: the offset only absorbs the first sample's
noise, and a prior of the spacecraft's own momentum scale keeps it so at any size)."""
SAMPLE_STEP_S = 60.0
"""Spacing (s) of the residual samples the monitor uses. Besides its white noise (~0.007 N m s
per sample) the residual carries a random walk: the gyroscopic impulse ``ΔG`` is integrated from
noisy rates (1 µrad/s × |H_RWA| ≈ 20 N m s: ~2e-5 N m s per √s, some 2e-3 N m s over 4 h) and
its 1 s trapezoid errs at every pulse (sd 2.4e-4 N m s over 1 h in noise-free telemetry). The
white model, which has no random walk, reads it as a torque change of ~1e-7 N m; the more samples
it uses, the surer it is. Measured on 24 four-hour cruise control stretches, the largest
``P(leak)`` (median / 90 % / max) is 0.014 / 0.50 / 1 (one alarm) at 10 s, 0.003 / 0.009 / 0.57
at 30 s and 0.003 / 0.011 / 0.032 at 60 s (docs/leak.md)."""
MAX_GRID = 20_000
"""Most steps of any of the monitor's grids (samples, checks, onsets) over a stretch."""


@dataclass(frozen=True)
class LeakInputs:
    """A stretch's residual momentum and modelled impulses.

    t : (n,) s. residual : (n, 3) ``R`` of Lee Eq 10, N m s, from the first sample.
    impulse : (n, m) modelled accumulated thruster impulses ``J`` from the first sample, N s.
    q_matrix : (3, m) moment matrix, m. thrust_n : (m,) modelled thrust per thruster, N.
    torque_sd_nm : prior sd of the external torque per axis, N m.
    source : the telemetry it came from, for error messages.
    thruster_names : (m,) the thrusters' names, in the order of the columns (Cassini's
        ``Z1 … Y4`` by default).
    offset_sd_nms : prior sd of the residual's offset per axis, N m s (:data:`OFFSET_SD_NMS`).
    noise_floor_nms : the white-noise level's floor per axis, N m s, for noise-free data (0:
        none, the residual must carry noise).
    """

    t: np.ndarray
    residual: np.ndarray
    impulse: np.ndarray
    q_matrix: np.ndarray
    thrust_n: np.ndarray
    torque_sd_nm: float
    source: str = "<telemetry>"
    thruster_names: tuple[str, ...] = THRUSTER_NAMES
    offset_sd_nms: float = OFFSET_SD_NMS
    noise_floor_nms: float = 0.0

    def __post_init__(self):
        m = len(self.thruster_names)
        shapes = {"impulse": (np.shape(self.impulse)[1:], (m,)),
                  "q_matrix": (np.shape(self.q_matrix), (3, m)),
                  "thrust_n": (np.shape(self.thrust_n), (m,))}
        for name, (got, want) in shapes.items():
            if tuple(got) != want:
                raise ValueError(f"LeakInputs.{name} has shape {got}, not {want} for the "
                                 f"{m} thrusters {', '.join(self.thruster_names)}")

    @property
    def hypotheses(self) -> tuple[str, ...]:
        """``none`` and one leak per thruster, the order of the monitor's probabilities."""
        return ("none",) + tuple(self.thruster_names)


@dataclass(frozen=True)
class LeakPosterior:
    """The running monitor's output.

    t_check : (c,) times of the checks, s. prob : (c, m + 1) posterior probability of
    ``hypotheses`` (``none`` and the model's thrusters, e.g. ``none, Z1 … Y4``) given the data
    up to each check.
    detection_time_s : first check with ``P(leak) ≥ p_detect`` (``None``: never).
    isolation_time_s : first check with one thruster's ``P ≥ p_detect`` (``None``: never), and
    ``thruster`` that thruster (``None``: none isolated).
    fraction_mean, fraction_sd, fraction_interval : posterior mean, sd and central 90 % interval
    of that thruster's leak fraction (without isolation: of the thruster most probable at the
    last check) given all the data, and ``torque_nm`` (3,) its mean torque, N m.
    onset_s, onset_sd_s : posterior mean and sd of its onset, s.
    noise_sd_nms : (3,) white-noise sd per axis, N m s.
    hypotheses : the order of ``prob``'s columns (:attr:`LeakInputs.hypotheses`).
    """

    t_check: np.ndarray
    prob: np.ndarray
    p_detect: float
    detection_time_s: float | None
    isolation_time_s: float | None
    thruster: str | None
    fraction_mean: float
    fraction_sd: float
    fraction_interval: tuple
    torque_nm: np.ndarray
    onset_s: float
    onset_sd_s: float
    noise_sd_nms: np.ndarray
    hypotheses: tuple[str, ...] = HYPOTHESES

    @property
    def p_leak(self) -> np.ndarray:
        """(c,) posterior probability of any leak at each check."""
        return 1.0 - self.prob[:, 0]

    def summary(self) -> dict:
        """JSON-able summary (the last check's probabilities, the detection)."""
        last = self.prob[-1]
        return {
            "p_hypothesis": {h: float(p) for h, p in zip(self.hypotheses, last)},
            "p_leak": float(1.0 - last[0]),
            "p_detect": self.p_detect,
            "detection_time_s": self.detection_time_s,
            "isolation_time_s": self.isolation_time_s,
            "thruster": self.thruster,
            "fraction_mean": self.fraction_mean,
            "fraction_sd": self.fraction_sd,
            "fraction_interval_90": [float(x) for x in self.fraction_interval],
            "torque_nm": [float(x) for x in self.torque_nm],
            "onset_s": self.onset_s,
            "onset_sd_s": self.onset_sd_s,
            "noise_sd_nms": [float(x) for x in self.noise_sd_nms],
            "n_checks": int(self.t_check.size),
        }


def _impulses(tel: Telemetry, pulses: PulseLog | None, sc: Spacecraft) -> np.ndarray:
    """Modelled impulses (n, m), N s, from the first sample: the pulse log under the model's
    pulse shape (:func:`~cassini_bayes.physics.pulse.pulse_impulse_until`), else the telemetry's
    on-times, each times its thruster's model thrust (Feldman & Lee Eq 17).

    A pulse has delivered all of its impulse ``_TAIL_TAUS`` fall times after its end (the rest is
    below e⁻⁴⁰), so each sample sums the finished pulses (a cumulative sum) and evaluates the
    profile only for the pulses still running: O(n + pulses) for a stretch of hours.
    """
    t = np.asarray(tel.t, float)
    if pulses is None:
        if tel.on_times is None:
            raise InputError("has neither on-times nor a pulse log; pass --pulses",
                             path=tel.source)
        return np.asarray(impulse_from_on_times(tel.on_times, sc.thrust_per_thruster))
    p, thrust = sc.pulse, sc.thrust_per_thruster
    t_on, k, w = (np.asarray(a) for a in (pulses.t_on, pulses.thruster, pulses.width))

    def delivered(dt, width, which):
        return np.asarray(pulse_impulse_until(dt, width, p.tau_delay, p.tau_rise, p.tau_fall),
                          float) * thrust[which]

    end = t_on + w + p.tau_delay + _TAIL_TAUS * p.tau_fall
    j = np.zeros((t.size, thrust.size))
    full = delivered(end - t_on, w, k)
    first_done = np.searchsorted(t, end, side="left")       # first sample after each pulse ends
    np.add.at(j, (first_done[first_done < t.size], k[first_done < t.size]),
              full[first_done < t.size])
    j = np.cumsum(j, axis=0)
    first = np.searchsorted(t, t_on, side="right")          # first sample after the command
    count = np.maximum(first_done - first, 0)
    rows = np.repeat(first - np.cumsum(count) + count, count) + np.arange(count.sum())
    which = np.repeat(np.arange(t_on.size), count)
    np.add.at(j, (rows, k[which]), delivered(t[rows] - t_on[which], w[which], k[which]))
    return j - j[:1]


_TAIL_TAUS = 40.0


def leak_inputs(tel: Telemetry, pulses: PulseLog | None, spacecraft: Spacecraft) -> LeakInputs:
    """Residual momentum (Lee Eq 10) and modelled impulses of a telemetry stretch; pulses of the
    log that act entirely outside the stretch are left out with a warning
    (:func:`~cassini_bayes.telemetry.pulses_in_span`).

    With a pulse log the residual has the trapezoidal ``ΔG``'s error across the pulses' rate
    steps put back (:func:`~cassini_bayes.estimators.leak.rate_step_columns`, and its second
    order, :func:`~cassini_bayes.estimators.leak.rate_step_second_order`) at the model's
    thrusts, time constants and inertia: the thrust errors ``δ`` move it by their own fraction
    only (second order), and without it a bus whose wheels hold N m s while its dead band
    fires carries a slow wander of the residual the white model cannot hold. On-times alone
    do not place the pulses within a sample, and are used as they are."""
    if pulses is not None:
        p = spacecraft.pulse
        pulses = pulses_in_span(pulses, tel, tail_s=p.tau_delay + _TAIL_TAUS * p.tau_fall)
    h = wheel_momentum(tel, spacecraft)
    q = spacecraft.moment_matrix
    j = _impulses(tel, pulses, spacecraft)
    r = residual_momentum(tel.t, tel.omega, spacecraft.inertia, h, q, j)
    if pulses is not None and np.asarray(pulses.t_on).size:
        p = spacecraft.pulse
        steps = rate_step_columns(tel.t, tel.omega, spacecraft.inertia, h,
                                  (pulses.t_on, pulses.thruster, pulses.width),
                                  (p.tau_delay, p.tau_rise, p.tau_fall), len(spacecraft.thrusters))
        r = r + np.einsum("nbsa,as,s->nb", steps, q, spacecraft.thrust_per_thruster)
        r = r + rate_step_second_order(tel.t, tel.omega, spacecraft.inertia, h,
                                       (pulses.t_on, pulses.thruster, pulses.width),
                                       (p.tau_delay, p.tau_rise, p.tau_fall),
                                       q * spacecraft.thrust_per_thruster[None, :])
    return LeakInputs(np.asarray(tel.t, float), r, j, q, spacecraft.thrust_per_thruster,
                      spacecraft.knowledge.torque_sd_nm, tel.source, spacecraft.thruster_names,
                      offset_sd_nms=spacecraft.momentum_capacity_nms,
                      noise_floor_nms=_noise_floor_nms(spacecraft))


def _noise_floor_nms(spacecraft: Spacecraft) -> float:
    """The momentum noise of one sample at the package's rate-noise floors, N m s:
    ``√((λ_max σ_ω)² + Σ_k (J_k σ_ρ)²)``, ``λ_max`` the model's largest principal moment, ``J_k``
    its wheels' spin inertias and ``(σ_ω, σ_ρ)`` :data:`~cassini_bayes.telemetry.RATE_NOISE_FLOORS`
    (the floors of measured body- and wheel-rate noise): the residual's white-noise level of
    noise-free data, in the spacecraft's own momentum (Cassini ~7e-6 N m s, the ESPA bus 2e-8)."""
    s_w, s_r = RATE_NOISE_FLOORS
    lam = float(np.max(np.linalg.eigvalsh(np.asarray(spacecraft.inertia, float))))
    j = np.array([w.inertia for w in spacecraft.wheels], float)
    return float(np.hypot(lam * s_w, s_r * np.linalg.norm(j)))


def noise_sd(r: np.ndarray, floor_nms: float) -> np.ndarray:
    """White-noise sd per axis (N m s) of rows ``r`` (n, 3), at least ``floor_nms``
    (:attr:`LeakInputs.noise_floor_nms`): the median absolute deviation of the second
    differences ÷ √6. A leak or a torque adds a constant to every first difference after its
    onset, which second differences remove (but at the onset's one row); first differences read
    a leak's slope as noise (1.1-2× the level, docs/sbc/leak)."""
    d = np.diff(r, n=2, axis=0)
    if d.shape[0] < 2:
        return np.full(3, floor_nms)
    mad = np.median(np.abs(d - np.median(d, axis=0)), axis=0)
    return np.maximum(1.4826 * mad / np.sqrt(6.0), floor_nms)


