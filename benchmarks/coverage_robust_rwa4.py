"""Coverage campaign: robust vs idealised RWA4 spin-axis posteriors on the `_real` scenarios.

For each scenario family (``rwa4_rcs_real``: Brown §III.B, RCS method; ``rwa4_rwa_real``: Brown
§III.C, RWA method) and each seed: draw the truth's sensor and actuator errors at the scale of the
robust model's prior (the prior model's :class:`~cassini_bayes.spacecraft.Knowledge`: gyro bias
and scale factor per axis, a shared and a per-wheel spin-inertia error, two tilt angles of each
*known* wheel's axis, a body-fixed torque of 15 µN m per axis, Feldman & Lee App. A), keep the
file's flexible mode, time-tag jitter and true RWA4 axis (and its inertia, unless ``--draw-inertia``
draws it from the fit's inertia prior), simulate, and fit both models (Brown's
idealised one and the robust one) with the nominal spacecraft model. Prints, per family and
model, how often the truth lies inside the posterior's 90 % cone (with the binomial sd), the
worst and median axis error against Brown's budgets (RCS ≤ 3°, RWA ≤ 1°), the median 90 % cone,
and the convergence record. Not a test.

    python benchmarks/coverage_robust_rwa4.py [--seeds 20] [--families rwa4_rcs_real rwa4_rwa_real]
        [--first-seed 0] [--draw-inertia] [--models idealised robust] [--chains 4]
        [--warmup 300] [--draws 300] [--target-accept 0.9] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import time
import tomllib
import warnings

FAMILIES = {"rwa4_rcs_real": "rcs", "rwa4_rwa_real": "rwa"}
BUDGET_DEG = {"rcs": 3.0, "rwa": 1.0}   # Brown §III.B / §III.C
MODELS = ("idealised", "robust")


def _scenario_with_errors(base: dict, key, prior, draw_inertia: bool):
    """The scenario dict with the truth's errors drawn at the knowledge priors' scale (``prior``
    the prior spacecraft model) and, with ``draw_inertia``, the true inertia drawn from the fit's
    stated inertia prior (:func:`~cassini_bayes.inference.rwa4.sample_inertia_prior`)."""
    import copy

    import jax
    import numpy as np

    from cassini_bayes.inference.inertia import INERTIA_NAMES, inertia_prior
    from cassini_bayes.inference.nuisance import prior_wheel_errors

    d = copy.deepcopy(base)
    k_b, k_s, k_c, k_a, k_t, k_i = jax.random.split(key, 6)
    knowledge = prior.knowledge
    known = [w for w in d["initial"]["wheels_on"] if w != "RWA4"]
    truth, noise = d["truth"], d["noise"]
    noise["gyro_bias_rad_s"] = (knowledge.gyro_bias_sd_rad_s
                                * np.asarray(jax.random.normal(k_b, (3,)))).tolist()
    noise["gyro_scale_factor"] = (knowledge.gyro_scale_factor_sd
                                  * np.asarray(jax.random.normal(k_s, (3,)))).tolist()
    truth["wheel_inertia_scale"] = 1.0       # each wheel c_s + d_k, from the robust prior
    truth["wheel_inertia_errors"] = prior_wheel_errors(prior, k_c).tolist()
    tilts = knowledge.wheel_axis_sd_deg * np.asarray(jax.random.normal(k_a, (max(len(known), 1),
                                                                             2)))
    truth["wheel_axis_tilt_deg"] = {w: tilts[i].tolist() for i, w in enumerate(known)}
    truth["external_torque_body_nm"] = (knowledge.torque_sd_nm * np.asarray(
        jax.random.normal(k_t, (3,)))).tolist()
    if draw_inertia:
        from cassini_bayes.inference.rwa4 import sample_inertia_prior

        ip = inertia_prior(prior)
        pi = sample_inertia_prior(k_i, ip.mean, np.diag(ip.sd**2), 1)[0]
        truth["inertia"] = dict(zip(INERTIA_NAMES, pi.tolist()))
    return d


def run_family(family: str, seeds: int, settings, first: int = 0,
               draw_inertia: bool = False, models=MODELS) -> dict:
    """Fit the models on ``seeds`` error draws of one family; per-model lists of results."""
    import jax
    import numpy as np

    from cassini_bayes.inference.rwa4 import fit_rwa4
    from cassini_bayes.inference.sphere import angles_deg
    from cassini_bayes.simulate import simulate
    from cassini_bayes.simulate.scenario import scenario_from_dict, scenario_path

    method = FAMILIES[family]
    path = scenario_path(family)
    base = tomllib.loads(path.read_text())
    out = {m: [] for m in models}
    t0 = time.perf_counter()
    for seed in range(first, first + seeds):
        k_err, k_sim, k_fit = jax.random.split(jax.random.key(3000 + seed), 3)
        nominal = scenario_from_dict(base, src=str(path))
        scenario = scenario_from_dict(_scenario_with_errors(base, k_err, nominal.prior,
                                                            draw_inertia), src=str(path))
        sim = simulate(k_sim, scenario)
        u_true = np.asarray(sim.params.wheel_axes)[list(scenario.wheel_names).index("RWA4")]
        line = []
        for m in models:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                post = fit_rwa4(k_fit, sim.telemetry, scenario.prior, method=method,
                                settings=settings, prior_draws=0, robust=(m == "robust"))
            err = float(angles_deg(np.array(post.direction["mean"])[None], u_true)[0])
            cone = float(post.direction["cone_deg"]["90"])
            d = post.diagnostics
            out[m].append(dict(seed=seed, err_deg=err, cone90_deg=cone, covered=err <= cone,
                               r_hat=float(d.max_r_hat), ess=float(d.min_ess_bulk),
                               divergences=int(d.divergences)))
            line.append(f"{m} err {err:.4f}° cone90 {cone:.4f}° {'in' if err <= cone else 'OUT'}")
        print(f"{family} seed {seed}: " + "; ".join(line)
              + f"  ({time.perf_counter() - t0:.0f} s)", flush=True)
    return out


def report(family: str, res: dict) -> None:
    import numpy as np

    budget = BUDGET_DEG[FAMILIES[family]]
    for m, r in res.items():
        n = len(r)
        cov = np.mean([x["covered"] for x in r])
        err = np.array([x["err_deg"] for x in r])
        print(f"{family} {m:9s}: 90 % cone coverage {cov:.2f} ({int(cov * n)}/{n}; nominal "
              f"0.90 ± {np.sqrt(0.09 / n):.2f} binomial sd); axis error median "
              f"{np.median(err):.3f}°, "
              f"worst {err.max():.3f}° (budget {budget:g}°); median cone90 "
              f"{np.median([x['cone90_deg'] for x in r]):.4f}°; max R-hat "
              f"{max(x['r_hat'] for x in r):.3f}, min bulk ESS {min(x['ess'] for x in r):.0f}, "
              f"divergences {sum(x['divergences'] for x in r)}", flush=True)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--draw-inertia", action="store_true",
                    help="draw the true inertia from the fit's prior too (default: the file's)")
    ap.add_argument("--families", nargs="+", default=list(FAMILIES), choices=list(FAMILIES))
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--warmup", type=int, default=300)
    ap.add_argument("--draws", type=int, default=300)
    ap.add_argument("--target-accept", type=float, default=0.9)
    ap.add_argument("--models", nargs="+", default=list(MODELS), choices=list(MODELS))
    ap.add_argument("--json", default=None, help="write every fit's record here")
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)

    from cassini_bayes.inference.runner import SamplerSettings

    settings = SamplerSettings(chains=args.chains, warmup=args.warmup, draws=args.draws,
                               target_accept=args.target_accept)
    t0 = time.perf_counter()
    results = {f: run_family(f, args.seeds, settings, args.first_seed, args.draw_inertia,
                             tuple(args.models))
               for f in args.families}
    print(f"\n{args.seeds} seeds per family, errors at the knowledge priors' scale; "
          f"{args.chains} chains x {args.draws} draws; {time.perf_counter() - t0:.0f} s")
    for f, res in results.items():
        report(f, res)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=1)


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    main()
