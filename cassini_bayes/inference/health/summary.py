"""One biasing event reduced to a Gaussian summary of its identifiable log thrusts.

The integrated Euler equation of a wheel-biasing event, ``V(t_i) = Q J(t_i) F`` (Feldman & Lee
2006 Eq 17, ``V = I Δω + ΔH_RWA + ΔG``), is linear in the thrusts given the pulse time constants.
The summary regresses all three rows of ``V`` on the *channels*, the thrust combinations the
events' firings can tell apart, found from the events' impulse design (:func:`health_channels`),
nothing named by hand:

* thrusters whose per-newton impulse ``j_s(t)`` is the same in every event (they always fire
  together, as Cassini's Y pairs {Y1, Y3}, {Y2, Y4} do) form one channel, their mean thrust
  (Feldman & Lee Eq 21: fired together, only the pair's sum is in Eq 20); a thruster whose
  firings differ from every other's is a channel of its own (Eq 19: Cassini's ``Z1 … Z4``);
* a channel is named as the thrust fit's ``summary.json`` names it: ``F[Z1]`` for one thruster,
  ``F_combination[0.5 F[Y1] + 0.5 F[Y3]]`` for a mean
  (:func:`~cassini_bayes.estimators.thrust.combination_label`);
* the split within a channel, its members' thrusts less their mean, moves the torque only through
  the members' different moment arms (for Cassini's Y pairs the X torque ``L (F_Y1 − F_Y3) J``
  that Eq 18 drops). It enters the regression as nuisance columns, one per direction of the
  members' torques beyond their sum's (without them a 3 % split biases Cassini's Z channels by
  ~10 %), and is never reported: it rests on the moment arms alone.

Every channel that fired is in the regression (leaving one out would hand its torque to the
others); a channel with fewer than ``min_pulses`` pulses is not *reported* (its estimate is NaN):
a biasing event fires the thrusters its wheel torques call for, a few pulses say little.

Errors. Weighted least squares (each axis weighted by its residual level), covariance by the
Newey-West (1987) heteroskedasticity- and autocorrelation-consistent estimator with Bartlett
weights: the residual of the cumulative regression is serially correlated (the gyroscopic term
``ΔG`` is an integral of noisy rates; time-tag jitter shifts whole pulses), which the plain
least-squares covariance ignores. Two per-event errors the residual cannot show are propagated
through the estimator's exact sensitivities: the pulse time constants of this event differing
from the model's by ``tau_sd_frac`` (each, independently; an event of short pulses is far more
sensitive than one of long pulses) and each wheel's spin inertia by the model's
``[wheel_knowledge] inertia_sd_frac`` (their effect depends on the event's wheel speeds). Errors
shared by every event (the spacecraft inertia, a common wheel-inertia scale, a time-constant error)
scale every event's thrust alike; they are not in this covariance — the health model absorbs them in
its baseline, which cancels in a ratio to the first calibration. The time constants are the
spacecraft model's (shared by all events).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import jax
import numpy as np

from cassini_bayes.errors import InputError
from cassini_bayes.estimators.baseline import wheel_momentum
from cassini_bayes.estimators.leak import (rate_step_columns, rate_step_second_order,
                                           rate_step_units)
from cassini_bayes.estimators.thrust import combination_label, regression_inputs
from cassini_bayes.physics.impulse import impulse_from_pulses, impulse_lhs
from cassini_bayes.telemetry import pulses_in_span

if TYPE_CHECKING:
    from cassini_bayes.spacecraft import Spacecraft
    from cassini_bayes.telemetry import PulseLog, Telemetry

__all__ = ["HealthChannels", "health_channels", "event_channels", "EventSummary",
           "EventDesign", "event_summary", "event_design", "channel_design", "weighted_fit",
           "residual_cov", "newey_west_lags", "left_out_channels"]

MIN_PULSES = 3
_SAME_RTOL = 1e-9
"""Two thrusters fire together in an event when their per-newton impulses agree to this share of
the larger's peak (identical pulse commands give identical impulses to rounding)."""
_RANK_RTOL = 1e-9
"""Torque directions below this share of the largest moment arm are none (a zero split column)."""


@dataclass(frozen=True)
class HealthChannels:
    """The thrust channels of a set of events (module docstring).

    thrusters : the model's thruster names (M). groups : per channel the indices of the thrusters
    whose mean thrust it is (in order of their first thruster). names : per channel its name in
    ``summary.json`` (``F[<name>]``, or ``F_combination[<label>]`` for a mean of several).
    not_fired : thrusters that fire in no event (in no channel).
    """

    thrusters: tuple[str, ...]
    groups: tuple[tuple[int, ...], ...]
    names: tuple[str, ...]
    not_fired: tuple[str, ...] = ()

    def __len__(self) -> int:
        return len(self.groups)

    @property
    def weights(self) -> np.ndarray:
        """(K, M): each channel's thrust as weights of the thrusts (N per N): ``1/g`` on its
        ``g`` members."""
        w = np.zeros((len(self.groups), len(self.thrusters)))
        for k, g in enumerate(self.groups):
            w[k, list(g)] = 1.0 / len(g)
        return w

    def columns(self, q_matrix: np.ndarray) -> list[list[tuple[int, np.ndarray]]]:
        """The regression's columns as ``[(thruster, torque per newton (3,)), …]`` each: the
        channels' sums ``Σ_s Q[:, s] j_s`` first, then each channel's split directions. A
        channel of ``g`` members with ``g`` independent torques gets ``Q_a j_a − Q_b j_b`` per
        other member ``b`` (``F_a = m + Σ s_b``, ``F_b = m − s_b``: ``m`` the mean); otherwise
        an orthogonal basis of its members' torques beyond their sum's."""
        q = np.asarray(q_matrix, float)
        scale = max(float(np.max(np.linalg.norm(q, axis=0), initial=0.0)), 1e-300)
        cols = [[(s, q[:, s]) for s in g] for g in self.groups]
        for g in self.groups:
            if len(g) < 2:
                continue
            qg = q[:, list(g)]
            sv = np.linalg.svd(qg, compute_uv=False)
            rank = int(np.sum(sv > _RANK_RTOL * scale))
            if rank == len(g):
                cols += [[(g[0], qg[:, 0]), (b, -q[:, b])] for b in g[1:]]
                continue
            tot = qg.sum(axis=1)
            u = tot / np.linalg.norm(tot)
            rest = qg - np.outer(u, u @ qg)
            ur, sr, _ = np.linalg.svd(rest)
            cols += [[(g[0], ur[:, i] * sr[i])] for i in range(rank - 1)
                     if sr[i] > _RANK_RTOL * scale]
        return cols


def health_channels(impulses: Sequence[np.ndarray], thrusters: Sequence[str],
                    q_matrix: np.ndarray) -> HealthChannels:
    """The channels of events whose per-newton impulses are ``impulses`` ((n_e, M) s each, as
    :func:`~cassini_bayes.estimators.thrust.regression_inputs` gives them): thrusters with the
    same impulse in every event share a channel (module docstring); thrusters that never fire
    are in none. Raises :class:`InputError` for a channel whose members' torques cancel (their
    mean moves nothing)."""
    js = [np.asarray(j, float) for j in impulses]
    names = tuple(thrusters)
    m = len(names)
    fired = np.zeros(m, bool)
    for j in js:
        fired |= np.any(j != 0.0, axis=0)
    groups: list[list[int]] = []
    for s in np.flatnonzero(fired):
        for g in groups:
            a = g[0]
            if all(np.allclose(j[:, s], j[:, a], rtol=0.0,
                               atol=_SAME_RTOL * max(np.max(np.abs(j[:, [a, s]])), 1e-300))
                   for j in js):
                g.append(int(s))
                break
        else:
            groups.append([int(s)])
    q = np.asarray(q_matrix, float)
    scale = max(float(np.max(np.linalg.norm(q, axis=0), initial=0.0)), 1e-300)
    out_names = []
    for g in groups:
        if np.linalg.norm(q[:, g].sum(axis=1)) <= _RANK_RTOL * scale:
            raise InputError(f"thrusters {', '.join(names[s] for s in g)} always fire together "
                             "and their torques cancel: no event tells their thrust; a health "
                             "fit needs events that fire them apart", path="events")
        w = np.zeros(m)
        w[g] = 1.0 / len(g)
        out_names.append(f"F[{names[g[0]]}]" if len(g) == 1 else
                         f"F_combination[{combination_label(w, names)}]")
    return HealthChannels(names, tuple(tuple(g) for g in groups), tuple(out_names),
                          tuple(n for n, f in zip(names, fired) if not f))


def event_channels(events: Sequence[tuple[Telemetry, PulseLog]],
                   spacecraft: Spacecraft) -> HealthChannels:
    """:func:`health_channels` of ``events``, ``(telemetry, pulse log)`` pairs, under the
    spacecraft model (its time constants give the impulses)."""
    return health_channels([_inputs(tel, log, spacecraft)[1] for tel, log in events],
                           spacecraft.thruster_names, spacecraft.moment_matrix)


@dataclass(frozen=True)
class EventSummary:
    """Gaussian summary of one event.

    log_thrust : (K,) log of the channels' thrust estimates (log N); NaN where the event does not
        identify the channel. cov : (K, K) covariance of ``log_thrust`` (NaN rows/columns for the
        missing channels). thrust_n : (K,) the estimates, N. n_pulses : (K,) pulses per channel.
    residual_rms_nms : (3,) rms residual per axis, N m s. channels : the
    :class:`HealthChannels` (K).
    """

    log_thrust: np.ndarray
    cov: np.ndarray
    thrust_n: np.ndarray
    n_pulses: np.ndarray
    residual_rms_nms: np.ndarray
    channels: HealthChannels

    @property
    def observed(self) -> np.ndarray:
        """(K,) bool: the channels this event identifies."""
        return np.isfinite(self.log_thrust)


def channel_design(j: np.ndarray, q_matrix: np.ndarray, channels: HealthChannels,
                   steps: np.ndarray | None = None) -> np.ndarray:
    """``(n, 3, P)``: the angular impulse per newton (N m s per N) of each regression column
    (:meth:`HealthChannels.columns`: each channel's ``Σ_s Q[:, s] J_s(t)`` over its members,
    then the split directions); ``j`` (n, M) per-newton impulses (s). ``steps`` (n, 3, M, 3):
    the trapezoidal ``ΔG``'s error across the pulses' rate steps per newton and per metre of arm
    (:func:`~cassini_bayes.estimators.leak.rate_step_columns`), taken off each column: Eq 17's
    left side misses ``Σ_s F_s steps[:, :, s] @ q_s``, linear in the thrusts, so the
    regression carries it on its columns rather than at a guessed thrust."""
    cols = [sum(vec[None, :] * j[:, s:s + 1]
                - (0.0 if steps is None else steps[:, :, s] @ vec) for s, vec in col)
            for col in channels.columns(q_matrix)]
    return np.stack(cols, axis=-1)


def _newey_west(x: np.ndarray, e: np.ndarray, lags: int) -> np.ndarray:
    """``Σ_l w_l Σ_t (s_t s_{t−l}ᵀ + s_{t−l} s_tᵀ)``, ``s_t = X_tᵀ e_t``; Bartlett weights."""
    s = np.einsum("tap,ta->tp", x, e)
    meat = s.T @ s
    for lag in range(1, lags + 1):
        g = s[lag:].T @ s[:-lag]
        meat += (1.0 - lag / (lags + 1.0)) * (g + g.T)
    return meat


TAU_SD_FRAC = 0.05
"""Assumed event-to-event variation of each pulse time constant (fraction, one sd): an
engineering value (valve temperature and feed pressure differ between events), not a paper's."""


_impulse = jax.jit(impulse_from_pulses, static_argnames="n_thrusters")
_lhs = jax.jit(impulse_lhs)
_PAD = 128


def _padded(log, t_end: float):
    """The pulse log padded to a multiple of ``_PAD`` pulses with empty pulses after the end
    (one compilation per size class, not per event)."""
    t_on, thr, width = (np.asarray(a) for a in log)
    extra = -t_on.size % _PAD
    return (np.r_[t_on, np.full(extra, t_end + 1e3)], np.r_[thr, np.zeros(extra, thr.dtype)],
            np.r_[width, np.zeros(extra)])


def _sensitivities(tel, des: EventDesign, sc, tau_sd_frac, f, xw, w_fit, a_inv):
    """One-sd changes of the weighted least-squares estimate (p,) for each time constant off by
    ``tau_sd_frac`` and each wheel's spin inertia off by its ``inertia_sd_frac``: the change of
    ``f = A⁻¹ Xᵀ W v`` at the fit's own weights ``w_fit`` (the weights of its last pass), the
    rate-step columns moved with them (the areas with ``τ``, the wheel momentum they turn)."""
    from cassini_bayes.estimators.baseline import wheel_geometry

    sw = np.sqrt(w_fit)[None, :, None]
    t = np.asarray(tel.t, float)
    omega = np.asarray(tel.omega, float)
    tau, q, channels, fired = des.tau, des.q, des.channels, des.fired
    log = _padded(des.log, t[-1])
    m = len(channels.thrusters)
    out = []
    for i in range(3):
        if tau_sd_frac <= 0 or tau[i] <= 0:
            continue
        tp = tau.copy()
        tp[i] *= 1.0 + tau_sd_frac
        jp = np.asarray(_impulse(t, *log, *tp, n_thrusters=m))
        cp = rate_step_columns(t, omega, sc.inertia, des.h, log, tp, m, des.units)
        dx = channel_design(jp, q, channels, cp)[:, :, fired] * sw - xw   # weighted change
        out.append(-a_inv @ np.einsum("tap,taq,q->p", xw, dx, f))
    axes, inertias = wheel_geometry(tel, sc)
    rates = np.nan_to_num(np.asarray(tel.wheel_rates, float))
    hs, dvs = [], []
    for k, name in enumerate(tel.wheel_names):
        sd = sc.wheel(name).inertia_sd_frac or sc.knowledge.wheel_inertia_sd_frac
        if not np.any(rates[:, k]) or not sd:
            continue
        hs.append(np.outer(rates[:, k] * inertias[k] * sd, axes[k]))   # its momentum × sd
        dvs.append(np.asarray(_lhs(t, omega, np.zeros((3, 3)), hs[-1])) * np.sqrt(w_fit)[None, :])
    if hs:
        # the rate-step units are affine in the wheel momentum: each wheel's change is its
        # units less those of no wheel momentum
        units = rate_step_units(t, omega, sc.inertia, np.stack(hs + [np.zeros_like(hs[0])]))
        for dv, du in zip(dvs, units[:-1] - units[-1]):
            dc = rate_step_columns(t, omega, sc.inertia, None, log, tau, m, du)
            dx = channel_design(np.zeros_like(des.j), q, channels, dc)[:, :, fired] * sw
            out.append(a_inv @ (np.einsum("tap,ta->p", xw, dv)
                                - np.einsum("tap,taq,q->p", xw, dx, f)))
    return out


class EventDesign(NamedTuple):
    """The regression of one event (Feldman & Lee Eq 17): ``v`` (n, 3) N m s, the per-newton
    impulses ``j`` (n, M) s, the design ``x`` (n, 3, p) of the fired columns (channels, then
    splits, each less its rate steps' share of ``ΔG``: :func:`channel_design`), ``fired`` (P,)
    bool over all the columns, ``n_pulses`` (K,), the moment matrix ``q`` (3, M) m, the pulse
    ``log`` arrays, the time constants ``tau`` (3,) s, the
    ``channels``, the wheel momentum ``h`` (n, 3) N m s and the rate-step ``units``
    (:func:`~cassini_bayes.estimators.leak.rate_step_units`)."""

    v: np.ndarray
    j: np.ndarray
    x: np.ndarray
    fired: np.ndarray
    n_pulses: np.ndarray
    q: np.ndarray
    log: tuple
    tau: np.ndarray
    channels: HealthChannels
    h: np.ndarray
    units: np.ndarray


def _inputs(tel, pulses, spacecraft):
    """``(v, j, log, tau, h)`` of one event (Feldman & Lee Eq 17 with the pulse response at the
    model's time constants; ``h`` the wheel momentum, N m s); pulses acting entirely outside the
    telemetry are left out with a warning (:func:`~cassini_bayes.telemetry.pulses_in_span`)."""
    if pulses is not None:
        p = spacecraft.pulse   # (its thrust is negligible 40 fall times after the command)
        pulses = pulses_in_span(pulses, tel, tail_s=p.tau_delay + 40.0 * p.tau_fall)
    if pulses is None or np.asarray(pulses.t_on).size == 0:
        raise InputError("has no thruster pulses; a thrust-health event needs the pulse log of a "
                         "biasing event", path=getattr(tel, "source", "telemetry"))
    p = spacecraft.pulse
    log = (pulses.t_on, pulses.thruster, pulses.width)
    tau = np.array([p.tau_delay, p.tau_rise, p.tau_fall])
    h = np.asarray(wheel_momentum(tel, spacecraft), float)
    m = len(spacecraft.thrusters)
    v, j = regression_inputs(tel.t, tel.omega, h, spacecraft.inertia, pulses=log,
                             tau=tuple(tau), n_thrusters=m)
    return v, j, log, tau, h


def event_design(tel, pulses, spacecraft, *, channels: HealthChannels | None = None,
                 min_pulses: int = MIN_PULSES) -> EventDesign:
    """The regression inputs of one event under the spacecraft model (its inertia, wheels,
    thruster geometry and time constants); refuses an event that identifies no channel.

    ``v`` carries the rate steps' second-order terms at the model's thrusts
    (:func:`~cassini_bayes.estimators.leak.rate_step_second_order`) as a known offset: they
    are quadratic in the thrusts, which the linear design's columns cannot hold, and an event
    that moves the thrusts by ``δ`` moves them by a fraction ``~δ`` of a term that is itself
    second order.

    ``channels``: those of all the events fitted together (:func:`event_channels`); by default
    this event's own."""
    v, j, log, tau, h = _inputs(tel, pulses, spacecraft)
    # the rate steps at the model's inertia and time constants (channel_design); their second
    # order, quadratic in the thrusts, at the model's thrusts on the left side
    units = rate_step_units(tel.t, tel.omega, spacecraft.inertia, h)
    steps = rate_step_columns(tel.t, tel.omega, spacecraft.inertia, h,
                              _padded(log, float(np.asarray(tel.t)[-1])), tau,
                              len(spacecraft.thrusters), units)
    q = spacecraft.moment_matrix
    v = v + rate_step_second_order(tel.t, tel.omega, spacecraft.inertia, h, log, tau,
                                   q * spacecraft.thrust_per_thruster[None, :])
    if channels is None:
        channels = health_channels([j], spacecraft.thruster_names, q)
    counts = np.bincount(np.asarray(log[1], int), minlength=len(channels.thrusters))
    n_pulses = np.array([counts[list(g)].sum() for g in channels.groups])
    cols = channels.columns(q)
    owner = [next(k for k, g in enumerate(channels.groups) if col[0][0] in g) for col in cols]
    fired = n_pulses[owner] > 0                          # the channels, then the splits
    x = channel_design(j, q, channels, steps)[:, :, fired]
    n = v.shape[0]
    if not (n_pulses >= min_pulses).any() or 3 * n <= fired.sum() + 2:
        raise InputError(f"identifies no thrust channel (pulses per channel "
                         f"{dict(zip(channels.names, n_pulses.tolist()))}, {n} samples)",
                         path=getattr(tel, "source", "telemetry"))
    _check_rank(x, j, channels, n_pulses, getattr(tel, "source", "telemetry"))
    return EventDesign(v, j, x, fired, n_pulses, q, log, tau, channels, h, units)


_RANK_COND_MAX = 1e10
"""An event's design is rank-deficient when its column-scaled condition number exceeds this."""


def _check_rank(x: np.ndarray, j: np.ndarray, channels: HealthChannels, n_pulses: np.ndarray,
                source: str) -> None:
    """Refuse, in one line, an event whose fired columns are dependent: channels that the other
    events fire apart fire alike here, more of them than their torques' directions can tell
    apart (e.g. a whole thruster set of four with no other firing)."""
    a = np.einsum("tap,taq->pq", x, x)
    d = np.sqrt(np.diag(a))
    if np.all(d > 0) and np.linalg.cond(a / np.outer(d, d)) < _RANK_COND_MAX:
        return
    fired = [k for k in range(len(channels.groups)) if n_pulses[k] > 0]
    alike: list[list[int]] = []
    for k in fired:
        jk = j[:, channels.groups[k][0]]
        for g in alike:
            jg = j[:, channels.groups[g[0]][0]]
            if np.allclose(jk, jg, rtol=0.0, atol=_SAME_RTOL * max(np.max(np.abs(jg)), 1e-300)):
                g.append(k)
                break
        else:
            alike.append([k])
    named = "; ".join(", ".join(channels.names[k] for k in g) for g in alike if len(g) > 1)
    raise InputError(f"cannot tell its thrust channels apart ({named or 'their firings'} fire "
                     "alike in this event, apart in others); fit this event's health with "
                     "events that fire them alike too, or leave it out", path=source)


def weighted_fit(x: np.ndarray, v: np.ndarray, w: np.ndarray | None = None):
    """Least squares of ``v`` (n, 3) on ``x`` (n, 3, p), each axis weighted by its residual
    level: two passes from equal weights, the second weighted by the first's residual levels;
    or one pass with the given per-axis weights ``w`` (3,).

    Returns ``(f (p,), w (3,) the weights of the last pass, a (p, p) its weighted normal
    matrix, e (n, 3) residuals, rms (3,) their level per axis)``."""
    passes, w = (2, np.ones(3)) if w is None else (1, np.asarray(w, float))
    rms = np.ones(3)
    for i in range(passes):
        if i:
            w = 1.0 / np.maximum(rms, 1e-12) ** 2
        xw = x * np.sqrt(w)[None, :, None]
        a = np.einsum("tap,taq->pq", xw, xw)
        f = np.linalg.solve(a, np.einsum("tap,ta->p", xw, v * np.sqrt(w)[None, :]))
        e = v - np.einsum("tap,p->ta", x, f)
        rms = np.sqrt(np.mean(e * e, axis=0))
    return f, w, a, e, rms


def residual_cov(x: np.ndarray, e: np.ndarray, w_fit: np.ndarray, w: np.ndarray, a: np.ndarray,
                 lags: int) -> np.ndarray:
    """(p, p) Newey-West covariance of a weighted fit's estimate: design ``x`` (n, 3, p) and
    residuals ``e`` (n, 3) of the fit with per-axis weights ``w_fit`` and normal matrix ``a``;
    the scores weighted by ``w`` (the residual levels); scaled by ``n / (n − p)``."""
    n = e.shape[0]
    a_inv = np.linalg.inv(a)
    xw = x * np.sqrt(w_fit)[None, :, None]
    cov = a_inv @ _newey_west(xw, e * np.sqrt(w)[None, :], lags) @ a_inv
    return cov * (n / max(n - x.shape[-1], 1))


def newey_west_lags(n: int) -> int:
    """The Newey-West bandwidth (samples) of an event of ``n`` samples: ``⌈4 (n/100)^{2/9}⌉ · 3``,
    three times the usual rule (the cumulative regression's residuals are long-correlated)."""
    return int(np.ceil(4.0 * (n / 100.0) ** (2.0 / 9.0))) * 3


def event_summary(tel, pulses, spacecraft, *, channels: HealthChannels | None = None,
                  min_pulses: int = MIN_PULSES, lags: int | None = None,
                  tau_sd_frac: float = TAU_SD_FRAC) -> EventSummary:
    """Summary of one event from its telemetry, pulse log and the spacecraft model.

    ``channels``: those of all the events fitted together (:func:`event_channels`); by default
    this event's own. ``lags``: Newey-West bandwidth in samples (default
    :func:`newey_west_lags`). ``tau_sd_frac``: per-event variation of the time constants
    propagated into the covariance. A channel that fired but is not reported (fewer than
    ``min_pulses`` pulses, or a thrust estimate that is not positive) is NaN in ``log_thrust``
    with a finite ``thrust_n`` (:func:`left_out_channels` says so for a fit).
    """
    des = event_design(tel, pulses, spacecraft, channels=channels, min_pulses=min_pulses)
    v, x, fired, n_pulses, ch = des.v, des.x, des.fired, des.n_pulses, des.channels
    k_ch = len(ch)
    n = v.shape[0]
    lags = newey_west_lags(n) if lags is None else int(lags)
    f, w_fit, a, e, rms = weighted_fit(x, v)
    xw = x * np.sqrt(w_fit)[None, :, None]
    w = 1.0 / np.maximum(rms, 1e-12) ** 2
    a_inv = np.linalg.inv(a)
    cov_f = residual_cov(x, e, w_fit, w, a, lags)
    for g in _sensitivities(tel, des, spacecraft, tau_sd_frac, f, xw, w_fit, a_inv):
        cov_f += np.outer(g, g)
    idx = np.flatnonzero(fired[:k_ch])
    f, cov_f = f[:idx.size], cov_f[:idx.size, :idx.size]    # the splits are nuisance
    thrust = np.full(k_ch, np.nan)
    thrust[idx] = f
    keep = (n_pulses[idx] >= min_pulses) & (f > 0)         # reported channels, among the fired
    log_thrust = np.full(k_ch, np.nan)
    log_thrust[idx[keep]] = np.log(f[keep])
    jac = 1.0 / np.abs(f)
    c_log = cov_f * np.outer(jac, jac)
    cov = np.full((k_ch, k_ch), np.nan)
    cov[np.ix_(idx[keep], idx[keep])] = c_log[np.ix_(keep, keep)]
    return EventSummary(log_thrust, cov, thrust, n_pulses, rms, ch)


def left_out_channels(summaries, dates_days) -> list[str]:
    """One warning line per channel that fired in some events but is left out of some of them
    (fewer than ``min_pulses`` pulses, or a thrust estimate that is not positive): those pulses
    are measured and not used, and a fit must say so (one line per channel, the events named by
    their dates in days)."""
    lines = []
    if not summaries:
        return lines
    for k, name in enumerate(summaries[0].channels.names):
        fired = [s.n_pulses[k] > 0 for s in summaries]
        out = [d for s, d, f in zip(summaries, dates_days, fired) if f and not s.observed[k]]
        if out:
            days = ", ".join(f"{d:g}" for d in out[:5]) + (", …" if len(out) > 5 else "")
            lines.append(f"channel {name} is left out of {len(out)} of the {sum(fired)} events in "
                         f"which it fired (fewer than {MIN_PULSES} pulses, or a thrust estimate "
                         f"that is not positive): days {days}")
    return lines
