"""Figures of the diagnostic report, rendered to PNG bytes (ArviZ + matplotlib, Agg).

Every function builds a :class:`matplotlib.figure.Figure` directly (no ``pyplot`` state, so nothing
to close and no interactive backend is touched), draws into it — with ArviZ where ArviZ has the plot
— and returns the PNG bytes, palette-quantised to keep a report with 4000 draws around a megabyte.
Draws are thinned for plotting only (``MAX_TRACE_DRAWS`` per chain, ``MAX_SCATTER`` points);
all numbers in the report come from the full posterior.
"""

from __future__ import annotations

import io
import math
import warnings
from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure

__all__ = [
    "DPI",
    "png_bytes",
    "thin",
    "trace_png",
    "rank_png",
    "prior_posterior_png",
    "pair_png",
    "residuals_png",
    "energy_png",
    "axis_sky_png",
    "RWA1_AXIS",
    "ARTICULATION_CONE_DEG",
]

DPI = 80
MAX_TRACE_DRAWS = 500  # per chain, trace plots
MAX_SCATTER = 1000  # points, pair and sky plots
# Brown (2012) §I: the RWA1 spin axis, RWA4's target when it replaces a failed RWA1
RWA1_AXIS = np.array([0.0, 0.816497, 0.577350])
# Brown (2012) §I: RWA4's spin axis is canted 54.7° from the articulation (+Z) axis
ARTICULATION_CONE_DEG = 54.7356
PRIOR_COLOR, POST_COLOR, BASE_COLOR, TRUTH_COLOR = "#9aa7b8", "#1f4e8c", "#222222", "#c0392b"


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
                 hspace: float = 0.55, **subplots_kw):
    """A figure of ``nrow × ncol`` axes with fixed margins in inches.

    Constrained layout costs several extra draw passes and dominates the time of figures with many
    axes (a pair plot of eleven variables: 20 s against 4 s), so grids are laid out by hand.
    """
    w = left + right + ncol * cell[0] + (ncol - 1) * wspace
    h = top + bottom + nrow * cell[1] + (nrow - 1) * hspace
    fig = Figure(figsize=(w, h))
    axes = fig.subplots(nrow, ncol, squeeze=False, **subplots_kw)
    fig.subplots_adjust(left=left / w, right=1 - right / w, bottom=bottom / h, top=1 - top / h,
                        wspace=wspace / cell[0], hspace=hspace / cell[1])
    return fig, axes


def thin(idata, max_draws: int):
    """Every k-th draw so that at most ``max_draws`` remain per chain (plots only)."""
    n = int(idata.posterior.sizes.get("draw", 0))
    k = max(1, math.ceil(n / max_draws))
    return idata if k == 1 else idata.isel(draw=slice(None, None, k))


def _n_components(ds, names: Sequence[str]) -> int:
    n = 0
    for name in names:
        shape = [s for d, s in ds[name].sizes.items() if d not in ("chain", "draw")]
        n += int(np.prod(shape)) if shape else 1
    return n


def trace_png(idata, var_names: Sequence[str]) -> bytes:
    """ArviZ trace plot: marginal density per chain | draws against iteration, a row a variable."""
    import arviz as az

    idata = thin(idata, MAX_TRACE_DRAWS)
    n = len(var_names)
    fig, axes = _grid_figure(n, 2, cell=(4.5, 1.35), left=0.45, right=0.15, top=0.35,
                             bottom=0.35, wspace=0.8, hspace=0.5)
    with warnings.catch_warnings(), az.rc_context({"plot.max_subplots": 2 * n + 1}):
        warnings.simplefilter("ignore")
        az.plot_trace(idata, var_names=list(var_names), axes=axes, compact=True,
                      chain_prop={"color": ["C0", "C1", "C2", "C3", "C4", "C5", "C6", "C8"]},
                      legend=True, trace_kwargs={"alpha": 0.6, "linewidth": 0.6})
    for ax in axes.ravel():
        ax.tick_params(labelsize=8)
        ax.title.set_fontsize(9)
    return png_bytes(fig)


def rank_png(idata, var_names: Sequence[str]) -> bytes:
    """ArviZ rank plots: per chain, the histogram of the draws' ranks (flat when chains mix)."""
    import arviz as az

    n = _n_components(idata.posterior, var_names)
    ncol = min(3, n)
    nrow = math.ceil(n / ncol)
    fig, axes = _grid_figure(nrow, ncol, cell=(3.0, 1.6), left=0.55, wspace=0.6, hspace=0.75)
    axes = axes.ravel()
    with warnings.catch_warnings(), az.rc_context({"plot.max_subplots": n + 1}):
        warnings.simplefilter("ignore")
        az.plot_rank(idata, var_names=list(var_names), ax=axes[:n], kind="bars")
    for ax in axes[n:]:
        ax.set_visible(False)
    for ax in axes[:n]:
        ax.tick_params(labelsize=8)
        ax.title.set_fontsize(9)
        ax.xaxis.label.set_fontsize(8)
        ax.yaxis.label.set_fontsize(8)
    return png_bytes(fig)


def _scaled_kde(ax, x: np.ndarray, *, color: str, label: str, fill: bool) -> None:
    import arviz as az

    x = x[np.isfinite(x)]
    if x.size < 2 or np.ptp(x) == 0:
        ax.axvline(x[0] if x.size else 0.0, color=color, label=label)
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        grid, pdf = az.kde(x)
    pdf = pdf / pdf.max()
    if fill:
        ax.fill_between(grid, pdf, color=color, alpha=0.45, linewidth=0, label=label)
    else:
        ax.plot(grid, pdf, color=color, linewidth=1.6, label=label)


def prior_posterior_png(
    posterior: Mapping[str, np.ndarray],
    prior: Mapping[str, np.ndarray],
    *,
    baseline: Mapping[str, float | None],
    truth: Mapping[str, float | None],
    contraction: Mapping[str, float | None],
    units: Mapping[str, str],
) -> bytes:
    """Prior (grey, filled) against posterior (blue) density per parameter, each scaled to peak 1.

    The x-range spans the prior's central 99 % and the whole posterior, so a well-identified
    parameter shows as a narrow spike inside a broad prior and a prior-dominated one as two
    overlapping curves. Baseline (least squares, black dashed) and truth (red) are marked.
    """
    labels = list(posterior)
    n = len(labels)
    ncol = min(3, n)
    nrow = math.ceil(n / ncol)
    fig, axes = _grid_figure(nrow, ncol, cell=(3.4, 1.65), left=0.2, top=0.65, wspace=0.3,
                             hspace=0.8)
    axes = axes.ravel()
    for ax, label in zip(axes, labels):
        x = np.asarray(posterior[label]).ravel()
        lo, hi = np.nanmin(x), np.nanmax(x)
        if label in prior:
            p = np.asarray(prior[label]).ravel()
            _scaled_kde(ax, p, color=PRIOR_COLOR, label="prior", fill=True)
            plo, phi = np.nanquantile(p, [0.005, 0.995])
            lo, hi = min(lo, plo), max(hi, phi)
        _scaled_kde(ax, x, color=POST_COLOR, label="posterior", fill=False)
        for value, color, style, name in (
            (baseline.get(label), BASE_COLOR, "--", "least squares"),
            (truth.get(label), TRUTH_COLOR, "-", "truth"),
        ):
            if value is not None:
                ax.axvline(value, color=color, linestyle=style, linewidth=1.2, label=name)
                lo, hi = min(lo, value), max(hi, value)
        pad = 0.04 * (hi - lo) if hi > lo else 1.0
        ax.set_xlim(lo - pad, hi + pad)
        ax.set_ylim(0, 1.08)
        c = contraction.get(label)
        title = label if c is None else f"{label}   contraction {c:.2f}"
        if label not in prior:
            title += "   (no prior draws)"
        ax.set_title(title, fontsize=9)
        unit = units.get(label, "")
        ax.set_xlabel(f"{label} ({unit})" if unit and unit != "–" else label, fontsize=8)
        ax.set_yticks([])
        ax.tick_params(labelsize=7)
    for ax in axes[n:]:
        ax.set_visible(False)
    handles, names = [], []
    for ax in axes[:n]:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab not in names:
                handles.append(h)
                names.append(lab)
    fig.legend(handles, names, loc="upper center", ncol=len(names), fontsize=8, frameon=False)
    return png_bytes(fig)


def pair_png(idata, var_names: Sequence[str]) -> bytes:
    """ArviZ pair plot (scatter of thinned draws, marginals on the diagonal, divergences marked)."""
    import arviz as az

    n_total = int(idata.posterior.sizes["chain"] * idata.posterior.sizes["draw"])
    k = max(1, math.ceil(n_total / MAX_SCATTER))
    idata = idata.isel(draw=slice(None, None, k)) if k > 1 else idata
    n = _n_components(idata.posterior, var_names)
    size = min(1.9, 11.0 / max(n, 1))
    fig, axes = _grid_figure(n, n, cell=(size, size), left=0.9, right=0.15, top=0.15, bottom=0.7,
                             wspace=0.1, hspace=0.1)
    divs = ("sample_stats" in idata.groups() and "diverging" in idata.sample_stats.data_vars
            and bool(np.asarray(idata.sample_stats["diverging"].values).any()))
    with warnings.catch_warnings(), az.rc_context({"plot.max_subplots": n * n + 1}):
        warnings.simplefilter("ignore")
        az.plot_pair(idata, var_names=list(var_names), kind="scatter", marginals=True, ax=axes,
                     divergences=divs, scatter_kwargs={"alpha": 0.5, "s": 7},
                     textsize=8)
    return png_bytes(fig)


def residuals_png(ds, *, var: str = "residual", ylabel: str) -> bytes:
    """Residuals against time: one panel per component of the ``axis`` dimension.

    Parameters
    ----------
    ds : xarray.Dataset
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
    comps = list(da.coords[comp_dim].values) if comp_dim and comp_dim in da.coords else (
        list(range(da.sizes[comp_dim])) if comp_dim else [None])
    other = [d for d in da.dims if d not in (tdim, comp_dim)]
    t = np.asarray(da.coords[tdim].values if tdim in da.coords else np.arange(da.sizes[tdim]),
                   dtype=float)
    seg_coord = next((c for c in ("file", "event", "segment")
                      if c in da.coords and da.coords[c].dims == (tdim,)), None)
    seg = np.asarray(da.coords[seg_coord].values) if seg_coord else np.zeros(t.size, int)
    segments = list(dict.fromkeys(seg.tolist()))
    fig, axes = _grid_figure(len(comps), 1, cell=(10.0, 1.55), left=0.85, top=0.3, bottom=0.5,
                             hspace=0.45, sharex=True)
    axes = axes.ravel()
    n_lines = 0
    for i, (ax, comp) in enumerate(zip(axes, comps)):
        sub = da.isel({comp_dim: i}) if comp_dim else da
        sub = sub.transpose(tdim, *other)
        vals = np.asarray(sub.values, dtype=float).reshape(sub.sizes[tdim], -1)
        names = [", ".join(str(sub.coords[d].values[k]) if d in sub.coords else str(k)
                           for d, k in zip(other, idx))
                 for idx in np.ndindex(*[sub.sizes[d] for d in other])] if other else [""]
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
        ax.tick_params(labelsize=8)
    axes[-1].set_xlabel("t (s)", fontsize=8)
    return png_bytes(fig)


def energy_png(idata) -> bytes:
    """ArviZ energy plot: marginal energy against energy transition, with E-BFMI per chain."""
    import arviz as az

    fig = Figure(figsize=(6.5, 3.8), layout="constrained")
    ax = fig.subplots()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        az.plot_energy(idata, ax=ax, textsize=8)
    return png_bytes(fig)


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


def axis_sky_png(
    draws: np.ndarray,
    *,
    mean: np.ndarray,
    cones_deg: Mapping[str, float] | None = None,
    truth: np.ndarray | None = None,
    baseline: np.ndarray | None = None,
    target: np.ndarray = RWA1_AXIS,
) -> bytes:
    """RWA4 spin-axis posterior: body azimuth–elevation overview and a zoom about the mean.

    Left: azimuth ``atan2(y, x)`` and elevation ``asin(z)`` of the draws in body axes, with the
    articulation cone (54.7356° from +Z, Brown §I) and the RWA1 target axis. Right: the draws in an
    azimuthal-equidistant projection about the posterior mean direction, so circles are true cones:
    1°, 2°, 3° (dotted) and the posterior 50/90/95 % cones of ``summary.json`` (solid); the target,
    truth and least-squares axis are marked, or their angular distance is written when off-scale.

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
    fig = Figure(figsize=(11.5, 5.0), layout="constrained")
    ax_g, ax_z = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.25, 1]})

    # overview in azimuth-elevation, a window about the mean wide enough for every marker
    ae_m = _az_el_deg(m)[0]

    def _ae(v):  # azimuth unwrapped next to the mean's, so the window never straddles ±180°
        p = _az_el_deg(v)
        p[:, 0] = ae_m[0] + (p[:, 0] - ae_m[0] + 180.0) % 360.0 - 180.0
        return p

    ae = _ae(draws)
    marks = [("RWA1 target", target, "*", "#e67e22")]
    if truth is not None:
        marks.append(("truth", truth, "x", TRUTH_COLOR))
    if baseline is not None:
        marks.append(("least squares", baseline, "+", BASE_COLOR))
    pts = np.concatenate([ae] + [_ae(v) for _, v, _, _ in marks])
    half = max(10.0, 1.2 * float(np.max(np.abs(pts - ae_m))))
    az_grid = np.linspace(ae_m[0] - half, ae_m[0] + half, 200)
    ax_g.plot(az_grid, np.full_like(az_grid, 90.0 - ARTICULATION_CONE_DEG), color="#888888",
              linewidth=1, linestyle=":", label="articulation cone (54.74° from +Z)")
    ax_g.scatter(ae[:, 0], ae[:, 1], s=4, color=POST_COLOR, alpha=0.5, label="posterior draws")
    for name, v, mk, col in marks:
        p = _ae(v)[0]
        ax_g.scatter([p[0]], [p[1]], marker=mk, s=120, color=col, label=name, zorder=5)
    ax_g.set_xlim(ae_m[0] - half, ae_m[0] + half)
    ax_g.set_ylim(max(-90.0, ae_m[1] - half), min(90.0, ae_m[1] + half))
    ax_g.grid(alpha=0.3)
    ax_g.set_xlabel("body azimuth atan2(y, x) (deg)", fontsize=9)
    ax_g.set_ylabel("body elevation asin(z) (deg)", fontsize=9)
    ax_g.set_title("spin axis in body axes (azimuth–elevation)", fontsize=10)
    ax_g.legend(fontsize=7, loc="lower left")

    # zoom about the posterior mean
    xy = _to_plane_deg(draws, m, east, north)
    ax_z.scatter(xy[:, 0], xy[:, 1], s=4, color=POST_COLOR, alpha=0.45, label="posterior draws")
    ang = np.linspace(0, 2 * np.pi, 241)
    for r in (1.0, 2.0, 3.0):
        ax_z.plot(r * np.cos(ang), r * np.sin(ang), color="#777777", linestyle=":", linewidth=1)
        ax_z.annotate(f"{r:g}°", (r * np.cos(np.pi / 4), r * np.sin(np.pi / 4)), fontsize=7,
                      color="#555555")
    for (key, r), col in zip(sorted((cones_deg or {}).items(), key=lambda kv: float(kv[0])),
                             ("#7fb3d5", "#2e86c1", "#1b4f72")):
        if r is not None and np.isfinite(r):
            ax_z.plot(r * np.cos(ang), r * np.sin(ang), color=col, linewidth=1.3,
                      label=f"{key} % cone ({r:.2f}°)")
    lim = max(3.3, 1.1 * float(np.max(np.hypot(xy[:, 0], xy[:, 1]))))
    off = []
    for name, v, mk, col in marks:
        p = _to_plane_deg(v, m, east, north)[0]
        d = float(np.hypot(*p))
        if d <= lim:
            ax_z.scatter([p[0]], [p[1]], marker=mk, s=120, color=col, label=f"{name} ({d:.2f}°)",
                         zorder=5)
        else:
            off.append(f"{name}: {d:.2f}° from mean (off-scale)")
    ax_z.scatter([0], [0], marker="o", s=25, color="k", label="posterior mean", zorder=6)
    ax_z.set_xlim(-lim, lim)
    ax_z.set_ylim(-lim, lim)
    ax_z.set_aspect("equal")
    ax_z.grid(alpha=0.3)
    ax_z.set_xlabel("east of mean (deg, azimuthal equidistant)", fontsize=9)
    ax_z.set_ylabel("north of mean (deg)", fontsize=9)
    ax_z.set_title("about the posterior mean: 1°, 2°, 3° cones", fontsize=10)
    if off:
        ax_z.text(0.02, 0.02, "\n".join(off), transform=ax_z.transAxes, fontsize=7,
                  va="bottom", color="#444444")
    ax_z.legend(fontsize=7, loc="upper right")
    for ax in (ax_g, ax_z):
        ax.tick_params(labelsize=8)
    return png_bytes(fig)
