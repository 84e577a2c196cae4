"""A shipped spacecraft model and scenario scaled by ``s``: every mass property, torque and
momentum times ``s``, rates, angles and fractions unchanged, so the same manoeuvre is flown.

A spacecraft scaled this way must give the same verdicts and the same relative posterior
(docs/model_file.md, "Thresholds relative to the spacecraft").
"""

from __future__ import annotations

import copy
import tomllib

import cassini_bayes as cb
from cassini_bayes.simulate.scenario import scenario_path

__all__ = ["scaled_model", "scaled_scenario"]


def scaled_model(name: str, s: float) -> dict:
    """The shipped model ``name`` as a model-file dict with every mass property, torque and
    momentum scaled by ``s`` (rates, angles and fractions unchanged)."""
    d = cb.load_spacecraft(name).to_dict()
    for k in ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz", "poi_uncertainty"):
        d["inertia"][k] *= s
    for w in d["wheel"]:
        w["inertia"] *= s
        if "max_torque_nm" in w:
            w["max_torque_nm"] *= s
    for x in d.get("thruster", []):
        if "F" in x:
            x["F"] *= s
    if "thrust" in d:
        d["thrust"]["F"] *= s
    d["torque_knowledge"] = {k: v * s for k, v in d["torque_knowledge"].items()}
    return d


def scaled_scenario(name: str, s: float, model_path: str) -> dict:
    """The shipped scenario ``name`` flying the model at ``model_path``, its true inertia and
    external torques scaled by ``s``."""
    d = tomllib.loads(scenario_path(name).read_text())
    d = copy.deepcopy(d)
    d["truth"]["model"] = d["prior"]["model"] = model_path
    truth = d["truth"]
    truth["inertia"] = {k: v * s for k, v in truth["inertia"].items()}
    for k in ("external_torque_inertial_nm", "external_torque_body_nm",
              "external_torque_inertial_rate_nm_s"):
        if k in truth:
            truth[k] = [v * s for v in truth[k]]
    for ramp in d.get("wheel_ramp", []):
        ramp["torque_nm"] *= s
    return d
