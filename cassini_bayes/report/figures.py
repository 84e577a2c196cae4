"""Figures of the reports, rendered to PNG bytes (matplotlib's Agg canvas, no ``pyplot``).

Every ``*_figure`` function builds a :class:`matplotlib.figure.Figure` directly (no ``pyplot``
state, so nothing to close and no interactive backend is touched); :func:`png_bytes` renders it,
palette-quantised to keep a page small. Every axis is labelled with its unit and carries at most
a few ticks, so no tick labels overlap (tests/test_report.py checks both). Draws are thinned for
plotting only (``MAX_TRACE_DRAWS`` per chain, ``MAX_SCATTER`` points); every number in a report
comes from the full posterior.

Plain NumPy and matplotlib, no ArviZ: importing ArviZ alone costs more CPU than the whole page
(docs/performance.md).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import NamedTuple

import numpy as np
from matplotlib.figure import Figure

from cassini_bayes.report._figure_base import (  # noqa: F401 - re-exported
    ARTICULATION_CONE_DEG as ARTICULATION_CONE_DEG,
    BASE_COLOR,
    CHAIN_COLORS as CHAIN_COLORS,
    DPI as DPI,
    MAX_SCATTER as MAX_SCATTER,
    MAX_TRACE_DRAWS as MAX_TRACE_DRAWS,
    POST_COLOR,
    PRIOR_COLOR,
    RANK_BINS,
    RWA1_AXIS as RWA1_AXIS,
    TRUTH_COLOR,
    WINDOW_SD as WINDOW_SD,
    _axis_label,
    _grid_figure,
    _thin,
    png_bytes as png_bytes,
    tidy_ticks as tidy_ticks,
)
from cassini_bayes.report._sky_figure import axis_sky_figure as axis_sky_figure

__all__ = [
    "DPI",
    "png_bytes",
    "Panel",
    "answer_figure",
    "trace_rank_figure",
    "residuals_figure",
    "pulse_impulse_figure",
    "axis_sky_figure",
    "tidy_ticks",
    "RWA1_AXIS",
    "ARTICULATION_CONE_DEG",
]

class Panel(NamedTuple):
    """One parameter of :func:`answer_figure`: its draws and the values marked beside them."""

    label: str
    unit: str
    draws: np.ndarray
    baseline: float | None = None
    truth: float | None = None
    prior_mean: float | None = None


def _mark(ax, value, lo, hi, mean, sd, *, color, style, name, text_y) -> str | None:
    """A vertical line at ``value`` inside ``[lo, hi]``; outside, an arrow at the nearer edge with
    the value and its distance in posterior sd. Returns the legend name when drawn as a line."""
    if value is None:
        return None
    if lo <= value <= hi:
        ax.axvline(value, color=color, linestyle=style, linewidth=1.3)
        return name
    right = value > hi
    dist = abs(value - mean) / sd if sd > 0 else float("inf")
    text = f"{name} {value:.6g}\n{dist:.0f} sd away"
    ax.annotate(f"{text} →" if right else f"← {text}",
                xy=(0.98 if right else 0.02, text_y), xycoords="axes fraction",
                ha="right" if right else "left", va="top", fontsize=7, color=color)
    return None


def answer_figure(panels: Sequence[Panel]) -> Figure:
    """Each calibrated parameter's posterior at the posterior's own scale: a histogram of the
    draws with the 90 % interval shaded, the papers' least squares (dashed) and the truth (red)
    beside it, and the model file's prediction (the prior's centre, dotted). A value further than
    ``WINDOW_SD`` posterior sd from the mean is written at the edge with its distance instead."""
    n = len(panels)
    ncol = min(3, n)
    nrow = math.ceil(n / ncol)
    fig, axes = _grid_figure(nrow, ncol, cell=(3.6, 1.9), left=0.7, right=0.25, top=0.6,
                             bottom=0.55, wspace=0.75, hspace=0.95)
    axes = axes.ravel()
    shown: list[str] = []
    for ax, p in zip(axes, panels):
        x = np.asarray(p.draws, float).ravel()
        x = x[np.isfinite(x)]
        mean, sd = float(np.mean(x)), float(np.std(x))
        lo, hi = (float(v) for v in np.quantile(x, [0.002, 0.998]))
        for v in (p.baseline, p.truth, p.prior_mean):
            if v is not None and abs(v - mean) <= WINDOW_SD * sd:
                lo, hi = min(lo, v), max(hi, v)
        pad = 0.08 * (hi - lo) if hi > lo else max(abs(mean) * 1e-6, 1e-12)
        lo, hi = lo - pad, hi + pad
        counts, edges = np.histogram(x, bins=40, range=(lo, hi), density=True)
        ax.stairs(counts, edges, fill=True, color=POST_COLOR, alpha=0.35, linewidth=0)
        ax.stairs(counts, edges, color=POST_COLOR, linewidth=1.0)
        q05, q95 = np.quantile(x, [0.05, 0.95])
        ax.axvspan(q05, q95, color=POST_COLOR, alpha=0.08, linewidth=0)
        ax.axvline(mean, color=POST_COLOR, linewidth=1.2)
        names = ["posterior mean, 90 % interval"]
        for value, color, style, name, y in (
                (p.baseline, BASE_COLOR, "--", "least squares", 0.97),
                (p.truth, TRUTH_COLOR, "-", "truth", 0.72),
                (p.prior_mean, PRIOR_COLOR, ":", "model file", 0.47)):
            drawn = _mark(ax, value, lo, hi, mean, sd, color=color, style=style, name=name,
                          text_y=y)
            if drawn:
                names.append(drawn)
        shown += [nm for nm in names if nm not in shown]
        ax.set_xlim(lo, hi)
        ax.set_ylim(0, counts.max() * 1.35 if counts.max() > 0 else 1)
        d = max(0, 1 - math.floor(math.log10(sd))) if sd > 0 else 4   # 2 digits of the sd
        ax.set_title(f"{p.label} = {mean:.{d}f} ± {sd:.{d}f}", fontsize=9)
        ax.set_xlabel(_axis_label(p.label, p.unit), fontsize=8)
        unit = p.unit if p.unit and p.unit not in ("–", "1") else ""
        ax.set_ylabel(f"density (1/{unit})" if unit else "density (dimensionless)", fontsize=8)
        ax.set_yticks([])  # a density's scale says nothing the x-axis does not
        tidy_ticks(ax, x=4, y=0)
    for ax in axes[n:]:
        ax.set_visible(False)
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    style = {"posterior mean, 90 % interval": Patch(color=POST_COLOR, alpha=0.35),
             "least squares": Line2D([], [], color=BASE_COLOR, linestyle="--"),
             "truth": Line2D([], [], color=TRUTH_COLOR),
             "model file": Line2D([], [], color=PRIOR_COLOR, linestyle=":")}
    fig.legend([style[s] for s in shown], shown, loc="upper center", ncol=len(shown),
               fontsize=8, frameon=False)
    return fig


def trace_rank_figure(draws: Mapping[str, np.ndarray], units: Mapping[str, str]) -> Figure:
    """Per parameter (a row): the draws of each chain against iteration (thinned to
    ``MAX_TRACE_DRAWS`` per chain) and each chain's histogram of the draws' ranks among all chains
    (Vehtari et al. 2021): chains that mix overlap as stationary noise and have flat rank
    histograms."""
    labels = list(draws)
    n = len(labels)
    fig, axes = _grid_figure(n, 2, cell=(4.0, 1.25), left=0.95, right=0.2, top=0.45,
                             bottom=0.5, wspace=0.85, hspace=0.75, width_ratios=(1.6, 0.7))
    for (ax_t, ax_r), label in zip(axes, labels):
        x = np.asarray(draws[label], float)
        chains, total = x.shape[0], x.size
        xt, it = _thin(x, MAX_TRACE_DRAWS)
        ranks = np.empty(total)
        ranks[np.argsort(x.ravel(), kind="stable")] = np.arange(total)
        ranks = ranks.reshape(x.shape)
        edges = np.linspace(0, total, RANK_BINS + 1)
        top = 0
        for c in range(chains):
            color = CHAIN_COLORS[c % len(CHAIN_COLORS)]
            ax_t.plot(it, xt[c], color=color, linewidth=0.6, alpha=0.7)
            counts, _ = np.histogram(ranks[c], bins=edges)
            ax_r.stairs(counts, edges, color=color, linewidth=1.0)
            top = max(top, int(counts.max()))
        ax_r.axhline(x.shape[1] / RANK_BINS, color="#555555", linestyle="--", linewidth=0.8)
        unit = units.get(label, "")
        ax_t.set_ylabel(_axis_label(label, unit), fontsize=8)
        ax_t.set_xlabel("iteration (draw)", fontsize=8)
        ax_r.set_xlabel(f"rank among all {total} draws (count)", fontsize=8)
        ax_r.set_ylabel("draws per bin (count)", fontsize=8)
        ax_r.set_ylim(0, 1.25 * top)
        ax_r.set_xlim(0, total)
        ax_r.set_xticks([0, total])
        tidy_ticks(ax_t, x=4, y=3)
        tidy_ticks(ax_r, x=0, y=2)
    return fig


def residuals_figure(ds, *, var: str = "residual", ylabel: str) -> Figure:
    """Residuals against time: one panel per component of the ``axis`` dimension.

    Parameters
    ----------
    ds : cassini_bayes.report.rundata.Group
        The ``residuals`` group: variables with a ``t`` dimension (s) and optionally ``axis``.
        Any other dimension (event) becomes separate lines; so does a coordinate along ``t`` that
        tells concatenated segments apart (``file``, ``event``: each segment has its own clock).
    var : str
        The variable to plot.
    ylabel : str
        Axis label with unit, e.g. ``"momentum residual (N m s)"``.
    """
    da = ds[var]
    tdim = "t" if "t" in da.dims else da.dims[0]
    comp_dim = "axis" if "axis" in da.dims else None
    comps = ds.labels(comp_dim) if comp_dim else [None]
    other = [d for d in da.dims if d not in (tdim, comp_dim)]
    t = np.asarray(ds.labels(tdim), dtype=float)
    seg_coord = next((c for c in ("file", "event", "segment")
                      if c in ds.coords and ds.coords[c].dims == (tdim,)), None)
    seg = np.asarray(ds.coords[seg_coord].values) if seg_coord else np.zeros(t.size, int)
    segments = list(dict.fromkeys(seg.tolist()))
    order = [tdim, *([comp_dim] if comp_dim else []), *other]
    vals_all = np.moveaxis(np.asarray(da.values, float), [da.dims.index(d) for d in order],
                           range(len(order)))
    fig, axes = _grid_figure(len(comps), 1, cell=(10.0, 1.55), left=0.95, top=0.3, bottom=0.5,
                             hspace=0.45, sharex=True)
    axes = axes.ravel()
    other_labels = [ds.labels(d) for d in other]
    names = [", ".join(str(other_labels[k][i]) for k, i in enumerate(idx))
             for idx in np.ndindex(*vals_all.shape[2 if comp_dim else 1:])] if other else [""]
    for i, (ax, comp) in enumerate(zip(axes, comps)):
        sub = vals_all[:, i] if comp_dim else vals_all
        vals = sub.reshape(sub.shape[0], -1)
        n_lines = 0
        for j in range(vals.shape[1]):
            for s_val in segments:
                m = seg == s_val
                label = ", ".join(x for x in (
                    f"{seg_coord} {s_val}" if seg_coord and len(segments) > 1 else "", names[j])
                    if x) or None
                style = ".-" if m.sum() <= 600 else "."  # dense series: points only
                ax.plot(t[m], vals[m, j], style, markersize=2, linewidth=0.6, alpha=0.85,
                        label=label)
                n_lines += 1
        if i == 0 and 1 < n_lines <= 12:
            ax.legend(fontsize=7, ncol=min(n_lines, 6), loc="upper right")
        ax.axhline(0.0, color="#555555", linewidth=0.8)
        rms = float(np.sqrt(np.nanmean(vals**2)))
        name = f"{var}[{comp}]" if comp is not None else var
        ax.set_title(f"{name}   rms {rms:.3g}", fontsize=9, loc="left")
        ax.set_ylabel(ylabel, fontsize=8)
        tidy_ticks(ax, x=8, y=3)
    axes[-1].set_xlabel("t (s)", fontsize=8)
    return fig


def pulse_impulse_figure(group) -> Figure:
    """Each pulse group's angular impulse, measured (the momentum's change across it, with the
    telemetry noise's 90 % bar) against the model's prediction (posterior 90 % band), and their
    ratio against the group's commanded on-time.

    ``group``: the ``pulse_impulses`` group of a thrust run (``measured``, ``measured_sd``,
    ``predicted`` (quantile 5/50/95 %) along each group's predicted direction, N m s;
    ``on_time`` s).
    """
    meas = np.asarray(group["measured"].values, float)
    msd = np.asarray(group["measured_sd"].values, float)
    pred = np.asarray(group["predicted"].values, float)
    on = np.asarray(group["on_time"].values, float)
    lo, med, hi = pred[:, 0], pred[:, 1], pred[:, 2]
    z90 = 1.6448536269514722
    fig, axes = _grid_figure(1, 2, cell=(4.6, 3.4), left=0.9, right=0.25, top=0.45,
                             bottom=0.6, wspace=0.9)
    ax, ax_r = axes[0]
    ax.errorbar(med, meas, yerr=z90 * msd, xerr=[med - lo, hi - med], fmt="o", ms=3,
                color=POST_COLOR, ecolor="#8fa6c8", elinewidth=0.8, capsize=0)
    top = float(np.nanmax(np.concatenate([hi, meas + z90 * msd]))) * 1.05
    bottom = min(0.0, float(np.nanmin(np.concatenate([lo, meas - z90 * msd]))))
    ax.plot([bottom, top], [bottom, top], color="#555555", linestyle="--", linewidth=0.8,
            label="measured = predicted")
    ax.set_xlim(bottom, top)
    ax.set_ylim(bottom, top)
    ax.set_xlabel("predicted impulse, posterior median (N m s)", fontsize=8)
    ax.set_ylabel("measured impulse (N m s)", fontsize=8)
    ax.set_title("angular impulse of each pulse group", fontsize=9)
    ax.legend(fontsize=7, loc="upper left")
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = 100.0 * (meas / med - 1.0)
        r_lo, r_hi = 100.0 * (lo / med - 1.0), 100.0 * (hi / med - 1.0)
        r_err = 100.0 * z90 * msd / med
    ok = np.isfinite(ratio)
    ax_r.errorbar(1e3 * on[ok], ratio[ok], yerr=r_err[ok], fmt="o", ms=3, color=POST_COLOR,
                  ecolor="#8fa6c8", elinewidth=0.8, capsize=0, label="measured, noise 90 %")
    order = np.argsort(on[ok])
    ax_r.fill_between(1e3 * on[ok][order], r_lo[ok][order], r_hi[ok][order], color=POST_COLOR,
                      alpha=0.15, linewidth=0, label="prediction, posterior 90 %")
    ax_r.axhline(0.0, color="#555555", linewidth=0.8)
    ax_r.set_xlabel("commanded on-time of the group (ms)", fontsize=8)
    ax_r.set_ylabel("measured / predicted − 1 (%)", fontsize=8)
    ax_r.set_title("misfit against pulse length", fontsize=9)
    ax_r.legend(fontsize=7, loc="upper right")
    tidy_ticks(ax, x=5, y=5)
    tidy_ticks(ax_r, x=5, y=5)
    return fig
