"""Per-wheel vs common wheel spin-inertia errors in the robust thrust model (docs/robust/
per_wheel.md): one biasing event of a scenario (default ``biasing_day028``) simulated with each
wheel's spin inertia off by its own fraction (``[truth] wheel_inertia_errors``), fitted with
``wheel_errors="per_wheel"`` and ``"common"``; prints the 90 % interval of ``F`` against the
truth, the posterior sd of ``F`` and the time constants, R-hat, divergences and wall time. Not a
test.

    python benchmarks/per_wheel_thrust.py [--errors 0.008 -0.009 0.006 -0.007] [--seed 13]
        [--chains 4] [--warmup 500] [--draws 500]
"""

from __future__ import annotations

import argparse
import time
import tomllib
import warnings


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="biasing_day028")
    ap.add_argument("--errors", type=float, nargs="+", default=[0.008, -0.009, 0.006, -0.007])
    ap.add_argument("--seed", type=int, default=13)
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--warmup", type=int, default=500)
    ap.add_argument("--draws", type=int, default=500)
    args = ap.parse_args(argv)

    import jax
    import numpy as np

    from cassini_bayes.inference.runner import SamplerSettings
    from cassini_bayes.inference.thrust import TAU_NAMES, fit_thrust
    from cassini_bayes.simulate import scenario_from_dict, simulate
    from cassini_bayes.simulate.scenario import scenario_path

    d = tomllib.loads(scenario_path(args.scenario).read_text())
    d["truth"]["wheel_inertia_errors"] = args.errors
    sc = scenario_from_dict(d, str(scenario_path(args.scenario)))
    sim = simulate(jax.random.key(args.seed), sc)
    f_true = float(np.mean(sc.thrust_n))
    settings = SamplerSettings(chains=args.chains, warmup=args.warmup, draws=args.draws)
    print(f"{sc.name}: wheel errors {args.errors}, true F {f_true:.5f} N")
    for model in ("per_wheel", "common"):
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            post = fit_thrust(jax.random.key(5), [(sim.telemetry, sim.pulses)], sc.prior,
                              settings=settings, wheel_errors=model, prior_draws=0)
        wall = time.perf_counter() - t0
        p = post.idata.posterior
        f = p["F"].values.ravel()
        lo, hi = np.quantile(f, [0.05, 0.95])
        taus = ", ".join(f"sd({n}) {1e3 * float(p[n].std()):.2f} ms" for n in TAU_NAMES)
        dg = post.diagnostics
        print(f"  {model:9s} F 90 % [{lo:.5f}, {hi:.5f}] {'covers' if lo <= f_true <= hi else 'MISSES'}"
              f"  z {(f.mean() - f_true) / f.std():+.2f}  sd(F) {100 * f.std() / f.mean():.3f} %"
              f"  {taus}  R-hat {dg.max_r_hat:.4f}  div {dg.divergences}  {wall:.0f} s")


if __name__ == "__main__":
    main()
