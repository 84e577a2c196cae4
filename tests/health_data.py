"""Synthetic thruster-health series: event dates and per-event log-thrust summaries of Cassini's
six channels, with a known step on chosen channels from a known day."""

from __future__ import annotations

import numpy as np

__all__ = ["synthetic_events"]


def synthetic_events(seed: int, n: int = 14, drop: float = 0.0, day: float = 200.0,
                     channels=(2, 3), se: float = 0.01, scatter: float = 0.01):
    """Event dates over 365 days and log-thrust summaries with a step of ``drop`` on
    ``channels`` from ``day`` (uniform, not Gaussian, scatter: not the model's law)."""
    rng = np.random.default_rng(seed)
    t = np.sort(np.r_[0.0, rng.uniform(0.0, 365.0, n - 1)])
    y = np.log(0.699) + rng.uniform(-0.03, 0.03, 6)[None, :] + np.zeros((n, 6))
    y = y + rng.normal(0.0, se, (n, 6)) + rng.uniform(-1.0, 1.0, (n, 6)) * scatter * np.sqrt(3)
    after = t >= day
    for k in channels:
        y[after, k] += np.log1p(-drop)
    return t, y, np.full((n, 6), se)
