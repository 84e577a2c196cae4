"""Linear interpolation between vector updates (Lee §3.3.3).

The flight software evaluates each vector (conic or polynomial) only every ``h`` seconds (100 s
"even for the most rapidly varying trajectory segments") and interpolates linearly in between.
:func:`interpolation_error` measures the angle that costs against the true vector.

Why it is small even at a close flyby: between updates the interpolated vector is off by
``−½ s(1−s) h² r̈ − ⅙ s(1−s)(1−2s) h³ r⃛`` (``s`` the fraction of the interval). For a vector from
the attracting body, ``r̈`` is along ``r`` itself, so the first term changes the length, not the
direction; the direction error comes from the ``h³`` term only.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from cassini_bayes.ivp._checks import check_interval, check_positive
from cassini_bayes.ivp.segmenter import angle_between_vectors

__all__ = ["interpolation_error"]


def interpolation_error(f: Callable[[np.ndarray], np.ndarray], t_start_s: float,
                        t_end_s: float, update_interval_s: float,
                        per_interval: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """Angle (rad) between ``f`` and its linear interpolation between updates every
    ``update_interval_s`` (s) from ``t_start_s``; returns ``(t_s, angle_rad)`` on
    ``per_interval`` points inside each interval (the updates themselves excluded: zero
    error there)."""
    check_interval(float(t_start_s), float(t_end_s), "the span")
    check_positive(update_interval_s, "update_interval_s")
    n = max(int(np.ceil((t_end_s - t_start_s) / update_interval_s)), 1)
    knots = t_start_s + update_interval_s * np.arange(n + 1)
    values = np.asarray(f(knots), float)
    s = (np.arange(per_interval) + 0.5) / per_interval
    t = (knots[:-1, None] + update_interval_s * s[None, :]).reshape(-1)
    w = np.tile(s, n)[:, None]
    k = np.repeat(np.arange(n), per_interval)
    interp = (1.0 - w) * values[k] + w * values[k + 1]
    return t, angle_between_vectors(interp, np.asarray(f(t), float))
