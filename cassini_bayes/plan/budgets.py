"""The papers' budget of each calibrated parameter, the yardstick of a plan's predicted sd.

* moments of inertia: ±1 % of the predicted moment (Feldman & Lee 2006 §VI, the method's quoted
  accuracy; their Eq 12 error);
* products of inertia: the model file's ``poi_uncertainty`` (Cassini's ±75 kg m² knowledge
  requirement, Feldman & Lee §IV; their Eq 13 error), as the open-world campaigns judge them
  (docs/robust/open_world.md).

A plan's *ratio* is a parameter's predicted posterior sd over its budget: at 1 the sd equals the
budget; a 95 % interval inside the budget needs a ratio below about 0.5.
"""

from __future__ import annotations

import numpy as np

from cassini_bayes.analysis.paper_facts import fact
from cassini_bayes.inference.inertia.prior import inertia_prior
from cassini_bayes.spacecraft import Spacecraft

__all__ = ["inertia_budgets"]


def inertia_budgets(spacecraft: Spacecraft) -> np.ndarray:
    """(6,) budgets of ``Ixx … Iyz``, kg m² (module docstring)."""
    moment_pct = fact("inertia_accuracy_pct").value
    mean = inertia_prior(spacecraft).mean
    return np.concatenate([0.01 * moment_pct * mean[:3],
                           np.full(3, spacecraft.poi_uncertainty)])
