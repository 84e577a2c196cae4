"""The noise levels every calibration centres its noise prior on, from the one robust
white-noise estimator of the package, :func:`cassini_bayes.telemetry.white_noise_sd` (in the
pure layer, so that the input checks use it too). Each caller floors the levels
(:func:`floored`) so that noise-free synthetic data stay finite.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from cassini_bayes.telemetry import RATE_NOISE_FLOORS, Telemetry, white_noise_sd

__all__ = ["RATE_FLOORS", "ATTITUDE_FLOOR", "MIN_UNBENT", "PULSE_SETTLE_S", "white_noise_sd",
           "floored", "pulse_bent", "rate_noise_levels"]

RATE_FLOORS = RATE_NOISE_FLOORS   # rad/s: gyro and wheel-rate levels below these are floored
ATTITUDE_FLOOR = 1e-9        # rad: attitude level floor


def floored(levels: Sequence[float], floors: Sequence[float]) -> np.ndarray:
    """``levels`` with each raised to its floor (same units)."""
    return np.maximum(np.array(levels, float), np.asarray(floors, float))


MIN_UNBENT = 20
"""Fewest unbent second differences :func:`rate_noise_levels` estimates from; with fewer it
uses them all."""


def rate_noise_levels(tel: Telemetry, bent: np.ndarray | None = None) -> np.ndarray:
    """White-noise levels ``(σ_ω, σ_ρ)`` (rad/s) of the body and wheel rates of one file.

    Median absolute deviation of second differences ÷ √6 (the sd of white noise; the median
    ignores the few samples where a pulse or a wheel ramp bends the signal), floored at 1e-9 and
    1e-7 rad/s so noise-free data stay finite. Only the centre of a wide prior.
    ``bent``: (n − 2,) bool, the second differences (centred on samples 1 … n − 2) that a known
    input bends, e.g. a thruster pulse (:func:`pulse_bent`); left out when at least
    :data:`MIN_UNBENT` others remain: a controller that fires between most samples bends more
    of them than a median can ignore.
    """
    keep = None
    if bent is not None and np.count_nonzero(~np.asarray(bent, bool)) >= MIN_UNBENT:
        keep = ~np.asarray(bent, bool)
    rates = np.asarray(tel.wheel_rates, float)
    active = np.any(np.isfinite(rates), axis=0)   # noise: every wheel with data, idle or not
    s_r = white_noise_sd(rates[:, active], keep=keep) if active.any() else 0.0
    s_w = white_noise_sd(np.asarray(tel.omega, float), keep=keep)
    return floored([s_w, s_r], RATE_FLOORS)


PULSE_SETTLE_S = 0.25
"""s after a pulse's commanded end during which it still acts (valve fall and delay)."""


def pulse_bent(t: np.ndarray, t_on: np.ndarray, width: np.ndarray) -> np.ndarray:
    """(n − 2,) bool: second difference ``i`` (samples ``i, i + 1, i + 2`` at times ``t``, s)
    spans a pulse commanded at ``t_on`` for ``width`` (s), which acts from its command until
    :data:`PULSE_SETTLE_S` after its end."""
    t = np.asarray(t, float)
    if t.size < 3:
        return np.zeros(0, bool)
    start = np.asarray(t_on, float)
    end = start + np.asarray(width, float) + PULSE_SETTLE_S
    lo, hi = t[:-2], t[2:]
    order = np.argsort(start)
    start, end = start[order], np.maximum.accumulate(end[order]) if start.size else end
    # a pulse overlaps (lo, hi] when it starts by hi and ends after lo: among the pulses that
    # start by hi (a prefix, start sorted), the latest end (running max) is after lo
    k = np.searchsorted(start, hi, side="right")
    ends = np.r_[-np.inf, end]
    return ends[k] > lo
