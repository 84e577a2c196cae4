"""The inertia a thrust fit does not know: a Table 2 event whose true moments are 3 % above the
model file's prediction, fitted by the robust thrust model with the inertia sampled from its
prior (the default) and held at the prediction (``inertia="fixed"``, the papers' practice).

``biasing_day028`` with its truth's moments ×1.03, simulated with key 13 and fitted with key 5
(the set-up of ``tests/test_inference_thrust.py::
test_inertia_off_its_prediction_reaches_f_only_when_fixed``). Per fit: F's mean, sd and z
against the truth, the posterior of Ixx where it is sampled, R-hat and divergences. With
``--json`` the records and a manifest; the table kind ``thrust_inertia_off`` reads them. Not a
test: nothing is asserted.

    python benchmarks/thrust_inertia_off.py [--chains 4] [--draws 400] [--json FILE]
"""

from __future__ import annotations

import argparse
import time
import tomllib
import warnings
from pathlib import Path

import numpy as np

F_TRUE = 0.699


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--draws", type=int, default=400, help="warm-up and draws each")
    ap.add_argument("--json", type=Path, help="write the records here (with a manifest)")
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    import jax

    from cassini_bayes.inference.runner import SamplerSettings
    from cassini_bayes.inference.thrust import fit_thrust
    from cassini_bayes.physics.momentum import INERTIA_NAMES, inertia_vector
    from cassini_bayes.simulate import simulate
    from cassini_bayes.simulate.scenario import scenario_from_dict, scenario_path

    d = tomllib.loads(scenario_path("biasing_day028").read_text())
    pred = np.asarray(inertia_vector(scenario_from_dict(d).prior.inertia))
    truth = pred * np.r_[1.03, 1.03, 1.03, 1.0, 1.0, 1.0]
    d["truth"]["inertia"] = dict(zip(INERTIA_NAMES, map(float, truth)))
    sc = scenario_from_dict(d)
    sim = simulate(jax.random.key(13), sc)
    settings = SamplerSettings(chains=args.chains, warmup=args.draws, draws=args.draws)
    records = []
    for inertia in ("sampled", "fixed"):
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            post = fit_thrust(jax.random.key(5), [(sim.telemetry, sim.pulses)], sc.prior,
                              inertia=None if inertia == "sampled" else "fixed",
                              settings=settings)
        p = post.idata.posterior
        f = p["F"].values.ravel()
        rec = {"inertia": inertia, "F_true": F_TRUE, "F_mean": float(f.mean()),
               "F_sd": float(f.std()), "z": float((f.mean() - F_TRUE) / f.std()),
               "Ixx_true": float(truth[0]), "Ixx_pred": float(pred[0]),
               "max_r_hat": float(post.diagnostics.max_r_hat),
               "divergences": int(post.diagnostics.divergences),
               "wall_s": time.perf_counter() - t0}
        if "Ixx" in p:
            rec.update(Ixx_mean=float(p["Ixx"].values.mean()), Ixx_sd=float(p["Ixx"].values.std()))
        records.append(rec)
        print(f"{inertia:8s} F {rec['F_mean']:.4f} ± {rec['F_sd']:.4f} N (z {rec['z']:+.1f})"
              + (f", Ixx {rec['Ixx_mean']:.0f} ± {rec['Ixx_sd']:.0f}" if "Ixx_mean" in rec
                 else "") + f", {rec['wall_s']:.0f} s")
    if args.json:
        from _provenance import write_json

        write_json(args.json, records)


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    main()
