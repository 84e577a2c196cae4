"""The thrust model's noise centre: white-noise levels from the second differences that no
thruster pulse bends (cassini_bayes.inference.noise)."""

from __future__ import annotations

import numpy as np

from cassini_bayes.inference.noise import MIN_UNBENT, pulse_bent, rate_noise_levels
from cassini_bayes.telemetry import Telemetry


def test_a_pulse_bends_the_differences_whose_samples_straddle_it():
    """A 0.1 s pulse at 3.2 s acts until 3.55 s: on 1 s samples it bends the second differences
    centred on samples 3 and 4 (spans (2, 4] and (3, 5]), and no other."""
    bent = pulse_bent(np.arange(10.0), np.array([3.2]), np.array([0.1]))
    assert np.flatnonzero(bent).tolist() == [2, 3]
    assert pulse_bent(np.arange(2.0), np.array([0.5]), np.array([0.1])).size == 0


def _stepped(n: int, every: int, rng) -> tuple[Telemetry, np.ndarray, np.ndarray]:
    """Rates with white noise 1e-6 rad/s (gyro) and 0.05 rad/s (wheels), the body rate stepped by
    ±1e-3 rad/s by a pulse every ``every`` samples."""
    t = np.arange(float(n))
    t_on = np.arange(1.3, n - 1, every)
    walk = np.r_[0.0, np.cumsum(rng.choice([-1e-3, 1e-3], size=t_on.size))]
    steps = walk[np.searchsorted(t_on, t, side="left")]    # the pulses commanded before each
    omega = 1e-6 * rng.normal(size=(n, 3)) + steps[:, None] * np.ones(3)
    wheels = 100.0 + 0.05 * rng.normal(size=(n, 4))
    q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    return Telemetry(t, q, omega, wheels), t_on, np.full(t_on.size, 0.1)


def test_pulse_free_differences_read_the_gyro_not_the_pulses():
    """With a pulse in every third interval (two of three second differences bent) the median of
    all differences reads the pulses (≥ 100 × the gyro's 1e-6 rad/s); the pulse-free ones give
    it within 20 % (sd of the estimate from ~130 × 3 differences ≈ 5 %, 4 sd). The wheels'
    level stays right."""
    tel, t_on, width = _stepped(400, 3, np.random.default_rng(3))
    plain = rate_noise_levels(tel)
    free = rate_noise_levels(tel, pulse_bent(tel.t, t_on, width))
    assert plain[0] > 100e-6
    assert abs(free[0] / 1e-6 - 1) < 0.2
    assert abs(free[1] / 0.05 - 1) < 0.2


def test_too_few_pulse_free_differences_use_them_all():
    """Fewer than MIN_UNBENT unbent differences: the estimate falls back on all of them."""
    tel, t_on, width = _stepped(MIN_UNBENT + 10, 1, np.random.default_rng(4))
    bent = pulse_bent(tel.t, t_on, width)
    assert np.count_nonzero(~bent) < MIN_UNBENT
    np.testing.assert_array_equal(rate_noise_levels(tel, bent), rate_noise_levels(tel))
