"""The default robust thrust fit of every shipped Cassini biasing scenario, once each: the thrust's
error and sd, its 90 % interval, the time constants and the diagnostics (docs/robust/README.md,
"Thrust pulse family").

Each scenario simulated with key ``--key`` (0) and fitted by ``fit_thrust`` (mode ``mean``, the
robust model, the inertia from the model file's knowledge) at 2 chains × 300 + 300, seed 0.
With ``--json``, one record per scenario; the table kind ``thrust_shipped_fits``
(``_tables_robust.py``) reads them.

    python benchmarks/thrust_shipped_fits.py [--scenarios ...] [--json thrust_shipped_fits.json]
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

SCENARIOS = ("fsds_biasing", "biasing_day028", "biasing_day049", "biasing_day061",
             "biasing_day071", "biasing_day094")
TAU = ("tau_delay", "tau_rise", "tau_fall")


def fit_one(name: str, key: int, folder: Path, sampler: dict) -> dict:
    """Simulate ``name`` with ``key``, fit it, and return its record."""
    import jax

    import cassini_bayes as cb
    from cassini_bayes.simulate import load_scenario, simulate
    from cassini_bayes.telemetry import write_pulses, write_telemetry

    s = load_scenario(name)
    sim = simulate(jax.random.key(key), s)
    tel, log = folder / f"{name}.csv", folder / f"{name}_pulses.csv"
    write_telemetry(tel, sim.telemetry)
    write_pulses(log, sim.pulses)
    idx = np.unique(np.asarray(sim.pulses.thruster))
    fired = [sim.pulses.thruster_names[i] for i in idx]
    thrust = np.asarray(sim.params.thrust_n)[idx]
    t0 = time.perf_counter()
    summ = json.loads(json.dumps(cb.fit_thrust(tel, log, s.prior,
                                               seed=0, **sampler).summary()))
    p, d = summ["parameters"], summ["diagnostics"]
    f_true = float(thrust.mean())
    return {"scenario": name, "key": key, "thrusters_fired": fired,
            "F_true": f_true, "F_true_spread": float(np.ptp(thrust)),
            "F": p["F"], "F_error_pct": 100 * (p["F"]["mean"] / f_true - 1),
            "F_sd_pct": 100 * p["F"]["sd"] / f_true,
            "F_covered_90": p["F"]["q05"] <= f_true <= p["F"]["q95"],
            "tau_true_ms": dict(zip(TAU, (1e3 * np.asarray(sim.params.tau_s)).tolist())),
            "tau": {n: p[n] for n in TAU if n in p}, "diagnostics": d,
            "warnings": summ["warnings"], "seconds": time.perf_counter() - t0}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenarios", nargs="+", default=list(SCENARIOS))
    ap.add_argument("--key", type=int, default=0)
    ap.add_argument("--chains", type=int, default=2)
    ap.add_argument("--warmup", type=int, default=300)
    ap.add_argument("--draws", type=int, default=300)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    import cassini_bayes

    cassini_bayes.setup_jax()
    sampler = {"chains": args.chains, "warmup": args.warmup, "draws": args.draws}
    records = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.scenarios:
            r = fit_one(name, args.key, Path(tmp), sampler)
            d = r["diagnostics"]
            print(f"{name:16s} F {r['F_error_pct']:+.2f} % (sd {r['F_sd_pct']:.2f} %, "
                  f"{'covers' if r['F_covered_90'] else 'MISSES'}), R-hat {d['max_r_hat']:.3f}, "
                  f"divergences {d['divergences']}, bulk ESS {d['min_ess_bulk']:.0f}, "
                  f"{r['seconds']:.0f} s", flush=True)
            records.append(r)
    if args.json:
        from _provenance import write_json

        write_json(args.json, records)


if __name__ == "__main__":
    main()
