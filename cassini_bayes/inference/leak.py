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
* ``δ_j`` the fractional thrust error of thruster ``j`` of the model's ``m`` (thruster-to-thruster
  variation, the Bayesian counterpart of Lee Eq 11), prior ``N(0, η²)``, η = 0.05 as Lee's launch
  value, times the modelled impulse ``J_j(t)`` (N s) and the moment arm ``Q[:, j]`` (Feldman & Lee
  Eq 16, column ``(r_j − e) × d_j`` of any thruster set);
* the leak column ``F_k Q[:, k] (t − t_L)_+``: a 10 % Z1 leak at 1 N is (−0.158, +0.123, 0) N m;
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
weights: close to log-uniform over the 0.1 % … 100 % range Lee's tests span). The onset is
continuous, uniform over the part of the stretch seen so far, and integrated cell by cell between
the used rows: with the onset in ``[t_{l−1}, t_l)`` the leak's columns are ``f P + D O`` with
``P = F Q[:, k] (t − t_l)₊``, ``O = F Q[:, k] 1(t ≥ t_l)`` and ``D = f d``, ``d = t_l − t_L``,
so the likelihood is Gaussian in ``(f, D)``. For a fixed ``f`` the integral over ``d ∈ [0, t_l −
t_{l−1}]`` is a normal CDF difference; integrating ``f`` against each half-normal component in
closed form first instead leaves, per cell, ``∫ exp(−A²/2 + log Φ(B)) dw`` over
``w = asinh(√(a_OO/p) (d + a_PO/a_OO))`` with ``A = b tanh w + g sech w``, ``B = b sech w −
g tanh w`` (``a`` the Gram terms of ``P, O``, ``p`` the fraction's precision with ``D`` profiled,
``b, g`` the scores of ``f`` and ``D`` in its sd): a bounded integrand with one peak or trough,
taken by Gauss-Legendre quadrature adapted to it (its error against adaptive quadrature:
docs/leak.md). Every quantity for all cells and check times comes from
cumulative sums; the running (sequential) monitor costs O(n + checks × cells × m) integrals.

Identifiability: a leak is told by its torque direction ``Q[:, k]``. On Cassini no two columns of
``Q`` are parallel, so every thruster's leak is distinct; the antiparallel pairs Z1/Z3, Z2/Z4,
Y1/Y4 and Y2/Y3 are told apart only by the sign of ``f`` (a leak only adds thrust). On another
layout two thrusters with parallel columns (same sign) cannot be told apart: their posterior
splits between them and neither is isolated. A leak that starts at the stretch's first sample
looks like an external torque; the torque prior (µN m) against leak torques of mN m resolves it. The thrust-error term can mimic
a leak only through the thruster that fights it, and only at the cost of a ~100 % thrust error.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass

import numpy as np
from scipy import optimize
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
"""Cassini's hypotheses (the Eq 16 layout); a run's own are :attr:`LeakInputs.hypotheses`:
``none`` and the model's thruster names."""
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
    impulse : (n, m) modelled accumulated thruster impulses ``J`` from the first sample, N s.
    q_matrix : (3, m) moment matrix, m. thrust_n : (m,) modelled thrust per thruster, N.
    torque_sd_nm : prior sd of the external torque per axis, N m.
    source : the telemetry it came from, for error messages.
    thruster_names : (m,) the thrusters' names, in the order of the columns (Cassini's
        ``Z1 … Y4`` by default).
    """

    t: np.ndarray
    residual: np.ndarray
    impulse: np.ndarray
    q_matrix: np.ndarray
    thrust_n: np.ndarray
    torque_sd_nm: float
    source: str = "<telemetry>"
    thruster_names: tuple[str, ...] = THRUSTER_NAMES

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
    (:func:`~cassini_bayes.telemetry.pulses_in_span`)."""
    if pulses is not None:
        p = spacecraft.pulse
        pulses = pulses_in_span(pulses, tel, tail_s=p.tau_delay + _TAIL_TAUS * p.tau_fall)
    h = wheel_momentum(tel, spacecraft)
    q = spacecraft.moment_matrix
    j = _impulses(tel, pulses, spacecraft)
    r = residual_momentum(tel.t, tel.omega, spacecraft.inertia, h, q, j)
    return LeakInputs(np.asarray(tel.t, float), r, j, q, spacecraft.thrust_per_thruster,
                      spacecraft.knowledge.torque_sd_nm, tel.source, spacecraft.thruster_names)


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


@dataclass(frozen=True)
class _Rule:
    """The onset quadrature: a cell whose integrand varies by less than ``easy_nats`` over at
    most ``easy_span`` in ``w`` takes Gauss-Legendre with ``easy_nodes`` nodes; any other is
    split at its peak or trough, each side at the points ``levels`` nats below its top, each
    piece mapped by ``w = w_top ± δ sinh y`` (``δ`` the e-folding length at the piece's top) and
    cut into parts of at most ``part_w`` in ``w`` and ``part_y`` in ``y``, each with
    ``part_nodes`` Gauss-Legendre nodes. Cells whose upper bound is ``prune_nats`` below their
    thruster's evidence are dropped. A finer rule is for measuring this one's error
    (benchmarks/leak_quadrature.py, docs/leak.md)."""

    easy_nats: float = 0.3
    easy_span: float = 2.0
    easy_nodes: int = 4
    levels: tuple[float, ...] = (1.0, 4.0, 12.0, 40.0)
    part_w: float = 0.5
    part_y: float = 1.0
    part_nodes: int = 5
    prune_nats: float = 40.0


_RULE = _Rule()


@functools.cache
def _gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on [−1, 1]."""
    return np.polynomial.legendre.leggauss(n)


class _Sums:
    """Prefix sums of a stretch for the closed-form evidence at any check."""

    def __init__(self, inp: LeakInputs, eta: float, raw: LeakInputs):
        t = inp.t - inp.t[0]
        n = t.size
        y, q = inp.residual, inp.q_matrix
        # nuisance columns (n, 3 axes, p0): r_0 (3), T (3), δ_j Q[:, j] J_j (m)
        eye = np.eye(3)
        cols = np.concatenate([np.broadcast_to(eye, (n, 3, 3)), t[:, None, None] * eye[None],
                               q[None, :, :] * inp.impulse[:, None, :]], axis=2)
        # one nuisance prior precision per component of the torque's scale mixture
        self.prior_prec = [1.0 / np.r_[np.full(3, OFFSET_SD_NMS ** 2),
                                       np.full(3, (scale * max(inp.torque_sd_nm, 1e-12)) ** 2),
                                       np.full(q.shape[1], max(eta, 1e-12) ** 2)]
                           for scale, _ in TORQUE_SCALES]
        self.log_w = np.log([w for _, w in TORQUE_SCALES])
        self.t, self.y = t, y
        self.raw_t, self.raw_y = raw.t, raw.residual
        self.nn = _cum(np.einsum("iap,iaq->iapq", cols, cols))
        self.ny = _cum(np.einsum("iap,ia->iap", cols, y))
        self.n1, self.nt = _cum(cols), _cum(t[:, None, None] * cols)
        self.y1, self.yt = _cum(y), _cum(t[:, None] * y)
        self.c1, self.ct, self.ctt = _cum(np.ones(n)), _cum(t), _cum(t * t)
        self.u = q * inp.thrust_n[None, :]              # (3, m): torque per unit fraction, N m

    def noise_sd(self, c: int) -> np.ndarray:
        """White-noise sd per axis (N m s) from the data up to row ``c``: the larger of the
        levels seen between the used rows and between the raw telemetry rows (the latter is
        reliable from a few dozen seconds on, the former holds the slow wander)."""
        raw = self.raw_y[:np.searchsorted(self.raw_t, self.t[c] + self.raw_t[0], "right")]
        return np.maximum(_noise_sd(self.y[:c + 1]), _noise_sd(raw))

    def check(self, c: int, rule: _Rule = _RULE) -> _Check:
        """The evidence of every thruster's leak with the data rows 0..c (module docstring), its
        onset integrated by ``rule``."""
        e, t = c + 1, self.t
        lam = 1.0 / self.noise_sd(c) ** 2               # (3,) noise precision per axis
        cell = np.arange(1, c + 1)                      # onset in [t_{l-1}, t_l): rows l..c
        tr = t[cell]                                    # the leak's columns from t_l on: f P + D O
        s0, s1, s2 = (x[e] - x[cell] for x in (self.c1, self.ct, self.ctt))
        sh, sh2 = s1 - tr * s0, s2 - 2.0 * tr * s1 + tr * tr * s0      # Σ h, Σ h², h = t − t_l
        n1 = self.n1[e] - self.n1[cell]
        nh = self.nt[e] - self.nt[cell] - tr[:, None, None] * n1
        y1 = self.y1[e] - self.y1[cell]
        yh = self.yt[e] - self.yt[cell] - tr[:, None] * y1
        lu = lam[:, None] * self.u
        lu2 = np.einsum("ak,ak->k", lu, self.u)
        g_p = np.einsum("ak,lap->lkp", lu, nh)          # Nᵀ Λ P, Nᵀ Λ O: (cells, m, p0)
        g_o = np.einsum("ak,lap->lkp", lu, n1)
        z_p0 = np.einsum("ak,la->lk", lu, yh)           # Pᵀ Λ y, Oᵀ Λ y
        z_o0 = np.einsum("ak,la->lk", lu, y1)
        p0 = g_p.shape[-1]
        gram, log_z0 = [], []
        for prior_prec in self.prior_prec:
            a_mat = np.diag(prior_prec) + np.einsum("a,apq->pq", lam, self.nn[e])
            b0 = np.einsum("a,ap->p", lam, self.ny[e])
            sol = np.linalg.solve(a_mat, np.concatenate(
                [b0[:, None], g_p.reshape(-1, p0).T, g_o.reshape(-1, p0).T], axis=1))
            sol_b = sol[:, 0]
            sol_p = sol[:, 1:1 + g_p[..., 0].size].T.reshape(g_p.shape)
            sol_o = sol[:, 1 + g_p[..., 0].size:].T.reshape(g_o.shape)
            # log evidence of "no leak" under this torque component, up to a common constant
            # (Gaussian marginal: −½ log|A| + ½ log|P| + ½ bᵀA⁻¹b)
            log_z0.append(0.5 * (np.sum(np.log(prior_prec)) - np.linalg.slogdet(a_mat)[1]
                                 + b0 @ sol_b))
            # Woodbury: the leak columns' Gram terms and scores with the nuisances integrated
            gram.append((lu2 * sh2[:, None] - np.einsum("lkp,lkp->lk", g_p, sol_p),
                         lu2 * sh[:, None] - np.einsum("lkp,lkp->lk", g_p, sol_o),
                         lu2 * s0[:, None] - np.einsum("lkp,lkp->lk", g_o, sol_o),
                         z_p0 - g_p @ sol_b, z_o0 - g_o @ sol_b))
        a_pp, a_po, a_oo, z_p, z_o = (np.stack(x, axis=-1)[..., None] for x in zip(*gram))
        log_z0 = self.log_w + np.array(log_z0)
        return _Check(t_ref=tr, width=tr - t[cell - 1], t_c=float(t[c]),
                      log_prior=log_z0 - logsumexp(log_z0), a_pp=a_pp, a_po=a_po,
                      a_oo=np.maximum(a_oo, 1e-300), z_p=z_p, z_o=z_o, rule=rule)


# The onset integral of one cell is ∫ exp(log_g(w)) dw over w ∈ [asinh r₀, asinh r₁]; log_g
# is unimodal in the angle θ = atan(sinh w) + atan2(g, b) (its peak at θ = 0, its trough at ±π).
# The rule and its settings: _Rule (above).
_LOG_SQRT_2PI = 0.5 * np.log(2.0 * np.pi)


def _log_g(w, b, g):
    """The cell's onset integrand, log: ``−A²/2 + log Φ(B)`` with ``A = b tanh w + g sech w``,
    ``B = b sech w − g tanh w`` (``A² + B² = b² + g²``)."""
    th, sh = np.tanh(w), 1.0 / np.cosh(w)
    a = b * th + g * sh
    return -0.5 * a * a + log_ndtr(b * sh - g * th)


def _mills(b):
    """φ(B) / Φ(B)."""
    return np.exp(-0.5 * b * b - _LOG_SQRT_2PI - log_ndtr(b))


def _dlog_g(w, b, g):
    """d log_g / dw = −A sech w (B + φ(B)/Φ(B))."""
    th, sh = np.tanh(w), 1.0 / np.cosh(w)
    bb = b * sh - g * th
    return -(b * th + g * sh) * sh * (bb + _mills(bb))


def _h_inverse(h, start):
    """``B`` with ``B²/2 + log Φ(B) = h`` by Newton from ``start`` above the root (the function
    is convex and increasing, so the iterates fall monotonically to it)."""
    b = np.array(start, float)
    live = np.arange(b.size)
    for _ in range(30):
        x = b[live]
        step = (0.5 * x * x + log_ndtr(x) - h[live]) / (x + _mills(x))
        b[live] = x - step
        live = live[np.abs(step) > 1e-10 * (1.0 + np.abs(x))]
        if not live.size:
            break
    return b


def _pieces(b, g, r0, r1, levels):
    """Bounds (…, 2 × len(levels)) of the pieces of each cell: the two monotone sides of its
    peak or trough, each cut where ``log_g`` has fallen ``levels`` nats below the side's top.
    Returns ``(top, end)``: each piece's end with the larger ``log_g`` and its other end
    (``w``)."""
    rho, phi = np.hypot(b, g), np.arctan2(g, b)
    w0, w1 = np.arcsinh(r0), np.arcsinh(r1)
    th0, th1 = np.arctan(r0) + phi, np.arctan(r1) + phi
    turn = np.select([(th0 < 0) & (th1 > 0), (th0 < np.pi) & (th1 > np.pi),
                      (th0 < -np.pi) & (th1 > -np.pi)], [0.0, np.pi, -np.pi], np.nan)
    split = ~np.isnan(turn)
    w_turn = np.where(split, np.arcsinh(-g / np.where(split, b, 1.0)), w1)
    th_turn = np.where(split, turn, th1)
    tops, ends = [], []
    for lo, hi, w_lo, w_hi in ((th0, th_turn, w0, w_turn), (th_turn, th1, w_turn, w1)):
        e_lo, e_hi = _log_g(w_lo, b, g), _log_g(w_hi, b, g)
        up = e_lo >= e_hi
        w_top, w_end = np.where(up, w_lo, w_hi), np.where(up, w_hi, w_lo)
        e_top, e_end = np.where(up, e_lo, e_hi), np.where(up, e_hi, e_lo)
        th_top, th_end = np.where(up, lo, hi), np.where(up, hi, lo)
        # on this side cos θ is monotone: θ = kπ ± acos(B/ρ)
        k = np.floor(0.5 * (lo + hi) / np.pi)
        odd = np.mod(k, 2.0) == 1.0
        bt = rho * np.cos(th_top)
        bound = w_top
        for level in levels:
            reached = e_end < e_top - level
            bt = np.where(reached, bt, 0.0)
            bt[reached] = _h_inverse(e_top[reached] + 0.5 * rho[reached] ** 2 - level,
                                     bt[reached])
            ac = np.arccos(np.clip(bt / np.where(rho > 0, rho, 1.0), -1.0, 1.0))
            th = np.clip(np.where(odd, (k + 1.0) * np.pi - ac, k * np.pi + ac),
                         np.minimum(th_top, th_end), np.maximum(th_top, th_end))
            w = np.where(reached, np.arcsinh(np.tan(th - phi)), w_end)
            w = np.where(w_end >= w_top, np.clip(w, bound, w_end), np.clip(w, w_end, bound))
            tops.append(bound)
            ends.append(w)
            bound = w
    return np.stack(tops, axis=-1), np.stack(ends, axis=-1)


def _nodes(b, g, r0, r1, easy, rule):
    """Quadrature of ``∫ exp(log_g(w)) dw`` over ``[asinh r0, asinh r1]`` for flat arrays of
    cells: ``(cell, w, log_weight)`` with each cell's nodes contiguous."""
    ie, ih = np.flatnonzero(easy), np.flatnonzero(~easy)
    x, wt = _gauss_legendre(rule.easy_nodes)
    w0, w1 = np.arcsinh(r0[ie]), np.arcsinh(r1[ie])
    half = 0.5 * (w1 - w0)[:, None]
    w_easy = (0.5 * (w0 + w1))[:, None] + half * x
    lw_easy = _log_g(w_easy, b[ie, None], g[ie, None]) + np.log(half * wt)
    top, end = _pieces(b[ih], g[ih], r0[ih], r1[ih], rule.levels)
    cell = np.repeat(ih, top.shape[-1])
    top, end = top.ravel(), end.ravel()
    length = np.abs(end - top)
    bp, gp = b[cell], g[cell]
    delta = np.maximum(np.minimum(length, 1.0 / np.maximum(np.abs(_dlog_g(top, bp, gp)),
                                                           1e-300)), 1e-300)
    y_max = np.arcsinh(length / delta)
    parts = np.where(length > 0, np.maximum(np.ceil(length / rule.part_w),
                                            np.ceil(y_max / rule.part_y)), 0).astype(int)
    piece = np.repeat(np.arange(top.size), parts)
    step = (y_max / np.maximum(parts, 1))[piece]
    first = (np.arange(piece.size) - np.repeat(np.cumsum(parts) - parts, parts)) * step
    x, wt = _gauss_legendre(rule.part_nodes)
    y = first[:, None] + 0.5 * step[:, None] * (x + 1.0)
    d = delta[piece, None]
    w_hard = top[piece, None] + np.sign(end - top)[piece, None] * d * np.sinh(y)
    cell = cell[piece]
    lw_hard = (_log_g(w_hard, b[cell, None], g[cell, None])
               + np.log(0.5 * step[:, None] * wt * d * np.cosh(y)))
    return (np.r_[np.repeat(ie, rule.easy_nodes), np.repeat(cell, rule.part_nodes)],
            np.r_[w_easy.ravel(), w_hard.ravel()], np.r_[lw_easy.ravel(), lw_hard.ravel()])


def _segment_logsumexp(idx, v, size):
    """logsumexp of ``v`` over each run of equal ``idx`` into ``size`` slots (each index's
    values one contiguous run)."""
    out = np.full(size, -np.inf)
    if idx.size == 0:
        return out
    start = np.flatnonzero(np.r_[True, idx[1:] != idx[:-1]])
    m = np.maximum.reduceat(v, start)
    out[idx[start]] = m + np.log(np.add.reduceat(np.exp(v - np.repeat(m, np.diff(
        np.r_[start, idx.size]))), start))
    return out


@dataclass
class _Check:
    """The evidence at one check: per cell (onset in ``[t_ref − width, t_ref)``), thruster,
    torque component and fraction scale (axes ``(cells, m, torques, scales)``), the Gram terms of
    the leak's columns ``P = F Q[:, k] (t − t_ref)₊`` and ``O = F Q[:, k] 1(t ≥ t_ref)`` and their
    scores, nuisances integrated; ``log_prior`` the torque components' posterior weights under
    no leak; ``rule`` the onset quadrature."""

    t_ref: np.ndarray
    width: np.ndarray
    t_c: float
    log_prior: np.ndarray
    a_pp: np.ndarray
    a_po: np.ndarray
    a_oo: np.ndarray
    z_p: np.ndarray
    z_o: np.ndarray
    rule: _Rule = _RULE

    def __post_init__(self):
        s = FRACTION_SCALES
        self.shift = self.a_po / self.a_oo               # s; onset offset of the D-P decoupling
        prec = np.maximum(self.a_pp - self.a_po * self.shift, 0.0) + 1.0 / s ** 2
        self.b = (self.z_p - self.shift * self.z_o) / np.sqrt(prec)
        self.g = -self.z_o / np.sqrt(self.a_oo)
        self.scale = np.sqrt(self.a_oo / prec)           # r = scale × (d + shift), 1/s
        self.r0 = self.scale * self.shift
        self.r1 = self.scale * (self.width[:, None, None, None] + self.shift)
        self.const = (self.log_prior[:, None] - np.log(self.t_c) - 0.5 * np.log(self.a_oo)
                      + np.log(2.0) - np.log(s) + 0.5 * (self.b ** 2 + self.g ** 2))
        w0, w1 = np.arcsinh(self.r0), np.arcsinh(self.r1)
        e0, e1 = _log_g(w0, self.b, self.g), _log_g(w1, self.b, self.g)
        ws = np.arcsinh(-self.g / np.where(self.b != 0, self.b, np.inf))
        inside = (self.b != 0) & (ws > w0) & (ws < w1)
        rho = np.hypot(self.b, self.g)
        top = np.maximum(np.maximum(e0, e1), np.where(inside & (self.b > 0), log_ndtr(rho),
                                                      -np.inf))
        low = np.minimum(np.minimum(e0, e1), np.where(inside & (self.b < 0), log_ndtr(-rho),
                                                      np.inf))
        self.easy = (top - low <= self.rule.easy_nats) & (w1 - w0 <= self.rule.easy_span)
        upper = self.const + top + np.log(np.maximum(w1 - w0, 1e-300))
        # every easy cell, and per thruster the hard cell of largest bound, exactly; then the
        # hard cells within rule.prune_nats of that thruster's evidence
        self.log_bf = np.full(self.const.shape, -np.inf)
        m = self.const.shape[1]
        hard = np.moveaxis(np.where(self.easy, -np.inf, upper), 1, 0).reshape(m, -1)
        first = np.zeros(hard.shape, bool)
        top_k = np.argmax(hard, axis=1)
        first[np.arange(m), top_k] = np.isfinite(hard[np.arange(m), top_k])
        first = np.moveaxis(first.reshape(np.moveaxis(upper, 1, 0).shape), 0, 1)
        self._integrate(self.easy | first)
        bound = (logsumexp(self.log_bf, axis=(0, 2, 3)) - self.rule.prune_nats
                 - np.log(upper.size))
        keep = ~self.easy & ~first & (upper >= bound[None, :, None, None])
        self._integrate(keep)

    def _integrate(self, sel):
        idx = np.flatnonzero(sel)
        cell, _, lw = self._nodes(idx)
        self.log_bf.flat[idx] = self.const.ravel()[idx] + _segment_logsumexp(cell, lw, idx.size)

    def _nodes(self, idx):
        """Quadrature nodes ``(i, w, log_weight)`` of the flat entries ``idx`` (``i`` indexes
        ``idx``; each entry's nodes contiguous)."""
        f = (lambda a: np.broadcast_to(a, self.const.shape).ravel()[idx])
        return _nodes(f(self.b), f(self.g), f(self.r0), f(self.r1), f(self.easy), self.rule)

    def log_evidence(self) -> np.ndarray:
        """(m,) log Bayes factor of each thruster's leak against none (onset uniform over the
        data seen, fraction scales equally weighted)."""
        return logsumexp(self.log_bf, axis=(0, 2, 3)) - np.log(FRACTION_SCALES.size)

    def mixture(self, k: int):
        """Thruster ``k``'s posterior of (onset, fraction) as a mixture over quadrature nodes:
        ``(weight, onset_s, mean, sd)``, the fraction given each onset a normal ``(mean, sd)``
        cut at 0 (weights normalised)."""
        sel = np.zeros(self.const.shape, bool)
        sel[:, k] = np.isfinite(self.log_bf[:, k])
        idx = np.flatnonzero(sel)
        i, w, lw = self._nodes(idx)
        f = (lambda a: np.broadcast_to(a, self.const.shape).ravel()[idx[i]])
        lw = lw + f(self.const)
        d = np.sinh(w) / f(self.scale) - f(self.shift)          # onset before t_ref, s
        s = f(np.broadcast_to(FRACTION_SCALES, self.const.shape))
        z = f(self.z_p) + d * f(self.z_o)
        prec = 1.0 / s ** 2 + np.maximum(f(self.a_pp) + d * (2.0 * f(self.a_po)
                                                             + d * f(self.a_oo)), 0.0)
        onset = f(np.broadcast_to(self.t_ref[:, None, None, None], self.const.shape)) - d
        return np.exp(lw - logsumexp(lw)), onset, z / prec, 1.0 / np.sqrt(prec)


    def onset_cdf(self, k: int, t_s: float) -> float:
        """Thruster ``k``'s posterior probability that its onset is before ``t_s`` (s from the
        stretch's first row)."""
        l = int(np.searchsorted(self.t_ref, t_s, side="right"))   # the cell holding t_s
        total = logsumexp(self.log_bf[:, k])
        parts = [logsumexp(self.log_bf[:l, k])] if l else []
        if l < self.t_ref.size:
            d = max(self.t_ref[l] - t_s, 0.0)
            f = (lambda a: np.broadcast_to(a, self.const.shape)[l, k].ravel())
            r = f(self.scale) * (d + f(self.shift))
            i, _, lw = _nodes(f(self.b), f(self.g), r, f(self.r1), np.zeros(r.size, bool),
                              self.rule)
            parts.append(logsumexp(f(self.const) + _segment_logsumexp(i, lw, r.size)))
        return float(np.exp(logsumexp(parts) - total)) if parts else 0.0


def _fraction(weight, mean, sd):
    """Mean, sd and the 5 % and 95 % quantiles of a mixture of normals cut at 0."""
    a = mean / sd
    ratio = np.exp(-0.5 * a * a - _LOG_SQRT_2PI - log_ndtr(a))   # φ(a) / Φ(a)
    m1 = mean + sd * ratio
    var = sd * sd * (1.0 - ratio * (a + ratio))
    mu = float(np.sum(weight * m1))
    sig = float(np.sqrt(max(np.sum(weight * (var + m1 * m1)) - mu * mu, 0.0)))
    keep = weight > 1e-12 * weight.max()
    wk, mk, sk = weight[keep] / weight[keep].sum(), mean[keep], sd[keep]
    log_mass = log_ndtr(mk / sk)

    def upper(x, p):        # P(f > x) − p
        return float(np.sum(wk * np.exp(log_ndtr((mk - x) / sk) - log_mass))) - p

    lo, hi = 0.0, float(np.max(mk + 10.0 * sk))
    q = [optimize.brentq(upper, lo, hi, args=(p,), xtol=1e-14, rtol=1e-10)
         for p in (0.95, 0.05)]
    return mu, sig, q[0], q[1]


def _thinned(inp: LeakInputs, step_s: float) -> LeakInputs:
    """The rows nearest a grid every ``step_s`` (and the last one)."""
    t = inp.t
    idx = np.unique(np.r_[np.searchsorted(t, np.arange(t[0], t[-1], step_s)), t.size - 1])
    return dataclasses.replace(inp, t=t[idx], residual=inp.residual[idx], impulse=inp.impulse[idx])


def leak_posterior(inp: LeakInputs, *, prior_leak: float = 0.01, eta: float = ETA,
                   sample_step_s: float = SAMPLE_STEP_S, check_step_s: float = 60.0,
                   p_detect: float = 0.99, _rule: _Rule = _RULE) -> LeakPosterior:
    """Run the Bayesian monitor over a stretch, as it would run on board: the residual taken
    every ``sample_step_s`` (:data:`SAMPLE_STEP_S`); a check every ``check_step_s`` (and at the
    last sample) sees only the data up to it, the onset uniform over that part of the stretch;
    ``prior_leak``: prior probability of a leak in the stretch, split evenly over the ``m``
    thrusters. Detection: the first check with
    ``P(leak) ≥ p_detect``; isolation: the first with one thruster's ``P ≥ p_detect`` (that
    thruster is the answer). ``_rule``: the onset quadrature (a finer one measures its error)."""
    for name, flag, v in (("prior_leak", "--prior-leak", prior_leak),
                          ("p_detect", "--p-detect", p_detect)):
        if not 0.0 < v < 1.0:
            raise InputError(f"must lie strictly between 0 and 1, got {v}",
                             path=spelled(flag, name))
    for name, flag, v in (("sample_step_s", "--sample-step", sample_step_s),
                          ("check_step_s", "--check-step", check_step_s)):
        if not v > 0:
            raise InputError(f"must be positive seconds, got {v}", path=spelled(flag, name))
        span = float(inp.t[-1] - inp.t[0])
        if span / v > MAX_GRID:  # the cells × checks table grows as the square
            raise InputError(f"{v:g} s makes {span / v:.3g} steps over the {span:.6g} s "
                             f"stretch, more than {MAX_GRID}; use at least "
                             f"{span / MAX_GRID:.3g} s", path=spelled(flag, name))
    raw, inp = inp, _thinned(inp, sample_step_s)
    n = inp.t.size
    if n < 3:
        raise InputError(f"has {n} rows {sample_step_s:g} s apart; the leak monitor needs at "
                         "least 3", path=inp.source)
    sums = _Sums(inp, eta, raw)
    t, m = sums.t, len(inp.thruster_names)
    checks = np.unique(np.r_[np.searchsorted(t, np.arange(check_step_s, t[-1], check_step_s)),
                             n - 1])
    checks = checks[checks >= 2]
    prob, det, iso = [], None, None
    for i, c in enumerate(checks):
        ev = sums.check(c, _rule)
        log_post = np.r_[np.log1p(-prior_leak), np.log(prior_leak / m) + ev.log_evidence()]
        prob.append(np.exp(log_post - logsumexp(log_post)))
        if det is None and 1.0 - prob[-1][0] >= p_detect:
            det = i
        if iso is None and prob[-1][1:].max() >= p_detect:
            iso = i
    prob = np.array(prob)
    # the fraction and onset of the most probable thruster, from all the data (the last check)
    k = int(np.argmax(prob[iso if iso is not None else -1][1:]))
    weight, onset, mean, sd = ev.mixture(k)
    fm, fs, f05, f95 = _fraction(weight, mean, sd)
    om = float(np.sum(weight * onset))
    t_check = inp.t[checks]
    return LeakPosterior(
        t_check=t_check, prob=prob, p_detect=p_detect,
        detection_time_s=None if det is None else float(t_check[det]),
        isolation_time_s=None if iso is None else float(t_check[iso]),
        thruster=None if iso is None else inp.thruster_names[k],
        fraction_mean=fm, fraction_sd=fs, fraction_interval=(f05, f95),
        torque_nm=fm * sums.u[:, k], onset_s=float(inp.t[0] + om),
        onset_sd_s=float(np.sqrt(max(np.sum(weight * (onset - om) ** 2), 0.0))),
        noise_sd_nms=sums.noise_sd(n - 1), hypotheses=inp.hypotheses)
