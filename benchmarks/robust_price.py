"""Price of the robust models on clean data: posterior widths of the idealised, common-scale and
per-wheel (default) fits of the RWA4 axis (``rwa4_rwa``, ``rwa4_rcs``, key 3) and the thrust
(``biasing_day028``, key 13), 4 chains × 500 warm-up + 500 draws. Prints one line per fit (axis
error and 90 % cone, or posterior mean and sd of F and the time constants; R-hat, divergences);
``--json`` writes them. Not a test; the numbers are in docs/robust/README.md ("Price on clean
data").

    python benchmarks/robust_price.py [--json price.json]
"""

from __future__ import annotations

import argparse
import warnings

RWA4_MODELS = {"idealised": dict(robust=False),
               "common": dict(robust=True, wheel_errors="common"),
               "per_wheel": dict(robust=True)}
THRUST_MODELS = {"idealised (inertia fixed)": dict(robust=False),
                 "common": dict(robust=True, wheel_errors="common"),
                 "per_wheel": dict(robust=True),
                 "per_wheel (inertia fixed)": dict(robust=True, inertia="fixed")}


def _rwa4(settings) -> dict:
    import jax
    import numpy as np

    from cassini_bayes.inference.rwa4 import fit_rwa4
    from cassini_bayes.simulate import load_scenario, simulate

    out = {}
    for name in ("rwa4_rwa", "rwa4_rcs"):
        scenario = load_scenario(name)
        sim = simulate(jax.random.key(3), scenario)
        truth = np.asarray(sim.params.wheel_axes)[list(scenario.wheel_names).index("RWA4")]
        for model, kw in RWA4_MODELS.items():
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                post = fit_rwa4(jax.random.key(1), sim.telemetry, scenario.prior,
                                method=name.split("_")[1], settings=settings, prior_draws=50,
                                **kw)
            cos = float(np.clip(np.dot(post.direction["mean"], truth), -1.0, 1.0))
            out[f"{name} {model}"] = {"error_deg": float(np.degrees(np.arccos(cos))),
                                      "cone90_deg": post.direction["cone_deg"]["90"],
                                      "r_hat": float(post.diagnostics.max_r_hat),
                                      "divergences": int(post.diagnostics.divergences)}
            print(name, model, out[f"{name} {model}"], flush=True)
    return out


def _thrust(settings) -> dict:
    import jax

    from cassini_bayes.inference.thrust import TAU_NAMES, fit_thrust
    from cassini_bayes.simulate import load_scenario, simulate

    scenario = load_scenario("biasing_day028")
    sim = simulate(jax.random.key(13), scenario)
    out = {}
    for model, kw in THRUST_MODELS.items():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            post = fit_thrust(jax.random.key(13), [(sim.telemetry, sim.pulses)], scenario.prior,
                              settings=settings, prior_draws=50, **kw)
        p = post.idata.posterior
        rec = {n: {"mean": float(p[n].mean()), "sd": float(p[n].std())}
               for n in ("F", *TAU_NAMES)}
        rec |= {"r_hat": float(post.diagnostics.max_r_hat),
                "divergences": int(post.diagnostics.divergences)}
        out[f"thrust {model}"] = rec
        print("thrust", model, rec, flush=True)
    return out


def main(argv=None) -> None:
    from cassini_bayes.inference.runner import SamplerSettings

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", default=None, help="write the results here")
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    settings = SamplerSettings(chains=4, warmup=500, draws=500)
    out = _rwa4(settings) | _thrust(settings)
    if args.json:
        from _provenance import write_json

        write_json(args.json, out)


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    main()
