"""Stale samples: a telemetry packet that repeats its neighbour's data.

A ground system that fills a lost packet with the last one received, or a time-tag slip of one
sample, leaves a row whose attitude, body rates and wheel rates equal its neighbour's exactly.
Sensor noise makes that impossible for a fresh sample. Across a thruster pulse the repeated rate
is a whole rate step away from the true one: on a small spacecraft a thousand gyro noise sds,
which one Gaussian likelihood cannot carry. The fits leave such rows out, with a warning.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

from cassini_bayes.telemetry._noise import white_noise_sd
from cassini_bayes.telemetry._types import Telemetry

__all__ = ["StaleSamplesWarning", "stale_samples", "without_stale_samples"]


NOISE_MIN_REL = 1e-9
"""A gyro axis whose white noise is below this fraction of the largest rate shows float rounding,
not sensor noise: its telemetry is noise-free, and quiet samples may repeat."""


class StaleSamplesWarning(UserWarning):
    """Samples that repeat a neighbour's data exactly were left out of a fit."""


def _same_as(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rows of ``a`` equal to those of ``b`` in every channel (NaN equal to NaN)."""
    return np.all((a == b) | (np.isnan(a) & np.isnan(b)), axis=1)


def stale_samples(tel: Telemetry) -> np.ndarray:
    """(n,) bool: the samples whose attitude, body rates and wheel rates all equal those of the
    sample before or after them (module docstring). Both of an equal pair: which of the two times
    the data belong to, the data cannot tell. None where a gyro axis shows no noise
    (:data:`NOISE_MIN_REL`) or three samples in a row are equal: noise-free or synthetic
    telemetry, whose quiet samples repeat."""
    omega = np.asarray(tel.omega, float)
    scale = float(np.max(np.abs(omega), initial=0.0))
    if tel.n < 3 or not all(white_noise_sd(omega[:, a]) > NOISE_MIN_REL * scale
                            for a in range(3)):
        return np.zeros(tel.n, bool)
    data = np.concatenate([np.asarray(tel.q, float), np.asarray(tel.omega, float),
                           np.asarray(tel.wheel_rates, float)], axis=1)
    same = _same_as(data[1:], data[:-1])
    if np.any(same[1:] & same[:-1]):
        return np.zeros(tel.n, bool)      # three equal samples: noise-free where it is quiet
    return np.r_[same, False] | np.r_[False, same]


def without_stale_samples(tel: Telemetry) -> Telemetry:
    """``tel`` without its stale samples (:func:`stale_samples`), with a
    :class:`StaleSamplesWarning` naming them; ``tel`` itself when it has none."""
    stale = stale_samples(tel)
    if not stale.any():
        return tel
    rows = np.flatnonzero(stale)
    shown = ", ".join(f"{i + 1} (t = {tel.t[i]:.6g} s)" for i in rows[:5])
    more = f" and {rows.size - 5} more" if rows.size > 5 else ""
    warnings.warn(f"{tel.source}: {rows.size} sample(s) repeat a neighbour's attitude, rates and "
                  f"wheel rates exactly (a stale packet), left out of the fit: data row(s) "
                  f"{shown}{more}", StaleSamplesWarning, stacklevel=2)
    keep = ~stale
    return replace(tel, t=tel.t[keep], q=tel.q[keep], omega=tel.omega[keep],
                   wheel_rates=tel.wheel_rates[keep],
                   on_times=None if tel.on_times is None else tel.on_times[keep])
