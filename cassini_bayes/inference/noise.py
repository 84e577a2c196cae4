"""The one robust white-noise estimator of the package (every calibration centres its noise
prior on it).

For white noise of sd ``σ`` on a smooth signal, second differences have sd ``√6 σ``; the median
absolute deviation (× 1.4826, the normal's MAD-to-sd factor) ignores the few samples where the
signal itself bends (a pulse, a wheel ramp, the slew profile). Each caller floors the levels
(:func:`floored`) so that noise-free synthetic data stay finite.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from cassini_bayes.telemetry import Telemetry

__all__ = ["RATE_FLOORS", "ATTITUDE_FLOOR", "white_noise_sd", "floored",
           "rate_noise_levels"]

RATE_FLOORS = (1e-9, 1e-7)   # rad/s: gyro and wheel-rate levels below these are floored
ATTITUDE_FLOOR = 1e-9        # rad: attitude level floor

_MAD_TO_SD = 1.4826


def white_noise_sd(x: np.ndarray, *, differenced: bool = False) -> float:
    """Robust sd of white noise on a smooth signal ``x`` (n, ...) sampled along axis 0: the MAD
    of its second differences (all components pooled, non-finite values left out) ÷ √6.

    ``differenced``: ``x`` already holds the signal's first differences (e.g. attitude
    increments ``rotvec(q_{t+1} q_t⁻¹)``), so one more difference is taken. 0 when the signal
    has fewer than four samples or no finite difference.
    """
    order = 1 if differenced else 2
    if x.shape[0] < 2 + order or x.size == 0:
        return 0.0
    d = np.diff(x, n=order, axis=0).ravel()
    d = d[np.isfinite(d)]
    if d.size == 0:
        return 0.0
    return float(_MAD_TO_SD * np.median(np.abs(d - np.median(d))) / np.sqrt(6.0))


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
