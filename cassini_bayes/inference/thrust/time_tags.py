"""The telemetry time tags' terms of the robust thrust model (data only).

A time-tag error ``δ_i`` (s) on sample ``i`` moves the residual of Feldman & Lee Eq 17 three ways:

- the pulses' impulse at the sample, ``−Q (F ⊙ ∂j/∂t) δ_i``;
- the left side at the sample, ``∂V_i/∂t_i δ_i``: the trapezoid of ``ΔG = ∫ ω × (I ω + H) dt``
  (Eq 15), ``½ (f_{i−1} + f_i)`` with ``f = ω × (I ω + H)``, and its correction across the
  pulses' rate steps, which places each pulse inside its interval by the tags;
- the left side at every later sample, by one step ``∂V_k/∂t_i δ_i`` (``½ (f_{i−1} − f_{i+1})``
  where no pulse is near): a random walk that steps where the pulses change the rates.

The first two are one rank-one covariance term per sample, ``m_i m_iᵀ`` with
``m_i = σ_t (Q (F ⊙ ∂j/∂t) − ∂V_i/∂t_i)`` (the likelihood's
:func:`~cassini_bayes.inference.thrust.likelihood.event_loglik`); the walk's steps are robust
nuisance columns, one per sample whose step matters, prior sd ``σ_t``, integrated out with the
others. The walk and the sample's own terms are given independent priors (their cross term left
out). The derivatives are taken of the left side as the model computes it, at the measured rates
and the prior's inertia, thrusts and time constants: the terms are variances, which a few per
cent of those move by as little.

The pulses' impulse is not linear in a tag where a pulse's edge lies within the tag's reach of
the sample: there the rank-one term's rate is the expected rate over the tag, the regression of
the impulse on the tag, at a pulse's transient samples (:func:`with_tag_expectation`) and at
the sample before its command (:func:`with_pre_command_rates`). The impulse itself stays the
one at the sample's time, so that a stated tag sd wider than the tags widens the variance only.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.inference.gaussian import RankOneRows
from cassini_bayes.inference.thrust.likelihood import (PulseLayout, events_time_tag_rates,
                                                       jump_area,
                                                       noise_covariances, time_tag_rows)
from cassini_bayes.physics.impulse import impulse_lhs, rate_step_correction
from cassini_bayes.physics.pulse import thrust_profile

__all__ = ["TAG_VARIANCE_SHARE", "TAG_NODES", "with_tag_expectation", "with_pre_command_rates",
           "TagSensitivity", "left_side_at_times",
           "tag_sensitivity", "events_tag_sensitivity", "tag_step_columns", "events_tag_steps",
           "gyro_tag_terms", "rank_one_rows", "tag_scale_fields"]

TAG_VARIANCE_SHARE = 0.01
"""Time-tag terms left out of the model add at most this share of one sample's smallest
white-noise variance: to the walk at the event's end (the largest steps get columns until the
rest is below it), and to a sample's own variance (a sample keeps its own term above it)."""


TAG_NODES = 11
"""Gauss–Hermite nodes of the expectation over a sample's time tag
(:func:`~cassini_bayes.inference.thrust.likelihood.tag_expectation`)."""


_TAIL_NODES = 241
"""Normal-tag grid points (±6 sd) of the rate before a command, whose expectation comes from the
tail of the tag's distribution alone (Gauss–Hermite's few nodes miss it)."""


def with_tag_expectation(layouts: PulseLayout, q_f, tau, b_covs, time_tag_sd) -> PulseLayout:
    """``layouts`` (stacked over the events) with each pulse's rate at a transient sample
    expected over the sample's time tag, Normal with sd ``time_tag_sd`` (s), where that
    matters: where, at the thrusts' torques ``q_f`` (3, M) N m and the time constants ``tau``
    (3,) s, it moves the sample's time-tag term by more than :data:`TAG_VARIANCE_SHARE` of the
    event's white-noise covariance ``b_covs`` (E, 3, 3) (N m s)². Elsewhere the rate stays the
    one at the sample's time."""
    if time_tag_sd <= 0.0:
        return layouts
    n_ev, n_thr = layouts.dt.shape[0], q_f.shape[1]
    x, w = np.polynomial.hermite_e.hermegauss(TAG_NODES)
    nodes = dict(tag_nodes=np.tile(x, (n_ev, 1)), tag_weights=np.tile(w / w.sum(), (n_ev, 1)))
    spread = layouts._replace(tag_spread=np.full(layouts.dt.shape, float(time_tag_sd)), **nodes)
    term = [q_f @ events_time_tag_rates(lay, tau, time_tag_sd, n_thr)
            for lay in (spread, layouts)]
    n = layouts.settled.shape[1]
    keep = np.zeros(layouts.dt.shape, bool)
    for e, b_cov in enumerate(b_covs):
        change = np.sum(((term[0][e] - term[1][e]).T @ _noise_whitener(b_cov))**2, 1)
        at = layouts.at[e]
        keep[e] = (at < n_thr * n) & (change[at % n] > TAG_VARIANCE_SHARE)
    if not keep.any():
        return layouts
    return layouts._replace(tag_spread=np.where(keep, float(time_tag_sd), 0.0), **nodes)


def with_pre_command_rates(rates, layouts: PulseLayout, q_f, tau, b_covs,
                           time_tag_sd) -> np.ndarray:
    """``rates`` (E, M, n) s (:func:`~cassini_bayes.inference.thrust.likelihood.time_tag_rates`
    of the stacked ``layouts``) with each pulse's rate at the sample before its command, expected
    over that sample's time tag (Normal, sd ``time_tag_sd`` s): zero at the sample's own time,
    but a tag within reach puts the sample inside the pulse. Kept where it moves the sample's
    time-tag term, at the torques ``q_f`` (3, M) N m and time constants ``tau`` (3,) s, by more
    than :data:`TAG_VARIANCE_SHARE` of the event's white-noise covariance ``b_covs`` (E, 3, 3)."""
    if time_tag_sd <= 0.0:
        return rates
    x = np.linspace(-6.0, 6.0, _TAIL_NODES)       # the tail past the delay: a dense grid
    w = np.exp(-0.5 * x * x)
    n_thr, n = q_f.shape[1], rates.shape[2]
    out = np.array(rates, float)
    for e, b_cov in enumerate(b_covs):
        first, dt_prev = np.asarray(layouts.at[e])[:, 0], np.asarray(layouts.dt_prev[e])
        width = np.asarray(layouts.width[e])
        ok = (first < n_thr * n) & (dt_prev < 0.0) & (width > 0.0)
        lag = dt_prev[ok][:, None] - time_tag_sd * x[None, :]
        rate = time_tag_sd * np.asarray(thrust_profile(lag, width[ok][:, None], *tau)) @ (
            w / w.sum())
        thr, prev = first[ok] // n, first[ok] % n - 1
        term = (q_f[:, thr] * rate[None, :]).T @ _noise_whitener(b_cov)
        big = np.sum(term**2, 1) > TAG_VARIANCE_SHARE
        np.add.at(out[e], (thr[big], prev[big]), rate[big])
    return out


def _noise_whitener(b_cov) -> np.ndarray:
    """(3, 3) ``L`` with ``|x L|² = xᵀ B⁻¹ x``."""
    return np.linalg.cholesky(np.linalg.inv(np.asarray(b_cov, float)))


class TagSensitivity(NamedTuple):
    """How one event's left side of Eq 17 moves with each sample's time tag (N m, per second of
    tag error): at the sample itself and, as one step, at every later sample."""

    own: np.ndarray     # (n, 3) ∂V_i/∂t_i
    step: np.ndarray    # (n, 3) ∂V_k/∂t_i for every k > i (0 at the last sample)


def left_side_at_times(t, omega, h_wheels, layout: PulseLayout, inertia, q_f, tau, omega_mid,
                       h_mid):
    """``tt -> (V (n, 3) N m s, layout)``: one event's left side of Eq 17 as the model computes
    it, with its samples at the times ``tt`` (n,) s instead of ``t``: the trapezoidal ``ΔG``
    (Feldman & Lee Eq 15) with its first-order correction across the pulses' rate steps
    (:func:`~cassini_bayes.physics.impulse.rate_step_correction`), which places each pulse
    inside its interval by the times; and ``layout`` with the samples moved (its ``dt`` and
    ``dt_prev``). ``q_f`` (3, M) N m the thrusters' torques, ``tau`` (3,) s the time constants,
    ``omega_mid``/``h_mid`` (3, n) the intervals' means; differentiable in ``tt``."""
    t = np.asarray(t, float)
    n = t.size
    rows = np.where(layout.at < q_f.shape[1] * n, layout.at % n, 0)
    on = (layout.at < q_f.shape[1] * n).astype(float)
    first = rows[:, 0]
    prev_ok = ((first >= 1) & (on[:, 0] > 0)).astype(float)
    prev = np.maximum(first - 1, 0)

    def left(tt):
        moved = tt - t
        lay = layout._replace(dt=layout.dt + moved[rows] * on,
                              dt_prev=layout.dt_prev + prev_ok * moved[prev]
                              + (1.0 - prev_ok) * moved[rows[:, 0]] * on[:, 0])
        v = impulse_lhs(tt, omega, inertia, h_wheels) + rate_step_correction(
            inertia, jump_area(lay, q_f, *tau), omega_mid, h_mid).T
        return v, lay

    return left


def tag_sensitivity(t, omega, h_wheels, layout: PulseLayout, inertia, q_f, tau, omega_mid,
                    h_mid) -> TagSensitivity:
    """:class:`TagSensitivity` of one event's left side as the model computes it
    (:func:`left_side_at_times`); ``layout`` one event's :class:`PulseLayout`, ``q_f`` (3, M)
    N m the thrusters' torques at the predicted thrust, ``tau`` (3,) s the prior's time
    constants, ``omega_mid``/``h_mid`` (3, n) the intervals' means. An interval's increment
    depends on its two ends only, so two derivatives (even and odd samples) give them all."""
    t = np.asarray(t, float)
    n = t.size
    left = left_side_at_times(t, omega, h_wheels, layout, inertia, q_f, tau, omega_mid, h_mid)

    def increments(tt):
        v = left(tt)[0]
        return jnp.diff(v, axis=0, prepend=v[:1])

    parity = np.arange(n) % 2
    d = [np.asarray(jax.jvp(increments, (jnp.asarray(t),),
                            (jnp.asarray((parity == c).astype(float)),))[1]) for c in (0, 1)]
    even = (parity == 0)[:, None]
    own = np.where(even, d[0], d[1])                                # ∂g_i/∂t_i
    nxt = np.zeros((n, 3))
    nxt[:-1] = np.where(even[:-1], d[0][1:], d[1][1:])              # ∂g_{i+1}/∂t_i
    step = own + nxt
    step[-1] = 0.0
    return TagSensitivity(own, step)


def tag_step_columns(sens: TagSensitivity, mask, b_cov, time_tag_sd) -> np.ndarray:
    """(P, 3, n) N m: the walk's columns for the ``P`` samples whose step matters, one event
    (module docstring): ``sens.step`` at every sample after ``i``. ``mask`` (n,) 1 on samples
    (padding last), ``b_cov`` (3, 3) (N m s)² one sample's white-noise covariance,
    ``time_tag_sd`` s. The first sample's step is the event's offset, and the last has no later
    sample: neither gets one."""
    size = np.size(mask)
    n = int(np.sum(np.asarray(mask) > 0))
    if time_tag_sd <= 0.0 or n < 3:
        return np.zeros((0, 3, size))
    step = sens.step[1:n - 1]                                       # samples 1 … n − 2
    var = time_tag_sd**2 * np.sum((step @ _noise_whitener(b_cov))**2, 1)
    order = np.argsort(var)[::-1]
    left = np.cumsum(var[order][::-1])[::-1]                        # the walk from rank k on
    keep = np.sort(order[left > TAG_VARIANCE_SHARE]) + 1            # sample indices
    cols = np.zeros((keep.size, 3, size))
    later = np.arange(n)[None, :] > keep[:, None]                   # (P, n)
    cols[:, :, :n] = np.where(later[:, None, :], sens.step[keep][:, :, None], 0.0)
    return cols


def events_tag_sensitivity(kw: dict, layouts: PulseLayout, inertia, q_f, tau,
                           steps: dict) -> list[TagSensitivity]:
    """Every event's :func:`tag_sensitivity` from a thrust problem's padded arrays ``kw``, its
    stacked pulse layouts and rate-step fields ``steps`` (``omega_mid``, ``h_mid``)."""
    return [tag_sensitivity(kw["t"][e], kw["omega"][e], kw["h_wheels"][e],
                            PulseLayout(*(x[e] for x in layouts)), inertia, q_f, tau,
                            steps["omega_mid"][e], steps["h_mid"][e])
            for e in range(len(kw["t"]))]


def gyro_tag_terms(sens: list[TagSensitivity], kw: dict, inertia, noise,
                   time_tag_sd) -> np.ndarray:
    """(E, 3, n) N m s: ``σ_t ∂V_i/∂t_i``, each sample's own time-tag term of the left side
    (module docstring; 0 at the first sample, where ``V`` is 0), zero where its variance is below
    :data:`TAG_VARIANCE_SHARE` of the sample's smallest white-noise variance and on padding;
    ``noise`` (E, 2) rad/s the white-noise levels."""
    out = np.zeros(np.shape(kw["omega"]))
    for e, b in enumerate(noise_covariances(inertia, noise, kw["wheel_cov"])):
        term = time_tag_sd * sens[e].own
        term[0] = 0.0
        small = np.sum((term @ _noise_whitener(b))**2, 1) < TAG_VARIANCE_SHARE
        out[e] = np.where((small | (np.asarray(kw["mask"][e]) <= 0))[:, None], 0.0, term)
    return np.ascontiguousarray(np.swapaxes(out, 1, 2))


def events_tag_steps(sens: list[TagSensitivity], kw: dict, inertia, noise,
                     time_tag_sd) -> np.ndarray:
    """(E, P, 3, n) N m: every event's :func:`tag_step_columns`, one block per event (an event's
    ``δ_i`` move no other event); ``noise`` (E, 2) rad/s the white-noise levels."""
    blocks = [tag_step_columns(sens[e], kw["mask"][e], b, time_tag_sd)
              for e, b in enumerate(noise_covariances(inertia, noise, kw["wheel_cov"]))]
    cols = np.zeros((len(blocks), sum(b.shape[0] for b in blocks), 3, np.shape(kw["t"])[1]))
    start = 0
    for e, b in enumerate(blocks):
        cols[e, start:start + b.shape[0]] = b
        start += b.shape[0]
    return cols


def rank_one_rows(rates, gyro, kw: dict, torque, noise, i_lin,
                  bucket: int) -> tuple[RankOneRows, np.ndarray, np.ndarray]:
    """The samples of each event that keep a rank-one time-tag term: a pulse's
    (:func:`~cassini_bayes.inference.thrust.likelihood.time_tag_rows`) or their own gyroscopic
    one (``gyro`` (E, 3, n), :func:`gyro_tag_terms`), padded to a common count (a multiple of
    ``bucket``): their indices and nuisance columns (:class:`RankOneRows`), their rates (E, M, p)
    and gyroscopic terms (E, 3, p). Padding rows have zero terms, which the likelihood's algebra
    leaves out exactly."""
    keep = []
    for e, b_hat in enumerate(noise_covariances(i_lin, noise, kw["wheel_cov"])):
        noise_sd = float(np.sqrt(np.linalg.eigvalsh(b_hat)[0]))
        pulses = time_tag_rows(rates[e], torque, noise_sd, kw["mask"][e])
        keep.append(np.flatnonzero(pulses | np.any(gyro[e] != 0.0, 0)))
    p_max = max(1, -(-max(k.size for k in keep) // bucket) * bucket)
    rows = np.zeros((len(keep), p_max), int)
    tag = np.zeros((len(keep), rates.shape[1], p_max))
    own = np.zeros((len(keep), 3, p_max))
    n_ev, n_nu = kw["nu_cols"].shape[:2]
    cols = np.zeros((n_ev, 3, n_nu, p_max))
    for e, k in enumerate(keep):
        rows[e, :k.size] = k
        tag[e, :, :k.size] = rates[e][:, k]
        own[e, :, :k.size] = gyro[e][:, k]
        cols[e, ..., :k.size] = kw["nu_cols"][e][..., k].transpose(1, 0, 2)
    return RankOneRows(rows, (cols[:, 0], cols[:, 1], cols[:, 2])), tag, own


def tag_scale_fields(layout, time_tag_sd: float) -> dict[str, np.ndarray]:
    """The thrust data's fields of the learned time-tag scale: ``tag_sd`` (1,) s, the stated sd
    the sampler's last coordinate scales (prior :func:`~cassini_bayes.inference.thrust.prior.
    tag_log_scale`), and ``tag_walk`` (R,), 1 on the walk's columns of the nuisance ``layout``,
    whose prior sd scales with it; the rank-one terms scale in the likelihood."""
    walk = np.zeros(layout.sd.shape[0])
    walk[layout.slices.get("time_tag_steps", slice(0, 0))] = 1.0
    return dict(tag_sd=np.array([float(time_tag_sd)]), tag_walk=walk)
