"""Lee §3.3's claims, measured on the n-body Titan flyby (:mod:`~cassini_bayes.ivp.nbody`):

1. vectors from the Sun to the planets and from Saturn to Titan hold 40 µrad as conics for
   months (a conic fitted over the span: :func:`~cassini_bayes.ivp.conic_fit.fit_conic`; and,
   for comparison, the osculating conic of one instant);
2. during a close Titan flyby one conic for the spacecraft fails, and a handful of Chebyshev
   segments over weeks meets 40 µrad (:func:`~cassini_bayes.ivp.fit_chebyshev_segments`),
   checked on a dense uniform grid independent of the fitting nodes;
3. linear interpolation between updates every 100 s is enough even in the fastest segment
   (:func:`~cassini_bayes.ivp.interpolation_error`);

and the vector tree of Fig 8 (spacecraft → Titan → Saturn → Sun → Earth) built from those
entries, against the integrated truth. Plain numbers, no plotting (the experiment renders them).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from cassini_bayes.ivp.conic import Conic
from cassini_bayes.ivp.conic_fit import fit_conic
from cassini_bayes.ivp.nbody import GM, Flyby, integrate_flyby
from cassini_bayes.ivp.segmenter import SegmentFit, angle_between_vectors, angular_error, \
    fit_chebyshev_segments
from cassini_bayes.ivp.tree import TreeEntry, VectorTree
from cassini_bayes.ivp.updates import interpolation_error

__all__ = ["ConicSpan", "FlybyStudy", "run_flyby_study", "CONIC_PAIRS"]

DAY_S = 86400.0
# (base, head, gravitational parameter of the pair, m^3/s^2)
CONIC_PAIRS = (
    ("sun", "earth", GM["sun"] + GM["earth"]),
    ("sun", "jupiter", GM["sun"] + GM["jupiter"]),
    ("sun", "saturn", GM["sun"] + GM["saturn"] + GM["titan"]),
    ("saturn", "titan", GM["saturn"] + GM["titan"]),
)
_GRID = 2001          # points per conic check (fixed: one compiled propagation)


class ConicSpan(NamedTuple):
    """One vector modelled by conics: the fitted conic's largest angle (rad) over each span of
    ``spans_days`` centred on ``t = 0``, and how long (days) the osculating conic of ``t = 0``
    holds the requirement (first crossing, either direction; ``inf`` when it holds over the
    longest span)."""

    base: str
    head: str
    spans_days: tuple[float, ...]
    fitted_max_rad: tuple[float, ...]
    osculating_days: float
    curve_t_s: np.ndarray          # the fitted conic over the longest span, and the osculating
    fitted_curve_rad: np.ndarray
    osculating_curve_rad: np.ndarray


class FlybyStudy(NamedTuple):
    """Everything the ``ivp_titan_flyby`` experiment reports (see the module docstring)."""

    requirement_rad: float
    flyby: Flyby
    conics: tuple[ConicSpan, ...]
    flyby_span_s: tuple[float, float]
    spacecraft_conics: dict            # "titan"/"saturn" → largest angle (rad) of a fitted conic
    segments: SegmentFit
    dense_t_s: np.ndarray
    dense_error_rad: np.ndarray
    fastest_segment: int
    update_interval_s: float
    interp_t_s: np.ndarray
    interp_error_rad: np.ndarray
    tree_error_rad: dict               # target name → largest angle along the flyby span
    closest_approach_m: float


def _first_crossing_days(t: np.ndarray, e: np.ndarray, requirement: float) -> float:
    bad = np.abs(t[e > requirement])
    return float(bad.min() / DAY_S) if bad.size else float("inf")


def run_flyby_study(*, requirement_rad: float = 40e-6, max_order: int = 12,
                    flyby: Flyby = Flyby(), flyby_span_days: float = 21.0,
                    conic_spans_days: tuple[float, ...] = (30.0, 60.0, 90.0, 120.0),
                    update_interval_s: float = 100.0, dense_step_s: float = 10.0) -> FlybyStudy:
    """Integrate the bodies and measure the three claims (module docstring)."""
    half = 0.5 * max(max(conic_spans_days), flyby_span_days) * DAY_S
    sol = integrate_flyby(-half, half, flyby)

    conics = []
    for base, head, mu in CONIC_PAIRS:
        f = sol.relative(base, head)
        r0, v0 = sol.state(head, 0.0, base)
        maxima = []
        for span in conic_spans_days:
            h = 0.5 * span * DAY_S
            c = fit_conic(f, -h, h, r0=r0, v0=v0, mu=mu, t0_s=0.0)
            grid = np.linspace(-h, h, _GRID)
            maxima.append(float(angle_between_vectors(np.asarray(c.position(grid)), f(grid)).max()))
        grid = np.linspace(-half, half, _GRID)
        fitted = angle_between_vectors(np.asarray(c.position(grid)), f(grid))
        osc = angle_between_vectors(np.asarray(Conic(r0, v0, mu, 0.0).position(grid)), f(grid))
        conics.append(ConicSpan(base, head, tuple(conic_spans_days), tuple(maxima),
                                _first_crossing_days(grid, osc, requirement_rad), grid, fitted,
                                osc))

    # the spacecraft over the flyby span: one conic (about Titan, about Saturn) vs segments
    h = 0.5 * flyby_span_days * DAY_S
    sc_conics = {}
    for base, mu in (("titan", GM["titan"]), ("saturn", GM["saturn"] + GM["titan"])):
        f = sol.relative(base, "spacecraft")
        r0, v0 = sol.state("spacecraft", 0.0, base)
        c = fit_conic(f, -h, h, r0=r0, v0=v0, mu=mu, t0_s=0.0, fit_mu=False)
        grid = np.linspace(-h, h, _GRID)
        sc_conics[base] = float(angle_between_vectors(np.asarray(c.position(grid)), f(grid)).max())
    f_sc = sol.relative("titan", "spacecraft")
    fit = fit_chebyshev_segments(f_sc, -h, h, requirement_rad=requirement_rad,
                                 max_order=max_order)
    dense_t = np.arange(-h, h, dense_step_s) + dense_step_s * (np.sqrt(2.0) - 1.0)  # off-node
    dense_err = angular_error(fit.segments, f_sc, dense_t)

    # §3.3.3: linear interpolation between updates, over the fastest (shortest) segment
    b = np.asarray(fit.segments.bounds_s)
    k = int(np.argmin(np.diff(b)))
    it, ie = interpolation_error(f_sc, b[k], b[k + 1], update_interval_s)

    # Fig 8: the tree during the flyby, entries from the fitted models above
    entries = []
    for base, head, mu in CONIC_PAIRS:
        r0, v0 = sol.state(head, 0.0, base)
        c = fit_conic(sol.relative(base, head), -h, h, r0=r0, v0=v0, mu=mu, t0_s=0.0)
        entries.append(TreeEntry(base, head, c, -h, h))
    entries.append(TreeEntry("titan", "spacecraft", fit.segments))
    tree = VectorTree(entries)
    grid = np.linspace(-h, h, 20001)
    tree_err = {}
    for base, head in (("spacecraft", "earth"), ("spacecraft", "saturn"), ("spacecraft", "sun")):
        est = np.asarray(tree.vector(base, head, grid))
        tree_err[f"{base}->{head}"] = float(angle_between_vectors(
            est, sol.relative(base, head)(grid)).max())
    ca = float(np.linalg.norm(f_sc(np.array([0.0]))[0]))
    return FlybyStudy(requirement_rad, flyby, tuple(conics), (-h, h), sc_conics, fit, dense_t,
                      dense_err, k, update_interval_s, it, ie, tree_err, ca)
