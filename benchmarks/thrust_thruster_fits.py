"""The per-thruster thrust fit (``mode="thruster"``) of a scenario over simulation seeds: each
thrust's error, its sd, the centre of mass's error, the 90 % coverage and the diagnostics
(docs/thrust_any_layout.md, "Validation on a non-Cassini spacecraft").

Each seed simulates the scenario (``cassini_bayes.simulate_scenario``) and fits it with
``cassini_bayes.fit_thrust(..., mode="thruster", seed=seed)`` at the default settings (4 chains
× 1000 + 1000) unless told otherwise. With ``--json``, one record per seed; the table kind
``thrust_thruster_fits`` (``_tables_robust.py``) reads them.

    python benchmarks/thrust_thruster_fits.py [--scenario pulses_espa_bus] [--seeds 1 2 3 4]
        [--json thrust_thruster_fits.json]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

TAU = ("tau_delay", "tau_rise", "tau_fall")


def fit_one(scenario: str, seed: int, sampler: dict) -> dict:
    """Simulate ``scenario`` with ``seed``, fit it per thruster, and return its record."""
    import cassini_bayes as cb

    sim = cb.simulate_scenario(scenario, seed=seed)
    truth = sim.truth()
    t0 = time.perf_counter()
    fit = cb.fit_thrust(sim.telemetry, sim.pulses, sim.prior, mode="thruster", seed=seed,
                        **sampler)
    seconds = time.perf_counter() - t0
    summ = json.loads(json.dumps(fit.summary()))
    p = summ["parameters"]
    thrusts = {}
    for name, f_true in truth["thrust_n"].items():
        q = p[f"F[{name}]"]
        thrusts[name] = {"truth": f_true, "error_pct": 100 * (q["mean"] / f_true - 1),
                         "sd_pct": 100 * q["sd"] / f_true,
                         "covered_90": bool(q["q05"] <= f_true <= q["q95"])}
    com = {}
    for axis, c_true in zip("xyz", np.asarray(truth["center_of_mass_offset_m"], float)):
        q = p[f"com_{axis}"]
        com[axis] = {"truth_m": float(c_true), "error_m": q["mean"] - float(c_true),
                     "sd_m": q["sd"], "covered_90": bool(q["q05"] <= c_true <= q["q95"])}
    tau_true = {n: float(truth[f"{n}_s"]) for n in TAU}
    tau = {n: {"truth_s": tau_true[n], "mean_s": p[n]["mean"], "sd_s": p[n]["sd"],
               "covered_90": bool(p[n]["q05"] <= tau_true[n] <= p[n]["q95"])} for n in TAU}
    return {"scenario": scenario, "seed": seed, "thrusts": thrusts, "com": com, "tau": tau,
            "diagnostics": summ["diagnostics"], "adequacy_ok": summ["adequacy"]["ok"],
            "seconds": seconds}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="pulses_espa_bus")
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4])
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--warmup", type=int, default=1000)
    ap.add_argument("--draws", type=int, default=1000)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    import cassini_bayes

    cassini_bayes.setup_jax()
    sampler = {"chains": args.chains, "warmup": args.warmup, "draws": args.draws}
    records = []
    for seed in args.seeds:
        r = fit_one(args.scenario, seed, sampler)
        err = max(abs(t["error_pct"]) for t in r["thrusts"].values())
        d = r["diagnostics"]
        print(f"{args.scenario} seed {seed}: max |thrust error| {err:.2f} %, R-hat "
              f"{d['max_r_hat']:.4f}, divergences {d['divergences']}, {r['seconds']:.0f} s",
              flush=True)
        records.append(r)
        if args.json:
            from _provenance import write_json

            write_json(args.json, records)


if __name__ == "__main__":
    main()
