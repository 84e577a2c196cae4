"""Coverage campaign: robust vs idealised thrust posteriors on biasing events with real errors.

For each seed: draw the truth's sensor and actuator errors at the scale of the robust model's
prior (the spacecraft model's :class:`~cassini_bayes.spacecraft.Knowledge`: gyro bias and scale
factor per axis, a shared and a per-wheel spin-inertia error, a tilt of each wheel's axis per
component, and a body-fixed external torque of 15 µN m per axis, Feldman & Lee App. A), simulate the
biasing event of a scenario (default ``biasing_day028``: Table 2, truth 0.699 N, 5/20/65 ms) with
the simulator's closed-loop RCS control, and fit both thrust models with the nominal spacecraft
model. Prints, per model, the 90 % coverage of ``F`` and of the three time constants with the
binomial standard error, the median posterior sd of ``F``, the worst ``|F − truth|`` (the
papers' ±10 % budget) and the convergence record. Not a test.

    python benchmarks/coverage_robust_thrust.py [--seeds 20] [--scenario biasing_day028]
        [--chains 4] [--warmup 300] [--draws 300] [--models idealised robust]
"""

from __future__ import annotations

import argparse
import time
import tomllib
import warnings


def _scenario_with_errors(base: dict, key, prior):
    """The scenario dict with the truth's errors drawn at the knowledge priors' scale."""
    import copy

    import jax
    import numpy as np

    from cassini_bayes.inference.nuisance import prior_wheel_errors

    d = copy.deepcopy(base)
    knowledge = prior.knowledge
    k_b, k_s, k_c, k_a, k_t = jax.random.split(key, 5)
    wheels = d["initial"]["wheels_on"]
    truth, noise = d["truth"], d["noise"]
    noise["gyro_bias_rad_s"] = (knowledge.gyro_bias_sd_rad_s
                                * np.asarray(jax.random.normal(k_b, (3,)))).tolist()
    noise["gyro_scale_factor"] = (knowledge.gyro_scale_factor_sd
                                  * np.asarray(jax.random.normal(k_s, (3,)))).tolist()
    truth["wheel_inertia_scale"] = 1.0       # each wheel c_s + d_k, from the robust prior
    truth["wheel_inertia_errors"] = prior_wheel_errors(prior, k_c).tolist()
    tilts = knowledge.wheel_axis_sd_deg * np.asarray(jax.random.normal(k_a, (len(wheels), 2)))
    truth["wheel_axis_tilt_deg"] = {w: tilts[i].tolist() for i, w in enumerate(wheels)}
    truth["external_torque_body_nm"] = (knowledge.torque_sd_nm * np.asarray(
        jax.random.normal(k_t, (3,)))).tolist()
    return d


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--scenario", default="biasing_day028")
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--warmup", type=int, default=300)
    ap.add_argument("--draws", type=int, default=300)
    ap.add_argument("--models", nargs="+", default=["idealised", "robust"],
                    choices=["idealised", "robust"])
    args = ap.parse_args(argv)

    import jax
    import numpy as np

    from cassini_bayes.inference.runner import SamplerSettings
    from cassini_bayes.inference.thrust import TAU_NAMES, fit_thrust
    from cassini_bayes.simulate import simulate
    from cassini_bayes.simulate.scenario import scenario_from_dict, scenario_path

    path = scenario_path(args.scenario)
    base = tomllib.loads(path.read_text())
    settings = SamplerSettings(chains=args.chains, warmup=args.warmup, draws=args.draws)
    names = ("F",) + TAU_NAMES
    models = tuple(args.models)
    hits = {m: [] for m in models}
    f_sd = {m: [] for m in models}
    f_err = {m: [] for m in models}
    conv = {m: [] for m in models}
    t0 = time.perf_counter()
    for seed in range(args.seeds):
        key = jax.random.key(2000 + seed)
        k_err, k_sim, k_fit = jax.random.split(key, 3)
        nominal = scenario_from_dict(base, src=str(path))
        scenario = scenario_from_dict(_scenario_with_errors(base, k_err, nominal.prior),
                                      src=str(path))
        sim = simulate(k_sim, scenario)
        truth = np.array([float(np.mean(np.asarray(sim.params.thrust_n)))]
                         + list(np.asarray(sim.params.tau_s, float)))
        for m in models:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                post = fit_thrust(k_fit, [(sim.telemetry, sim.pulses)], scenario.prior,
                                  settings=settings, robust=(m == "robust"), prior_draws=0)
            draws = np.stack([post.idata.posterior[n].values.ravel() for n in names], -1)
            q05, q95 = np.quantile(draws, [0.05, 0.95], axis=0)
            hits[m].append((q05 <= truth) & (truth <= q95))
            f_sd[m].append(draws[:, 0].std() / truth[0])
            f_err[m].append(abs(draws[:, 0].mean() - truth[0]) / truth[0])
            d = post.diagnostics
            conv[m].append((d.max_r_hat, d.min_ess_bulk, d.divergences))
        print(f"seed {seed}: " + "; ".join(
            f"{m} F in 90 %: {bool(hits[m][-1][0])}, sd {100 * f_sd[m][-1]:.3f} %, "
            f"err {100 * f_err[m][-1]:.3f} %" for m in models)
            + f"  ({time.perf_counter() - t0:.0f} s)", flush=True)

    print(f"\n{args.seeds} seeds of {args.scenario} with errors at the knowledge priors' scale; "
          f"{args.chains} chains x {args.draws} draws")
    for m in models:
        h = np.array(hits[m], float)
        n = h.shape[0]
        cov = h.mean(0)
        se = np.sqrt(0.9 * 0.1 / n)
        c = np.array(conv[m])
        print(f"{m:9s}: 90 % coverage " + ", ".join(
            f"{name} {cov[i]:.2f}" for i, name in enumerate(names))
            + f" (nominal 0.90 ± {se:.2f} binomial sd); median sd(F) "
            f"{100 * np.median(f_sd[m]):.3f} %; worst |F − truth| {100 * np.max(f_err[m]):.3f} % "
            f"(budget 10 %); max R-hat {c[:, 0].max():.3f}, min bulk ESS {c[:, 1].min():.0f}, "
            f"divergences {int(c[:, 2].sum())}")
    print(f"total {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    main()
