"""Per-pulse impulses of a thrust fit (``pulse_impulses`` group; the thrust report's plot)."""

from __future__ import annotations

import jax
import numpy as np
import pytest

from cassini_bayes.inference.thrust.pulses import pulse_groups, pulse_impulses


def test_pulse_groups_join_overlapping_spans():
    """A group runs from the sample before its first pulse to the sample at which its last has
    delivered everything (``k`` samples after its first); overlapping spans join; a group that
    starts at the first sample or ends past the last is left out; padding (width 0) is not a
    pulse."""
    slot = np.array([5, 6, 12, 0, 18, 20])
    width = np.array([0.125, 0.25, 0.125, 0.125, 0.5, 0.0])
    groups = pulse_groups(slot, width, n=20, k=3)
    assert groups == [(4, 9, [0, 1]), (11, 15, [2])]
    # spans that only touch (one ends where the next starts) stay apart
    assert pulse_groups(np.array([5, 9]), np.array([0.1, 0.1]), n=20, k=3) == [
        (4, 8, [0]), (8, 12, [1])]


class _Post(dict):
    """A posterior group stand-in: ``name -> object with .values (1, S[, E])``."""

    def __init__(self, **arrays):
        super().__init__({k: type("V", (), {"values": np.asarray(v, float)})()
                          for k, v in arrays.items()})


@pytest.mark.slow
def test_measured_impulses_agree_with_the_truth_and_catch_a_wrong_thrust():
    """On the FSDS biasing event (truth: 0.75 N, 5/20/65 ms, the model's inertia), a "posterior"
    sitting at the truth predicts each group's measured impulse within the telemetry noise: the
    normalised misfits have mean 0 and sd 1 (tolerances 0.4 and [0.6, 1.6], many sd wide for
    ~100 groups of known noise; false failure below 1e-4). Predicted 5 % too strong, the
    misfits' mean moves by far more than that tolerance: the check can fail."""
    from cassini_bayes.inference.thrust.data import prepare_thrust
    from cassini_bayes.simulate import load_scenario, simulate

    scenario = load_scenario("fsds_biasing")
    r = simulate(jax.random.key(11), scenario)
    problem = prepare_thrust([(r.telemetry, r.pulses)], scenario.prior)
    noise = np.asarray(problem.noise_hat)[0]
    s = 50

    def misfits(thrust_n):
        post = _Post(F=np.full((1, s), thrust_n), tau_delay=np.full((1, s), 0.005),
                     tau_rise=np.full((1, s), 0.020), tau_fall=np.full((1, s), 0.065),
                     sigma_omega=np.full((1, s, 1), noise[0]),
                     sigma_rho=np.full((1, s, 1), noise[1]))
        g = pulse_impulses(problem, post)
        assert g["predicted"].dims == ("group", "quantile")
        return (g["measured"].values - g["predicted"].values[:, 1]) / g["measured_sd"].values

    z = misfits(0.75)
    assert z.size >= 30
    assert abs(z.mean()) < 0.4 and 0.6 < z.std() < 1.6
    assert misfits(0.75 * 1.05).mean() < -3.0
