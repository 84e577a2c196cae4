"""Per-wheel vs common wheel spin-inertia errors in the robust thrust and RWA4 models
(docs/robust/per_wheel.md): one simulated scenario whose wheels' spin inertias are each off by
their own fraction (``[truth] wheel_inertia_errors``; for RWA4 the solved wheel's included),
fitted with ``wheel_errors="per_wheel"`` and ``"common"``. Prints, per model, the 90 % interval of
``F`` (thrust) or the axis error and 90 % cone (RWA4) against the truth, R-hat, divergences and
wall time. Not a test.

    python benchmarks/per_wheel_events.py thrust [--scenario biasing_day028] [--seed 13]
    python benchmarks/per_wheel_events.py rwa4 [--scenario rwa4_rwa] [--method rwa] [--seed 0]
        common: [--errors 0.008 -0.009 0.006 -0.007] [--chains 4] [--warmup W] [--draws D]
        [--json FILE]

``--json`` writes one record per model with a manifest; the table kind ``per_wheel_events``
reads the thrust and RWA4 records together.

Defaults: thrust ``biasing_day028``, seed 13, 4 × 500; RWA4 ``rwa4_rwa`` (Brown's RWA method),
seed 0, 4 × 400.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
import tomllib
import warnings

DEFAULTS = {"thrust": {"scenario": "biasing_day028", "seed": 13, "n": 500},
            "rwa4": {"scenario": "rwa4_rwa", "seed": 0, "n": 400}}


def _thrust(post, sc, sim) -> dict:
    import numpy as np

    from cassini_bayes.inference.thrust import TAU_NAMES

    f_true = float(np.mean(sc.thrust_n))
    p = post.idata.posterior
    f = p["F"].values.ravel()
    lo, hi = np.quantile(f, [0.05, 0.95])
    return {"truth": f_true, "q05": float(lo), "q95": float(hi),
            "covered": bool(lo <= f_true <= hi),
            "z": float((f.mean() - f_true) / f.std()), "sd_pct": float(100 * f.std() / f.mean()),
            "tau_sd_ms": {n: float(1e3 * p[n].std()) for n in TAU_NAMES}}


def _rwa4(post, sc, sim) -> dict:
    import numpy as np

    from cassini_bayes.inference.sphere import angles_deg

    u_true = np.asarray(sim.params.wheel_axes)[list(sc.wheel_names).index("RWA4")]
    err = float(angles_deg(np.array(post.direction["mean"])[None], u_true)[0])
    cone = float(post.direction["cone_deg"]["90"])
    return {"error_deg": err, "cone90_deg": cone, "covered": err <= cone}


def _line(r: dict) -> str:
    if "error_deg" in r:
        return (f"error {r['error_deg']:.4f} deg  cone90 {r['cone90_deg']:.4f} deg "
                f"{'covers' if r['covered'] else 'MISSES'}")
    taus = ", ".join(f"sd({n}) {v:.2f} ms" for n, v in r["tau_sd_ms"].items())
    return (f"F 90 % [{r['q05']:.5f}, {r['q95']:.5f}] (truth {r['truth']:.5f}) "
            f"{'covers' if r['covered'] else 'MISSES'}  z {r['z']:+.2f}  sd(F) "
            f"{r['sd_pct']:.3f} %  {taus}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("calibration", choices=sorted(DEFAULTS))
    ap.add_argument("--scenario")
    ap.add_argument("--method", default="rwa", choices=["rwa", "rcs"], help="RWA4 only")
    ap.add_argument("--errors", type=float, nargs="+", default=[0.008, -0.009, 0.006, -0.007])
    ap.add_argument("--seed", type=int)
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--warmup", type=int)
    ap.add_argument("--draws", type=int)
    ap.add_argument("--json", type=Path, help="write the records here (with a manifest)")
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    dflt = DEFAULTS[args.calibration]

    import jax

    from cassini_bayes.inference.runner import SamplerSettings
    from cassini_bayes.inference.rwa4 import fit_rwa4
    from cassini_bayes.inference.thrust import fit_thrust
    from cassini_bayes.simulate import scenario_from_dict, simulate
    from cassini_bayes.simulate.scenario import scenario_path

    name = args.scenario or dflt["scenario"]
    d = tomllib.loads(scenario_path(name).read_text())
    d["truth"]["wheel_inertia_errors"] = args.errors
    sc = scenario_from_dict(d, str(scenario_path(name)))
    sim = simulate(jax.random.key(dflt["seed"] if args.seed is None else args.seed), sc)
    settings = SamplerSettings(chains=args.chains, warmup=args.warmup or dflt["n"],
                               draws=args.draws or dflt["n"])
    print(f"{sc.name} ({args.calibration}): wheel errors {args.errors}")
    records = []
    for model in ("per_wheel", "common"):
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if args.calibration == "thrust":
                post = fit_thrust(jax.random.key(5), [(sim.telemetry, sim.pulses)], sc.prior,
                                  settings=settings, wheel_errors=model, prior_draws=0)
            else:
                post = fit_rwa4(jax.random.key(1), sim.telemetry, sc.prior, method=args.method,
                                settings=settings, prior_draws=0, wheel_errors=model)
        wall = time.perf_counter() - t0
        r = (_thrust if args.calibration == "thrust" else _rwa4)(post, sc, sim)
        dg = post.diagnostics
        records.append({"calibration": args.calibration, "scenario": sc.name, "model": model,
                        "errors": args.errors, **r, "max_r_hat": float(dg.max_r_hat),
                        "divergences": int(dg.divergences), "wall_s": wall})
        print(f"  {model:9s} {_line(r)}  R-hat {dg.max_r_hat:.4f}  div {dg.divergences}  "
              f"{wall:.0f} s")
    if args.json:
        from _provenance import write_json

        write_json(args.json, records)


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    main()
