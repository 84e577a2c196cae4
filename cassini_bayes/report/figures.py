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

import io
import math
from collections.abc import Mapping, Sequence
from typing import NamedTuple

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator, ScalarFormatter

from cassini_bayes.names import axis_label

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

DPI = 80
MAX_TRACE_DRAWS = 500  # per chain, trace plots
MAX_SCATTER = 1000  # points, sky plots
RANK_BINS = 20
WINDOW_SD = 6.0  # a marker further than this many posterior sd from the mean is off-scale
# Brown (2012) §I: the RWA1 spin axis, RWA4's target when it replaces a failed RWA1
RWA1_AXIS = np.array([0.0, 0.816497, 0.577350])
# Brown (2012) §I: RWA4's spin axis is canted 54.7° from the articulation (+Z) axis
ARTICULATION_CONE_DEG = 54.7356
PRIOR_COLOR, POST_COLOR, BASE_COLOR, TRUTH_COLOR = "#6b7a8f", "#1f4e8c", "#222222", "#c0392b"
CHAIN_COLORS = ("C0", "C1", "C2", "C3", "C4", "C5", "C6", "C8")


def png_bytes(fig: Figure, *, dpi: int = DPI) -> bytes:
    """Render ``fig`` with Agg to PNG, quantised to a 256-colour palette (about 3× smaller).

    The canvas's RGBA pixels go to Pillow directly: ``savefig`` would encode a full-colour PNG
    only for it to be decoded again before the quantisation (a third of a report's figure time).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    try:
        from PIL import Image
    except ImportError:  # pragma: no cover - Pillow ships with matplotlib
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=dpi)
        return buf.getvalue()
    fig.set_dpi(dpi)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    # the buffer's own shape: get_width_height rounds a fractional size up, the renderer down
    img = Image.fromarray(np.asarray(canvas.buffer_rgba()), "RGBA")
    out = io.BytesIO()
    img.convert("RGB").quantize(colors=256, method=Image.Quantize.FASTOCTREE).save(out, "PNG")
    return out.getvalue()


def _grid_figure(nrow: int, ncol: int, *, cell: tuple[float, float], left: float = 0.75,
                 right: float = 0.2, top: float = 0.45, bottom: float = 0.55, wspace: float = 0.45,
                 hspace: float = 0.55, width_ratios: Sequence[float] | None = None,
                 **subplots_kw):
    """A figure of ``nrow × ncol`` axes with fixed margins in inches.

    Constrained layout costs several extra draw passes and dominates the time of figures with many
    axes, so grids are laid out by hand. ``cell`` is the size of the mean cell; ``width_ratios``
    widens some columns.
    """
    ratios = list(width_ratios) if width_ratios is not None else [1.0] * ncol
    w = left + right + cell[0] * sum(ratios) + (ncol - 1) * wspace
    h = top + bottom + nrow * cell[1] + (nrow - 1) * hspace
    fig = Figure(figsize=(w, h))
    if width_ratios is not None:
        subplots_kw["gridspec_kw"] = {"width_ratios": ratios}
    axes = fig.subplots(nrow, ncol, squeeze=False, **subplots_kw)
    fig.subplots_adjust(left=left / w, right=1 - right / w, bottom=bottom / h, top=1 - top / h,
                        wspace=wspace / (cell[0] * np.mean(ratios)), hspace=hspace / cell[1])
    return fig, axes


def _axis_label(name: str, unit: str) -> str:
    """``"Ixx (kg m²)"``; a dimensionless quantity says so."""
    unit = unit if unit and unit not in ("–", "1") else "dimensionless"
    return f"{name} ({unit})"


def tidy_ticks(ax, *, x: int = 4, y: int = 4) -> None:
    """At most ``x``/``y`` major ticks, plain numbers without an offset: labels never overlap and
    read without a separate ``+7.1e3`` corner note."""
    for axis, n in ((ax.xaxis, x), (ax.yaxis, y)):
        if n:
            axis.set_major_locator(MaxNLocator(nbins=n, min_n_ticks=2))
            if isinstance(axis.get_major_formatter(), ScalarFormatter):
                fmt = ScalarFormatter(useOffset=False)
                fmt.set_powerlimits((-4, 6))
                axis.set_major_formatter(fmt)
    ax.tick_params(labelsize=8)


def _thin(x: np.ndarray, max_draws: int) -> tuple[np.ndarray, np.ndarray]:
    """Every k-th draw of a (chain, draw) array, so that at most ``max_draws`` remain per chain;
    returns the kept draws and their iteration numbers."""
    k = max(1, math.ceil(x.shape[1] / max_draws))
    it = np.arange(0, x.shape[1], k)
    return x[:, ::k], it


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


def _unit(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _tangent_basis(m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """East (increasing azimuth) and north (increasing elevation) unit vectors at ``m``."""
    ref = np.array([0.0, 0.0, 1.0]) if abs(m[2]) < 0.999 else np.array([1.0, 0.0, 0.0])
    east = _unit(np.cross(ref, m))
    north = np.cross(m, east)
    return east, north


def _to_plane_deg(u: np.ndarray, m: np.ndarray, east: np.ndarray, north: np.ndarray) -> np.ndarray:
    """Azimuthal-equidistant projection about ``m``: distances from ``m`` are true angles (deg)."""
    u = _unit(np.atleast_2d(u))
    theta = np.degrees(np.arccos(np.clip(u @ m, -1.0, 1.0)))
    phi = np.arctan2(u @ north, u @ east)
    return np.stack([theta * np.cos(phi), theta * np.sin(phi)], -1)


def _az_el_deg(u: np.ndarray) -> np.ndarray:
    u = _unit(np.atleast_2d(u))
    return np.degrees(np.stack([np.arctan2(u[:, 1], u[:, 0]), np.arcsin(np.clip(u[:, 2], -1, 1))],
                               -1))


def _cone_panel(ax, xy, marks, cones, lim, rings, title, m, east, north) -> None:
    """One azimuthal-equidistant view about the posterior mean: draws, the posterior cones, the
    dotted ``rings`` (deg) and the marked axes, those beyond ``lim`` written as off-scale."""
    ax.scatter(xy[:, 0], xy[:, 1], s=4, color=POST_COLOR, alpha=0.45, label="posterior draws")
    ang = np.linspace(0, 2 * np.pi, 241)
    for r in rings:
        ax.plot(r * np.cos(ang), r * np.sin(ang), color="#777777", linestyle=":", linewidth=1)
        ax.annotate(f"{r:g}°", (r * np.cos(np.pi / 4), r * np.sin(np.pi / 4)), fontsize=7,
                    color="#555555")
    for (key, r), col in zip(sorted((cones or {}).items(), key=lambda kv: float(kv[0])),
                             ("#7fb3d5", "#2e86c1", "#1b4f72")):
        if r is not None and np.isfinite(r):
            ax.plot(r * np.cos(ang), r * np.sin(ang), color=col, linewidth=1.3,
                    label=f"{key} % cone ({r:.3g}°)")
    off = []
    for name, v, mk, col in marks:
        p = _to_plane_deg(v, m, east, north)[0]
        d = float(np.hypot(*p))
        if max(abs(p[0]), abs(p[1])) <= lim:
            ax.scatter([p[0]], [p[1]], marker=mk, s=120, color=col, label=f"{name} ({d:.3g}°)",
                       zorder=5)
        else:
            off.append(f"{name}: {d:.3g}° from the mean (off-scale)")
    ax.scatter([0], [0], marker="o", s=25, color="k", label="posterior mean", zorder=6)
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.set_xlabel("east of the mean (deg)", fontsize=8)
    ax.set_ylabel("north of the mean (deg)", fontsize=8)
    ax.set_title(title, fontsize=9)
    if off:
        ax.text(0.02, 0.02, "\n".join(off), transform=ax.transAxes, fontsize=7, va="bottom",
                color="#444444")
    ax.legend(fontsize=6.5, loc="upper right")
    tidy_ticks(ax, x=5, y=5)



def axis_sky_figure(
    draws: np.ndarray,
    *,
    mean: np.ndarray,
    cones_deg: Mapping[str, float] | None = None,
    truth: np.ndarray | None = None,
    baseline: np.ndarray | None = None,
    target: tuple[str, np.ndarray] | None = ("RWA1", RWA1_AXIS),
    cone: tuple[np.ndarray, float] | None = (np.eye(3)[2], ARTICULATION_CONE_DEG),
) -> Figure:
    """A wheel's spin-axis posterior in three views.

    Left: azimuth ``atan2(y, x)`` and elevation ``asin(z)`` of the draws in body axes, with the
    wheel's articulation ``cone`` (its axis and angle, deg, from the model file; Cassini's RWA4:
    54.7356° from +Z, Brown §I) and its reference wheel's axis ``target`` (name, axis; RWA1 for
    RWA4), each when known. Middle: the draws in
    an azimuthal-equidistant projection about the posterior mean direction, so circles are true
    cones, at the papers' budgets' scale: 1°, 2°, 3° (dotted). Right: the same at the posterior's
    own scale, with the posterior 50/90/95 % cones (solid) and the least-squares axis and truth;
    a marked axis beyond a view's edge is written with its angular distance instead.

    Parameters
    ----------
    draws : numpy.ndarray, shape (n, 3)
        Posterior draws of the unit axis in body axes.
    mean : numpy.ndarray, shape (3,)
        Posterior mean direction.
    """
    draws = _unit(draws)
    if len(draws) > MAX_SCATTER:
        draws = draws[:: math.ceil(len(draws) / MAX_SCATTER)]
    m = _unit(mean)
    east, north = _tangent_basis(m)
    fig, axes = _grid_figure(1, 3, cell=(4.1, 4.1), left=0.75, right=0.2, top=0.4, bottom=0.6,
                             wspace=0.85, width_ratios=(1.15, 1, 1))
    ax_g, ax_b, ax_z = axes[0]

    # overview in azimuth-elevation, a window about the mean wide enough for every marker
    ae_m = _az_el_deg(m)[0]

    def _ae(v):  # azimuth unwrapped next to the mean's, so the window never straddles ±180°
        p = _az_el_deg(v)
        p[:, 0] = ae_m[0] + (p[:, 0] - ae_m[0] + 180.0) % 360.0 - 180.0
        return p

    ae = _ae(draws)
    target_label = None if target is None else f"{target[0]} target"
    marks = [] if target is None else [(target_label, np.asarray(target[1], float), "*",
                                        "#e67e22")]
    if truth is not None:
        marks.append(("truth", truth, "x", TRUTH_COLOR))
    if baseline is not None:
        marks.append(("least squares", baseline, "+", BASE_COLOR))
    pts = np.concatenate([ae] + [_ae(v) for _, v, _, _ in marks])
    half = max(10.0, 1.2 * float(np.max(np.abs(pts - ae_m))))
    if cone is not None:
        c_axis, c_deg = _unit(np.asarray(cone[0], float)), float(cone[1])
        e1, e2 = _tangent_basis(c_axis)
        phi = np.linspace(0.0, 2.0 * np.pi, 721)[:, None]
        ring = _ae(np.cos(np.radians(c_deg)) * c_axis + np.sin(np.radians(c_deg))
                   * (np.cos(phi) * e1 + np.sin(phi) * e2))
        jump = np.flatnonzero(np.abs(np.diff(ring[:, 0])) > 180.0) + 1   # the azimuth wraps
        ring = np.insert(ring, jump, np.nan, axis=0)
        ax_g.plot(ring[:, 0], ring[:, 1], color="#888888", linewidth=1, linestyle=":",
                  label=f"articulation cone ({c_deg:.2f}° from {axis_label(c_axis, 3)})")
    ax_g.scatter(ae[:, 0], ae[:, 1], s=4, color=POST_COLOR, alpha=0.5, label="posterior draws")
    for name, v, mk, col in marks:
        p = _ae(v)[0]
        ax_g.scatter([p[0]], [p[1]], marker=mk, s=120, color=col, label=name, zorder=5)
    ax_g.set_xlim(ae_m[0] - half, ae_m[0] + half)
    ax_g.set_ylim(max(-90.0, ae_m[1] - half), min(90.0, ae_m[1] + half))
    ax_g.grid(alpha=0.3)
    ax_g.set_xlabel("body azimuth atan2(y, x) (deg)", fontsize=8)
    ax_g.set_ylabel("body elevation asin(z) (deg)", fontsize=8)
    ax_g.set_title("spin axis in body axes", fontsize=9)
    ax_g.legend(fontsize=6.5, loc="lower left")
    tidy_ticks(ax_g, x=5, y=5)

    xy = _to_plane_deg(draws, m, east, north)
    spread = float(np.max(np.hypot(xy[:, 0], xy[:, 1])))
    _cone_panel(ax_b, xy, marks, {}, max(3.3, 1.1 * spread), (1.0, 2.0, 3.0),
                "at the budgets' scale: 1°, 2°, 3° cones", m, east, north)
    zoom = 1.15 * max([spread] + [float(r) for r in (cones_deg or {}).values()
                                  if r is not None and np.isfinite(r)])
    _cone_panel(ax_z, xy, [mk for mk in marks if mk[0] != target_label], cones_deg, zoom,
                [r for r in (1.0, 2.0, 3.0) if r <= zoom], "at the posterior's scale", m, east,
                north)
    return fig
