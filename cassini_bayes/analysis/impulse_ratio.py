"""Impulse ratio ``R`` of Cassini's thruster pulses, and what it does to the thrust estimates.

Feldman & Lee (2006) §V: the impulse model (Eq 17) assumes a pulse of commanded width ``Δ`` delivers
``F Δ``; the thrust profile with delay, rise and fall time constants delivers more, by the ratio
``R = impulse / (F Δ)``. A thrust fitted with the ideal model is therefore ``R`` times too large and
is corrected by dividing by ``R`` (0.98 N → 0.98 / 1.3406 ≈ 0.731 N in the FSDS test; Table 2's
adjusted columns).

This module evaluates ``R`` (via :mod:`cassini_bayes.physics.pulse`) for single pulses and for the
FSDS pulse mix, over grids of ``tau_fall`` × ``tau_rise`` spanning the manufacturer's test ranges
(broadcast, no Python loops), and returns an :class:`ImpulseRatioAnalysis`. Times in seconds,
thrust in newtons.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.analysis.paper_facts import (
    FSDS_LS_THRUST_N,
    FSDS_PULSE_MIX,
    TABLE2,
)
from cassini_bayes.physics.pulse import impulse_ratio, mix_ratio

__all__ = [
    "ImpulseRatioAnalysis",
    "ratio_grid",
    "mix_ratio_grid",
    "adjust_thrust",
    "analyse_impulse_ratio",
    "plot_impulse_ratio",
]


@dataclass(frozen=True)
class ImpulseRatioAnalysis:
    """Impulse ratios at the nominal time constants and over the manufacturer's ranges.

    Attributes
    ----------
    widths_s : (w,) commanded pulse widths, s.
    tau_delay_s, tau_rise_s, tau_fall_s : nominal time constants, s.
    tau_fall_alt_s : the paper's alternative fall time constant (40 ms), s.
    ratio : (w,) ``R`` of each width at the nominal time constants.
    ratio_alt : (w,) ``R`` of each width with ``tau_fall_alt_s``.
    mix_widths_s, mix_counts : the FSDS Y2 pulse mix.
    mix_on_time_s : its total commanded on-time, s.
    mix_ratio : ``R`` of the mix at the nominal time constants.
    ls_thrust_n : the FSDS plain least-squares thrust, N (0.98).
    corrected_thrust_n : ``ls_thrust_n / mix_ratio``, N.
    tau_fall_grid_s : (nf,) grid over the fall-time range, s.
    tau_rise_grid_s : (nr,) grid over the rise-time range, s.
    ratio_on_grid : (w + 1, nf, nr) ``R`` over the grid; the last row is the FSDS mix.
    table2_days : (5,) days of the 2004 biasing events.
    table2_no_adjustment_n : (5,) Table 2's unadjusted thrusts, N.
    table2_adjusted_n : (5,) adjusted with ``R(125 ms)`` at the nominal ``tau_fall``, N.
    table2_adjusted_alt_n : (5,) adjusted with ``R(125 ms)`` at ``tau_fall_alt_s``, N.
    table2_ratio_decimals : decimals ``R`` was rounded to before dividing (the paper divides by the
        printed 1.395 and 1.195), or ``None`` for the exact ``R``.
    """

    widths_s: np.ndarray
    tau_delay_s: float
    tau_rise_s: float
    tau_fall_s: float
    tau_fall_alt_s: float
    ratio: np.ndarray
    ratio_alt: np.ndarray
    mix_widths_s: np.ndarray
    mix_counts: np.ndarray
    mix_on_time_s: float
    mix_ratio: float
    ls_thrust_n: float
    corrected_thrust_n: float
    tau_fall_grid_s: np.ndarray
    tau_rise_grid_s: np.ndarray
    ratio_on_grid: np.ndarray
    table2_days: np.ndarray
    table2_no_adjustment_n: np.ndarray
    table2_adjusted_n: np.ndarray
    table2_adjusted_alt_n: np.ndarray
    table2_ratio_decimals: int | None

    @property
    def mix_ratio_range(self) -> tuple[float, float]:
        """Smallest and largest ``R`` of the FSDS mix over the manufacturer's ranges."""
        g = self.ratio_on_grid[-1]
        return float(g.min()), float(g.max())

    @property
    def corrected_thrust_range_n(self) -> tuple[float, float]:
        """The corrected FSDS thrust, N, over the manufacturer's ranges (low, high)."""
        lo, hi = self.mix_ratio_range
        return self.ls_thrust_n / hi, self.ls_thrust_n / lo

    def to_dict(self) -> dict[str, Any]:
        """JSON-able summary (units in the key names)."""
        lo, hi = self.corrected_thrust_range_n
        return {
            "tau_delay_s": self.tau_delay_s, "tau_rise_s": self.tau_rise_s,
            "tau_fall_s": self.tau_fall_s, "tau_fall_alt_s": self.tau_fall_alt_s,
            "ratio": {f"{w * 1e3:g}ms": float(r) for w, r in zip(self.widths_s, self.ratio)},
            "ratio_tau_fall_alt": {f"{w * 1e3:g}ms": float(r)
                                   for w, r in zip(self.widths_s, self.ratio_alt)},
            "ratio_range_over_manufacturer_box": {
                f"{w * 1e3:g}ms": [float(g.min()), float(g.max())]
                for w, g in zip(self.widths_s, self.ratio_on_grid[:-1])},
            "fsds_mix": {"widths_s": self.mix_widths_s.tolist(),
                         "counts": self.mix_counts.tolist(),
                         "on_time_s": self.mix_on_time_s, "ratio": self.mix_ratio,
                         "ratio_range": list(self.mix_ratio_range),
                         "ls_thrust_n": self.ls_thrust_n,
                         "corrected_thrust_n": self.corrected_thrust_n,
                         "corrected_thrust_range_n": [lo, hi],
                         "corrected_thrust_spread_pct": 100 * (hi - lo) / (hi + lo)},
            "grid": {"tau_fall_s": self.tau_fall_grid_s.tolist(),
                     "tau_rise_s": self.tau_rise_grid_s.tolist()},
            "table2": {"day": self.table2_days.tolist(),
                       "no_adjustment_n": self.table2_no_adjustment_n.tolist(),
                       "adjusted_n": self.table2_adjusted_n.tolist(),
                       "adjusted_tau_fall_alt_n": self.table2_adjusted_alt_n.tolist(),
                       "ratio_decimals": self.table2_ratio_decimals},
        }


def ratio_grid(widths_s, tau_fall_s, tau_rise_s, tau_delay_s) -> np.ndarray:
    """``R`` (Feldman & Lee §V) of each width over a ``tau_fall`` × ``tau_rise`` grid.

    Parameters
    ----------
    widths_s : (w,) commanded widths, s.
    tau_fall_s : (nf,) fall time constants, s.
    tau_rise_s : (nr,) rise time constants, s.
    tau_delay_s : valve delay, s.

    Returns
    -------
    (w, nf, nr) array of ratios.
    """
    w = np.asarray(widths_s, float)[:, None, None]
    tf = np.asarray(tau_fall_s, float)[None, :, None]
    tr = np.asarray(tau_rise_s, float)[None, None, :]
    return np.asarray(impulse_ratio(w, tau_delay_s, tr, tf))


def mix_ratio_grid(widths_s, counts, tau_fall_s, tau_rise_s, tau_delay_s) -> np.ndarray:
    """``R`` of a pulse mix (Feldman & Lee §V: 1.3406 for FSDS) over a τ_fall × τ_rise grid.

    Returns an (nf, nr) array; ``widths_s`` (s) and ``counts`` are (k,).
    """
    tf = np.asarray(tau_fall_s, float)[:, None, None]
    tr = np.asarray(tau_rise_s, float)[None, :, None]
    w = np.asarray(widths_s, float)[None, None, :]
    n = np.broadcast_to(np.asarray(counts, float), w.shape)
    return np.asarray(mix_ratio(w, n, tau_delay_s, tr, tf))


def adjust_thrust(thrust_n, ratio, decimals: int | None = None) -> np.ndarray:
    """Thrust corrected for pulse dynamics: ``F / R`` (Feldman & Lee §V, Table 2).

    ``decimals`` rounds ``R`` first, as the paper does when it divides by the printed 1.395.
    """
    r = np.asarray(ratio, float)
    if decimals is not None:
        r = np.round(r, decimals)
    return np.asarray(thrust_n, float) / r


@jax.jit
def _ratios(widths, mix_w, mix_n, tf_grid, tr_grid, td, tr, tf, tf_alt):
    """Every ratio of the analysis in one compiled call (eager dispatch of small ops is slow)."""
    ratio = impulse_ratio(widths, td, tr, tf)
    ratio_alt = impulse_ratio(widths, td, tr, tf_alt)
    r_mix = mix_ratio(mix_w, mix_n, td, tr, tf)
    w = widths[:, None, None]
    tfg, trg = tf_grid[None, :, None], tr_grid[None, None, :]
    grid_w = impulse_ratio(w, td, trg, tfg)
    grid_mix = mix_ratio(mix_w[None, None, :], mix_n[None, None, :], td,
                         tr_grid[None, :, None], tf_grid[:, None, None])
    grid = jnp.concatenate([grid_w, grid_mix[None]])
    # Table 2: nearly all day-28 pulses are 125 ms, so the paper divides by R(125 ms).
    r125 = impulse_ratio(0.125, td, tr, tf)
    r125_alt = impulse_ratio(0.125, td, tr, tf_alt)
    return ratio, ratio_alt, r_mix, grid, r125, r125_alt


def analyse_impulse_ratio(
    widths_s=(0.125, 0.250, 0.500, 0.750),
    *,
    tau_delay_s: float = 0.005,
    tau_rise_s: float = 0.020,
    tau_fall_s: float = 0.065,
    tau_fall_alt_s: float = 0.040,
    tau_fall_range_s=(0.040, 0.090),
    tau_rise_range_s=(0.015, 0.025),
    grid_points: int = 51,
    pulse_mix=FSDS_PULSE_MIX,
    ls_thrust_n: float = FSDS_LS_THRUST_N,
    table2_ratio_decimals: int | None = 3,
) -> ImpulseRatioAnalysis:
    """Feldman & Lee (2006) §V impulse-ratio analysis.

    Parameters
    ----------
    widths_s : commanded pulse widths, s.
    tau_delay_s, tau_rise_s, tau_fall_s : nominal time constants, s (manufacturer: 5, 20, 65 ms).
    tau_fall_alt_s : alternative fall time the paper also evaluates (40 ms), s.
    tau_fall_range_s, tau_rise_range_s : manufacturer test ranges, s (40-90 ms, 15-25 ms).
    grid_points : points per axis of the ``tau_fall`` × ``tau_rise`` grid.
    pulse_mix : ((width s, count), ...) of the FSDS scenario's Y2 pulses.
    ls_thrust_n : thrust fitted with the ideal impulse model, N (0.98 in the FSDS test).
    table2_ratio_decimals : round ``R(125 ms)`` to this many decimals before adjusting Table 2 (the
        paper divides by the printed 1.395 / 1.195); ``None`` divides by the exact ``R``.
    """
    if grid_points < 2:
        raise ValueError("grid_points must be at least 2")
    widths = np.asarray(widths_s, float)
    mix_w = np.array([w for w, _ in pulse_mix], float)
    mix_n = np.array([n for _, n in pulse_mix], float)
    tf_grid = np.linspace(*tau_fall_range_s, grid_points)
    tr_grid = np.linspace(*tau_rise_range_s, grid_points)
    ratio, ratio_alt, r_mix, grid, r125, r125_alt = (np.asarray(x) for x in _ratios(
        widths, mix_w, mix_n, tf_grid, tr_grid, tau_delay_s, tau_rise_s, tau_fall_s,
        tau_fall_alt_s))
    r_mix, r125, r125_alt = float(r_mix), float(r125), float(r125_alt)
    no_adj = np.asarray(TABLE2["no_adjustment_n"], float)
    return ImpulseRatioAnalysis(
        widths_s=widths, tau_delay_s=tau_delay_s, tau_rise_s=tau_rise_s, tau_fall_s=tau_fall_s,
        tau_fall_alt_s=tau_fall_alt_s, ratio=ratio, ratio_alt=ratio_alt, mix_widths_s=mix_w,
        mix_counts=mix_n.astype(int), mix_on_time_s=float(mix_w @ mix_n), mix_ratio=r_mix,
        ls_thrust_n=ls_thrust_n, corrected_thrust_n=ls_thrust_n / r_mix,
        tau_fall_grid_s=tf_grid, tau_rise_grid_s=tr_grid, ratio_on_grid=grid,
        table2_days=np.asarray(TABLE2["day"]), table2_no_adjustment_n=no_adj,
        table2_adjusted_n=adjust_thrust(no_adj, r125, table2_ratio_decimals),
        table2_adjusted_alt_n=adjust_thrust(no_adj, r125_alt, table2_ratio_decimals),
        table2_ratio_decimals=table2_ratio_decimals,
    )


def plot_impulse_ratio(a: ImpulseRatioAnalysis):
    """Figure: ``R`` of the FSDS mix over the manufacturer box, and ``R`` against ``tau_fall``.

    Left: heat map of the mix ratio over ``tau_fall`` × ``tau_rise`` with the nominal point and the
    1.3406 contour. Right: ``R`` of each width against ``tau_fall`` at the nominal ``tau_rise``,
    with the band swept by ``tau_rise`` over its range. Returns a matplotlib ``Figure``.
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 4.2), layout="constrained")
    ax0, ax1 = fig.subplots(1, 2)
    tf_ms, tr_ms = a.tau_fall_grid_s * 1e3, a.tau_rise_grid_s * 1e3
    mix = a.ratio_on_grid[-1]
    im = ax0.pcolormesh(tf_ms, tr_ms, mix.T, shading="auto", cmap="viridis")
    cs = ax0.contour(tf_ms, tr_ms, mix.T, levels=[a.mix_ratio], colors="w", linewidths=1)
    ax0.clabel(cs, fmt="R = %.4f", manual=[(a.tau_fall_s * 1e3 + 4, a.tau_rise_s * 1e3 - 3)])
    ax0.plot(a.tau_fall_s * 1e3, a.tau_rise_s * 1e3, "w*", ms=12, mec="k")
    ax0.set(xlabel="τ_fall (ms)", ylabel="τ_rise (ms)",
            title="R of the FSDS pulse mix")
    fig.colorbar(im, ax=ax0, label="impulse ratio R")
    i_rise = int(np.argmin(np.abs(a.tau_rise_grid_s - a.tau_rise_s)))
    series = [(f"{w * 1e3:g} ms", g) for w, g in zip(a.widths_s, a.ratio_on_grid[:-1])]
    series.append(("FSDS mix", mix))
    for label, g in series:
        (line,) = ax1.plot(tf_ms, g[:, i_rise], label=label)
        ax1.fill_between(tf_ms, g.min(axis=1), g.max(axis=1), color=line.get_color(), alpha=0.15)
    ax1.axvline(a.tau_fall_s * 1e3, color="k", lw=0.8, ls="--")
    ax1.axvline(a.tau_fall_alt_s * 1e3, color="k", lw=0.8, ls=":")
    ax1.set(xlabel="τ_fall (ms)", ylabel="impulse ratio R",
            title=f"R vs τ_fall (band: τ_rise {tr_ms[0]:g}-{tr_ms[-1]:g} ms)")
    ax1.legend(fontsize=8)
    return fig
