"""Trajectory files for ``cassini-bayes ivp fit``: one row per sample of a relative position
vector, columns ``t`` (s, strictly increasing) and ``x y z`` (m, inertial axes).

Read with the telemetry reader's CSV machinery (same limits and one-line errors naming the file,
column and row); a non-finite value, a time that does not increase, or a zero vector (whose
direction is undefined) is refused. Between samples the vector is a quintic spline through
them (:func:`interpolant`), accurate to far below 40 µrad at the sampling of a flyby (60 s).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cassini_bayes.errors import InputError, as_path

__all__ = ["Trajectory", "read_trajectory", "write_trajectory", "validate_trajectory",
           "interpolant", "interpolant_derivative", "COLUMNS"]

COLUMNS = ("t", "x", "y", "z")
MIN_ROWS = 8     # a quintic spline needs six; two more to have something left to check


@dataclass(frozen=True)
class Trajectory:
    """Samples of a vector: times ``t_s`` (N,) s and vectors ``r_m`` (N, 3) m."""

    t_s: np.ndarray
    r_m: np.ndarray
    source: str = "<memory>"


def validate_trajectory(traj: Trajectory) -> Trajectory:
    """Refuse non-finite values, non-increasing times, zero vectors and too few rows."""
    from cassini_bayes.telemetry import _check_time, _fail_nonfinite

    t, r = np.asarray(traj.t_s, float), np.asarray(traj.r_m, float)
    if t.ndim != 1 or r.shape != (t.size, 3):
        raise InputError(f"expected t (N,) and x, y, z (N, 3), got {t.shape} and {r.shape}",
                         path=traj.source)
    if t.size < MIN_ROWS:
        raise InputError(f"has {t.size} data rows; a trajectory needs at least {MIN_ROWS}",
                         path=traj.source)
    _fail_nonfinite(t, "t", traj.source, None, "fix or drop the row")
    for j, c in enumerate(COLUMNS[1:]):
        _fail_nonfinite(r[:, j], c, traj.source, t, "fix or drop the row")
    _check_time(t, traj.source)
    zero = np.linalg.norm(r, axis=1) == 0
    if zero.any():
        i = int(np.argmax(zero))
        raise InputError(f"data row {i + 1} (t = {t[i]:.10g} s): x, y, z is a zero vector, "
                         "whose direction is undefined; fix or drop the row",
                         path=traj.source)
    return Trajectory(t, r, traj.source)


def read_trajectory(path: str | os.PathLike) -> Trajectory:
    """Read and validate a trajectory CSV (module docstring)."""
    from cassini_bayes.telemetry import _read_numeric_csv

    p = as_path(path, "a trajectory file")
    idx, cols = _read_numeric_csv(p, "trajectory", COLUMNS, "t, x, y, z")
    missing = [c for c in COLUMNS if c not in idx]
    if missing:
        raise InputError(f"missing column(s) {', '.join(missing)}; a trajectory has columns "
                         "t (s), x, y, z (m)", path=str(p))
    t = cols[idx["t"]]
    r = np.column_stack([cols[idx[c]] for c in COLUMNS[1:]])
    return validate_trajectory(Trajectory(t, r, str(p)))


def write_trajectory(path: str | os.PathLike, traj: Trajectory, *, force: bool = False) -> None:
    """Write a trajectory CSV atomically (repr-precision floats)."""
    from cassini_bayes.telemetry import _write_frame

    traj = validate_trajectory(traj)
    cols = {"t": traj.t_s, **{c: traj.r_m[:, j] for j, c in enumerate(COLUMNS[1:])}}
    _write_frame(Path(path), cols, force)


def interpolant(traj: Trajectory):
    """The vector between samples: a quintic spline, times (N,) s → (N, 3) m."""
    from scipy.interpolate import make_interp_spline

    spline = make_interp_spline(traj.t_s, traj.r_m, k=5)
    return lambda t: spline(np.asarray(t, float))


def interpolant_derivative(traj: Trajectory):
    """The time derivative of :func:`interpolant`: times (N,) s → (N, 3) m/s."""
    from scipy.interpolate import make_interp_spline

    spline = make_interp_spline(traj.t_s, traj.r_m, k=5).derivative()
    return lambda t: spline(np.asarray(t, float))
