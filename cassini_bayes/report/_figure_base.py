"""The figures' shared ground: sizes, colours, the PNG renderer and tidy axes.

:func:`png_bytes` renders a figure palette-quantised to keep a page small; :func:`tidy_ticks`
leaves an axis a few ticks, so no tick labels overlap (tests/test_report.py checks both).
"""

from __future__ import annotations

import io
import math
from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator, ScalarFormatter


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


