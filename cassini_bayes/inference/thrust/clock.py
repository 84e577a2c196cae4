"""A regular telemetry clock: the labels put on their grid, the grid's error integrated out.

Where the model file states ``[telemetry_knowledge] regular_clock = true`` the telemetry is
sampled on a regular clock and only its labels carry the time-tag error. The robust thrust fit
then replaces each event's labels by their least-squares line in the sample index,
``t̂_i = t̂₀ + P̂ (i − ī)``, which leaves no error per sample: what the grid keeps of the labels'
errors ``ε_i`` (sd ``σ``) is an offset ``a`` (sd ``σ/√n``) and a period error ``b`` (sd
``σ/√S``, ``S = Σ (i − ī)²``), independent of each other. Both shift every sample against the
pulse commands, which the delay ``τd`` alone would otherwise absorb as a shift (docs/planning.md,
"A regular clock"). They are two robust nuisance columns per event,
``∂r/∂a = Σ_i ∂r/∂t_i`` and ``∂r/∂b = Σ_i (i − ī) ∂r/∂t_i`` of the residual of Feldman & Lee
Eq 17 (the thrusters' impulse and the left side's trapezoid, at the prior's thrust, time
constants and inertia), integrated out with the others; ``σ`` is the labels' scatter about the
grid, or a stated one (a plan's telemetry has none).
"""

from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.errors import InputError
from cassini_bayes.inference.thrust.likelihood import PulseLayout, thruster_impulse
from cassini_bayes.inference.thrust.time_tags import left_side_at_times
from cassini_bayes.telemetry import Telemetry

__all__ = ["ClockGrid", "clock_grid", "on_grid", "events_on_grid", "clock_columns",
           "events_clock_columns"]

GRID_TOLERANCE = 0.25
"""Largest label error, as a share of the sampling period, that a regular clock's labels may
carry: a label further from its grid is not on it (or the index of a gap is ambiguous)."""


class ClockGrid(NamedTuple):
    """One event's labels on their least-squares grid (:func:`clock_grid`)."""

    t: np.ndarray            # (n,) s, the grid at each sample
    index: np.ndarray        # (n,) each sample's place on the clock, centred (i − ī)
    scatter_s: float         # the labels' sd about the grid (n − 2 degrees of freedom)
    offset_sd_s: float       # the grid's offset error at ``ī``, σ/√n
    period_sd_s: float       # its period error, σ/√S (s per sample)

    def to_dict(self) -> dict:
        """The grid's period (s), the labels' scatter removed and the errors integrated out."""
        span = float(self.index[-1] - self.index[0])
        return {"period_s": float(self.t[-1] - self.t[0]) / span, "scatter_s": self.scatter_s,
                "offset_sd_s": self.offset_sd_s, "period_sd_s": self.period_sd_s}


def clock_grid(t, source: str = "<telemetry>", sd_s: float | None = None) -> ClockGrid:
    """:class:`ClockGrid` of labels ``t`` (n,) s on a regular clock: each sample's place the
    last one's plus its step in median steps, rounded (a gap keeps its places), the grid the
    places' least-squares line; ``sd_s`` the labels' error sd (``None``: their scatter about
    the grid).

    Raises
    ------
    InputError
        Fewer than 3 samples, or a label further than :data:`GRID_TOLERANCE` of a period from
        the grid (the clock is not regular).
    """
    t = np.asarray(t, float)
    if t.size < 3:
        raise InputError(f"{source}: a regular clock needs 3 or more samples, got {t.size}")
    step = np.diff(t)
    place = np.r_[0.0, np.cumsum(np.maximum(np.round(step / np.median(step)), 1.0))]
    idx = place - place.mean()
    s = float(np.sum(idx**2))
    slope = float(np.sum(idx * (t - t.mean())) / s)
    grid = t.mean() + slope * idx
    resid = t - grid
    worst = int(np.argmax(np.abs(resid)))
    if abs(resid[worst]) > GRID_TOLERANCE * slope:
        raise InputError(f"{source}: the sample labelled t = {t[worst]:.10g} s is "
                         f"{resid[worst] * 1e3:.3g} ms off the regular {slope:.6g}-s clock the "
                         "model file states; remove [telemetry_knowledge] regular_clock for "
                         "telemetry sampled irregularly")
    sigma = float(np.sqrt(np.sum(resid**2) / (t.size - 2))) if sd_s is None else float(sd_s)
    return ClockGrid(grid, idx, sigma, sigma / np.sqrt(t.size), sigma / np.sqrt(s))


def on_grid(tel: Telemetry, sd_s: float | None = None) -> tuple[Telemetry, ClockGrid]:
    """``tel`` with its labels on their grid (:func:`clock_grid`), and the grid."""
    grid = clock_grid(tel.t, tel.source, sd_s)
    return replace(tel, t=grid.t), grid


def events_on_grid(tels: list[Telemetry], regular: bool, sd_s: float | None = None
                   ) -> tuple[list[Telemetry], list[ClockGrid] | None]:
    """Every event's :func:`on_grid` where the clock is ``regular``, and the grids; else the
    telemetry unchanged and ``None``."""
    if not regular:
        return tels, None
    tels, grids = zip(*(on_grid(tel, sd_s) for tel in tels))
    return list(tels), list(grids)


def clock_columns(t, omega, h_wheels, layout: PulseLayout, inertia, q_f, tau, omega_mid, h_mid,
                  grid: ClockGrid) -> np.ndarray:
    """(2, 3, n) N m s per s of offset and per s/sample of period: ``∂r/∂a`` and ``∂r/∂b`` of
    one event (module docstring), on its ``n`` padded samples (0 on padding): ``layout`` its
    :class:`PulseLayout`, ``q_f`` (3, M) N m the thrusters' torques at the predicted thrust,
    ``tau`` (3,) s the prior's time constants, ``omega_mid``/``h_mid`` (3, n) the intervals'
    means."""
    n_pad, n = np.size(t), grid.t.size
    left = left_side_at_times(t, omega, h_wheels, layout, inertia, q_f, tau, omega_mid, h_mid)

    def residual(tt):
        v, moved = left(tt)
        return v.T - thruster_impulse(moved, q_f, *tau)                # Eq 17, (3, n)

    out = np.zeros((2, 3, n_pad))
    for k, shape in enumerate((np.ones(n), grid.index)):
        tangent = np.zeros(n_pad)
        tangent[:n] = shape
        d = jax.jvp(residual, (jnp.asarray(t, float),), (jnp.asarray(tangent),))[1]
        out[k, :, :n] = np.asarray(d)[:, :n]
    return out


def events_clock_columns(kw: dict, layouts: PulseLayout, inertia, q_f, tau, steps: dict,
                         grids: list[ClockGrid]) -> tuple[np.ndarray, np.ndarray]:
    """Every event's :func:`clock_columns` as nuisance columns (E, 2E, 3, n), each event's two
    in its own block (a clock moves no other event), and their prior sds (2E,) s, s/sample."""
    n_ev = len(grids)
    cols = np.zeros((n_ev, 2 * n_ev, 3, np.shape(kw["t"])[1]))
    for e, grid in enumerate(grids):
        cols[e, 2 * e:2 * e + 2] = clock_columns(
            kw["t"][e], kw["omega"][e], kw["h_wheels"][e],
            PulseLayout(*(x[e] for x in layouts)), inertia, q_f, tau,
            steps["omega_mid"][e], steps["h_mid"][e], grid)
    sd = np.ravel([(g.offset_sd_s, g.period_sd_s) for g in grids])
    return cols, sd
