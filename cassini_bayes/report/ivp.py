"""Figures and the page of the IVP (``cassini-bayes ivp fit``, the ``ivp_titan_flyby``
experiment): angular error against time per segment with the requirement line, the
equi-oscillation of one segment's fitting error, conic errors against time."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure

from cassini_bayes.report.figures import png_bytes
from cassini_bayes.report.html import figure, html_page, meta_list, paragraph, section, table

__all__ = ["segment_errors_png", "equioscillation_png", "most_uniform_segment", "errors_png",
           "ivp_fit_page"]

REQ_COLOR = "#c0392b"
_MAX_PANELS = 12


def _time_unit(span_s: float) -> tuple[float, str]:
    if span_s >= 3 * 86400:
        return 86400.0, "d"
    if span_s >= 3 * 3600:
        return 3600.0, "h"
    return 60.0, "min"


def segment_errors_png(t_s: np.ndarray, err_rad: np.ndarray, bounds_s: np.ndarray,
                       orders: Sequence[int] | np.ndarray, requirement_rad: float,
                       samples: tuple[np.ndarray, np.ndarray] | None = None) -> bytes:
    """Angle between fitted and true vector (µrad) against time: the whole span on top (segment
    boundaries dotted), then one panel per segment (up to 12), each with the requirement."""
    bounds = np.asarray(bounds_s, float)
    n_seg = len(bounds) - 1
    shown = min(n_seg, _MAX_PANELS)
    ncol = min(3, shown)
    nrow = 1 + int(np.ceil(shown / ncol))
    fig = Figure(figsize=(10.5, 2.5 * nrow), layout="constrained")
    grid = fig.add_gridspec(nrow, ncol)
    req = requirement_rad * 1e6
    scale, unit = _time_unit(bounds[-1] - bounds[0])
    ax = fig.add_subplot(grid[0, :])
    ax.plot(t_s / scale, err_rad * 1e6, lw=0.7, color="#1f4e8c", label="fit vs true")
    if samples is not None:
        ax.plot(samples[0] / scale, samples[1] * 1e6, ".", ms=2, color="#555",
                label="at the file's samples")
    for b in bounds[1:-1]:
        ax.axvline(b / scale, color="#999", lw=0.6, ls=":")
    ax.axhline(req, color=REQ_COLOR, lw=1.0, label=f"requirement {req:g} µrad")
    ax.set_xlabel(f"t ({unit})")
    ax.set_ylabel("angle (µrad)")
    ax.set_title(f"{n_seg} segments", fontsize=10)
    ax.legend(fontsize=8, loc="upper right")
    for k in range(shown):
        a = fig.add_subplot(grid[1 + k // ncol, k % ncol])
        t0, t1 = bounds[k], bounds[k + 1]
        s, u = _time_unit(t1 - t0)
        m = (t_s >= t0) & (t_s <= t1)
        a.plot((t_s[m] - t0) / s, err_rad[m] * 1e6, lw=0.8, color="#1f4e8c")
        a.axhline(req, color=REQ_COLOR, lw=1.0)
        a.set_ylim(0, 1.15 * req)
        a.set_title(f"segment {k + 1}: order {int(orders[k])}, {(t1 - t0) / s:.3g} {u}",
                    fontsize=9)
        a.set_xlabel(f"time since segment start ({u})", fontsize=8)
        a.tick_params(labelsize=7)
    return png_bytes(fig)


def most_uniform_segment(segments, f) -> tuple[int, np.ndarray, np.ndarray, float]:
    """The segment whose fitting error is closest to equi-oscillation: ``(k, τ, fitted − true
    (1001, 3), ratio)``, where ``ratio`` is the smallest over the largest extremum of the error
    of its largest-error axis (1 for a perfect minimax error)."""
    b = np.asarray(segments.bounds_s)
    tau = np.linspace(-1.0, 1.0, 1001)
    best = None
    for k in range(len(b) - 1):
        t = np.clip(0.5 * (b[k] + b[k + 1]) + 0.5 * (b[k + 1] - b[k]) * tau, b[k], b[k + 1])
        err = np.asarray(segments.position(t)) - np.asarray(f(t))
        e = err[:, int(np.argmax(np.abs(err).max(0)))]
        turn = np.nonzero(np.diff(np.sign(np.diff(e))) != 0)[0] + 1
        ext = np.abs(np.concatenate([e[[0, -1]], e[turn]]))
        ratio = float(ext.min() / ext.max()) if ext.max() > 0 else 0.0
        if best is None or ratio > best[3]:
            best = (k, tau, err, ratio)
    return best


def equioscillation_png(tau: np.ndarray, err_xyz: np.ndarray, order: int,
                        length_s: float) -> bytes:
    """Fitting error of each Cartesian component over one segment against the normalised time τ
    (Lee Eq 17): the Chebyshev fit's error alternates in sign between nearly equal extrema."""
    fig = Figure(figsize=(9.0, 3.4), layout="constrained")
    ax = fig.add_subplot()
    colors = ("#1f4e8c", "#2e8b57", "#b8860b")
    for j, (c, name) in enumerate(zip(colors, "xyz")):
        e = err_xyz[:, j]
        peak = np.max(np.abs(e))
        ax.plot(tau, e / peak, color=c, lw=1.0, label=f"{name}: max |e| = {peak:.3g} m")
    ax.axhline(1.0, color="#999", lw=0.6, ls="--")
    ax.axhline(-1.0, color="#999", lw=0.6, ls="--")
    ax.set_xlabel("τ = (2t − t_f − t_s)/(t_f − t_s)")
    ax.set_ylabel("e(τ) / max |e|")
    s, u = _time_unit(length_s)
    ax.set_title(f"error of an order-{order} Chebyshev fit over {length_s / s:.3g} {u}: "
                 f"{order + 2} alternating extrema", fontsize=10)
    ax.legend(fontsize=8, loc="lower center", ncol=3)
    return png_bytes(fig)


def errors_png(curves: Sequence[tuple[str, np.ndarray, np.ndarray]], requirement_rad: float,
               title: str, *, scale_s: float = 86400.0,
               xlabel: str = "t (days from the flyby's closest approach)") -> bytes:
    """Angle between each model and the true vector (µrad, log scale) against time, with the
    requirement line; ``curves`` are ``(label, t_s, angle_rad)``."""
    fig = Figure(figsize=(9.0, 3.6), layout="constrained")
    ax = fig.add_subplot()
    for label, t, e in curves:
        ax.semilogy(t / scale_s, np.maximum(e, 1e-6) * 1e6, lw=1.0, label=label)
    ax.axhline(requirement_rad * 1e6, color=REQ_COLOR, lw=1.0,
               label=f"requirement {requirement_rad * 1e6:g} µrad")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("angle (µrad)")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=7, loc="best")
    return png_bytes(fig)


def ivp_fit_page(summary: Mapping, figures: Sequence[tuple[bytes, str]]) -> str:
    """The ``report.html`` of ``cassini-bayes ivp fit``."""
    segs = summary["segments"]
    rows = [[k + 1, f"{s['t_start_s']:.6g}", f"{s['t_end_s']:.6g}", s["order"],
             s["coefficients"], f"{s['max_error_urad']:.2f}"] for k, s in enumerate(segs)]
    meta = meta_list([
        ("trajectory", summary["trajectory"]),
        ("requirement", f"{summary['requirement_urad']:g} µrad"),
        ("segments", f"{len(segs)} (max order {summary['max_order']})"),
        ("coefficients", summary["n_coefficients"]),
        ("largest error, dense grid", f"{summary['max_error_urad']:.2f} µrad"),
        ("largest error at the file's samples", f"{summary['max_error_samples_urad']:.2f} µrad"),
        ("meets the requirement", "yes" if summary["meets_requirement"] else "NO"),
    ])
    secs = [section("Segments", table(["segment", "t_s (s)", "t_f (s)", "order",
                                       "coefficients 3(n+1)+1", "max error (µrad)"], rows))]
    if summary.get("conic"):
        c = summary["conic"]
        secs.append(section("A conic instead", paragraph(
            f"One conic (7 numbers) fitted over the whole span with mu = {c['mu_m3_s2']:.6g} "
            f"m³/s²: largest error {c['max_error_urad']:.3g} µrad "
            f"({'meets' if c['meets_requirement'] else 'misses'} the requirement).")))
    secs.append(section("Error against time", [figure(png, cap) for png, cap in figures]))
    secs.append(section("Method", paragraph(
        "Chebyshev interpolation at the nodes of each segment (Lee §3.3.2, Eqs 15-18), one order "
        "for the three axes; segments as long as order 12 allows, then the lowest order that "
        "still holds. The error is the angle between the fitted and the true vector, on a dense "
        "grid of the file's quintic-spline interpolant and at the file's own samples "
        "(docs/ivp.md).")))
    return html_page(f"cassini-bayes ivp fit: {summary['trajectory']}", secs, header=meta)
