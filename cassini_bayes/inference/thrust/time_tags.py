"""The telemetry time tags' terms of the robust thrust model (data only).

A time-tag error ``δ_i`` (s) on sample ``i`` moves the residual of Feldman & Lee Eq 17 three ways:

- the pulses' impulse at the sample, ``−Q (F ⊙ ∂j/∂t) δ_i``;
- the trapezoid of ``ΔG = ∫ ω × (I ω + H) dt`` (Eq 15) at the sample, ``+½ δ_i (f_{i−1} + f_i)``
  (``f = ω × (I ω + H)``);
- that trapezoid at every later sample, ``½ δ_i (f_{i−1} − f_{i+1})``: a random walk that steps
  where the pulses change the rates.

The first two are one rank-one covariance term per sample, ``m_i m_iᵀ`` with
``m_i = σ_t (Q (F ⊙ ∂j/∂t) − ½ (f_{i−1} + f_i))`` (the likelihood's
:func:`~cassini_bayes.inference.thrust.likelihood.event_loglik`); the walk's steps are robust
nuisance columns, one per sample whose step matters, prior sd ``σ_t``, integrated out with the
others. The walk and the sample's own terms are given independent priors (their cross term left
out). ``f`` holds the measured rates and the inertia's prior mean: the terms are variances, which
a few per cent of the inertia move by as little.
"""

from __future__ import annotations

import numpy as np

from cassini_bayes.inference.gaussian import RankOneRows
from cassini_bayes.inference.thrust.likelihood import time_tag_rows

__all__ = ["TAG_VARIANCE_SHARE", "gyro_tag_terms", "tag_step_columns", "events_tag_steps",
           "rank_one_rows"]

TAG_VARIANCE_SHARE = 0.01
"""Time-tag terms left out of the model add at most this share of one sample's smallest
white-noise variance: to the walk at the event's end (the largest steps get columns until the
rest is below it), and to a sample's own variance (a sample keeps its ``f_i`` term above it)."""


def _gyroscopic(omega, h_wheels, inertia) -> np.ndarray:
    """(n, 3) N m: ``f = ω × (I ω + H)`` (Feldman & Lee Eq 15's integrand)."""
    w = np.asarray(omega, float)
    return np.cross(w, w @ np.asarray(inertia, float).T + np.asarray(h_wheels, float))


def _noise_whitener(b_cov) -> np.ndarray:
    """(3, 3) ``L`` with ``|x L|² = xᵀ B⁻¹ x``."""
    return np.linalg.cholesky(np.linalg.inv(np.asarray(b_cov, float)))


def tag_step_columns(t, omega, h_wheels, mask, inertia, b_cov, time_tag_sd) -> np.ndarray:
    """(P, 3, n) N m: the walk's columns for the ``P`` samples whose step matters, one event
    (module docstring): ``½ (f_{i−1} − f_{i+1})`` at every sample after ``i``. ``t`` (n,) s,
    ``omega`` (n, 3) rad/s, ``h_wheels`` (n, 3) N m s body axes, ``mask`` (n,) 1 on samples
    (padding last), ``inertia`` (3, 3) kg m², ``b_cov`` (3, 3) (N m s)² one sample's
    white-noise covariance, ``time_tag_sd`` s. The first sample's step is the event's offset,
    and the last has no later sample: neither gets one."""
    n = int(np.sum(np.asarray(mask) > 0))
    if time_tag_sd <= 0.0 or n < 3:
        return np.zeros((0, 3, np.size(t)))
    f = _gyroscopic(np.asarray(omega)[:n], np.asarray(h_wheels)[:n], inertia)
    step = 0.5 * (f[:-2] - f[2:])                                   # samples 1 … n − 2
    var = time_tag_sd**2 * np.sum((step @ _noise_whitener(b_cov))**2, 1)
    order = np.argsort(var)[::-1]
    left = np.cumsum(var[order][::-1])[::-1]                        # the walk from rank k on
    keep = np.sort(order[left > TAG_VARIANCE_SHARE]) + 1            # sample indices
    cols = np.zeros((keep.size, 3, np.size(t)))
    later = np.arange(n)[None, :] > keep[:, None]                   # (P, n)
    cols[:, :, :n] = np.where(later[:, None, :], step[keep - 1][:, :, None], 0.0)
    return cols


def gyro_tag_terms(kw: dict, inertia, noise, time_tag_sd) -> np.ndarray:
    """(E, 3, n) N m s: ``½ σ_t (f_{i−1} + f_i)``, each sample's own gyroscopic time-tag term
    (module docstring; 0 at the first sample, where ``ΔG`` is 0), zero where its variance is
    below :data:`TAG_VARIANCE_SHARE` of the sample's smallest white-noise variance and on
    padding; from a thrust problem's padded arrays ``kw`` and white-noise levels ``noise``
    (E, 2) rad/s."""
    out = np.zeros(np.shape(kw["omega"]))
    for e, b in enumerate(_noise_covs(kw, inertia, noise)):
        f = _gyroscopic(kw["omega"][e], kw["h_wheels"][e], inertia)
        term = 0.5 * time_tag_sd * np.concatenate([np.zeros((1, 3)), f[:-1] + f[1:]])
        small = np.sum((term @ _noise_whitener(b))**2, 1) < TAG_VARIANCE_SHARE
        out[e] = np.where((small | (np.asarray(kw["mask"][e]) <= 0))[:, None], 0.0, term)
    return np.ascontiguousarray(np.swapaxes(out, 1, 2))


def _noise_covs(kw: dict, inertia, noise) -> list[np.ndarray]:
    """Each event's white-noise covariance of one sample's left side (N m s)²."""
    i_sq = np.asarray(inertia, float) @ np.asarray(inertia, float)
    return [noise[e, 0]**2 * i_sq + noise[e, 1]**2 * kw["wheel_cov"][e]
            for e in range(len(kw["t"]))]


def events_tag_steps(kw: dict, inertia, noise, time_tag_sd) -> np.ndarray:
    """(E, P, 3, n) N m: every event's :func:`tag_step_columns`, one block per event (an event's
    ``δ_i`` move no other event), from a thrust problem's padded arrays ``kw`` (``t``, ``omega``,
    ``h_wheels``, ``mask``, ``wheel_cov``) and white-noise levels ``noise`` (E, 2) rad/s."""
    blocks = [tag_step_columns(kw["t"][e], kw["omega"][e], kw["h_wheels"][e], kw["mask"][e],
                               inertia, b, time_tag_sd)
              for e, b in enumerate(_noise_covs(kw, inertia, noise))]
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
    for e, b_hat in enumerate(_noise_covs(kw, i_lin, noise)):
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
