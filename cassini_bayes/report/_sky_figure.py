"""The spin-axis sky figure: a wheel's axis posterior in body azimuth and elevation and in two
azimuthal-equidistant views about the posterior mean (circles there are true cones)."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from matplotlib.figure import Figure

from cassini_bayes.names import axis_label
from cassini_bayes.report._figure_base import (ARTICULATION_CONE_DEG, BASE_COLOR, MAX_SCATTER,
                                               POST_COLOR, RWA1_AXIS, TRUTH_COLOR, _grid_figure,
                                               tidy_ticks)

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


def _overview_panel(ax, draws: np.ndarray, m: np.ndarray, marks, cone) -> None:
    """The draws and the ``marks`` in body azimuth ``atan2(y, x)`` and elevation ``asin(z)``,
    in a window about the mean ``m`` wide enough for every mark, with the articulation ``cone``
    (axis, deg) dotted; azimuths are unwrapped next to the mean's so the window never straddles
    ±180°."""
    ae_m = _az_el_deg(m)[0]

    def _ae(v):
        p = _az_el_deg(v)
        p[:, 0] = ae_m[0] + (p[:, 0] - ae_m[0] + 180.0) % 360.0 - 180.0
        return p

    ae = _ae(draws)
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
        ax.plot(ring[:, 0], ring[:, 1], color="#888888", linewidth=1, linestyle=":",
                label=f"articulation cone ({c_deg:.2f}° from {axis_label(c_axis, 3)})")
    ax.scatter(ae[:, 0], ae[:, 1], s=4, color=POST_COLOR, alpha=0.5, label="posterior draws")
    for name, v, mk, col in marks:
        p = _ae(v)[0]
        ax.scatter([p[0]], [p[1]], marker=mk, s=120, color=col, label=name, zorder=5)
    ax.set_xlim(ae_m[0] - half, ae_m[0] + half)
    ax.set_ylim(max(-90.0, ae_m[1] - half), min(90.0, ae_m[1] + half))
    ax.grid(alpha=0.3)
    ax.set_xlabel("body azimuth atan2(y, x) (deg)", fontsize=8)
    ax.set_ylabel("body elevation asin(z) (deg)", fontsize=8)
    ax.set_title("spin axis in body axes", fontsize=9)
    ax.legend(fontsize=6.5, loc="lower left")
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
    target_label = None if target is None else f"{target[0]} target"
    marks = [] if target is None else [(target_label, np.asarray(target[1], float), "*",
                                        "#e67e22")]
    if truth is not None:
        marks.append(("truth", truth, "x", TRUTH_COLOR))
    if baseline is not None:
        marks.append(("least squares", baseline, "+", BASE_COLOR))
    _overview_panel(ax_g, draws, m, marks, cone)

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
