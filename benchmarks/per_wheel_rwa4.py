"""Per-wheel vs common wheel spin-inertia errors in the robust RWA4 model (docs/robust/
per_wheel.md): a scenario (default ``rwa4_rwa``, Brown's RWA method) simulated with each wheel's
spin inertia off by its own fraction (``[truth] wheel_inertia_errors``, the solved RWA4's
included), fitted with ``wheel_errors="per_wheel"`` and ``"common"``; prints the axis error, the
90 % cone, whether it covers the truth, R-hat, divergences and wall time. Not a test.

    python benchmarks/per_wheel_rwa4.py [--scenario rwa4_rwa] [--method rwa]
        [--errors 0.008 -0.009 0.006 -0.007] [--seed 0] [--chains 4] [--warmup 400] [--draws 400]
"""

from __future__ import annotations

import argparse
import time
import tomllib
import warnings


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="rwa4_rwa")
    ap.add_argument("--method", default="rwa", choices=["rwa", "rcs"])
    ap.add_argument("--errors", type=float, nargs="+", default=[0.008, -0.009, 0.006, -0.007])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--warmup", type=int, default=400)
    ap.add_argument("--draws", type=int, default=400)
    args = ap.parse_args(argv)

    import jax
    import numpy as np

    from cassini_bayes.inference.runner import SamplerSettings
    from cassini_bayes.inference.rwa4 import fit_rwa4
    from cassini_bayes.inference.sphere import angles_deg
    from cassini_bayes.simulate import scenario_from_dict, simulate
    from cassini_bayes.simulate.scenario import scenario_path

    d = tomllib.loads(scenario_path(args.scenario).read_text())
    d["truth"]["wheel_inertia_errors"] = args.errors
    sc = scenario_from_dict(d, str(scenario_path(args.scenario)))
    sim = simulate(jax.random.key(args.seed), sc)
    u_true = np.asarray(sim.params.wheel_axes)[list(sc.wheel_names).index("RWA4")]
    settings = SamplerSettings(chains=args.chains, warmup=args.warmup, draws=args.draws)
    print(f"{sc.name} ({args.method}): wheel errors {args.errors}")
    for model in ("per_wheel", "common"):
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            post = fit_rwa4(jax.random.key(1), sim.telemetry, sc.prior, method=args.method,
                            settings=settings, prior_draws=0, wheel_errors=model)
        wall = time.perf_counter() - t0
        err = float(angles_deg(np.array(post.direction["mean"])[None], u_true)[0])
        cone = post.direction["cone_deg"]["90"]
        dg = post.diagnostics
        print(f"  {model:9s} error {err:.4f} deg  cone90 {cone:.4f} deg "
              f"{'covers' if err <= cone else 'MISSES'}  R-hat {dg.max_r_hat:.4f}  "
              f"div {dg.divergences}  {wall:.0f} s")


if __name__ == "__main__":
    main()
