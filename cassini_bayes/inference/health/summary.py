"""One biasing event reduced to a Gaussian summary of its identifiable log thrusts.

The integrated Euler equation of a wheel-biasing event, ``V(t_i) = Q J(t_i) F`` (Feldman & Lee
2006 Eq 17, ``V = I Δω + ΔH_RWA + ΔG``), is linear in the thrusts given the pulse time constants.
The summary regresses all three rows of ``V`` on six *channels*, the combinations an event can
identify:

* ``Z1 … Z4`` one each (Eq 19: their X/Y moment columns differ);
* ``Y13``, ``Y24`` the pair means ``(F_Y1 + F_Y3)/2``, ``(F_Y2 + F_Y4)/2`` (Eq 21): the Y
  thrusters fire in the pairs {Y1, Y3}, {Y2, Y4}, so Eq 20 has rank 2 and the split within a pair
  is not in Eq 20. The pair's X torque, ``L (F_Y1 − F_Y3) J`` (the X-row term Eq 18 drops,
  assuming equal thrusts), does carry the split: it enters the regression as a nuisance column
  per pair (without it a 3 % split biases the Z channels by ~10 %), and is never reported — it
  rests on the X moment arms of the Y thrusters alone.

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

from dataclasses import dataclass
from typing import NamedTuple

import jax
import numpy as np

from cassini_bayes.errors import InputError
from cassini_bayes.estimators.baseline import wheel_momentum
from cassini_bayes.estimators.thrust import regression_inputs
from cassini_bayes.physics.impulse import impulse_from_pulses, impulse_lhs
from cassini_bayes.telemetry import pulses_in_span

__all__ = ["CHANNELS", "CHANNEL_THRUSTERS", "EventSummary", "EventDesign", "event_summary",
           "event_design", "channel_design", "weighted_fit", "residual_cov", "newey_west_lags",
           "left_out_channels"]

CHANNELS = ("Z1", "Z2", "Z3", "Z4", "Y13", "Y24")
"""The identifiable thrust combinations of one event (Feldman & Lee Eqs 19 and 21)."""
CHANNEL_THRUSTERS = ((0,), (1,), (2,), (3,), (4, 6), (5, 7))
"""Thruster indices (``Z1 … Y4`` order) that share each channel's thrust."""
MIN_PULSES = 3


@dataclass(frozen=True)
class EventSummary:
    """Gaussian summary of one event.

    log_thrust : (6,) log of the channels' thrust estimates (log N); NaN where the event does not
        identify the channel. cov : (6, 6) covariance of ``log_thrust`` (NaN rows/columns for the
        missing channels). thrust_n : (6,) the estimates, N. n_pulses : (6,) pulses per channel.
    residual_rms_nms : (3,) rms residual per axis, N m s.
    """

    log_thrust: np.ndarray
    cov: np.ndarray
    thrust_n: np.ndarray
    n_pulses: np.ndarray
    residual_rms_nms: np.ndarray

    @property
    def observed(self) -> np.ndarray:
        """(6,) bool: the channels this event identifies."""
        return np.isfinite(self.log_thrust)


def channel_design(j: np.ndarray, q_matrix: np.ndarray) -> np.ndarray:
    """``(n, 3, 8)``: the angular impulse per newton (N m s per N) of each channel,
    ``Σ_s Q[:, s] J_s(t)`` over its thrusters, then of the two pair splits, ``Q[:, a] J_a −
    Q[:, b] J_b`` for ``(a, b) = (Y1, Y3), (Y2, Y4)`` (``F_a = m + s``, ``F_b = m − s``);
    ``j`` (n, 8) per-newton impulses (s)."""
    q = np.asarray(q_matrix)

    def col(s):
        return q[:, s][None, :] * j[:, s:s + 1]

    cols = [sum(col(s) for s in idx) for idx in CHANNEL_THRUSTERS]
    cols += [col(a) - col(b) for a, b in (CHANNEL_THRUSTERS[4], CHANNEL_THRUSTERS[5])]
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


_impulse = jax.jit(impulse_from_pulses)
_lhs = jax.jit(impulse_lhs)
_PAD = 128


def _padded(log, t_end: float):
    """The pulse log padded to a multiple of ``_PAD`` pulses with empty pulses after the end
    (one compilation per size class, not per event)."""
    t_on, thr, width = (np.asarray(a) for a in log)
    extra = -t_on.size % _PAD
    return (np.r_[t_on, np.full(extra, t_end + 1e3)], np.r_[thr, np.zeros(extra, thr.dtype)],
            np.r_[width, np.zeros(extra)])


def _sensitivities(tel, log, sc, tau, tau_sd_frac, q, fired, f, xw, w, a_inv):
    """One-sd changes of the weighted least-squares estimate (p,) for each time constant off by
    ``tau_sd_frac`` and each wheel's spin inertia off by its ``inertia_sd_frac``."""
    from cassini_bayes.estimators.baseline import wheel_geometry

    sw = np.sqrt(w)[None, :, None]
    t = np.asarray(tel.t, float)
    log = _padded(log, t[-1])
    out = []
    for i in range(3):
        if tau_sd_frac <= 0 or tau[i] <= 0:
            continue
        tp = tau.copy()
        tp[i] *= 1.0 + tau_sd_frac
        jp = np.asarray(_impulse(t, *log, *tp))
        dx = (channel_design(jp, q)[:, :, fired] - xw / sw) * sw      # weighted design change
        out.append(-a_inv @ np.einsum("tap,taq,q->p", xw, dx, f))
    axes, inertias = wheel_geometry(tel, sc)
    rates = np.nan_to_num(np.asarray(tel.wheel_rates, float))
    omega = np.asarray(tel.omega, float)
    for k, name in enumerate(tel.wheel_names):
        sd = sc.wheel(name).inertia_sd_frac or sc.knowledge.wheel_inertia_sd_frac
        if not np.any(rates[:, k]) or not sd:
            continue
        h = np.outer(rates[:, k] * inertias[k] * sd, axes[k])     # the wheel's momentum × sd
        dv = np.asarray(_lhs(t, omega, np.zeros((3, 3)), h)) * np.sqrt(w)[None, :]
        out.append(a_inv @ np.einsum("tap,ta->p", xw, dv))
    return out


class EventDesign(NamedTuple):
    """The regression of one event (Feldman & Lee Eq 17): ``v`` (n, 3) N m s, the per-newton
    impulses ``j`` (n, 8) s, the design ``x`` (n, 3, p) of the fired channels and pair splits,
    ``fired`` (8,) bool (channels, then splits), ``n_pulses`` (6,), the moment matrix ``q``
    (3, 8) m, the pulse ``log`` arrays and the time constants ``tau`` (3,) s."""

    v: np.ndarray
    j: np.ndarray
    x: np.ndarray
    fired: np.ndarray
    n_pulses: np.ndarray
    q: np.ndarray
    log: tuple
    tau: np.ndarray


def event_design(tel, pulses, spacecraft, *, min_pulses: int = MIN_PULSES) -> EventDesign:
    """The regression inputs of one event under the spacecraft model (its inertia, wheels,
    thruster geometry and time constants); refuses an event that identifies no channel.

    Pulses acting entirely outside the telemetry are left out with a warning
    (:func:`~cassini_bayes.telemetry.pulses_in_span`)."""
    if pulses is not None:
        p = spacecraft.pulse   # (its thrust is negligible 40 fall times after the command)
        pulses = pulses_in_span(pulses, tel, tail_s=p.tau_delay + 40.0 * p.tau_fall)
    if pulses is None or np.asarray(pulses.t_on).size == 0:
        raise InputError("has no thruster pulses; a thrust-health event needs the pulse log of a "
                         "biasing event", path=getattr(tel, "source", "telemetry"))
    p = spacecraft.pulse
    q = spacecraft.moment_matrix
    log = (pulses.t_on, pulses.thruster, pulses.width)
    tau = np.array([p.tau_delay, p.tau_rise, p.tau_fall])
    v, j = regression_inputs(tel.t, tel.omega, wheel_momentum(tel, spacecraft),
                             spacecraft.inertia, pulses=log, tau=tuple(tau))
    counts = np.bincount(np.asarray(pulses.thruster, int), minlength=8)
    n_pulses = np.array([counts[list(idx)].sum() for idx in CHANNEL_THRUSTERS])
    fired = np.r_[n_pulses, n_pulses[4:]] > 0              # the channels, then the splits
    x = channel_design(j, q)[:, :, fired]
    n = v.shape[0]
    if not (n_pulses >= min_pulses).any() or 3 * n <= fired.sum() + 2:
        raise InputError(f"identifies no thrust channel (pulses per channel "
                         f"{dict(zip(CHANNELS, n_pulses.tolist()))}, {n} samples)",
                         path=getattr(tel, "source", "telemetry"))
    return EventDesign(v, j, x, fired, n_pulses, q, log, tau)


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


def event_summary(tel, pulses, spacecraft, *, min_pulses: int = MIN_PULSES,
                  lags: int | None = None, tau_sd_frac: float = TAU_SD_FRAC) -> EventSummary:
    """Summary of one event from its telemetry, pulse log and the spacecraft model.

    ``lags``: Newey-West bandwidth in samples (default :func:`newey_west_lags`).
    ``tau_sd_frac``: per-event variation of the time constants propagated into the covariance.
    A channel that fired but is not reported (fewer than ``min_pulses`` pulses, or a thrust
    estimate that is not positive) is NaN in ``log_thrust`` with a finite ``thrust_n``
    (:func:`left_out_channels` says so for a fit).
    """
    des = event_design(tel, pulses, spacecraft, min_pulses=min_pulses)
    v, x, fired, n_pulses, q = des.v, des.x, des.fired, des.n_pulses, des.q
    n = v.shape[0]
    lags = newey_west_lags(n) if lags is None else int(lags)
    f, w_fit, a, e, rms = weighted_fit(x, v)
    xw = x * np.sqrt(w_fit)[None, :, None]
    w = 1.0 / np.maximum(rms, 1e-12) ** 2
    a_inv = np.linalg.inv(a)
    cov_f = residual_cov(x, e, w_fit, w, a, lags)
    for g in _sensitivities(tel, des.log, spacecraft, des.tau, tau_sd_frac, q, fired, f, xw, w,
                            a_inv):
        cov_f += np.outer(g, g)
    idx = np.flatnonzero(fired[:6])
    f, cov_f = f[:idx.size], cov_f[:idx.size, :idx.size]    # the splits are nuisance
    thrust = np.full(6, np.nan)
    thrust[idx] = f
    keep = (n_pulses[idx] >= min_pulses) & (f > 0)         # reported channels, among the fired
    log_thrust = np.full(6, np.nan)
    log_thrust[idx[keep]] = np.log(f[keep])
    jac = 1.0 / np.abs(f)
    c_log = cov_f * np.outer(jac, jac)
    cov = np.full((6, 6), np.nan)
    cov[np.ix_(idx[keep], idx[keep])] = c_log[np.ix_(keep, keep)]
    return EventSummary(log_thrust, cov, thrust, n_pulses, rms)


def left_out_channels(summaries, dates_days) -> list[str]:
    """One warning line per channel that fired in some events but is left out of some of them
    (fewer than ``min_pulses`` pulses, or a thrust estimate that is not positive): those pulses
    are measured and not used, and a fit must say so (one line per channel, the events named by
    their dates in days)."""
    lines = []
    for k, name in enumerate(CHANNELS):
        fired = [s.n_pulses[k] > 0 for s in summaries]
        out = [d for s, d, f in zip(summaries, dates_days, fired) if f and not s.observed[k]]
        if out:
            days = ", ".join(f"{d:g}" for d in out[:5]) + (", …" if len(out) > 5 else "")
            lines.append(f"channel {name} is left out of {len(out)} of the {sum(fired)} events in "
                         f"which it fired (fewer than {MIN_PULSES} pulses, or a thrust estimate "
                         f"that is not positive): days {days}")
    return lines
