"""The thruster-health report (``report.html`` of ``fit health``) and its figure: thrust against
mission time with posterior bands (Agg).

The page opens with the answer: per channel, the thrust at the last event relative to the first
calibration, the probability it is down by more than the asked fraction and the verdict, beside
the papers' per-event least squares and the model file's thrust; the adequacy verdict and the
change point under it.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

__all__ = ["plot_health", "health_report_html", "REQUIREMENT_PROB", "HEALTH_NOTE"]

REQUIREMENT_PROB = 0.95   # a channel is called down (or not) at this posterior probability
HEALTH_NOTE = ("Self-checks of the health fit that need no truth. inertia_conflict: each event "
               "refitted with its own principal moments; the change of each channel's thrust "
               "that the events do not share, in the event's own sd (the health model takes the "
               "spacecraft model's inertia as exact up to a scale shared by all events). "
               "held_out: each event's thrust against the change-point posterior of the other "
               "events. Thresholds and the false-alarm rates measured on correctly specified "
               "campaigns: docs/health.md.")


def plot_health(post, fraction: float = 0.05, n_grid: int = 300) -> Figure:
    """One panel per channel (the fit's channels, e.g. Cassini's ``F[Z1]`` … and its Y-pair
    means): the thrust relative to the first
    calibration, posterior median with 50 % and 90 % bands (exact draws, seed 0), each event's
    estimate over the posterior baseline (±1 sd), the ``1 − fraction`` line, and below each
    panel's title the posterior ``P(down by more than fraction)`` at the last event."""
    from cassini_bayes.report.figures import tidy_ticks

    grid = np.linspace(post.dates[0], post.dates[-1], n_grid)
    q = post.relative_thrust_bands(grid, np.random.default_rng(0), 4000,
                                   (0.05, 0.25, 0.5, 0.75, 0.95))
    base = post.draws(np.random.default_rng(1), 2000)["b"].mean(axis=0)   # first calibration
    k_ch = len(post.channels)
    ncol = min(k_ch, 3 if k_ch <= 6 else 4)
    nrow = -(-k_ch // ncol)
    fig = Figure(figsize=(3.7 * ncol, 3.3 * nrow))
    axes = np.atleast_1d(fig.subplots(nrow, ncol, sharex=True, squeeze=False).ravel())
    for ax in axes[k_ch:]:
        ax.set_visible(False)
    for k, (ax, name) in enumerate(zip(axes, post.channels)):
        ax.fill_between(grid, q[k, :, 0], q[k, :, 4], color="#9ecae1", lw=0, label="90 %")
        ax.fill_between(grid, q[k, :, 1], q[k, :, 3], color="#4292c6", lw=0, label="50 %")
        ax.plot(grid, q[k, :, 2], color="#08306b", lw=1.2, label="median")
        ok = np.isfinite(post.y[:, k])
        r = np.exp(post.y[ok, k] - base[k])
        ax.errorbar(post.dates[ok], r, yerr=r * np.minimum(post.s[ok, k], 0.2), fmt=".",
                    color="0.3", ms=4, lw=0.6, label="event estimate")
        ax.axhline(1.0 - fraction, color="firebrick", lw=0.8, ls="--")
        p = post.p_down([k], fraction)[-1]
        ax.set_title(f"{name}\nP(>{fraction:.0%} down) = {p:.3f}", fontsize=8)
        ax.set_ylim(0.85, 1.1)
        ax.grid(alpha=0.3)
        ax.set_xlabel("days after the first event (d)", fontsize=8)
        ax.set_ylabel("thrust / first calibration (ratio)", fontsize=8)
        ax.xaxis.set_tick_params(labelbottom=True)
        tidy_ticks(ax, x=5, y=4)
    axes[0].legend(fontsize=7, loc="lower left")
    lo, hi = post.change_date_interval(0.9)
    fig.suptitle(f"Thruster health: P(change) = {post.p_change:.3f}; change date 90 % interval "
                 f"[{lo:.0f}, {hi:.0f}] d (given a change)", fontsize=10)
    fig.subplots_adjust(left=0.07, right=0.98, bottom=0.09, top=1.0 - 0.55 / (3.3 * nrow),
                        wspace=0.32, hspace=0.5)
    return fig


def _verdict(p_down: float) -> tuple[str, bool | None]:
    """Down with probability ≥ 0.95, healthy at ≤ 0.05, else undecided (the data do not
    settle it)."""
    if p_down >= REQUIREMENT_PROB:
        return "DOWN", False
    if p_down <= 1.0 - REQUIREMENT_PROB:
        return "healthy", True
    return "undecided", None


def health_report_html(res, png: bytes) -> str:
    """The self-contained ``report.html`` of a health fit
    (:class:`~cassini_bayes.api.HealthResult`) with ``png``, the figure of :func:`plot_health`:
    the answer table and the figure, the adequacy verdict, the change point, the events."""
    from cassini_bayes import __version__
    from cassini_bayes.report.adequacy import adequacy_section
    from cassini_bayes.report.build import verdict_badges
    from cassini_bayes.report.html import (Raw, badge, details, figure, html_page, page_header,
                                           paragraph, section, table)

    post, s, frac = res.posterior, res.summary(), res.fraction
    first = np.exp(post.draws(np.random.default_rng(1), 2000)["b"])    # N, first calibration
    nominal = np.broadcast_to(np.asarray(post.prior.nominal_thrust_n, float),
                              (len(post.channels),))
    rows, classes, calls = [], [], []
    for k, name in enumerate(post.channels):
        c = s["channels"][name]
        ok = np.flatnonzero(np.isfinite(post.y[:, k]))
        ls = (f"{np.exp(post.y[ok[-1], k] - post.y[ok[0], k]):.3f}" if ok.size > 1 else "–")
        f_lo, f_hi = np.quantile(first[:, k], [0.05, 0.95])
        word, good = _verdict(c["p_down_last"])
        calls.append(good)
        lo, hi = c["ratio_last_90"]
        rows.append([name, "ratio", f"{c['ratio_last_mean']:.3f}", f"[{lo:.3f}, {hi:.3f}]", ls,
                     f"{c['p_down_last']:.3f}", f"{first[:, k].mean():.3f} [{f_lo:.3f}, "
                     f"{f_hi:.3f}]", f"{nominal[k]:.3f}", str(c["n_events"]),
                     Raw(badge(word, good))])
        classes.append([""] * 5 + ["bad" if good is False else ("good" if good else "warn")]
                       + [""] * 4)
    answer = table(["channel", "unit", "thrust at the last event / first calibration: posterior "
                    "mean", "90 % interval", "least squares (papers): last / first event",
                    f"P(more than {frac:.0%} down)", "first calibration (N): mean [90 %]",
                    "model file (N)", "events", "verdict"], rows, left=1, classes=classes)
    lo, hi = s["change_date_days"]["interval_90"]
    change = table(["quantity", "unit", "value"], [
        ["P(a change in the span)", "–", f"{s['p_change']:.3f}"],
        ["change date, median (given a change)", "d", f"{s['change_date_days']['median']:.0f}"],
        ["change date, 90 % interval (given a change)", "d", f"[{lo:.0f}, {hi:.0f}]"],
        *[[f"P({'any channel' if g == 'any' else g} more than {frac:.0%} down at the last "
            "event)", "–", f"{p:.3f}"] for g, p in s.get("p_down_last", {}).items()],
        *[[f"P({name} stepped | a change)", "–", f"{c['p_step_given_change']:.3f}"]
          for name, c in s["channels"].items()],
        ["events", "–", f"{s['n_events']} over [{s['first_date_days']:.0f}, "
                        f"{s['last_date_days']:.0f}] d"],
    ], left=1)
    call = (badge("ALL CHANNELS HEALTHY", True) if all(g is True for g in calls) else
            badge("A CHANNEL IS DOWN", False) if any(g is False for g in calls) else
            badge("UNDECIDED", None))
    header = page_header(f"{verdict_badges(s)} {call}",
                         f"{s['command']} · cassini-bayes {__version__} · {s['n_events']} events "
                         f"· loss asked about: {frac:.0%}", s.get("warnings") or [])
    events = table(["date (d)", "telemetry", "pulses"],
                   [[f"{d:g}", str(t), str(p)] for d, t, p in res.files], left=3)
    fig = figure(png, "Each channel's thrust relative to its first calibration: posterior median "
                 "with 50 % and 90 % bands, each event's least-squares estimate (±1 sd), the "
                 f"{1 - frac:.0%} line dashed.", alt="thrust history")
    sections = [
        section("Answer", [answer, paragraph(
            "Verdict: DOWN when P(more than the fraction below the first calibration) ≥ 0.95 at "
            "the last event, healthy when ≤ 0.05, else undecided. Least squares: each event's "
            "weighted least squares of Feldman & Lee Eqs 17-21 (thrusters that always fire "
            "together as their mean, Eq 21). Model file: the spacecraft model's predicted "
            "thrust, the prior's centre of the baselines. docs/health.md.", note=True), fig],
                id="answer"),
        adequacy_section(s, HEALTH_NOTE),
        section("Change point", change, id="change"),
        section("Events", details(f"{len(res.files)} events", events), id="events"),
    ]
    return html_page("cassini-bayes thruster health", sections, header=header)
