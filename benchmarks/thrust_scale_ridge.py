"""Does the robust thrust fit's density hold the common-scale ridge where the wheels put it?

Scaling the inertia, every thrust and every wheel's spin inertia by one factor ``s`` leaves the
measured rates and wheel speeds of a biasing event unchanged (Feldman & Lee Eq 17 is
homogeneous in them), so the data cannot tell ``s``: only the priors can (the wheels' spin
inertias, about 0.5 %). The fit (``ThrustProblem.scale_free``) holds the wheels at the model
file's common scale in its likelihood (the nuisance ``ν`` keeps each wheel's deviation from it),
draws the common scale ``u`` from its prior and reports the thrusts and the inertia times
``1 + u``. This script puts the fit's own log density (``inference/thrust/model.py::
log_density``) on the event flown without noise at its truth, moves ``F`` and ``I`` × ``s`` with
the wheels held, and reports the curvature as an sd of ``s`` and the slope as the offset of the
maximum. Held consistently, the maximum is at the truth and the sd is what the event measures of
the inertia and thrusts against the wheels, narrower than the prior of ``u``
(``prior_sd``), which the fit adds.

Before that change (record ``docs/planning/thrust_scale_ridge.json``) the common scale was a
column of ``ν`` while the left side's wheel-rate noise and the rate-step corrections stayed at
the file's spin inertias; the same probe then moved along the ridge and found it tilted.

    python benchmarks/thrust_scale_ridge.py --case biasing_espa_bus:thruster [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STEP = 0.0002           # the probe's step, a fraction of s; evaluated at ±STEP and ±2 STEP


def ridge(case: str) -> dict:
    """The fit's log density along ``F``, ``I`` × ``s`` at the model file's wheels (module
    docstring): ``sd`` and ``peak_offset`` of ``s``, ``prior_sd`` the prior sd of the common
    scale ``u`` (``NuisanceLayout.common_scale_sd``)."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    from cassini_bayes.inference.thrust.model import log_density
    from cassini_bayes.plan.thrust import (_site_names, _truth, _truth_vector,
                                           noise_free_problem, representable)
    from cassini_bayes.simulate import load_scenario

    name, mode = case.rsplit(":", 1)
    sc = load_scenario(name)
    _, problem, _ = noise_free_problem(sc, mode)
    names = _site_names(problem)
    truth = _truth(representable(sc, mode), problem, names)
    scaled = np.array([n.startswith("F") or n in ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")
                       for n in names])
    k = problem.n_f + problem.n_c + 3

    def theta(factor: float) -> np.ndarray:
        x = _truth_vector(problem, names, np.where(scaled, truth * factor, truth))
        return np.r_[x[:k], 0.0, x[k:]]                          # the noise at the sensors'

    density = jax.jit(jax.vmap(lambda t, kw: log_density(t, kw, problem.n_f, problem.n_c, True),
                               in_axes=(0, None)))
    steps = STEP * np.array([-2.0, -1.0, 1.0, 2.0])
    thetas = jnp.asarray(np.stack([theta(f) for f in 1.0 + np.r_[0.0, steps]]), float)
    dens = np.asarray(density(thetas, problem.data))
    lp = dens[1:] - dens[0]
    coef = np.polyfit(steps, lp, 2)                      # lp ≈ −b d² + a d
    b, a = -coef[0], coef[1]
    row = {"variant": "as fitted, the wheels at the file's common scale",
           "log_density": lp.tolist(),
           "sd": float(1.0 / np.sqrt(2.0 * b)) if b > 0 else None,
           "peak_offset": float(a / (2.0 * b)) if b > 0 else None}
    print(f"{case}: sd {row['sd']}, peak at {row['peak_offset']}", file=sys.stderr, flush=True)
    return {"case": case, "steps": steps.tolist(), "prior_sd": problem.layout.common_scale_sd,
            "rows": [row]}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", nargs="+", required=True, help="SCENARIO:MODE ...")
    ap.add_argument("--json", type=Path)
    a = ap.parse_args(argv)
    if a.json:
        from _provenance import start
        start(a.json, vars(a), argv, replace=True)
    sys.path.insert(0, str(ROOT))
    import cassini_bayes
    from cassini_bayes.files import write_text

    cassini_bayes.setup_jax()
    out = {"step": STEP, "cases": [ridge(c) for c in a.case]}
    if a.json:
        write_text(a.json, json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
