"""Does a health fit's spacecraft model fit its events? Two self-checks that need no truth.

* ``inertia_conflict`` — each event's prior–data conflict. The integrated Euler equation
  (Feldman & Lee 2006 Eq 17, ``V = I Δω + ΔH_RWA + ΔG``) is linear in the inertia, so each event
  also measures the spacecraft's principal moments: refitting the event with three more columns,
  ``π_k ∂V/∂π_k`` (the moment ``k`` scaled), gives the thrusts the event implies with its *own*
  inertia. The health model fixes the inertia at the model file's and counts on its error being
  shared by all events (absorbed in each channel's baseline). The statistic is the change of
  each reported channel's thrust between the two fits, less its precision-weighted mean over the
  events (the shared part), in the sd the event supports with its own inertia: ``max_ek |Δ_ek −
  Δ̄_k| / s_ek``; ``parameter`` names the event and channel, and the note gives the moments the
  events imply. (A wrong inertia also inflates the summary's own sd, by up to 80× on the
  degradation campaign fitted with the Pre-SOI model, which would hide the shift.)
* ``held_out`` — the events' consistency with one another: each event's log thrust per channel
  against the exact posterior predictive of the change-point model fitted to the *other* events
  (the step, the baseline, the scatter ``σ_k`` and the event's own sd), as the normal deviate of
  the smallest Bonferroni-adjusted two-sided tail probability over events and channels.

Both fail beyond 4 (the fits' thresholds, :mod:`cassini_bayes.inference.adequacy`): a shift of
4 event sd beyond the shared one, or a normal deviate of 4 (two-sided 6e-5 after Bonferroni).
Measured false-alarm rates and power: docs/health.md.
"""

from __future__ import annotations

from typing import NamedTuple, Sequence

import jax
import numpy as np
from scipy import stats
from scipy.special import ndtr

from cassini_bayes.estimators.baseline import wheel_momentum
from cassini_bayes.inference.adequacy.check import (PRIOR_CONFLICT_SD, Z_THRESHOLD, Adequacy,
                                                    Check, z_check, normal_deviate,
                                                    not_applicable)
from cassini_bayes.inference.health.changepoint import (SCATTER_GRID, HealthPrior,
                                                        health_posterior)
from cassini_bayes.inference.health.summary import (EventSummary, event_design, newey_west_lags,
                                                    residual_cov, weighted_fit)
from cassini_bayes.physics.impulse import impulse_lhs_basis

__all__ = ["InertiaProbe", "inertia_probe", "inertia_conflict", "held_out_events",
           "predictive_cdf", "health_adequacy", "MOMENT_NAMES"]

MOMENT_NAMES = ("Ixx", "Iyy", "Izz")
_basis = jax.jit(impulse_lhs_basis)


class InertiaProbe(NamedTuple):
    """What one event says about the model's inertia.

    shift : (K,) relative change of each reported channel's thrust, ``(F_model − F_own) /
        F_model``, from the model file's inertia to the event's own principal moments (NaN where
        the channel is not reported).
    own_sd : (K,) the sd of the event's log thrust with its own moments: the summary's, with its
        Newey-West part replaced by the own-inertia fit's (the time-constant and wheel terms
        kept).
    moments : (3,) the event's principal moments relative to the model's, ``I_own / I_model − 1``.
    moments_sd : (3,) their Newey-West sd.

    All NaN when the event's body rates cannot tell the moments from the thrusts (a quiet
    event: the extended design is rank-deficient).
    """

    shift: np.ndarray
    own_sd: np.ndarray
    moments: np.ndarray
    moments_sd: np.ndarray


def inertia_probe(tel, pulses, spacecraft, summary: EventSummary, *,
                  lags: int | None = None) -> InertiaProbe:
    """The event refitted with its principal moments free (:class:`InertiaProbe`), with the
    per-axis weights of the summary's own fit so that only the added columns differ."""
    des = event_design(tel, pulses, spacecraft, channels=summary.channels)
    basis = np.asarray(_basis(np.asarray(tel.t, float), np.asarray(tel.omega, float),
                              np.asarray(wheel_momentum(tel, spacecraft), float)))
    inertia = np.asarray(spacecraft.inertia, float)
    # π_k ∂V/∂π_k: V's change per unit relative change of moment k (Feldman & Lee Eq 17 is
    # linear in π). V at the model's inertia carries Σ_k (π_model,k − π_own,k) ∂V/∂π_k beyond
    # the thrusts, so the fitted coefficient δ_k is 1 − π_own,k / π_model,k
    x1 = np.concatenate([des.x, np.stack([inertia[k, k] * basis[1 + k] for k in range(3)],
                                         axis=-1)], axis=-1)
    lags = newey_west_lags(des.v.shape[0]) if lags is None else int(lags)
    f0, w_fit, a0, e0, rms = weighted_fit(des.x, des.v)
    w = 1.0 / np.maximum(rms, 1e-12) ** 2                  # the scores' weights, as the summary
    k_ch = len(summary.channels)
    if not _separable(x1, w_fit):     # body rates too quiet to tell the moments from thrust
        nan_k, nan3 = np.full(k_ch, np.nan), np.full(3, np.nan)
        return InertiaProbe(nan_k, nan_k, nan3, nan3)
    f1, _, a1, e1, _ = weighted_fit(x1, des.v, w_fit)
    nw0 = np.sqrt(np.diag(residual_cov(des.x, e0, w_fit, w, a0, lags)))
    cov1 = residual_cov(x1, e1, w_fit, w, a1, lags)
    nw1 = np.sqrt(np.diag(cov1))
    idx = np.flatnonzero(des.fired[:k_ch])
    p = idx.size
    rep = np.isfinite(summary.log_thrust[idx])
    k = idx[rep]
    shift, own_sd = np.full(k_ch, np.nan), np.full(k_ch, np.nan)
    f = np.abs(f0[:p][rep])
    shift[k] = (f0[:p] - f1[:p])[rep] / f0[:p][rep]
    s2 = np.diag(summary.cov)[k]
    own_sd[k] = np.sqrt(np.maximum(s2 - (nw0[:p][rep] / f) ** 2, 0.0) + (nw1[:p][rep] / f) ** 2)
    return InertiaProbe(shift, own_sd, -f1[-3:], nw1[-3:])


def _separable(x: np.ndarray, w: np.ndarray, max_cond: float = 1e10) -> bool:
    """Whether the weighted design ``x`` (n, 3, p) has full rank: the condition number of its
    correlation-scaled normal matrix below ``max_cond``."""
    xw = x * np.sqrt(w)[None, :, None]
    a = np.einsum("tap,taq->pq", xw, xw)
    d = np.sqrt(np.diag(a))
    if not np.all(d > 0):
        return False
    return bool(np.linalg.cond(a / np.outer(d, d)) < max_cond)


def inertia_conflict(probes: Sequence[InertiaProbe], labels: Sequence[str],
                     channels: Sequence[str], threshold: float = PRIOR_CONFLICT_SD) -> Check:
    """``max_ek |Δ_ek − Δ̄_k| / s_ek`` (module docstring): the part of each event's thrust
    change under its own inertia that the events do not share, in the sd ``s_ek`` of the
    event's thrust under its own inertia; ``Δ̄_k`` the precision-weighted mean over the events
    of channel ``k`` (``channels`` names them)."""
    name = "inertia_conflict"
    shift = np.array([p.shift for p in probes], float)
    se = np.array([p.own_sd for p in probes], float)
    ok = np.isfinite(shift) & np.isfinite(se) & (se > 0)
    if not ok.any():
        return not_applicable(name, threshold, "no event reports a channel whose body motion "
                              "tells its principal moments from its thrusts")
    w = np.where(ok, 1.0 / np.where(ok, se, 1.0) ** 2, 0.0)
    shared = np.sum(w * np.where(ok, shift, 0.0), axis=0) / np.maximum(w.sum(axis=0), 1e-300)
    z = np.where(ok, np.abs(shift - shared[None, :]) / np.where(ok, se, 1.0), -1.0)
    e, k = np.unravel_index(int(np.argmax(z)), z.shape)
    mom = np.array([p.moments for p in probes])
    wm = np.nan_to_num(1.0 / np.maximum(np.array([p.moments_sd for p in probes]), 1e-12) ** 2)
    pooled = np.sum(wm * np.nan_to_num(mom), axis=0) / np.maximum(np.sum(wm, axis=0), 1e-300)
    note = ("the events' own principal moments differ from the model's by " + ", ".join(
        f"{n} {100 * x:+.1f} %" for n, x in zip(MOMENT_NAMES, pooled))
        + f"; {labels[e]} {channels[k]}: thrust {-100 * shift[e, k]:+.2g} % under its own "
        f"inertia (events' shared part {-100 * shared[k]:+.2g} %), sd {100 * se[e, k]:.2g} %")
    if z[e, k] > threshold:
        note += ("; the health model takes the model's inertia as exact up to a shared scale: "
                 "give the spacecraft model of the events' epoch (fit inertia calibrates it)")
    return z_check(name, float(z[e, k]), threshold, f"{labels[e]} {channels[k]}", note)


def predictive_cdf(post, date_days: float, log_thrust: float, se: float, k: int) -> float:
    """``P(y ≤ log_thrust)`` for an event at ``date_days`` with sd ``se`` (log units) in channel
    ``k`` under the posterior predictive of ``post``
    (:class:`~cassini_bayes.inference.health.HealthPosterior` of other events): a mixture over
    no change, the change intervals (a change within the interval holding the date counts with
    the interval's fraction before it), step or no step, and the scatter grid."""
    var_extra = se ** 2 + SCATTER_GRID ** 2

    def mix(w, mean, var):
        return np.sum(w * ndtr((log_thrust - mean) / np.sqrt(var + var_extra)), axis=-1)

    w0 = post._w0[k] / post._w0[k].sum()
    c_flat = mix(w0, post._mean0[k], post._var0[k])              # the channel did not step
    w1 = post._w[:, k] / post._w[:, k].sum(axis=-1, keepdims=True)
    m, c = post._mean[:, k], post._cov[:, k]
    c_after = mix(w1, m[..., 0] + m[..., 1], c[..., 0, 0] + 2 * c[..., 0, 1] + c[..., 1, 1])
    c_before = mix(w1, m[..., 0], c[..., 0, 0])
    lo, hi = post.dates[:-1], post.dates[1:]
    before = np.clip((date_days - lo) / np.maximum(hi - lo, 1e-300), 0.0, 1.0)  # P(τ ≤ date)
    stepped = before * c_after + (1.0 - before) * c_before
    sp = post.step_prob[:, k]
    per_interval = sp * stepped + (1.0 - sp) * c_flat
    return float((1.0 - post.p_change) * c_flat + np.sum(post.interval_prob * per_interval))


def held_out_events(dates_days, log_thrust, se, prior: HealthPrior, labels: Sequence[str],
                    channels: Sequence[str], threshold: float = Z_THRESHOLD) -> Check:
    """Leave one event out (module docstring): the normal deviate of the smallest
    Bonferroni-adjusted two-sided predictive tail probability over events and channels
    (``channels`` names them)."""
    name = "held_out"
    t = np.asarray(dates_days, float)
    y, s = np.asarray(log_thrust, float), np.asarray(se, float)
    if t.size < 3:
        return not_applicable(name, threshold, f"{t.size} events: the others cannot fit the "
                              "change-point model")
    z = np.full(y.shape, np.nan)
    for e in range(t.size):
        keep = np.arange(t.size) != e
        post = health_posterior(t[keep], y[keep], s[keep], prior)
        for k in range(y.shape[1]):
            if np.isfinite(y[e, k]) and np.isfinite(s[e, k]) and s[e, k] > 0:
                u = predictive_cdf(post, t[e], y[e, k], s[e, k], k)
                z[e, k] = stats.norm.isf(min(max(min(u, 1.0 - u), 1e-300), 0.5))
    if not np.isfinite(z).any():
        return not_applicable(name, threshold, "no event reports a channel")
    n_tests = int(np.isfinite(z).sum())
    e, k = np.unravel_index(int(np.nanargmax(z)), z.shape)
    p = 2.0 * stats.norm.sf(z[e, k])
    return z_check(name, normal_deviate(min(p * n_tests, 1.0)), threshold,
                  f"{labels[e]} {channels[k]}",
                  f"largest |z| {z[e, k]:.2f} of {n_tests} event channels, each against the "
                  "others' change-point posterior")


def health_adequacy(dates_days, summaries: Sequence[EventSummary],
                    probes: Sequence[InertiaProbe], prior: HealthPrior,
                    labels: Sequence[str]) -> Adequacy:
    """The checks of a health fit (module docstring); ``labels`` name the events."""
    y = np.array([s.log_thrust for s in summaries])
    se = np.array([np.sqrt(np.diag(s.cov)) for s in summaries])
    names = summaries[0].channels.names
    return Adequacy((inertia_conflict(probes, labels, names),
                     held_out_events(dates_days, y, se, prior, labels, names)))
