"""Plan an inertia calibration: search, optimise, write the scenario, check it at full step.

:func:`plan_inertia_slews` runs :func:`cassini_bayes.plan.optimise.optimise_slews` for each slew
count that fits the limits, keeps the best, writes it as a scenario (the limits file's sections,
the spacecraft model as truth and prior, the ``[[slew]]`` list), loads that scenario with the
simulator's own checks and evaluates it at the scenario's integration step
(:func:`cassini_bayes.plan.evaluate.evaluate_inertia`), limits usage included. The comparison
is Feldman & Lee's manoeuvre of the same duration under the same limits
(:func:`papers_slews`), or any scenario given.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from cassini_bayes.errors import InputError
from cassini_bayes.plan.evaluate import InertiaPrediction, evaluate_inertia
from cassini_bayes.plan.limits import Limits, base_scenario_dict
from cassini_bayes.plan.manoeuvre import accel_limit, rate_limit, slew_table
from cassini_bayes.plan.optimise import (
    SLEW_COUNTS,
    TARGETS,
    OptimisedSlews,
    optimise_slews,
    slew_bounds,
    slew_counts,
)
from cassini_bayes.simulate.controllers import slew_duration
from cassini_bayes.simulate.scenario import Scenario, scenario_from_dict

__all__ = [
    "PAPERS_ANGLE_DEG",
    "InertiaPlan",
    "papers_slews",
    "plan_inertia_slews",
    "target_value",
]

MIN_SLEW_DEG = 0.5
"""A planned slew of a smaller angle is dropped from the plan: the optimiser gave it (almost) no
time, and flying it would only add a command."""
PAPERS_ANGLE_DEG = 30.0
"""Feldman & Lee's calibration slews: ±30° about X, Y and Z in turn (Fig. B3; the Post-Probe
scenario)."""


class InertiaPlan(NamedTuple):
    """A planned inertia calibration.

    scenario : the plan as a scenario dict (``simulate`` runs it; TOML-ready).
    prediction : its predicted posterior at the scenario's step, limits usage included.
    baseline : the comparison's prediction; ``baseline_name`` what it is, ``baseline_scenario``
        its scenario dict.
    target : the target minimised (:data:`~cassini_bayes.plan.optimise.TARGETS`).
    search : the best slews found per slew count tried.
    """

    limits: Limits
    scenario: dict
    prediction: InertiaPrediction
    baseline: InertiaPrediction
    baseline_name: str
    baseline_scenario: dict
    target: str
    search: tuple[OptimisedSlews, ...]


def target_value(p: InertiaPrediction, target: str) -> float:
    """The largest ratio of ``p`` that ``target`` names."""
    return float(np.max(p.ratio if target == "max_ratio" else p.ratio_data))


def _scenario(limits: Limits, spacecraft_path: str, slews: list[dict], name: str,
              description: str) -> dict:
    d = base_scenario_dict(limits, spacecraft_path)
    d["name"], d["description"] = name, description
    d["slew"] = slews
    return d


def papers_slews(limits: Limits, base: Scenario) -> list[dict]:
    """Feldman & Lee's six slews (X, Y, Z, −X, −Y, −Z, :data:`PAPERS_ANGLE_DEG` each) in equal
    slots of the duration, each at the largest rate and acceleration the limits allow about its
    axis (:func:`~cassini_bayes.plan.manoeuvre.rate_limit`, ``accel_limit``); an angle that does
    not fit its slot with the quiet time is shortened to the largest that does."""
    b = slew_bounds(limits, base, 6)
    axes = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, -1, 0], [0, 0, -1]], float)
    rates = np.asarray(rate_limit(b, axes))
    accs = np.asarray(accel_limit(b, axes))
    slot = (limits.duration_s - limits.quiet_s) / 6.0
    room = (1.0 - 1e-6) * (slot - limits.quiet_s)
    out = []
    for j in range(6):
        r, a = float(rates[j]), float(accs[j])
        angle = np.deg2rad(PAPERS_ANGLE_DEG)
        if slew_duration(angle, r, a) > room:       # the angle that fills the room exactly
            angle = r * (room - r / a) if room >= 2 * r / a else 0.25 * a * room ** 2
            r = min(r, 0.5 * a * room)
        out.append({"t_start_s": limits.quiet_s + j * slot, "axis": axes[j].tolist(),
                    "angle_deg": float(np.rad2deg(angle)), "rate_mrad_s": r * 1e3,
                    "accel_mrad_s2": a * 1e3})
    return out


def plan_inertia_slews(limits: Limits, base: Scenario, spacecraft_path: str, *,
                       target: str = "max_ratio", counts=None, baseline: Scenario | None = None,
                       max_iter: int = 60,
                       progress: Callable[[str], None] | None = None) -> InertiaPlan:
    """Plan the slews of an inertia calibration within ``limits`` (module docstring).

    ``counts``: the slew counts to try (default the feasible ones of
    :data:`~cassini_bayes.plan.optimise.SLEW_COUNTS`); ``baseline``: the scenario to compare
    with (default :func:`papers_slews` under the same limits).
    """
    if target not in TARGETS:
        raise InputError(f"target {target!r}: choose one of {', '.join(TARGETS)}")
    feasible = slew_counts(limits, base, SLEW_COUNTS if counts is None else counts)
    if not feasible:
        asked = ", ".join(str(n) for n in (SLEW_COUNTS if counts is None else counts))
        raise InputError(f"no slew count among {asked} fits 'limits.duration_s' = "
                         f"{limits.duration_s:g} s with {limits.quiet_s:g} s quiet around each "
                         "slew", path=limits.source)
    search = []
    for n in feasible:
        if progress is not None:
            progress(f"optimising {n} slews")
        search.append(optimise_slews(limits, base, n, target=target, max_iter=max_iter,
                                     progress=progress))
    best = min(search, key=lambda r: r.objective)
    slews = [r for r in slew_table(best.slews) if r["angle_deg"] >= MIN_SLEW_DEG]
    d = _scenario(limits, spacecraft_path, slews, f"plan_{limits.name}",
                  f"Planned inertia calibration ({len(slews)} slews) within {limits.name}'s "
                  "limits")
    plan_s = scenario_from_dict(d, f"<plan {limits.name}>")
    pred = evaluate_inertia(plan_s, limits)
    if baseline is None:
        bd = _scenario(limits, spacecraft_path, papers_slews(limits, base),
                       f"papers_{limits.name}",
                       "Feldman & Lee's six slews (X, Y, Z, -X, -Y, -Z) within the same limits")
        baseline = scenario_from_dict(bd, f"<papers {limits.name}>")
        name = "Feldman & Lee's six slews (±30° about X, Y, Z) within the same limits"
    else:
        bd, name = None, f"scenario {baseline.name}"
    base_pred = evaluate_inertia(baseline, limits)
    return InertiaPlan(limits, d, pred, base_pred, name, bd, target, tuple(search))
