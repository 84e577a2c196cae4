"""Thrust against mission time with posterior bands: the figure of a health fit (Agg)."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

__all__ = ["plot_health"]


def plot_health(post, fraction: float = 0.05, n_grid: int = 300) -> Figure:
    """One panel per channel (``Z1 … Z4``, ``Y13``, ``Y24``): the thrust relative to the first
    calibration, posterior median with 50 % and 90 % bands (exact draws, seed 0), each event's
    estimate over the posterior baseline (±1 sd), the ``1 − fraction`` line, and below each
    panel's title the posterior ``P(down by more than fraction)`` at the last event."""
    from cassini_bayes.inference.health import CHANNELS

    grid = np.linspace(post.dates[0], post.dates[-1], n_grid)
    q = post.relative_thrust_bands(grid, np.random.default_rng(0), 4000,
                                   (0.05, 0.25, 0.5, 0.75, 0.95))
    base = post.draws(np.random.default_rng(1), 2000)["b"].mean(axis=0)   # first calibration
    fig = Figure(figsize=(11.0, 6.2))
    axes = fig.subplots(2, 3, sharex=True).ravel()
    for k, (ax, name) in enumerate(zip(axes, CHANNELS)):
        ax.fill_between(grid, q[k, :, 0], q[k, :, 4], color="#9ecae1", lw=0, label="90 %")
        ax.fill_between(grid, q[k, :, 1], q[k, :, 3], color="#4292c6", lw=0, label="50 %")
        ax.plot(grid, q[k, :, 2], color="#08306b", lw=1.2, label="median")
        ok = np.isfinite(post.y[:, k])
        r = np.exp(post.y[ok, k] - base[k])
        ax.errorbar(post.dates[ok], r, yerr=r * np.minimum(post.s[ok, k], 0.2), fmt=".",
                    color="0.3", ms=4, lw=0.6, label="event estimate")
        ax.axhline(1.0 - fraction, color="firebrick", lw=0.8, ls="--")
        p = post.p_down([k], fraction)[-1]
        ax.set_title(f"{name}: P(>{fraction:.0%} down) = {p:.3f}", fontsize=9)
        ax.set_ylim(0.85, 1.1)
        ax.grid(alpha=0.3)
    for ax in axes[3:]:
        ax.set_xlabel("days after the first event")
    for ax in axes[::3]:
        ax.set_ylabel("thrust / first calibration")
    axes[0].legend(fontsize=7, loc="lower left")
    lo, hi = post.change_date_interval(0.9)
    fig.suptitle(f"Thruster health: P(change) = {post.p_change:.3f}; change date 90 % interval "
                 f"[{lo:.0f}, {hi:.0f}] d (given a change)", fontsize=10)
    fig.tight_layout()
    return fig
