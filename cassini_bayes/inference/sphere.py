"""Directions on the unit sphere: summaries of draws of a unit vector (NumPy).

* :func:`mean_direction` — the normalised arithmetic mean of unit vectors (the maximum-likelihood
  mean direction of a von Mises–Fisher sample);
* :func:`cone_radii` — angular radii around a direction holding given fractions of the draws;
* :func:`direction_summary` — the ``direction`` entry of an RWA4 run's ``summary.json``
  (docs/design.md §4.5): ``{"mean": [x, y, z], "cone_deg": {"50": a, "90": b, "95": c}}``.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

__all__ = ["CONE_LEVELS", "mean_direction", "angles_deg", "cone_radii", "direction_summary"]

CONE_LEVELS = (50, 90, 95)


def mean_direction(draws) -> np.ndarray:
    """Unit mean direction (3,) of unit vectors ``draws`` (..., 3), flattened over draws.

    Raises ``ValueError`` when the resultant vanishes (draws spread evenly over the sphere).
    """
    x = np.asarray(draws, float).reshape(-1, 3)
    m = x.mean(0)
    norm = np.linalg.norm(m)
    if not norm > 1e-12:
        raise ValueError("the draws have no mean direction (zero resultant)")
    return m / norm


def angles_deg(draws, direction) -> np.ndarray:
    """Angles (deg) between each draw (flattened, (S,)) and ``direction`` (3,)."""
    x = np.asarray(draws, float).reshape(-1, 3)
    x = x / np.linalg.norm(x, axis=1, keepdims=True)
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    # atan2 of |cross| and dot: accurate for tiny angles too
    return np.degrees(np.arctan2(np.linalg.norm(np.cross(x, d), axis=1), x @ d))


def cone_radii(draws, direction=None, levels: Sequence[float] = CONE_LEVELS) -> dict[str, float]:
    """Angular radii (deg) of the cones about ``direction`` (default: the mean direction) holding
    ``levels`` percent of the draws, keyed by the level as a string (``"50"``, ``"90"``…)."""
    d = mean_direction(draws) if direction is None else direction
    a = angles_deg(draws, d)
    return {f"{lv:g}": float(np.percentile(a, lv)) for lv in levels}


def direction_summary(draws) -> dict:
    """``{"mean": [x, y, z], "cone_deg": {"50": a, "90": b, "95": c}}`` of unit-vector draws."""
    m = mean_direction(draws)
    return {"mean": [float(v) for v in m], "cone_deg": cone_radii(draws, m)}
