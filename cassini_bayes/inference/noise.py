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

__all__ = ["RATE_FLOORS", "ATTITUDE_FLOOR", "white_noise_sd", "quantisation_sd", "floored",
           "rate_noise_levels"]

RATE_FLOORS = (1e-9, 1e-7)   # rad/s: gyro and wheel-rate levels below these are floored
ATTITUDE_FLOOR = 1e-9        # rad: attitude level floor

_QUANT_REPEAT = 0.2    # share of exactly repeated samples that marks a rounded signal
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
    mad_sd = float(_MAD_TO_SD * np.median(np.abs(d - np.median(d))) / np.sqrt(6.0))
    return mad_sd if differenced else max(mad_sd, quantisation_sd(x))


def quantisation_sd(x: np.ndarray) -> float:
    """``q/√12`` when ``x`` (n, ...) is visibly rounded to a grid ``q`` (a tachometer's 1 rpm),
    else 0: at least :data:`_QUANT_REPEAT` of its steps are exact repeats and its other steps are
    whole multiples of the smallest one. Rounding then hides the noise from the second
    differences (mostly exact zeros: their MAD is 0), while the rounding error itself is a
    uniform error of sd ``q/√12`` (1-rpm tachometers had been read as noise-free, and the inertia
    fit came out 2.6 sd off with a residual false alarm)."""
    d = np.abs(np.diff(np.asarray(x, float), axis=0)).ravel()
    d = d[np.isfinite(d)]
    if d.size == 0 or np.mean(d == 0.0) < _QUANT_REPEAT:
        return 0.0
    steps = d[d > 0]
    if steps.size == 0:
        return 0.0
    q = float(steps.min())
    ratio = steps / q
    if np.mean(np.abs(ratio - np.round(ratio)) < 1e-6 * np.maximum(ratio, 1.0)) < 0.95:
        return 0.0
    return q / np.sqrt(12.0)


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
    active = tel.active_mask()
    s_r = white_noise_sd(rates[:, active]) if active.any() else 0.0
    s_w = white_noise_sd(np.asarray(tel.omega, float))
    return floored([s_w, s_r], RATE_FLOORS)
