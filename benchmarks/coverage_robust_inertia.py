"""Coverage campaign: robust vs idealised inertia posteriors on the `_real` slew scenarios.

For each scenario family (``experiments/scenarios/*_real.toml``: the Pre-SOI, Post-PRM and
Post-Probe slews of Feldman & Lee Table 1 and the March 2000 slew; ``espa_bus`` and
``cubesat_12u``, the slews of two other spacecraft) and each seed: draw the
sensor and wheel errors from the prior model's knowledge (``Spacecraft.knowledge``: gyro bias and
scale factor per axis, a shared and a per-wheel spin-inertia error, two tilt angles per wheel
axis) — or,
with ``--errors fixed``, keep the values the scenario file states — keep the scenario's realistic
external torques (Feldman & Lee App. A), flexible mode and time-tag jitter, simulate the slews
(the compiled simulator, truth and noise traced), and fit both the idealised model (the papers')
and the robust one with the scenario's prior model. Prints, per family and model, the 90 %
coverage of the six inertia entries with its binomial standard error, the error-budget pass rate
(posterior mean within 1 % on every moment and the prior model's ``poi_uncertainty`` on every
product — Cassini's 75 kg m², Feldman & Lee §VI and Eq 12-13), the largest R-hat and the
divergences. Not a test.

    python benchmarks/coverage_robust_inertia.py [--seeds 20] [--workers 1]
        [--families pre_soi_real post_prm_real post_probe_real 2000_03_15_real]
        [--models idealised robust]
        [--chains 4] [--warmup 500] [--draws 500] [--errors drawn|fixed] [--json out.json]

Each worker process fits one (family, seed) at a time, single-threaded; the simulator compiles
once per family and worker.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FAMILIES = {"pre_soi_real": "slews_pre_soi_real", "post_prm_real": "slews_post_prm_real",
            "post_probe_real": "slews_post_probe_real",
            "2000_03_15_real": "slew_2000_03_15_real",
            "espa_bus": "slews_espa_bus", "cubesat_12u": "slews_cubesat_12u"}
MODELS = ("idealised", "robust")
MOMENT_BUDGET = 0.01      # Feldman & Lee §VI: ±1 % on the moments; the products: the prior
                          # model's poi_uncertainty (Cassini's 75 kg m², Feldman & Lee §IV)


def _errors(key, scenario, drawn: bool):
    """True parameters and noise of one seed: the scenario's, with the gyro and wheel errors
    redrawn from the prior model's knowledge when ``drawn``."""
    import jax
    import numpy as np

    from cassini_bayes.inference.nuisance import prior_wheel_errors
    from cassini_bayes.simulate import noise_params, truth_params, with_errors

    tp, nz = truth_params(scenario), noise_params(scenario)
    if not drawn:
        return tp, nz
    kn, prior = scenario.prior.knowledge, scenario.prior
    k_b, k_s, k_c, k_a = jax.random.split(key, 4)
    n_w = len(prior.wheels)
    bias = kn.gyro_bias_sd_rad_s * jax.random.normal(k_b, (3,))
    scale = kn.gyro_scale_factor_sd * jax.random.normal(k_s, (3,))
    c = prior_wheel_errors(prior, k_c)            # c_s + d_k per wheel
    tilt = np.deg2rad(kn.wheel_axis_sd_deg) * np.asarray(jax.random.normal(k_a, (n_w, 2)))
    names = [w.name for w in prior.wheels]
    return with_errors(scenario, tp, nz, wheel_scale=dict(zip(names, c)),
                       wheel_tilt_rad=dict(zip(names, tilt)), gyro_bias_rad_s=bias,
                       gyro_scale_factor=scale)


def _wheel_error_mean(key, scenario) -> float:
    """The mean of the wheels' drawn spin-inertia errors (``c_s + mean d_k``) of :func:`_errors`
    with ``key``: the common scale the momentum balance cannot see."""
    import jax
    import numpy as np

    from cassini_bayes.inference.nuisance import prior_wheel_errors

    return float(np.mean(prior_wheel_errors(scenario.prior, jax.random.split(key, 4)[2])))


def _run_one(job) -> dict:
    """Simulate one (family, seed) and fit both models; returns plain numbers."""
    family, seed, opts = job
    import warnings

    import jax
    import numpy as np

    from cassini_bayes.inference.inertia import fit_inertia
    from cassini_bayes.inference.runner import SamplerSettings
    from cassini_bayes.physics.momentum import INERTIA_NAMES
    from cassini_bayes.simulate import load_scenario, simulate_arrays
    from cassini_bayes.telemetry import Telemetry

    scenario = load_scenario(FAMILIES[family])
    key = jax.random.key(10_000 * (list(FAMILIES).index(family) + 1) + seed)
    k_err, k_sim, k_fit = jax.random.split(key, 3)
    tp, nz = _errors(k_err, scenario, opts["errors"] == "drawn")
    a = jax.tree_util.tree_map(np.asarray, simulate_arrays(k_sim, scenario, tp, nz))
    tel = Telemetry(t=a.t_meas, q=a.q_meas, omega=a.omega_meas, wheel_rates=a.wheel_rates_meas,
                    wheel_names=scenario.wheel_names, on_times=None,
                    source=f"<{scenario.name} seed {seed}>")
    truth = np.asarray(tp.inertia)
    s = SamplerSettings(chains=opts["chains"], warmup=opts["warmup"], draws=opts["draws"],
                        chain_method="vectorized")
    out = {"family": family, "seed": seed, "truth": truth.tolist()}
    if opts["errors"] == "drawn":
        out["wheel_error_mean"] = _wheel_error_mean(k_err, scenario)
    for model in opts["models"]:
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            post = fit_inertia(k_fit, [tel], scenario.prior, robust=model == "robust",
                               settings=s, prior_draws=0)
        p = post.idata.posterior
        d = np.stack([p[n].values.ravel() for n in INERTIA_NAMES], 1)
        q05, q95 = np.quantile(d, [0.05, 0.95], axis=0)
        mean = d.mean(0)
        err = mean - truth
        budget = bool(np.all(np.abs(err[:3]) <= MOMENT_BUDGET * truth[:3])
                      and np.all(np.abs(err[3:]) <= scenario.prior.poi_uncertainty))
        out[model] = {"hit": ((q05 <= truth) & (truth <= q95)).tolist(),
                      "sd": d.std(0).tolist(), "error": err.tolist(), "budget": budget,
                      "r_hat": float(post.diagnostics.max_r_hat),
                      "divergences": int(post.diagnostics.divergences),
                      "seconds": time.perf_counter() - t0}
    return out


def _init_worker(single_thread: bool) -> None:
    if single_thread:
        os.environ["XLA_FLAGS"] = ("--xla_cpu_multi_thread_eigen=false "
                                   "intra_op_parallelism_threads=1")
    sys.path.insert(0, str(ROOT))


def _summary(results: list[dict]) -> dict:
    import numpy as np

    from cassini_bayes.physics.momentum import INERTIA_NAMES

    table = {}
    for family in dict.fromkeys(r["family"] for r in results):
        rows = [r for r in results if r["family"] == family]
        for model in (m for m in MODELS if m in rows[0]):
            h = np.array([r[model]["hit"] for r in rows], float)
            cov, n = float(h.mean()), h.size
            table[f"{family}/{model}"] = {
                "seeds": len(rows), "coverage_90": cov,
                "coverage_se": float(np.sqrt(cov * (1.0 - cov) / n)),
                "coverage_per_entry": dict(zip(INERTIA_NAMES, h.mean(0).round(3).tolist())),
                "budget_pass": float(np.mean([r[model]["budget"] for r in rows])),
                "max_abs_error": dict(zip(INERTIA_NAMES, np.abs(
                    [r[model]["error"] for r in rows]).max(0).tolist())),
                "max_rel_moment_error": float(np.max(np.abs(
                    [np.asarray(r[model]["error"][:3]) / np.asarray(r["truth"][:3])
                     for r in rows]))),
                "median_sd": dict(zip(INERTIA_NAMES, np.median(
                    [r[model]["sd"] for r in rows], 0).tolist())),
                "max_r_hat": max(r[model]["r_hat"] for r in rows),
                "divergences": sum(r[model]["divergences"] for r in rows),
                "median_fit_s": float(np.median([r[model]["seconds"] for r in rows])),
            }
    return table


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--families", nargs="+", default=list(FAMILIES), choices=list(FAMILIES))
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--warmup", type=int, default=500)
    ap.add_argument("--draws", type=int, default=500)
    ap.add_argument("--errors", choices=("drawn", "fixed"), default="drawn")
    ap.add_argument("--models", nargs="+", default=list(MODELS), choices=list(MODELS))
    ap.add_argument("--json", type=Path, default=None, help="write per-seed results and summary")
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    opts = {k: getattr(args, k) for k in ("chains", "warmup", "draws", "errors", "models")}
    jobs = [(f, s, opts) for s in range(args.first_seed, args.first_seed + args.seeds)
            for f in args.families]                  # seed-major: every family gets going early
    t0 = time.perf_counter()
    results = []
    with ProcessPoolExecutor(args.workers, initializer=_init_worker,
                             initargs=(args.workers > 1,)) as pool:
        for r in pool.map(_run_one, jobs):
            results.append(r)
            print(f"{r['family']:16s} seed {r['seed']:3d}  " + "  ".join(
                f"{m} {''.join(str(int(x)) for x in r[m]['hit'])} "
                f"budget {int(r[m]['budget'])} R-hat {r[m]['r_hat']:.3f} "
                f"div {r[m]['divergences']}" for m in args.models)
                + f"  ({time.perf_counter() - t0:.0f} s)", flush=True)
    table = _summary(results)
    for name, row in table.items():
        print(f"{name:26s} 90 % coverage {row['coverage_90']:.3f} ± {row['coverage_se']:.3f} "
              f"({row['seeds']} seeds × 6)  budget pass {row['budget_pass']:.2f}  "
              f"max R-hat {row['max_r_hat']:.4f}  divergences {row['divergences']}  "
              f"max moment error {100 * row['max_rel_moment_error']:.2f} %  "
              f"median fit {row['median_fit_s']:.0f} s")
        print(" " * 27 + "per entry " + "  ".join(f"{k} {v:.2f}" for k, v in
                                                   row["coverage_per_entry"].items()))
        print(" " * 27 + "median sd " + "  ".join(f"{k} {v:.3g}" for k, v in
                                                   row["median_sd"].items()))
    if args.json is not None:
        args.json.write_text(json.dumps({"options": vars(args) | {"json": str(args.json)},
                                         "results": results, "summary": table}, indent=1))


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    main()
