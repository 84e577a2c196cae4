"""Propagating posterior draws through a budget line: credible interval and attribution.

A *budget line* is a function of calibrated parameters, ``line(draws) -> (n,)``: ``draws`` maps
each parameter name to its ``n`` posterior draws, shape ``(n,)`` for a scalar parameter or
``(n, k)`` for a vector one (the RWA4 axis). :func:`propagate` evaluates the line on the joint draws
and returns

* the line's posterior median and equal-tailed credible interval (default 90 %: the 5th and 95th
  percentiles of the line's draws);
* its **attribution**: for each parameter, the share of the line's posterior variance it explains
  *one at a time*: the line evaluated with that parameter at its draws and every other parameter
  at its posterior median, ``share_p = Var(line | only p varies) / Var(line)``.

The one-at-a-time shares sum to 1 for a line that is a sum of terms of one parameter each, with
independent parameters; the sum (``share_sum``) departs from 1 by the part of the variance due to
interactions (a product, a maximum, an absolute value near zero) and to posterior correlations
between the parameters, which the one-at-a-time evaluation drops (the interval itself uses the
joint draws, correlations included). A line that depends on one parameter only gets 100 % on it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import NamedTuple

import numpy as np

__all__ = ["LineInterval", "credible_interval", "propagate"]

Draws = Mapping[str, np.ndarray]
Line = Callable[[Draws], np.ndarray]


class LineInterval(NamedTuple):
    """A budget line propagated from posterior draws (values in the line's unit).

    Attributes
    ----------
    median : posterior median of the line.
    low, high : equal-tailed credible interval at ``level``.
    level : credible level (0.9: the 5th and 95th percentiles).
    shares : parameter → share of the line's variance it explains alone (0-1; module docstring).
    share_sum : sum of ``shares`` (1 for an additive line of independent parameters).
    n_draws : number of joint draws.
    """

    median: float
    low: float
    high: float
    level: float
    shares: dict[str, float]
    share_sum: float
    n_draws: int

    def to_dict(self) -> dict:
        return {"median": self.median, "low": self.low, "high": self.high, "level": self.level,
                "shares": dict(self.shares), "share_sum": self.share_sum,
                "n_draws": self.n_draws}

    def text(self, decimals: int = 3) -> str:
        """``median [low, high]`` with ``decimals`` significant figures."""
        g = f".{decimals}g"
        return f"{self.median:{g}} [{self.low:{g}}, {self.high:{g}}]"


def credible_interval(values, level: float = 0.9) -> tuple[float, float, float]:
    """``(median, low, high)`` of ``values``: the equal-tailed interval at ``level``."""
    if not 0.0 < level < 1.0:
        raise ValueError(f"level must be in (0, 1), got {level}")
    v = np.asarray(values, float).ravel()
    q = 100.0 * (1.0 - level) / 2.0
    med, lo, hi = np.percentile(v, [50.0, q, 100.0 - q])
    return float(med), float(lo), float(hi)


def _median_center(draws: Draws) -> dict[str, np.ndarray]:
    """Posterior median of every parameter (component-wise for a vector parameter)."""
    return {k: np.median(np.asarray(v, float), axis=0) for k, v in draws.items()}


def _n_draws(draws: Draws) -> int:
    sizes = {np.shape(v)[0] for v in draws.values()}
    if len(sizes) != 1:
        raise ValueError(f"every parameter needs the same number of draws, got {sorted(sizes)}")
    return sizes.pop()


def propagate(line: Line, draws: Draws, *, level: float = 0.9,
              center: Mapping[str, np.ndarray] | None = None) -> tuple[np.ndarray, LineInterval]:
    """The line's draws and their :class:`LineInterval` (module docstring).

    Parameters
    ----------
    line : ``line(draws) -> (n,)``, vectorised over the leading (draw) axis.
    draws : parameter → (n,) or (n, k) joint posterior draws.
    level : credible level of the interval.
    center : parameter → value the others are held at in the attribution (default: the
        posterior medians).

    Returns
    -------
    values : (n,) the line at every joint draw.
    interval : LineInterval
    """
    if not draws:
        raise ValueError("propagate needs at least one parameter")
    n = _n_draws(draws)
    draws = {k: np.asarray(v, float) for k, v in draws.items()}
    center = dict(_median_center(draws) if center is None else center)
    values = np.asarray(line(draws), float).reshape(n)
    med, lo, hi = credible_interval(values, level)
    total = float(np.var(values))
    shares = {}
    for name in draws:
        alone = {k: (v if k == name else np.broadcast_to(center[k], v.shape))
                 for k, v in draws.items()}
        var = float(np.var(np.asarray(line(alone), float)))
        shares[name] = var / total if total > 0 and var > 1e-12 * total else 0.0
    return values, LineInterval(med, lo, hi, level, shares, float(sum(shares.values())), n)
