"""The noise levels every calibration centres its noise prior on, from the one robust
white-noise estimator of the package, :func:`cassini_bayes.telemetry.white_noise_sd` (in the
pure layer, so that the input checks use it too). Each caller floors the levels
(:func:`floored`) so that noise-free synthetic data stay finite.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from cassini_bayes.telemetry import RATE_NOISE_FLOORS, Telemetry, white_noise_sd

__all__ = ["RATE_FLOORS", "ATTITUDE_FLOOR", "white_noise_sd", "floored",
           "rate_noise_levels"]

RATE_FLOORS = RATE_NOISE_FLOORS   # rad/s: gyro and wheel-rate levels below these are floored
ATTITUDE_FLOOR = 1e-9        # rad: attitude level floor


def floored(levels: Sequence[float], floors: Sequence[float]) -> np.ndarray:
    """``levels`` with each raised to its floor (same units)."""
    return np.maximum(np.array(levels, float), np.asarray(floors, float))


def rate_noise_levels(tel: Telemetry) -> np.ndarray:
    """White-noise levels ``(σ_ω, σ_ρ)`` (rad/s) of the body and wheel rates of one file.

    Median absolute deviation of second differences ÷ √6 (the sd of white noise; the median
    ignores the few samples where a pulse or a wheel ramp bends the signal), floored at 1e-9 and
    1e-7 rad/s so noise-free data stay finite. Only the centre of a wide prior.
    """
    rates = np.asarray(tel.wheel_rates, float)
    active = np.any(np.isfinite(rates), axis=0)   # noise: every wheel with data, idle or not
    s_r = white_noise_sd(rates[:, active]) if active.any() else 0.0
    s_w = white_noise_sd(np.asarray(tel.omega, float))
    return floored([s_w, s_r], RATE_FLOORS)
