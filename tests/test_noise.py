"""White-noise levels of rate telemetry (cassini_bayes.inference.noise)."""

from __future__ import annotations

import numpy as np

from cassini_bayes.inference.noise import quantisation_sd, white_noise_sd
from cassini_bayes.telemetry import RPM_TO_RAD_S


def test_a_rounded_tachometer_is_not_read_as_noise_free():
    """A wheel's rate with 0.06 rpm of noise, rounded to 1 rpm as many tachometers report it:
    the second differences are mostly exact zeros (MAD 0), so the level is the rounding's own
    sd, 1/√12 rpm; without rounding the MAD estimate (0.06 rpm, to 5 % on 3 000 samples: its sd
    is 2 %); a ramp or a constant is not mistaken for a rounded signal."""
    rng = np.random.default_rng(0)
    t = np.arange(3000.0)
    rpm = 500.0 + 0.05 * t + rng.normal(0.0, 0.06, t.size)
    rounded = np.round(rpm)[:, None] * RPM_TO_RAD_S
    assert white_noise_sd(rounded) == quantisation_sd(rounded)
    assert abs(white_noise_sd(rounded) / (RPM_TO_RAD_S / np.sqrt(12.0)) - 1) < 1e-9
    raw = rpm[:, None] * RPM_TO_RAD_S
    assert quantisation_sd(raw) == 0.0
    assert abs(white_noise_sd(raw) / (0.06 * RPM_TO_RAD_S) - 1) < 0.1
    ramp = (500.0 + 0.25 * t)[:, None] * RPM_TO_RAD_S
    assert quantisation_sd(ramp) == 0.0
    assert quantisation_sd(np.full((100, 1), 3.0)) == 0.0
