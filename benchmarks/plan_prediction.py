"""The predicted posterior of a manoeuvre (``cassini-bayes plan evaluate``) against NUTS fits.

For each scenario: the predicted posterior sd of every site of the robust inertia fit (Laplace
on the flight simulated without noise, :func:`cassini_bayes.plan.evaluate.evaluate_inertia`);
then ``--seeds`` noisy replicates of the same scenario (its own sensor noise and errors, the
compiled simulator), each fitted with the default robust model by NUTS
(:func:`cassini_bayes.inference.inertia.fit_inertia`); per site the ratio of the fitted
posterior sd to the predicted one (median over the seeds, and its range). Not a test.

    python benchmarks/plan_prediction.py [--scenarios slews_espa_bus slews_cubesat_12u
        slews_post_prm] [--seeds 4] [--chains 4] [--warmup 500] [--draws 500] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ("slews_espa_bus", "slews_cubesat_12u", "slews_post_prm")
INERTIA = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")


def _fitted_sd_data(posterior) -> list[float]:
    """Posterior sd of ``π̃ = π/(1 + c)`` (the data part: the wheels' common spin-inertia scale
    ``c`` divided out), ``c`` the mean over the wheels of each draw's total scale ``c_k``
    (``inference.inertia.model``: the mean of ``d_k`` is ``m``, so mean ``c_k = m + c_s = c``)."""
    import numpy as np

    c = np.asarray(posterior["wheel_scale"].values)
    c = c.reshape(c.shape[0] * c.shape[1], -1).mean(1)
    pi = np.stack([np.asarray(posterior[n].values).ravel() for n in INERTIA], 1)
    return (pi / (1.0 + c[:, None])).std(0).tolist()


def run(scenario_name: str, seeds: int, settings) -> dict:
    import jax
    import numpy as np

    from cassini_bayes.inference.inertia import fit_inertia
    from cassini_bayes.plan.evaluate import evaluate_inertia, wheels_on
    from cassini_bayes.plan.inertia import fitted_site_sd, inertia_model
    from cassini_bayes.simulate import load_scenario, simulate_arrays
    from cassini_bayes.telemetry import Telemetry

    s = load_scenario(scenario_name)
    t0 = time.perf_counter()
    pred = evaluate_inertia(s)
    t_pred = time.perf_counter() - t0
    model = inertia_model(s.prior, wheels_on(s))
    fits = []
    for seed in range(seeds):
        k_sim, k_fit = jax.random.split(jax.random.key(7000 + seed))
        a = jax.tree_util.tree_map(np.asarray, simulate_arrays(k_sim, s))
        tel = Telemetry(t=a.t_meas, q=a.q_meas, omega=a.omega_meas,
                        wheel_rates=a.wheel_rates_meas, wheel_names=s.wheel_names,
                        on_times=None, source=f"<{s.name} seed {seed}>")
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            post = fit_inertia(k_fit, [tel], s.prior, settings=settings, prior_draws=0)
        fits.append({"seed": seed, "sd": fitted_site_sd(model, post.idata.posterior).tolist(),
                     "sd_data": _fitted_sd_data(post.idata.posterior),
                     "r_hat": float(post.diagnostics.max_r_hat),
                     "divergences": int(post.diagnostics.divergences),
                     "seconds": time.perf_counter() - t0})
        print(f"{scenario_name} seed {seed}: {fits[-1]['seconds']:.0f} s, "
              f"R-hat {fits[-1]['r_hat']:.3f}", file=sys.stderr, flush=True)
    sd = np.array([f["sd"] for f in fits])
    ratio = sd / pred.site_sd[None, :]
    per_site = {lab: {"predicted": float(pred.site_sd[i]), "prior": float(pred.site_prior_sd[i]),
                      "fitted_median": float(np.median(sd[:, i])),
                      "ratio_median": float(np.median(ratio[:, i])),
                      "ratio_min": float(ratio[:, i].min()), "ratio_max": float(ratio[:, i].max())}
                for i, lab in enumerate(pred.sites)}
    # sites the data inform (posterior sd below 0.9 of the prior): where the prediction matters
    informed = [i for i in range(len(pred.sites)) if pred.site_sd[i] < 0.9 * pred.site_prior_sd[i]]
    sd_data = np.array([f["sd_data"] for f in fits])
    data_part = {n: {"predicted": float(pred.sd_data[i]),
                     "fitted_median": float(np.median(sd_data[:, i])),
                     "ratio_median": float(np.median(sd_data[:, i] / pred.sd_data[i]))}
                 for i, n in enumerate(INERTIA)}
    med = np.median(ratio, 0)
    return {"scenario": scenario_name, "seeds": seeds, "predict_seconds": t_pred,
            "sites": per_site, "data_part": data_part, "fits": fits,
            "worst_ratio_all": float(med[np.argmax(np.abs(np.log(med)))]),
            "worst_ratio_informed": float(med[informed][np.argmax(np.abs(np.log(med[informed])))]),
            "within_10pct": int(np.sum(np.abs(med - 1) <= 0.10)),
            "within_20pct": int(np.sum(np.abs(med - 1) <= 0.20)), "n_sites": len(pred.sites),
            "n_informed": len(informed)}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenarios", nargs="+", default=list(SCENARIOS))
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--warmup", type=int, default=500)
    ap.add_argument("--draws", type=int, default=500)
    ap.add_argument("--json", type=Path)
    a = ap.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    import cassini_bayes
    from cassini_bayes.inference.runner import SamplerSettings

    cassini_bayes.setup_jax()
    settings = SamplerSettings(chains=a.chains, warmup=a.warmup, draws=a.draws,
                               chain_method="vectorized")
    out = {"settings": {"chains": a.chains, "warmup": a.warmup, "draws": a.draws},
           "results": []}
    for name in a.scenarios:
        r = run(name, a.seeds, settings)
        out["results"].append(r)
        print(f"\n{name}: fitted sd / predicted sd, median over {a.seeds} seeds "
              f"(min–max); {r['within_20pct']}/{r['n_sites']} sites within 20 %")
        for lab, v in r["sites"].items():
            print(f"  {lab:22s} pred {v['predicted']:10.4g}  fit {v['fitted_median']:10.4g}  "
                  f"ratio {v['ratio_median']:.3f} ({v['ratio_min']:.3f}–{v['ratio_max']:.3f})"
                  f"  prior {v['prior']:.4g}")
        for lab, v in r["data_part"].items():
            print(f"  {lab + ' data part':22s} pred {v['predicted']:10.4g}  "
                  f"fit {v['fitted_median']:10.4g}  ratio {v['ratio_median']:.3f}")
        if a.json:
            a.json.parent.mkdir(parents=True, exist_ok=True)
            a.json.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
