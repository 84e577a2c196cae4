"""Bayesian thruster-leak monitor: posterior probability of a leak per thruster (Lee §3.2).

Model
-----
The residual momentum of Lee Eq 10, ``R(t) = I Δω + ΔH_RWA + ΔG − Q J(t)`` (N m s, counted from
the stretch's first sample; :func:`cassini_bayes.estimators.leak.residual_momentum`), is, under
hypothesis ``k`` (thruster ``k`` leaks a fraction ``f`` of its thrust from ``t_L``) ::

    R(t_i) = r_0 + T (t_i − t_0) + Σ_j δ_j Q[:, j] J_j(t_i) + f F Q[:, k] (t_i − t_L)_+ + e_i

* ``r_0`` (3,) the offset of the first sample's noise, prior ``N(0, 10² N m s)`` per axis;
* ``T`` (3,) an unknown constant external torque (N m), prior a scale mixture of normals: with
  probability 0.9 ``N(0, σ_T²)``, ``σ_T`` the spacecraft model's ``[torque_knowledge] sd_nm``,
  and with 0.1 ten times wider (:data:`TORQUE_SCALES`): a torque several ``σ_T`` off the model
  file's knowledge is then an unusual torque, not a leak that started with the stretch (with a
  normal prior alone one of 7 σ_T raised a false alarm, docs/leak.md);
* ``δ_j`` the fractional thrust error of thruster ``j`` (thruster-to-thruster variation, the
  Bayesian counterpart of Lee Eq 11), prior ``N(0, η²)``, η = 0.05 as Lee's launch value, times
  the modelled impulse ``J_j(t)`` (N s) and the moment arm ``Q[:, j]`` (Feldman & Lee Eq 16);
* the leak column ``F Q[:, k] (t − t_L)_+``: a 10 % Z1 leak at 1 N is (−0.158, +0.123, 0) N m;
* ``e_i`` white noise, per axis, its sd from the data (median absolute deviation of the second
  differences ÷ √6, blind to a leak's slope; the larger of the levels of the raw rows and of the rows used). ``R`` is an
  *integral* of the torque residual, but its noise is not a random walk: ``I Δω`` and
  ``ΔH_RWA`` are differences of sampled states, so the gyro and tach noise enter each sample
  once. What is integrated — the gyroscopic impulse ``ΔG`` from noisy 1 s rates, across pulses —
  makes a random walk of ~2e-3 N m s over hours, which a white model on 1 s samples takes for a
  torque of ~1e-7 N m; the monitor therefore uses the residual every :data:`SAMPLE_STEP_S` =
  60 s, where the white level covers it (measured, docs/leak.md). A random-walk term in the
  likelihood (a Kalman filter per hypothesis) would be the exact remedy; it is not done here.

``r_0``, ``T`` and ``δ`` are Gaussian and the model is linear, so they are integrated out exactly
(Woodbury). The leak fraction has a scale-mixture of half-normal priors (scales 10⁻⁴ … 1, equal
weights: close to log-uniform over the 0.1 % … 100 % range Lee's tests span); each component's
evidence is closed-form (a Gaussian evidence times ``2 Φ(m/s)``). The onset is marginalised over a
grid, uniform over the part of the stretch seen so far; the prior probability of a leak in the
stretch is ``prior_leak`` shared equally by the eight thrusters. Every quantity needed for all
onsets and all check times comes from cumulative sums, so the running (sequential) monitor costs
O(n + checks × onsets × 8).

Identifiability: no two columns of ``Q`` are parallel, so every thruster's leak is distinct; the
antiparallel pairs Z1/Z3, Z2/Z4, Y1/Y4 and Y2/Y3 are told apart only by the sign of ``f`` (a leak
only adds thrust). A leak that starts at the stretch's first sample looks like an external torque;
the torque prior (µN m) against leak torques of mN m resolves it. The thrust-error term can mimic
a leak only through the thruster that fights it, and only at the cost of a ~100 % thrust error.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy.special import log_ndtr, logsumexp

from cassini_bayes.errors import InputError, spelled
from cassini_bayes.estimators.baseline import wheel_momentum
from cassini_bayes.estimators.leak import ETA, residual_momentum
from cassini_bayes.physics.impulse import THRUSTER_NAMES, impulse_from_on_times
from cassini_bayes.physics.pulse import pulse_impulse_until
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import PulseLog, Telemetry, pulses_in_span

__all__ = ["LeakInputs", "LeakPosterior", "leak_inputs", "leak_posterior", "HYPOTHESES",
           "FRACTION_SCALES", "OFFSET_SD_NMS", "SAMPLE_STEP_S", "TORQUE_SCALES"]

HYPOTHESES = ("none",) + THRUSTER_NAMES
FRACTION_SCALES = 10.0 ** np.arange(-4.0, 0.01, 0.5)
"""Scales of the half-normal mixture prior on the leak fraction (fractions of the thrust)."""
TORQUE_SCALES = ((1.0, 0.9), (10.0, 0.1))
"""The external torque's prior: ``(multiple of the model file's sd, weight)`` of each normal
component of its scale mixture (a contaminated normal)."""
OFFSET_SD_NMS = 10.0
"""Prior sd of the residual's offset ``r_0`` per axis, N m s (wide: it only absorbs noise)."""
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
_NOISE_FLOOR_NMS = 1e-6


@dataclass(frozen=True)
class LeakInputs:
    """A stretch's residual momentum and modelled impulses.

    t : (n,) s. residual : (n, 3) ``R`` of Lee Eq 10, N m s, from the first sample.
    impulse : (n, 8) modelled accumulated thruster impulses ``J`` from the first sample, N s.
    q_matrix : (3, 8) moment matrix, m. thrust_n : (8,) modelled thrust per thruster, N.
    torque_sd_nm : prior sd of the external torque per axis, N m.
    source : the telemetry it came from, for error messages.
    """

    t: np.ndarray
    residual: np.ndarray
    impulse: np.ndarray
    q_matrix: np.ndarray
    thrust_n: np.ndarray
    torque_sd_nm: float
    source: str = "<telemetry>"


@dataclass(frozen=True)
class LeakPosterior:
    """The running monitor's output.

    t_check : (c,) times of the checks, s. prob : (c, 9) posterior probability of
    ``HYPOTHESES`` (``none, Z1 … Y4``) given the data up to each check.
    detection_time_s : first check with ``P(leak) ≥ p_detect`` (``None``: never).
    isolation_time_s : first check with one thruster's ``P ≥ p_detect`` (``None``: never), and
    ``thruster`` that thruster (``None``: none isolated).
    fraction_mean, fraction_sd : posterior of that thruster's leak fraction (without isolation:
    of the thruster most probable at the last check) given all the data, and ``torque_nm`` (3,)
    its mean torque, N m. onset_s : posterior mean of its onset, s.
    noise_sd_nms : (3,) white-noise sd per axis, N m s.
    """

    t_check: np.ndarray
    prob: np.ndarray
    p_detect: float
    detection_time_s: float | None
    isolation_time_s: float | None
    thruster: str | None
    fraction_mean: float
    fraction_sd: float
    torque_nm: np.ndarray
    onset_s: float
    noise_sd_nms: np.ndarray

    @property
    def p_leak(self) -> np.ndarray:
        """(c,) posterior probability of any leak at each check."""
        return 1.0 - self.prob[:, 0]

    def summary(self) -> dict:
        """JSON-able summary (the last check's probabilities, the detection)."""
        last = self.prob[-1]
        return {
            "p_hypothesis": {h: float(p) for h, p in zip(HYPOTHESES, last)},
            "p_leak": float(1.0 - last[0]),
            "p_detect": self.p_detect,
            "detection_time_s": self.detection_time_s,
            "isolation_time_s": self.isolation_time_s,
            "thruster": self.thruster,
            "fraction_mean": self.fraction_mean,
            "fraction_sd": self.fraction_sd,
            "torque_nm": [float(x) for x in self.torque_nm],
            "onset_s": self.onset_s,
            "noise_sd_nms": [float(x) for x in self.noise_sd_nms],
            "n_checks": int(self.t_check.size),
        }


def _impulses(tel: Telemetry, pulses: PulseLog | None, sc: Spacecraft) -> np.ndarray:
    """Modelled impulses (n, 8), N s, from the first sample: the pulse log under the model's
    pulse shape (:func:`~cassini_bayes.physics.pulse.pulse_impulse_until`), else the telemetry's
    on-times times the model thrust (Feldman & Lee Eq 17).

    A pulse has delivered all of its impulse ``_TAIL_TAUS`` fall times after its end (the rest is
    below e⁻⁴⁰), so each sample sums the finished pulses (a cumulative sum) and evaluates the
    profile only for the pulses still running: O(n + pulses) for a stretch of hours.
    """
    t = np.asarray(tel.t, float)
    if pulses is None:
        if tel.on_times is None:
            raise InputError("has neither on-times nor a pulse log; pass --pulses",
                             path=tel.source)
        return np.asarray(impulse_from_on_times(tel.on_times, sc.thrust))
    p = sc.pulse
    t_on, k, w = (np.asarray(a) for a in (pulses.t_on, pulses.thruster, pulses.width))

    def delivered(dt, width):
        return np.asarray(pulse_impulse_until(dt, width, p.tau_delay, p.tau_rise, p.tau_fall),
                          float) * sc.thrust

    end = t_on + w + p.tau_delay + _TAIL_TAUS * p.tau_fall
    j = np.zeros((t.size, 8))
    full = delivered(end - t_on, w)
    first_done = np.searchsorted(t, end, side="left")       # first sample after each pulse ends
    np.add.at(j, (first_done[first_done < t.size], k[first_done < t.size]),
              full[first_done < t.size])
    j = np.cumsum(j, axis=0)
    first = np.searchsorted(t, t_on, side="right")          # first sample after the command
    count = np.maximum(first_done - first, 0)
    rows = np.repeat(first - np.cumsum(count) + count, count) + np.arange(count.sum())
    which = np.repeat(np.arange(t_on.size), count)
    np.add.at(j, (rows, k[which]), delivered(t[rows] - t_on[which], w[which]))
    return j - j[:1]


_TAIL_TAUS = 40.0


def leak_inputs(tel: Telemetry, pulses: PulseLog | None, spacecraft: Spacecraft) -> LeakInputs:
    """Residual momentum (Lee Eq 10) and modelled impulses of a telemetry stretch; pulses of the
    log that act entirely outside the stretch are left out with a warning
    (:func:`~cassini_bayes.telemetry.pulses_in_span`)."""
    if pulses is not None:
        p = spacecraft.pulse
        pulses = pulses_in_span(pulses, tel, tail_s=p.tau_delay + _TAIL_TAUS * p.tau_fall)
    h = wheel_momentum(tel, spacecraft)
    q = spacecraft.moment_matrix
    j = _impulses(tel, pulses, spacecraft)
    r = residual_momentum(tel.t, tel.omega, spacecraft.inertia, h, q, j)
    return LeakInputs(np.asarray(tel.t, float), r, j, q, np.full(8, float(spacecraft.thrust)),
                      spacecraft.knowledge.torque_sd_nm, tel.source)


def _noise_sd(r: np.ndarray) -> np.ndarray:
    """White-noise sd per axis (N m s) of rows ``r`` (n, 3): the median absolute deviation of
    the second differences ÷ √6. A leak or a torque adds a constant to every first difference
    after its onset, which second differences remove (but at the onset's one row); first
    differences read a leak's slope as noise (1.1-2× the level, docs/sbc/leak)."""
    d = np.diff(r, n=2, axis=0)
    if d.shape[0] < 2:
        return np.full(3, _NOISE_FLOOR_NMS)
    mad = np.median(np.abs(d - np.median(d, axis=0)), axis=0)
    return np.maximum(1.4826 * mad / np.sqrt(6.0), _NOISE_FLOOR_NMS)


def _cum(a: np.ndarray) -> np.ndarray:
    """Cumulative sums along axis 0 with a leading zero row (prefix sums)."""
    return np.concatenate([np.zeros((1,) + a.shape[1:]), np.cumsum(a, axis=0)])


class _Sums:
    """Prefix sums of a stretch for the closed-form evidence at any check and onset."""

    def __init__(self, inp: LeakInputs, eta: float, raw: LeakInputs):
        t = inp.t - inp.t[0]
        n = t.size
        y, q = inp.residual, inp.q_matrix
        # nuisance columns (n, 3 axes, p0): r_0 (3), T (3), δ_j Q[:, j] J_j (8)
        eye = np.eye(3)
        cols = np.concatenate([np.broadcast_to(eye, (n, 3, 3)), t[:, None, None] * eye[None],
                               q[None, :, :] * inp.impulse[:, None, :]], axis=2)
        # one nuisance prior precision per component of the torque's scale mixture
        self.prior_prec = [1.0 / np.r_[np.full(3, OFFSET_SD_NMS ** 2),
                                       np.full(3, (scale * max(inp.torque_sd_nm, 1e-12)) ** 2),
                                       np.full(8, max(eta, 1e-12) ** 2)]
                           for scale, _ in TORQUE_SCALES]
        self.log_w = np.log([w for _, w in TORQUE_SCALES])
        self.t, self.y = t, y
        self.raw_t, self.raw_y = raw.t, raw.residual
        self.nn = _cum(np.einsum("iap,iaq->iapq", cols, cols))
        self.ny = _cum(np.einsum("iap,ia->iap", cols, y))
        self.n1, self.nt = _cum(cols), _cum(t[:, None, None] * cols)
        self.y1, self.yt = _cum(y), _cum(t[:, None] * y)
        self.c1, self.ct, self.ctt = _cum(np.ones(n)), _cum(t), _cum(t * t)
        self.u = q * inp.thrust_n[None, :]              # (3, 8): torque per unit fraction, N m

    def noise_sd(self, c: int) -> np.ndarray:
        """White-noise sd per axis (N m s) from the data up to row ``c``: the larger of the
        levels seen between the used rows and between the raw telemetry rows (the latter is
        reliable from a few dozen seconds on, the former holds the slow wander)."""
        raw = self.raw_y[:np.searchsorted(self.raw_t, self.t[c] + self.raw_t[0], "right")]
        return np.maximum(_noise_sd(self.y[:c + 1]), _noise_sd(raw))

    def evidence(self, c: int, tl: np.ndarray):
        """Per onset (G), thruster (8) and prior component (S fraction scales × the torque's
        components, weighted), with the data rows 0..c: the log Bayes factor against no leak
        (weighted so that its mean over onsets and fraction scales is the thruster's), and the
        Gaussian-prior posterior mean ``m`` and precision of the fraction (its half-normal
        posterior is that Gaussian cut at 0)."""
        lam = 1.0 / self.noise_sd(c) ** 2               # (3,) noise precision per axis
        parts = [self._evidence(c, tl, lam, prec) for prec in self.prior_prec]
        # log evidence of "no leak" under each torque component, up to a common constant
        # (Gaussian marginal: −½ log|A| + ½ log|P| + ½ bᵀA⁻¹b)
        log_z0 = self.log_w + np.array([p[3] for p in parts])
        log_none = logsumexp(log_z0)
        log_bf = np.concatenate([lz - log_none + p[0] for lz, p in zip(log_z0, parts)], axis=-1)
        return (log_bf, np.concatenate([p[1] for p in parts], axis=-1),
                np.concatenate([p[2] for p in parts], axis=-1))

    def _evidence(self, c: int, tl: np.ndarray, lam: np.ndarray, prior_prec: np.ndarray):
        """:meth:`evidence` under one nuisance prior (precisions ``prior_prec``), with the log
        evidence of "no leak" under it (up to a constant common to all priors)."""
        e, t = c + 1, self.t
        a_mat = np.diag(prior_prec) + np.einsum("a,apq->pq", lam, self.nn[e])
        b0 = np.einsum("a,ap->p", lam, self.ny[e])
        sol_b = np.linalg.solve(a_mat, b0)
        log_z0 = 0.5 * (np.sum(np.log(prior_prec)) - np.linalg.slogdet(a_mat)[1] + b0 @ sol_b)
        onsets = np.searchsorted(t, tl, side="right")   # first row after each onset
        # sums over rows L..c of h = t − t_L: Σh², Σ h N, Σ h y
        s1, st = self.c1[e] - self.c1[onsets], self.ct[e] - self.ct[onsets]
        sh2 = (self.ctt[e] - self.ctt[onsets]) - 2 * tl * st + tl ** 2 * s1
        shn = (self.nt[e] - self.nt[onsets]) - tl[:, None, None] * (self.n1[e] - self.n1[onsets])
        shy = (self.yt[e] - self.yt[onsets]) - tl[:, None] * (self.y1[e] - self.y1[onsets])
        lu = lam[:, None] * self.u
        xx = np.einsum("ak,ak->k", lu, self.u)[None, :] * sh2[:, None]        # (G, 8)
        g = np.einsum("ak,gap->gkp", lu, shn)                                  # (G, 8, p0)
        xy = np.einsum("ak,ga->gk", lu, shy)
        p0 = g.shape[-1]
        sol_g = np.linalg.solve(a_mat, g.reshape(-1, p0).T).T.reshape(g.shape)
        s_xx = np.maximum(xx - np.einsum("gkp,gkp->gk", g, sol_g), 1e-300)    # xᵀ C⁻¹ x
        z = (xy - np.einsum("gkp,p->gk", g, sol_b))[..., None]                 # xᵀ C⁻¹ y
        s2 = FRACTION_SCALES ** 2
        prec = 1.0 / s2 + s_xx[..., None]                                      # (G, 8, S)
        m = z / prec
        log_bf = (-0.5 * np.log(prec * s2) + 0.5 * z * z / prec + np.log(2.0)
                  + log_ndtr(m * np.sqrt(prec)))
        return log_bf, m, prec, log_z0


def _fraction(log_bf: np.ndarray, m: np.ndarray, prec: np.ndarray, k: int):
    """Posterior mean and sd of thruster ``k``'s fraction (a mixture of cut normals) and the
    posterior weights of the onsets (G,)."""
    w = np.exp(log_bf[:, k] - logsumexp(log_bf[:, k]))                         # (G, S)
    s = 1.0 / np.sqrt(prec[:, k])
    a = m[:, k] / s
    ratio = np.exp(-0.5 * a * a - 0.5 * np.log(2.0 * np.pi) - log_ndtr(a))   # φ(a) / Φ(a)
    mean = m[:, k] + s * ratio
    var = s * s * (1.0 - ratio * (a + ratio))
    mu = float(np.sum(w * mean))
    sd = float(np.sqrt(max(np.sum(w * (var + mean * mean)) - mu * mu, 0.0)))
    return mu, sd, w.sum(axis=1)


def _thinned(inp: LeakInputs, step_s: float) -> LeakInputs:
    """The rows nearest a grid every ``step_s`` (and the last one)."""
    t = inp.t
    idx = np.unique(np.r_[np.searchsorted(t, np.arange(t[0], t[-1], step_s)), t.size - 1])
    return dataclasses.replace(inp, t=t[idx], residual=inp.residual[idx], impulse=inp.impulse[idx])


def leak_posterior(inp: LeakInputs, *, prior_leak: float = 0.01, eta: float = ETA,
                   sample_step_s: float = SAMPLE_STEP_S, check_step_s: float = 60.0,
                   onset_step_s: float = 20.0, p_detect: float = 0.99) -> LeakPosterior:
    """Run the Bayesian monitor over a stretch, as it would run on board: the residual taken
    every ``sample_step_s`` (:data:`SAMPLE_STEP_S`); a check every ``check_step_s`` (and at the
    last sample) sees only the data up to it; onsets on a grid every ``onset_step_s`` from the
    first sample up to the check; ``prior_leak``: prior probability of a leak in the stretch.
    Detection: the first check with ``P(leak) ≥ p_detect``; isolation: the first with one
    thruster's ``P ≥ p_detect`` (that thruster is the answer)."""
    for name, flag, v in (("prior_leak", "--prior-leak", prior_leak),
                          ("p_detect", "--p-detect", p_detect)):
        if not 0.0 < v < 1.0:
            raise InputError(f"must lie strictly between 0 and 1, got {v}",
                             path=spelled(flag, name))
    for name, flag, v in (("sample_step_s", "--sample-step", sample_step_s),
                          ("check_step_s", "--check-step", check_step_s),
                          ("onset_step_s", "--onset-step", onset_step_s)):
        if not v > 0:
            raise InputError(f"must be positive seconds, got {v}", path=spelled(flag, name))
        span = float(inp.t[-1] - inp.t[0])
        if span / v > MAX_GRID:  # the onset grid × checks table grows as the square
            raise InputError(f"{v:g} s makes {span / v:.3g} steps over the {span:.6g} s "
                             f"stretch, more than {MAX_GRID}; use at least "
                             f"{span / MAX_GRID:.3g} s", path=spelled(flag, name))
    raw, inp = inp, _thinned(inp, sample_step_s)
    n = inp.t.size
    if n < 3:
        raise InputError(f"has {n} rows {sample_step_s:g} s apart; the leak monitor needs at "
                         "least 3", path=inp.source)
    sums = _Sums(inp, eta, raw)
    t = sums.t
    checks = np.unique(np.r_[np.searchsorted(t, np.arange(check_step_s, t[-1], check_step_s)),
                             n - 1])
    checks = checks[checks >= 2]
    grid = np.arange(0.0, t[-1], onset_step_s)                 # onset times (s from t_0)
    prob, det, iso = [], None, None
    for i, c in enumerate(checks):
        onsets = grid[grid < t[c]]
        log_bf, m, prec = sums.evidence(c, onsets)
        log_k = logsumexp(log_bf, axis=(0, 2)) - np.log(onsets.size * FRACTION_SCALES.size)
        log_post = np.r_[np.log1p(-prior_leak), np.log(prior_leak / 8.0) + log_k]
        prob.append(np.exp(log_post - logsumexp(log_post)))
        if det is None and 1.0 - prob[-1][0] >= p_detect:
            det = i
        if iso is None and prob[-1][1:].max() >= p_detect:
            iso = i
    prob = np.array(prob)
    # the fraction and onset of the most probable thruster, from all the data (the last check)
    k = int(np.argmax(prob[iso if iso is not None else -1][1:]))
    fm, fs, w_onset = _fraction(log_bf, m, prec, k)
    t_check = inp.t[checks]
    return LeakPosterior(
        t_check=t_check, prob=prob, p_detect=p_detect,
        detection_time_s=None if det is None else float(t_check[det]),
        isolation_time_s=None if iso is None else float(t_check[iso]),
        thruster=None if iso is None else THRUSTER_NAMES[k],
        fraction_mean=fm, fraction_sd=fs, torque_nm=fm * sums.u[:, k],
        onset_s=float(inp.t[0] + np.sum(w_onset * onsets)),
        noise_sd_nms=sums.noise_sd(n - 1))
