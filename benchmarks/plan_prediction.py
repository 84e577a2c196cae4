"""The predicted posterior of a manoeuvre (``cassini-bayes plan evaluate``) against NUTS fits.

For each scenario: the predicted posterior sd of every site of the robust inertia fit (Laplace
on the flight simulated without noise, :func:`cassini_bayes.plan.evaluate.evaluate_inertia`);
then ``--seeds`` noisy replicates of the same scenario (its own sensor noise and errors, the
compiled simulator), each fitted with the default robust model by NUTS
(:func:`cassini_bayes.inference.inertia.fit_inertia`); per site the ratio of the fitted
posterior sd to the predicted one (median over the seeds, and its range). Not a test.

    python benchmarks/plan_prediction.py [--scenarios slews_espa_bus slews_cubesat_12u
        slews_post_prm] [--seeds 4] [--chains 4] [--warmup 500] [--draws 500] [--open-world]
        [--json out.json]

``--open-world``: each seed's truth drawn by :func:`cassini_bayes.simulate.open_world.
draw_open_world` (errors the fit does not assume), and the 90 % coverage of the inertia.
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


def _hits(posterior, truth) -> list[bool]:
    """Whether each true inertia entry lies in the fit's central 90 % interval."""
    import numpy as np

    d = np.stack([np.asarray(posterior[n].values).ravel() for n in INERTIA], 1)
    lo, hi = np.quantile(d, [0.05, 0.95], axis=0)
    return ((lo <= truth) & (truth <= hi)).tolist()


def _fitted_sd_data(posterior) -> list[float]:
    """Posterior sd of ``π̃ = π/(1 + c)`` (the data part: the wheels' common spin-inertia scale
    ``c`` divided out), ``c`` the mean over the wheels of each draw's total scale ``c_k``
    (``inference.inertia.model``: the mean of ``d_k`` is ``m``, so mean ``c_k = m + c_s = c``)."""
    import numpy as np

    c = np.asarray(posterior["wheel_scale"].values)
    c = c.reshape(c.shape[0] * c.shape[1], -1).mean(1)
    pi = np.stack([np.asarray(posterior[n].values).ravel() for n in INERTIA], 1)
    return (pi / (1.0 + c[:, None])).std(0).tolist()


def _replicate(s, scenario_name: str, seed: int, open_world: bool):
    """One noisy replicate: ``(telemetry, true π)``; with ``open_world`` the errors drawn by
    :func:`cassini_bayes.simulate.open_world.draw_open_world` (non-Normal, 1.5× the priors,
    a flexible mode, time-tag errors, a drifting torque) instead of the scenario's own."""
    import jax
    import numpy as np

    from cassini_bayes.physics.momentum import inertia_vector
    from cassini_bayes.simulate import scenario_from_dict, simulate
    from cassini_bayes.simulate.open_world import apply_time_tags, draw_open_world

    k_sim = jax.random.split(jax.random.key(7000 + seed))[0]
    if open_world:
        ow = draw_open_world(scenario_name, np.random.default_rng([seed, 32]))
        s = scenario_from_dict(ow.scenario, src=s.source)
    sim = simulate(k_sim, s)
    tel = apply_time_tags(sim.telemetry, ow) if open_world else sim.telemetry
    return tel, np.asarray(inertia_vector(s.truth.inertia), float)


def run(scenario_name: str, seeds: int, settings, open_world: bool = False) -> dict:
    import jax
    import numpy as np

    from cassini_bayes.inference.inertia import fit_inertia
    from cassini_bayes.plan.evaluate import evaluate_inertia, wheels_on
    from cassini_bayes.plan.inertia import fitted_site_sd, inertia_model
    from cassini_bayes.simulate import load_scenario

    s = load_scenario(scenario_name)
    t0 = time.perf_counter()
    pred = evaluate_inertia(s)
    t_pred = time.perf_counter() - t0
    model = inertia_model(s.prior, wheels_on(s))
    fits = []
    for seed in range(seeds):
        k_fit = jax.random.split(jax.random.key(7000 + seed))[1]
        tel, truth = _replicate(s, scenario_name, seed, open_world)
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            post = fit_inertia(k_fit, [tel], s.prior, settings=settings, prior_draws=0)
        fits.append({"seed": seed, "sd": fitted_site_sd(model, post.idata.posterior).tolist(),
                     "sd_data": _fitted_sd_data(post.idata.posterior),
                     "hit90": _hits(post.idata.posterior, truth),
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
    hits = np.array([f["hit90"] for f in fits], float)
    return {"scenario": scenario_name, "seeds": seeds, "open_world": open_world,
            "predict_seconds": t_pred,
            "coverage90": float(hits.mean()), "coverage90_per_entry": hits.mean(0).tolist(),
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
    ap.add_argument("--open-world", action="store_true",
                    help="draw each seed's errors open-world (simulate/open_world.py)")
    ap.add_argument("--json", type=Path)
    a = ap.parse_args(argv)
    if a.json:
        from _provenance import start

        a.json.parent.mkdir(parents=True, exist_ok=True)
        start(a.json, vars(a), argv, replace=True)
    sys.path.insert(0, str(ROOT))
    import cassini_bayes
    from cassini_bayes.inference.runner import SamplerSettings

    cassini_bayes.setup_jax()
    settings = SamplerSettings(chains=a.chains, warmup=a.warmup, draws=a.draws,
                               chain_method="vectorized")
    out = {"settings": {"chains": a.chains, "warmup": a.warmup, "draws": a.draws},
           "results": []}
    for name in a.scenarios:
        r = run(name, a.seeds, settings, a.open_world)
        out["results"].append(r)
        print(f"\n{name}: fitted sd / predicted sd, median over {a.seeds} seeds "
              f"(min–max); {r['within_20pct']}/{r['n_sites']} sites within 20 %; inertia 90 % "
              f"coverage {r['coverage90']:.3f}")
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
