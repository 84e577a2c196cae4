"""SBC of the exact health and leak models, with the statistics of
:mod:`cassini_bayes.analysis.sbc`.

Both models are exact (no sampler), so each replicate draws its truth from the model's own prior,
simulates the model's own data, and ranks the truth under the exact posterior:

* :func:`changepoint_sbc` — the change-point model of
  :mod:`cassini_bayes.inference.health.changepoint` on a fixed design (the event dates, standard
  errors and missing channels of one simulated campaign); ranks among ``n_draws`` exact draws of
  every channel's ``b``, ``d`` and ``sigma`` (:func:`changepoint_names`) and ``tau*`` (the
  change date, or a sentinel after the last event when there is none; ties broken at random);
* :func:`leak_sbc` — the Bayesian leak monitor of :mod:`cassini_bayes.inference.leak` on
  synthetic residuals drawn from its own model (offset, torque, thrust errors, white noise, a
  leak of a thruster drawn uniformly with the half-normal-mixture fraction and an onset uniform
  over the stretch). The monitor gives closed-form posteriors, not draws: the rank of the truth
  is ``⌊u (L + 1)⌋`` with ``u`` the posterior CDF at the truth, uniform on ``0..L`` exactly when
  ``u`` is uniform — for the leak fraction and the onset *given the true thruster*; and a
  calibration table of ``P(leak)``.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import numpy as np
from scipy.special import log_ndtr

from cassini_bayes.analysis.sbc import SbcResult, ranks, sbc_result

__all__ = ["changepoint_sbc", "changepoint_names", "leak_sbc", "LeakSbc", "calibration_table",
           "LEAK_NAMES"]

_CP_QUANTITIES = ("b", "d", "sigma")


def changepoint_names(channels) -> tuple[str, ...]:
    """The SBC parameters of the change-point model on ``channels`` (names): ``b[<channel>]``,
    ``d[<channel>]``, ``sigma[<channel>]`` per channel, then ``tau_star``."""
    return tuple(f"{a}[{c}]" for c in channels for a in _CP_QUANTITIES) + ("tau_star",)


LEAK_NAMES = ("fraction", "onset")


def changepoint_sbc(seed: int, n_replicates: int, dates, se, n_draws: int = 99,
                    prior=None, channels=None) -> SbcResult:
    """SBC of the change-point model on the design ``dates`` (N,), ``se`` (N, K) (NaN:
    missing); ``channels`` (K,) their names (default ``channel 0`` …)."""
    from cassini_bayes.inference.health import HealthPrior, health_posterior
    from cassini_bayes.inference.health.changepoint import SCATTER_GRID

    prior = prior or HealthPrior()
    rng = np.random.default_rng([seed, 1])
    t = np.asarray(dates, float)
    s = np.asarray(se, float)
    sentinel = t[-1] + 1.0
    k_ch = s.shape[-1]
    names = tuple(f"channel {k}" for k in range(k_ch)) if channels is None else tuple(channels)
    cols = [(a, k) for k in range(k_ch) for a in _CP_QUANTITIES]
    truth, draws = [], []
    for _ in range(n_replicates):
        change = rng.uniform() < prior.p_change
        tau = rng.uniform(t[0], t[-1]) if change else np.nan
        step = change & (rng.uniform(size=k_ch) < prior.p_channel)
        d = np.where(step, rng.normal(0.0, prior.step_sd, k_ch), 0.0)
        b = np.log(prior.nominal_thrust_n) + rng.normal(0.0, prior.baseline_sd, k_ch)
        sig = SCATTER_GRID[rng.integers(0, SCATTER_GRID.size, k_ch)]
        after = (t >= tau)[:, None] if change else np.zeros((t.size, 1), bool)
        y = b + d * after + rng.normal(size=s.shape) * np.sqrt(s ** 2 + sig ** 2)
        y = np.where(np.isfinite(s), y, np.nan)
        post = health_posterior(t, y, s, prior)
        dr = post.draws(rng, n_draws)
        tv = {"b": b, "d": d, "sigma": sig}
        truth.append([tv[a][k] for a, k in cols] + [tau if change else sentinel])
        draws.append([dr[a][:, k] for a, k in cols]
                     + [np.where(dr["change"], dr["tau"], sentinel)])
    truth, draws = np.array(truth), np.array(draws)                 # (R, P), (R, P, L)
    r = np.asarray(ranks(jax.random.key(seed), draws, truth))
    return sbc_result(changepoint_names(names), r, n_draws)


class LeakSbc(NamedTuple):
    """The leak monitor's SBC: ``result`` (fraction and onset, given the true thruster),
    ``prob`` (R, 9) the posterior of ``none, Z1 … Y4`` given all the data and ``truth`` (R,) the
    index of the true hypothesis."""

    result: SbcResult
    prob: np.ndarray
    truth: np.ndarray

    @property
    def p_leak(self) -> np.ndarray:
        return 1.0 - self.prob[:, 0]

    @property
    def leak(self) -> np.ndarray:
        return self.truth > 0


def _leak_design(rng, n: int, step_s: float, thrust_n: float, pulses_per_sample: float):
    """Times (n,) and modelled impulses (n, 8), N s: dead-band pulses of 0.1 s at random,
    ``pulses_per_sample`` per thruster between samples on average."""
    t = step_s * np.arange(n)
    inc = rng.poisson(pulses_per_sample, (n, 8)) * 0.1 * thrust_n
    inc[0] = 0.0
    return t, np.cumsum(inc, axis=0)


def leak_sbc(seed: int, n_replicates: int, *, hours: float = 4.0, prior_leak: float = 0.5,
             noise_nms: float = 0.007, pulses_per_sample: float = 0.02,
             n_draws: int = 99) -> LeakSbc:
    """SBC of the leak monitor under its own model (module docstring): ``hours`` of residual
    every :data:`~cassini_bayes.inference.leak.SAMPLE_STEP_S`, white noise ``noise_nms`` per
    sample and axis, ``pulses_per_sample`` 0.1 s pulses per thruster between samples, the
    monitor's priors (``prior_leak`` of a leak, shared by the eight thrusters; the spacecraft
    model ``cassini_post_probe``'s moment arms and torque prior).

    The torque is drawn from the monitor's scale-mixture prior (``TORQUE_SCALES``). The monitor
    takes its white-noise level from the data (median absolute second difference): where the
    thrust errors' share of each difference, ``δ_j Q[:, j] ΔJ_j``, is comparable with the noise
    (many pulses per sample), that level is too high and the fraction's posterior too wide
    (docs/sbc/leak/README.md)."""
    from cassini_bayes.estimators.leak import ETA
    from cassini_bayes.inference.leak import (FRACTION_SCALES, OFFSET_SD_NMS, SAMPLE_STEP_S,
                                              TORQUE_SCALES, LeakInputs, leak_posterior)
    from cassini_bayes.inference.leak._posterior import Sums
    from cassini_bayes.spacecraft import load_spacecraft

    sc = load_spacecraft("cassini_post_probe")
    q = sc.moment_matrix
    f_n, torque_sd = float(sc.thrust), sc.knowledge.torque_sd_nm
    rng = np.random.default_rng([seed, 2])
    n = int(round(hours * 3600.0 / SAMPLE_STEP_S)) + 1
    u_f, u_on, prob, truth = [], [], [], []
    for _ in range(n_replicates):
        t, j = _leak_design(rng, n, SAMPLE_STEP_S, f_n, pulses_per_sample)
        is_leak = rng.uniform() < prior_leak
        k = int(rng.integers(0, 8))
        frac = abs(rng.normal(0.0, FRACTION_SCALES[rng.integers(0, FRACTION_SCALES.size)]))
        onset = rng.uniform(0.0, t[-1])
        scales, weights = zip(*TORQUE_SCALES)
        t_sd = torque_sd * scales[rng.choice(len(scales), p=weights)]
        r = (rng.normal(0.0, OFFSET_SD_NMS, 3)[None, :]
             + t[:, None] * rng.normal(0.0, t_sd, 3)[None, :]
             + (j * rng.normal(0.0, ETA, 8)[None, :]) @ q.T
             + rng.normal(0.0, noise_nms, (n, 3)))
        if is_leak:
            r = r + frac * f_n * np.maximum(t - onset, 0.0)[:, None] * q[:, k][None, :]
        inp = LeakInputs(t, r, j, q, np.full(8, f_n), torque_sd)
        post = leak_posterior(inp, prior_leak=prior_leak, check_step_s=t[-1] + 1.0)
        prob.append(post.prob[-1])
        truth.append(1 + k if is_leak else 0)
        if not is_leak:
            continue
        # the true thruster's posterior of (onset, fraction) given all the data
        ev = Sums(inp, ETA, inp).check(n - 1)
        w, _, m, sd = ev.mixture(k)
        # P(f ≤ frac) of each node's normal cut at 0: 1 − Φ((m − frac)/sd) / Φ(m/sd)
        cdf = -np.expm1(log_ndtr((m - frac) / sd) - log_ndtr(m / sd))
        u_f.append(float(np.sum(w * np.clip(cdf, 0.0, 1.0))))
        u_on.append(ev.onset_cdf(k, onset))
    u = np.column_stack([u_f, u_on])
    rank = np.minimum(np.floor(u * (n_draws + 1)), n_draws).astype(int)
    return LeakSbc(sbc_result(LEAK_NAMES, rank, n_draws), np.array(prob), np.array(truth))


def calibration_table(p, outcome, edges=(0.0, 0.01, 0.1, 0.5, 0.9, 0.99, 1.0)) -> list[dict]:
    """Events with a predicted probability in each bin: count, mean predicted, observed rate and
    its binomial sd at the mean predicted probability."""
    p, outcome = np.asarray(p, float), np.asarray(outcome, bool)
    rows = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (p >= lo) & ((p < hi) if hi < 1.0 else (p <= hi))
        n = int(sel.sum())
        if not n:
            rows.append({"bin": [lo, hi], "n": 0})
            continue
        mp = float(p[sel].mean())
        rows.append({"bin": [lo, hi], "n": n, "mean_p": mp, "rate": float(outcome[sel].mean()),
                     "sd": float(np.sqrt(mp * (1 - mp) / n))})
    return rows
