"""The Inertial Vector Propagator of Cassini's pointing system (Lee §3.3; docs/ivp.md).

Pure layer (no NumPyro, ArviZ, matplotlib or CLI code):

* :mod:`~cassini_bayes.ivp.conic` — conic propagation by Goodyear's universal-variable method
  (Eqs 12-14), pure JAX, vectorised and differentiable; :mod:`~cassini_bayes.ivp.conic_fit`
  fits a conic's seven numbers to a perturbed trajectory;
* :mod:`~cassini_bayes.ivp.chebyshev` — Chebyshev polynomial segments (Eqs 15-18);
  :mod:`~cassini_bayes.ivp.segmenter` chooses their boundaries and orders for a direction
  requirement (40 µrad);
* :mod:`~cassini_bayes.ivp.tree` — the vector tree (Inertial Vector Table) and targets as
  signed paths (Fig 8);
* :mod:`~cassini_bayes.ivp.updates` — linear interpolation between updates (§3.3.3);
* :mod:`~cassini_bayes.ivp.nbody` — the n-body Titan-flyby trajectories the experiment fits;
* :mod:`~cassini_bayes.ivp.trajectory` — trajectory files (``t, x, y, z``).
"""

from cassini_bayes.ivp.chebyshev import ChebyshevSegments, chebyshev_fit, chebyshev_sum, \
    coefficient_count
from cassini_bayes.ivp.conic import Conic, ConicState, goodyear_series, propagate_conic, \
    propagate_conic_unchecked
from cassini_bayes.ivp.conic_fit import fit_conic
from cassini_bayes.ivp.segmenter import DEFAULT_REQUIREMENT_RAD, SegmentFit, \
    angle_between_vectors, angular_error, fit_chebyshev_segments
from cassini_bayes.ivp.tree import TreeEntry, VectorTree
from cassini_bayes.ivp.updates import interpolation_error

__all__ = [
    "ChebyshevSegments", "chebyshev_fit", "chebyshev_sum", "coefficient_count",
    "Conic", "ConicState", "goodyear_series", "propagate_conic", "propagate_conic_unchecked",
    "fit_conic", "DEFAULT_REQUIREMENT_RAD", "SegmentFit", "angle_between_vectors",
    "angular_error", "fit_chebyshev_segments", "TreeEntry", "VectorTree",
    "interpolation_error",
]
