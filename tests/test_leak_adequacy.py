"""The adequacy verdict of ``monitor leak`` (:mod:`cassini_bayes.inference.leak_adequacy`).

Synthetic stretches (4 h at 1 s, Poisson pulses of 0.1 s at 0.7 N, white noise 0.007 N m s as
the simulator's, the torque and thrust errors drawn from the monitor's own priors), each with a
fixed generator, so every test is deterministic; the margins are in each docstring. The rates
over simulated cruise stretches are measured by ``benchmarks/verdict_false_alarms.py leak``
(docs/leak.md).
"""

from __future__ import annotations

import numpy as np

from cassini_bayes.estimators.leak import leak_torque
from cassini_bayes.inference.leak import LeakInputs, leak_posterior
from cassini_bayes.inference.leak_adequacy import leak_adequacy
from cassini_bayes.spacecraft import eq16_moment_matrix as moment_matrix

Q = np.asarray(moment_matrix(1.234, 1.580, 2.880, 3.019))
F_N, TORQUE_SD, ETA = 0.7, 15e-6, 0.05


def _stretch(seed: int, *, thrust_error=None, extra=None, leak=None) -> LeakInputs:
    """A 4 h residual momentum under the monitor's own model (``thrust_error`` (8,) fractions,
    default drawn with sd η; ``extra`` (n, 3) N m s added; ``leak`` (thruster, fraction,
    onset s))."""
    rng = np.random.default_rng(seed)
    t = np.arange(14401.0)
    j = np.cumsum(rng.poisson(0.02 / 60.0, (t.size, 8)) * 0.1 * F_N, axis=0)   # N s
    err = ETA * rng.standard_normal(8) if thrust_error is None else np.asarray(thrust_error)
    torque = TORQUE_SD * rng.standard_normal(3)
    r = (t[:, None] * torque + np.einsum("ak,nk->na", Q, err * j)
         + rng.normal(0.0, 0.007, (t.size, 3)))
    if extra is not None:
        r = r + extra(t)
    if leak is not None:
        k, f, t0 = leak
        r = r + np.clip(t - t0, 0, None)[:, None] * leak_torque(Q, k, f, F_N)[None, :]
    return LeakInputs(t, r, j, Q, np.full(8, F_N), TORQUE_SD)


def _checks(inp: LeakInputs) -> dict:
    post = leak_posterior(inp, check_step_s=600.0)
    return {c.name: c for c in leak_adequacy(inp, post, eta=ETA, sample_step_s=60.0,
                                             onset_step_s=20.0).checks}


def test_clean_stretches_and_a_modelled_leak_pass():
    """Data from the monitor's own model pass every check (observed: residual_fit ≤ 0.6,
    prior_data_conflict ≤ 2.5, autocorrelation ≤ 0.10; thresholds 4, 4, 0.5), with no leak and
    with a 0.5 % leak of Y2 from 1 h, which the checks take out as fitted."""
    for seed in range(3):
        for leak in (None, (5, 0.005, 3600.0)):
            c = _checks(_stretch(seed, leak=leak))
            assert c["residual_fit"].statistic < 2.0, c
            assert c["prior_data_conflict"].statistic < 3.0, c
            assert c["residual_autocorrelation"].statistic < 0.3, c


def test_a_wrong_thrust_in_the_model_fails_prior_data_conflict():
    """The deliberately wrong model: every thruster delivers 70 % of the model file's thrust.
    The monitor explains it by thrust errors near −30 %, 6 prior sd (η = 5 %) out: the check
    fails and names a thrust error (observed 6.2); with thrusts as modelled it passes (above)."""
    c = _checks(_stretch(1, thrust_error=np.full(8, -0.3)))
    pdc = c["prior_data_conflict"]
    assert not pdc.ok and pdc.statistic > 5.0 and pdc.parameter.startswith("thrust_error")


def test_an_unmodelled_wander_fails_the_residual_checks():
    """A torque that swings with a 2 h period (amplitude 0.2 N m s in the residual, some 30× the
    noise) is not in the monitor's model (a constant torque): the residual far exceeds the noise
    level read from the second differences, which a smooth swing does not raise, and is
    correlated from sample to sample (observed: residual_fit 40, the cap; ρ̂₁ 0.98)."""
    c = _checks(_stretch(2, extra=lambda t: 0.2 * np.sin(2 * np.pi * t / 7200.0)[:, None]
                         * np.array([1.0, -0.5, 0.3])[None, :]))
    assert not c["residual_fit"].ok and c["residual_fit"].statistic > 8.0
    assert not c["residual_autocorrelation"].ok
