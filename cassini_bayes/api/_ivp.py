"""Chebyshev segments for a trajectory file: :func:`fit_trajectory`, what ``cassini-bayes ivp
fit`` runs (docs/ivp.md).

The conic propagator, the segmenter and the vector tree themselves come from
:mod:`cassini_bayes.ivp` (``cb.propagate_conic``, ``cb.fit_chebyshev_segments``,
``cb.VectorTree``), here set to compute in 64-bit (:func:`cassini_bayes.setup_jax`) when called
or built, as every public function that computes is.
"""

from __future__ import annotations

import copy
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from cassini_bayes import __version__, ivp
from cassini_bayes._devices import jax_entry, setup_jax
from cassini_bayes.errors import InputError, spelled

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from cassini_bayes.ivp.segmenter import SegmentFit
    from cassini_bayes.ivp.trajectory import Trajectory
    from cassini_bayes.ivp.tree import TreeEntry

__all__ = ["TrajectoryFit", "fit_trajectory", "propagate_conic", "fit_chebyshev_segments",
           "VectorTree"]

propagate_conic = jax_entry(ivp.propagate_conic)
fit_chebyshev_segments = jax_entry(ivp.fit_chebyshev_segments)


class VectorTree(ivp.VectorTree):
    __doc__ = ivp.VectorTree.__doc__

    def __init__(self, entries: Sequence[TreeEntry]) -> None:
        setup_jax()
        super().__init__(entries)

_DENSE_PER_SEGMENT = 400   # report grid points per segment (besides the file's samples)


@dataclass(frozen=True)
class TrajectoryFit:
    """Segments fitted to one trajectory file.

    Attributes
    ----------
    fit : the :class:`~cassini_bayes.ivp.segmenter.SegmentFit`.
    trajectory : the :class:`~cassini_bayes.ivp.trajectory.Trajectory` read.
    dense_t_s, dense_error_rad : the angle between fitted and interpolated vector on a grid of
        ``400`` uniform points per segment (independent of the fitting nodes).
    sample_error_rad : the angle at each of the file's samples.
    summary, config : ``summary.json`` and ``config.toml`` as dicts.
    files : the input files.
    """

    fit: SegmentFit
    trajectory: Trajectory
    dense_t_s: np.ndarray
    dense_error_rad: np.ndarray
    sample_error_rad: np.ndarray
    _summary: dict = field(repr=False)
    config: dict
    files: tuple

    def summary(self) -> dict:
        """``summary.json`` as a dict (a copy; the same protocol as :meth:`FitResult.summary`)."""
        return copy.deepcopy(self._summary)

    def save(self, out: str | os.PathLike, *, force: bool = False) -> Path:
        """Write ``segments.csv`` (one row per segment: ``t_start_s, t_end_s, order,
        max_error_urad`` and the coefficients ``cx_0 … cz_12``, m), ``summary.json``,
        ``config.toml`` and ``report.html`` into ``out`` atomically; ``force`` replaces only a
        directory cassini-bayes wrote."""
        from cassini_bayes.report.ivp import (
            equioscillation_png,
            ivp_fit_page,
            most_uniform_segment,
            segment_errors_png,
        )
        from cassini_bayes.rundir import RunDir, write_config, write_summary

        seg = self.fit.segments
        bounds = np.asarray(seg.bounds_s)
        coeffs = np.asarray(seg.coeffs)
        orders = np.asarray(seg.orders)
        header = ["t_start_s", "t_end_s", "order", "max_error_urad"] + [
            f"c{a}_{i}" for a in "xyz" for i in range(coeffs.shape[-1])]
        rows = np.column_stack([bounds[:-1], bounds[1:], orders, self.fit.max_error_rad * 1e6,
                                coeffs.reshape(len(orders), -1)])
        figures = [(segment_errors_png(self.dense_t_s, self.dense_error_rad, bounds, orders,
                                       self.fit.requirement_rad,
                                       samples=(self.trajectory.t_s, self.sample_error_rad)),
                    "Angle between the fitted and the true vector: the whole span (top) and each "
                    "segment; red: the requirement.")]
        k, tau, err, ratio = most_uniform_segment(seg, self.fit_function)
        figures.append((equioscillation_png(tau, err, int(orders[k]), bounds[k + 1] - bounds[k]),
                        f"Segment {k + 1}: fitting error of x, y, z against τ (Lee Eq 17); its "
                        f"smallest extremum is {ratio:.2f} of its largest."))
        with RunDir(out, force=force, inputs=list(self.files)) as rd:
            write_summary(rd.path, self._summary)
            write_config(rd.path, self.config)
            np.savetxt(rd.path / "segments.csv", rows, delimiter=",", fmt="%.17g",
                       header=",".join(header), comments="")
            (rd.path / "report.html").write_text(ivp_fit_page(self._summary, figures),
                                                 encoding="utf-8")
        return rd.final

    @property
    def fit_function(self) -> Callable[[np.ndarray], np.ndarray]:
        from cassini_bayes.ivp.trajectory import interpolant

        return interpolant(self.trajectory)


def _conic_block(traj: Trajectory, mu: float, requirement_urad: float) -> dict[str, Any]:
    """The conic about the body of ``mu`` fitted over the whole span (its state at the span's
    middle), and its largest angular error on a 2000-point grid, as summary.json holds it."""
    from cassini_bayes.ivp.conic_fit import fit_conic
    from cassini_bayes.ivp.segmenter import angle_between_vectors
    from cassini_bayes.ivp.trajectory import interpolant, interpolant_derivative

    f = interpolant(traj)
    t0, t1 = float(traj.t_s[0]), float(traj.t_s[-1])
    r0 = f(np.array([0.5 * (t0 + t1)]))[0]
    v0 = np.asarray(interpolant_derivative(traj)(0.5 * (t0 + t1)))
    conic = fit_conic(f, t0, t1, r0=r0, v0=v0, mu=mu, t0_s=0.5 * (t0 + t1), fit_mu=False)
    grid = np.linspace(t0, t1, 2000)
    c_err = angle_between_vectors(np.asarray(conic.position(grid)), f(grid))
    return {"mu_m3_s2": mu, "t0_s": conic.t0_s, "r0_m": [float(x) for x in conic.r0],
            "v0_m_s": [float(x) for x in conic.v0], "max_error_urad": float(c_err.max() * 1e6),
            "meets_requirement": bool(c_err.max() <= requirement_urad * 1e-6)}


@jax_entry
def fit_trajectory(trajectory: Trajectory | str | os.PathLike, *, requirement_urad: float = 40.0,
                   max_order: int = 12, mu: float | None = None) -> TrajectoryFit:
    """Chebyshev segments of a trajectory whose direction stays within ``requirement_urad`` of
    the trajectory's (Lee §3.3.2; :func:`~cassini_bayes.ivp.fit_chebyshev_segments`).

    Parameters
    ----------
    trajectory : a trajectory CSV path (columns ``t`` s, ``x y z`` m) or a
        :class:`~cassini_bayes.ivp.trajectory.Trajectory`.
    requirement_urad : the largest angle allowed between fitted and true vector, µrad.
    max_order : the highest order of a segment, 0 .. 12.
    mu : optional gravitational parameter (m³/s²) of the body the vector is measured from: a
        conic is then also fitted over the whole span and its error reported beside the
        segments'.
    """
    from cassini_bayes.ivp._checks import check_mu, check_order
    from cassini_bayes.ivp.segmenter import angle_between_vectors, fit_chebyshev_segments
    from cassini_bayes.ivp.trajectory import (
        Trajectory,
        interpolant,
        read_trajectory,
        validate_trajectory,
    )
    from cassini_bayes.rundir import file_record

    where_req = spelled("--requirement-urad", "requirement_urad")
    if not (np.isfinite(requirement_urad) and requirement_urad > 0):
        raise InputError(f"{where_req} must be a positive number of µrad, got {requirement_urad}")
    check_order(max_order, spelled("--max-order", "max_order"))
    if mu is not None:
        check_mu(np.asarray(mu, float), spelled("--mu", "mu"))
    if isinstance(trajectory, Trajectory):
        files: tuple[Path, ...] = ()
        traj, record = validate_trajectory(trajectory), {"source": trajectory.source}
    else:
        traj = read_trajectory(trajectory)
        record, files = file_record(trajectory), (Path(trajectory),)
    f = interpolant(traj)
    t0, t1 = float(traj.t_s[0]), float(traj.t_s[-1])
    fit = fit_chebyshev_segments(f, t0, t1, requirement_rad=requirement_urad * 1e-6,
                                 max_order=max_order)
    seg = fit.segments
    bounds = np.asarray(seg.bounds_s)
    u = (np.arange(_DENSE_PER_SEGMENT) + 0.5) / _DENSE_PER_SEGMENT
    dense_t = (bounds[:-1, None] + np.diff(bounds)[:, None] * u[None, :]).reshape(-1)
    dense_err = angle_between_vectors(np.asarray(seg.position(dense_t)), f(dense_t))
    sample_err = angle_between_vectors(np.asarray(seg.position(traj.t_s)), traj.r_m)
    orders = np.asarray(seg.orders)
    summary = {
        "command": "ivp fit", "version": __version__, "trajectory": traj.source,
        "t_start_s": t0, "t_end_s": t1, "requirement_urad": float(requirement_urad),
        "max_order": int(max_order), "n_segments": int(len(orders)),
        "n_coefficients": seg.n_coefficients,
        "max_error_urad": float(dense_err.max() * 1e6),
        "max_error_samples_urad": float(sample_err.max() * 1e6),
        "meets_requirement": bool(max(dense_err.max(), sample_err.max())
                                  <= requirement_urad * 1e-6),
        "segments": [{"t_start_s": float(bounds[k]), "t_end_s": float(bounds[k + 1]),
                      "order": int(orders[k]), "coefficients": 3 * (int(orders[k]) + 1) + 1,
                      "max_error_urad": float(fit.max_error_rad[k] * 1e6)}
                     for k in range(len(orders))],
    }
    if mu is not None:
        summary["conic"] = _conic_block(traj, float(mu), requirement_urad)
    config = {"command": "ivp fit", "version": __version__, "inputs": {"trajectory": record},
              "settings": {"requirement_urad": float(requirement_urad),
                           "max_order": int(max_order),
                           **({"mu_m3_s2": float(mu)} if mu is not None else {})}}
    return TrajectoryFit(fit, traj, dense_t, dense_err, sample_err, summary, config, files)

