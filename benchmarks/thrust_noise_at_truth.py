"""Which open-world effect makes the thrust fit learn a noise level above its sensors'?

For the open-world truths of ``benchmarks/plan_thrust.py`` (same seeds and keys), the noise
level the robust thrust fit's own density (``inference/thrust/model.py::log_density``: Feldman &
Lee Eq 17 with the offsets and the robust nuisance integrated out) puts at the truth: every
other coordinate at the true thrusts, centre of mass, time constants and inertia
(``plan.thrust.truth_coordinates``), the event's common noise scale maximised on a grid, the
reference level being the scenario's sensors' (``prepare_thrust(..., noise_hat=)``). Reported as
that scale (σ at the maximum over the sensors' σ) with every open-world effect on, with none
(the scenario's own noise only), and with each effect alone
(:func:`cassini_bayes.simulate.open_world.without` on all the others). A scale near 1 means the
data at the truth are what the likelihood assumes; well above 1, residuals the model has no
term for, which the fit absorbs into its noise level and so into every sd. No sampling.

    python benchmarks/thrust_noise_at_truth.py --case biasing_espa_bus:thruster --seeds 0 1
        [--flex model] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
GRID = (-15.0, 40.0, 111)   # the noise coordinate (log σ = log σ̂ + NOISE_STEP z): σ/σ̂ 0.2-55


def noise_scale(s, si, tel, pulses, mode: str, flex: str = "off") -> float:
    """σ/σ_sensor at the maximum of the fit's log density over the noise coordinate, every other
    coordinate at the truth of ``si`` (``s`` the nominal scenario: the model file)."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    from cassini_bayes.inference.thrust import prepare_thrust, resolve_inertia
    from cassini_bayes.inference.thrust.model import log_density
    from cassini_bayes.inference.thrust.prior import NOISE_STEP
    from cassini_bayes.plan.thrust import _site_names, _truth, _truth_vector
    from cassini_bayes.plan.wheel_axis import scenario_noise

    sig = np.asarray(scenario_noise(si)[:2], float)
    problem = prepare_thrust([(tel, pulses)], s.prior, mode=mode,
                             inertia=resolve_inertia(None, s.prior, True), robust=True,
                             noise_hat=sig[None], flex=flex)
    names = _site_names(problem)
    x = jnp.asarray(_truth_vector(problem, names, _truth(si, problem, names)), float)
    k = problem.n_f + problem.n_c + 3
    kw = problem.data
    z = jnp.linspace(*GRID)

    @jax.jit
    def dens(zz):
        return jax.vmap(lambda q: log_density(
            jnp.concatenate([x[:k], q[None], x[k:]]), kw, problem.n_f, problem.n_c, True))(zz)

    lp = np.asarray(dens(z))
    return float(np.exp(NOISE_STEP * float(z[int(np.nanargmax(lp))])))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", required=True, help="SCENARIO:MODE")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0])
    ap.add_argument("--flex", default="off", choices=["off", "model"],
                    help="the fit's flexible mode: none, or the one its search finds modelled")
    ap.add_argument("--json", type=Path)
    a = ap.parse_args(argv)
    if a.json:
        from _provenance import start

        start(a.json, vars(a), argv, replace=True)
    sys.path.insert(0, str(ROOT))
    import jax
    import numpy as np

    import cassini_bayes
    from cassini_bayes.files import write_text
    from cassini_bayes.simulate import load_scenario, scenario_from_dict, simulate
    from cassini_bayes.simulate.open_world import (EFFECTS_OFF, apply_time_tags,
                                                   draw_open_world, without)

    cassini_bayes.setup_jax()
    name, mode = a.case.rsplit(":", 1)
    s = load_scenario(name)
    out = {"case": a.case, "grid": GRID, "flex": a.flex, "seeds": []}
    for seed in a.seeds:
        k_sim, _ = jax.random.split(jax.random.key(3200 + seed))     # plan_thrust.py's keys
        ow = draw_open_world(name, np.random.default_rng([seed, 3232]), draw_inertia=True)
        row = {}
        for label, off in ([("all", ()), ("none", EFFECTS_OFF)]
                           + [(e, tuple(x for x in EFFECTS_OFF if x != e)) for e in EFFECTS_OFF]):
            w = without(ow, off)
            si = scenario_from_dict(w.scenario, src=s.source)
            sim = simulate(k_sim, si)
            row[label] = noise_scale(s, si, apply_time_tags(sim.telemetry, w), sim.pulses, mode,
                                     a.flex)
            print(f"seed {seed} {label:10s} σ/σ_sensor at the truth {row[label]:.2f}",
                  file=sys.stderr, flush=True)
        fm = ow.record["flex_mode"]
        share = float(np.asarray(fm["coupling"]) @ np.linalg.solve(
            np.asarray(scenario_from_dict(ow.scenario, src=s.source).truth.inertia),
            np.asarray(fm["coupling"])))
        out["seeds"].append({"seed": seed, "noise_over_sensor": row,
                             "flex": {"freq_hz": fm["freq_hz"], "damping": fm["damping"],
                                      "share": share}})
        if a.json:
            write_text(a.json, json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
