"""Exact change-point posterior of per-channel thrust over many events.

Model (channel ``k``, one of the events' thrust channels,
:func:`~cassini_bayes.inference.health.summary.health_channels`; event ``e`` at date ``t_e``, days
after the first)::

    y_ek = b_k + d_k · 1[t_e ≥ τ] + ε_ek,     ε_ek ~ N(0, s_ek² + σ_k²)

* ``y_ek`` the event's log thrust estimate and ``s_ek`` its standard error
  (:func:`~cassini_bayes.inference.health.summary.event_summary`; missing where the event does not
  identify the channel);
* ``b_k ~ N(log F_nominal,k, 0.5²)`` (``F_nominal,k`` the model file's thrust of the channel's
  thrusters, their mean): the channel's log thrust at the first calibration, *including*
  every error shared by all events (the spacecraft inertia, a common wheel-inertia scale, a
  time-constant error scale all events' estimates alike). Health is judged on ``d_k``, the log of
  the ratio to the first calibration, in which they cancel;
* with prior probability ``p_change`` one change at ``τ`` (uniform in days over
  ``(t_first, t_last]``); at that change each channel independently steps, with probability
  ``p_channel``, by ``d_k ~ N(0, step_sd²)`` (log ratio), else keeps ``d_k = 0`` (a
  spike-and-slab prior: a branch degradation hits some thrusters, not all); without a change
  ``d = 0``;
* ``σ_k`` the event-to-event scatter of channel ``k`` (per-event thrust variation, per-event
  errors the summary's covariance misses: time constants varying between events, wheel-inertia
  errors weighted differently by each event's wheel speeds), log-uniform on a grid
  :data:`SCATTER_GRID`, independent between channels;
* channels independent given ``τ`` (the summary's within-event cross-channel covariance is
  dropped: small beside ``σ``).

The likelihood depends on ``τ`` only through which events come after it, so ``τ`` is summed
exactly over the intervals between event dates (prior weight ∝ interval length, uniform within);
given the interval and ``σ_k``, ``(b_k, d_k)`` is Gaussian and its evidence closed-form. Every
posterior quantity below is exact (no sampling); draws are offered for plots and SBC.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import log_ndtr, logsumexp

from cassini_bayes.errors import InputError

__all__ = ["HealthPrior", "HealthPosterior", "health_posterior", "SCATTER_GRID"]

SCATTER_GRID = np.geomspace(0.001, 0.1, 21)
"""Event-to-event scatter levels ``σ_k`` (fraction of the thrust, log scale), equal prior weight."""


@dataclass(frozen=True)
class HealthPrior:
    """Prior of the change-point model (fractions are of the thrust, as log ratios).

    p_change : probability of one change within the events' span. p_channel : probability that
    a channel steps at the change. step_sd : sd of a stepping channel's log step ``d_k``.
    baseline_sd : sd of each ``b_k`` about ``log(nominal_thrust_n)``. nominal_thrust_n : the
    channels' predicted thrust, N: one for all, or one per channel (K,).
    """

    p_change: float = 0.1
    p_channel: float = 0.5
    step_sd: float = 0.1
    baseline_sd: float = 0.5
    nominal_thrust_n: float | tuple[float, ...] = 0.699

    def check(self) -> "HealthPrior":
        for name in ("p_change", "p_channel"):
            if not 0.0 < getattr(self, name) < 1.0:
                raise InputError(f"must lie strictly between 0 and 1, got "
                                 f"{getattr(self, name)}", path=name)
        for name in ("step_sd", "baseline_sd", "nominal_thrust_n"):
            if not np.all(np.asarray(getattr(self, name), float) > 0):
                raise InputError(f"must be positive, got {getattr(self, name)}", path=name)
        return self


@dataclass(frozen=True)
class HealthPosterior:
    """Exact posterior of the change-point model.

    dates : (N,) event dates, days. channels : (K,) the channels' names. y, s : (N, K) log
    thrusts and their standard errors (NaN: missing). p_change : posterior probability of a
    change. interval_prob : (N − 1,) posterior probability that the change lies in
    ``(dates[j], dates[j+1]]`` (sums to ``p_change``).
    step_prob : (N − 1, K) posterior probability that channel ``k`` stepped, given a change in
    interval ``j``. Internals for the conditional posteriors: ``_w`` (N−1, K, G) posterior weight
    of ``σ_k`` given the interval and a step; ``_mean``, ``_cov`` (N−1, K, G, 2), (…, 2, 2) of
    ``(b_k, d_k)``; ``_w0``, ``_mean0``, ``_var0`` the same for a channel that does not step.
    """

    dates: np.ndarray
    channels: tuple[str, ...]
    y: np.ndarray
    s: np.ndarray
    prior: HealthPrior
    p_change: float
    interval_prob: np.ndarray
    step_prob: np.ndarray
    log_evidence: float
    _w: np.ndarray
    _mean: np.ndarray
    _cov: np.ndarray
    _w0: np.ndarray
    _mean0: np.ndarray
    _var0: np.ndarray

    # ------------------------------------------------------------------ change date
    def change_date_quantiles(self, probs) -> np.ndarray:
        """Quantiles (days) of the change date given that there is a change (uniform within
        each interval between events)."""
        w = self.interval_prob / max(self.interval_prob.sum(), 1e-300)
        cdf = np.r_[0.0, np.cumsum(w)]
        return np.interp(np.asarray(probs, float), cdf, self.dates, left=self.dates[0],
                         right=self.dates[-1])

    def change_date_interval(self, level: float = 0.9) -> tuple[float, float]:
        """Central ``level`` interval of the change date (days), given a change."""
        lo, hi = self.change_date_quantiles([(1 - level) / 2, (1 + level) / 2])
        return float(lo), float(hi)

    # ------------------------------------------------------------------ health probabilities
    def _p_step_below(self, k: int, log_ratio: float) -> np.ndarray:
        """(N−1,) ``P(d_k < log_ratio | change in interval j, y)`` (``log_ratio < 0``)."""
        m, v = self._mean[:, k, :, 1], self._cov[:, k, :, 1, 1]
        slab = np.sum(self._w[:, k] * np.exp(log_ndtr((log_ratio - m) / np.sqrt(v))), axis=1)
        return self.step_prob[:, k] * slab

    def p_down(self, channels, fraction: float) -> np.ndarray:
        """(N,) posterior probability, at each event date, that any of ``channels`` (indices)
        is more than ``fraction`` below its first calibration."""
        c = np.log1p(-fraction)
        none_below = np.ones(self.dates.size - 1)
        for k in np.atleast_1d(channels):
            none_below = none_below * (1.0 - self._p_step_below(int(k), c))
        per_interval = self.interval_prob * (1.0 - none_below)
        # the change counts at date t_e when its interval ends by t_e (interval j ends at e = j+1)
        return np.r_[0.0, np.cumsum(per_interval)]

    # ------------------------------------------------------------------ draws
    def draws(self, rng: np.random.Generator, n: int) -> dict:
        """``n`` exact posterior draws: ``change`` (bool), ``tau`` (days; NaN without a
        change), ``b``, ``d`` (n, K) and ``sigma`` (n, K)."""
        k_ch = self._w.shape[1]
        p = np.maximum(np.r_[1.0 - self.p_change, self.interval_prob], 0.0)
        p = p / p.sum()
        which = rng.choice(p.size, size=n, p=p)          # 0: no change, j+1: interval j
        out = {"change": which > 0, "tau": np.full(n, np.nan), "b": np.zeros((n, k_ch)),
               "d": np.zeros((n, k_ch)), "sigma": np.zeros((n, k_ch))}
        for i, c in enumerate(which):
            j = c - 1
            if c > 0:
                out["tau"][i] = rng.uniform(self.dates[j], self.dates[j + 1])
            for k in range(k_ch):
                if c == 0 or rng.uniform() >= self.step_prob[j, k]:
                    g = rng.choice(SCATTER_GRID.size, p=self._w0[k] / self._w0[k].sum())
                    out["sigma"][i, k] = SCATTER_GRID[g]
                    out["b"][i, k] = rng.normal(self._mean0[k, g], np.sqrt(self._var0[k, g]))
                    continue
                g = rng.choice(SCATTER_GRID.size, p=self._w[j, k] / self._w[j, k].sum())
                out["sigma"][i, k] = SCATTER_GRID[g]
                out["b"][i, k], out["d"][i, k] = rng.multivariate_normal(self._mean[j, k, g],
                                                                         self._cov[j, k, g])
        return out


    def relative_thrust_bands(self, grid_days, rng: np.random.Generator, n_draws: int = 4000,
                              quantiles=(0.05, 0.5, 0.95)) -> np.ndarray:
        """``(K, G, Q)``: quantiles of each channel's thrust relative to its first calibration,
        ``exp(d_k 1[t ≥ τ])``, at the dates ``grid_days`` (from ``n_draws`` exact draws)."""
        dr = self.draws(rng, n_draws)
        grid = np.asarray(grid_days, float)
        after = np.where(dr["change"][:, None], dr["tau"][:, None] <= grid[None, :], False)
        ratio = np.exp(dr["d"][:, :, None] * after[:, None, :])          # (D, K, G)
        return np.moveaxis(np.quantile(ratio, quantiles, axis=0), 0, -1)


def _cum(a: np.ndarray) -> np.ndarray:
    """Prefix sums over events (axis 0) with a leading zero."""
    return np.concatenate([np.zeros((1,) + a.shape[1:]), np.cumsum(a, axis=0)])


def health_posterior(dates_days, log_thrust, se, prior: HealthPrior = HealthPrior(),
                     channels=None) -> HealthPosterior:
    """Exact posterior of the change-point model.

    Parameters
    ----------
    dates_days : (N,) event dates, days (any origin; sorted here).
    log_thrust : (N, K) log thrust estimates, log N; NaN where an event does not identify a
        channel.
    se : (N, K) their standard errors (log units).
    prior : :class:`HealthPrior`.
    channels : (K,) the channels' names (default ``channel 0`` …).
    """
    prior.check()
    t = np.asarray(dates_days, float)
    y = np.asarray(log_thrust, float)
    s = np.asarray(se, float)
    if t.ndim != 1 or t.size < 2 or y.shape != (t.size, y.shape[-1]) or s.shape != y.shape:
        raise InputError(f"needs at least 2 events with dates (N,) and estimates (N, K); got "
                         f"{t.shape}, {y.shape}, {s.shape}", path="events")
    if not np.all(np.isfinite(t)):
        raise InputError("event dates must be finite days", path="events")
    k_ch = y.shape[-1]
    names = (tuple(f"channel {k}" for k in range(k_ch)) if channels is None
             else tuple(str(c) for c in channels))
    log_nom = np.log(np.broadcast_to(np.asarray(prior.nominal_thrust_n, float), (k_ch,)))
    if len(names) != k_ch:
        raise InputError(f"{len(names)} channel names for {k_ch} channels", path="channels")
    order = np.argsort(t, kind="stable")
    t, y, s = t[order], y[order], s[order]
    obs = np.isfinite(y) & np.isfinite(s) & (s > 0)
    yc = np.where(obs, y - log_nom, 0.0)
    # per event, channel, scatter level: precision (0 where missing)
    w = np.where(obs[..., None], 1.0 / (np.where(obs, s, 1.0)[..., None] ** 2
                                        + SCATTER_GRID ** 2), 0.0)      # (N, K, G)
    cw, cwy = _cum(w), _cum(w * yc[..., None])
    wyy = np.sum(w * yc[..., None] ** 2, axis=0)
    logdet = np.sum(np.where(w > 0, np.log(np.where(w > 0, w, 1.0)), 0.0), axis=0)
    n_obs = obs.sum(axis=0)[:, None]
    base = -0.5 * (wyy - logdet + n_obs * np.log(2 * np.pi))            # (K, G)
    pb, pd = 1.0 / prior.baseline_sd ** 2, 1.0 / prior.step_sd ** 2
    tot_w, tot_h = cw[-1], cwy[-1]                                       # (K, G)
    # no change: b only
    a0 = pb + tot_w
    ev0 = base + 0.5 * np.log(pb / a0) + 0.5 * tot_h ** 2 / a0           # (K, G)
    # change in interval j (events j+1 … N−1 after it), j = 0 … N−2
    wpost = tot_w[None] - cw[1:-1]                                        # (N−1, K, G)
    hpost = tot_h[None] - cwy[1:-1]
    a11, a12, a22 = pb + tot_w[None], wpost, pd + wpost
    det = a11 * a22 - a12 ** 2
    h1 = np.broadcast_to(tot_h[None], hpost.shape)
    quad = (a22 * h1 ** 2 - 2 * a12 * h1 * hpost + a11 * hpost ** 2) / det
    ev1 = base[None] + 0.5 * np.log(pb * pd / det) + 0.5 * quad          # (N−1, K, G)
    g = SCATTER_GRID.size
    log_k0 = logsumexp(ev0, axis=1) - np.log(g)                           # (K,)
    log_k1 = logsumexp(ev1, axis=2) - np.log(g)                           # (N−1, K)
    span = t[-1] - t[0]
    widths = np.diff(t)
    with np.errstate(divide="ignore"):
        log_pi = (np.log(widths / span) if span > 0 else
                  np.full(widths.size, -np.log(widths.size)))
    # spike and slab per channel: no step (the no-change evidence) or a step
    log_q, log_1q = np.log(prior.p_channel), np.log1p(-prior.p_channel)
    log_ch = np.logaddexp(log_1q + log_k0[None, :], log_q + log_k1)         # (N−1, K)
    step_prob = np.exp(log_q + log_k1 - log_ch)
    log_h1 = np.log(prior.p_change) + log_pi + log_ch.sum(axis=1)          # (N−1,)
    log_h0 = np.log1p(-prior.p_change) + log_k0.sum()
    log_z = logsumexp(np.r_[log_h0, log_h1])
    interval_prob = np.exp(log_h1 - log_z)
    w1 = np.exp(ev1 - log_k1[..., None] - np.log(g))
    w0 = np.exp(ev0 - log_k0[:, None] - np.log(g))
    mean = np.stack([(a22 * h1 - a12 * hpost) / det, (a11 * hpost - a12 * h1) / det], axis=-1)
    mean[..., 0] += log_nom[:, None]
    cov = np.stack([np.stack([a22 / det, -a12 / det], -1),
                    np.stack([-a12 / det, a11 / det], -1)], -2)
    return HealthPosterior(
        dates=t, channels=names, y=y, s=s, prior=prior, p_change=float(interval_prob.sum()),
        interval_prob=interval_prob, step_prob=step_prob, log_evidence=float(log_z), _w=w1,
        _mean=mean, _cov=cov,
        _w0=w0, _mean0=tot_h / a0 + log_nom[:, None], _var0=1.0 / a0)
