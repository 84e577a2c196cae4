"""Thrust against mission time with posterior bands: the figure of a health fit (Agg)."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

__all__ = ["plot_health", "health_page"]


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


HEALTH_NOTE = ("Self-checks of the health fit that need no truth. inertia_conflict: each event "
               "refitted with its own principal moments; the change of each channel's thrust "
               "that the events do not share, in the event's own sd (the health model takes the "
               "spacecraft model's inertia as exact up to a scale shared by all events). "
               "held_out: each event's thrust against the change-point posterior of the other "
               "events. Thresholds and the false-alarm rates measured on correctly specified "
               "campaigns: docs/health.md.")


def health_page(summary: dict, png: bytes, files) -> str:
    """``report.html`` of a health fit: the adequacy badge and section, the figure of
    :func:`plot_health` (``png``), the channels at the last event and the events read
    (``files``: (date, telemetry, pulses) each)."""
    from cassini_bayes.report.adequacy import adequacy_section, verdict_header
    from cassini_bayes.report.html import figure, html_page, section, table
    from cassini_bayes.report.tables import fmt

    rows = [[name, c["n_events"], fmt(c["p_down_last"], 3), fmt(c["ratio_last_mean"], 4),
             f"[{fmt(c['ratio_last_90'][0], 4)}, {fmt(c['ratio_last_90'][1], 4)}]",
             fmt(c["p_step_given_change"], 3)] for name, c in summary["channels"].items()]
    lo, hi = summary["change_date_days"]["interval_90"]
    frac = summary["fraction"]
    return html_page("Thruster health", [
        adequacy_section(summary, HEALTH_NOTE),
        section("Thrust over time", figure(png, "Thrust relative to the first calibration: "
                                           "posterior median, 50 % and 90 % bands; dots are "
                                           "the events' estimates")),
        section("Channels at the last event", [
            table(["channel", "events", f"P(> {frac:.0%} down)", "thrust ratio, mean",
                   "90 % interval", "P(step | change)"], rows),
            f"<p>P(change) = {fmt(summary['p_change'], 3)}; change date 90 % interval "
            f"[{lo:.0f}, {hi:.0f}] d (given a change).</p>"]),
        section("Events", table(["date, d", "telemetry", "pulses"],
                                [[f"{d:g}", str(t), str(p)] for d, t, p in files], left=3))],
        header=verdict_header(summary))
