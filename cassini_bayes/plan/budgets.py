"""The papers' budget of each calibrated parameter, the yardstick of a plan's predicted sd.

* moments of inertia: ±1 % of the predicted moment (Feldman & Lee 2006 §VI, the method's quoted
  accuracy; their Eq 12 error);
* products of inertia: the model file's ``poi_uncertainty`` (Cassini's ±75 kg m² knowledge
  requirement, Feldman & Lee §IV; their Eq 13 error), as the open-world campaigns judge them
  (docs/robust/open_world.md).

* thrust: ±10 % of the predicted thrust (Feldman & Lee §V's stated accuracy,
  ``thrust_accuracy_pct``), per thrust parameter and per identified combination of thrusts;
* pulse time constants: half the width of the manufacturer's test range of the model file's
  ``[pulse]`` section (delay 3-7 ms, rise 15-25 ms, fall 40-90 ms for Cassini, Feldman & Lee §V):
  a calibration whose sd is not below it adds nothing to what the valve's data sheet says;
* the centre of mass and the inertia in a thrust fit have no budget (they are nuisances there).

A plan's *ratio* is a parameter's predicted posterior sd over its budget: at 1 the sd equals the
budget; a 95 % interval inside the budget needs a ratio below about 0.5.
"""

from __future__ import annotations

import numpy as np

from cassini_bayes.analysis.paper_facts import fact
from cassini_bayes.inference.inertia.prior import inertia_prior
from cassini_bayes.spacecraft import Spacecraft

__all__ = ["inertia_budgets", "thrust_budgets"]


def inertia_budgets(spacecraft: Spacecraft) -> np.ndarray:
    """(6,) budgets of ``Ixx … Iyz``, kg m² (module docstring)."""
    moment_pct = fact("inertia_accuracy_pct").value
    mean = inertia_prior(spacecraft).mean
    return np.concatenate([0.01 * moment_pct * mean[:3],
                           np.full(3, spacecraft.poi_uncertainty)])


def thrust_budgets(spacecraft: Spacecraft, sites, thrust_pred) -> np.ndarray:
    """Budget of each site of a thrust fit (N, s; NaN where none), module docstring. ``sites``:
    ``F``, ``F_Z``, ``F_Y``, ``F[<name>]``, ``tau_*``, ``com_*``, ``Ixx …``; ``thrust_pred``
    the fit's predicted thrust (a number, or one per thruster in mode ``thruster``)."""
    pct = 0.01 * fact("thrust_accuracy_pct").value
    p = spacecraft.pulse
    tau = {"tau_delay": p.tau_delay_range, "tau_rise": p.tau_rise_range,
           "tau_fall": p.tau_fall_range}
    per = np.atleast_1d(np.asarray(thrust_pred, float))
    names = spacecraft.thruster_names
    out = []
    for s in sites:
        if s.startswith("F["):
            out.append(pct * per[list(names).index(s[2:-1])])
        elif s.startswith("F"):
            out.append(pct * float(np.mean(per)))
        elif s in tau:
            out.append(0.5 * (tau[s][1] - tau[s][0]))
        else:
            out.append(np.nan)
    return np.asarray(out, float)
