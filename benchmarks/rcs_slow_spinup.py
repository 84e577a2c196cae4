"""RCS spin-axis fits of slow spin-ups from tiny residual rates, at the default settings.

Two parts (docs/robust/README.md, "RWA4 RCS chart"):

* ``family`` (default): for each seed ``s``, ``experiments/scenarios/rwa4_rcs_slow.toml`` (RWA4
  alone, 0 -> 200 rpm at 0.0056 N m) with the true RWA4 axis on the articulation cone at an
  azimuth drawn from ``s`` (Brown §I: RWA4 can be articulated to any angle), residual body rates
  ``N(0, (1e-5 rad/s)²)`` per axis drawn from ``s``, sensor noise key ``s``; fitted with
  :func:`cassini_bayes.api.fit_rwa4` at its defaults (what ``cassini-bayes fit rwa4 --method rcs
  --seed s`` runs: 4 chains x 1000 + 1000, target acceptance 0.95). Prints each fit's
  divergences, max R-hat, min bulk ESS, convergence (R-hat <= 1.01, ESS >= 400, 0 divergences),
  axis error and 90 % cone, and the count of converged fits.
* ``posterior``: long fits (4 x ``--long-draws``) of the shipped RCS scenarios (and of
  ``rwa4_rcs`` with the articulation-cone prior, the pinned fit's), printing the mean
  axis, the 50/90/95 % cone radii and the inertia means with their Monte Carlo standard errors
  (ArviZ ``mcse``), to compare two versions of the model draw for draw in distribution.

The scenario is read from this checkout, the package from the interpreter's path, so the same
script measures an older version (``PYTHONPATH=<git archive of that commit>``).

    nice -n 10 python benchmarks/rcs_slow_spinup.py [family|posterior] [--seeds 20]
        [--first-seed 0] [--long-draws 10000] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import time
import tomllib
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "experiments" / "scenarios" / "rwa4_rcs_slow.toml"
SHIPPED_RCS = (("rwa4_rcs", "uniform"), ("rwa4_rcs", "cone"), ("rwa4_rcs_real", "uniform"),
               ("rwa4_rcs_slow", "uniform"))
RATE_SD_RAD_S = 1e-5
CONE_DEG = 54.7356103172453  # Brown §I: the articulation cone's half-angle about +Z


def family_case(seed: int) -> dict:
    """The scenario dict of ``seed``: the file's, with the RWA4 azimuth and the residual rates
    drawn from ``seed``."""
    import numpy as np

    d = tomllib.loads(SCENARIO.read_text())
    rng = np.random.default_rng([28, seed])
    az = rng.uniform(0.0, 2.0 * np.pi)
    cone = np.radians(CONE_DEG)
    d["truth"]["rwa4_axis"] = [np.sin(cone) * np.cos(az), np.sin(cone) * np.sin(az),
                               np.cos(cone)]
    d["initial"]["rates_rad_s"] = (RATE_SD_RAD_S * rng.standard_normal(3)).tolist()
    d["seed"] = seed
    return d


def run_family(seeds, log=print) -> list[dict]:
    """Simulate and fit each seed's case at the API's defaults; one record per seed."""
    import jax
    import numpy as np

    from cassini_bayes import setup_jax
    from cassini_bayes.api import fit_rwa4
    from cassini_bayes.inference.sphere import angles_deg
    from cassini_bayes.simulate import scenario_from_dict, simulate

    setup_jax()

    out = []
    t0 = time.perf_counter()
    for seed in seeds:
        scenario = scenario_from_dict(family_case(seed), src=f"{SCENARIO.name}[seed {seed}]")
        sim = simulate(jax.random.key(seed), scenario)
        truth = np.asarray(scenario.truth.wheel("RWA4").axis)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = fit_rwa4(sim.telemetry, scenario.prior, method="rcs", seed=seed)
        post = res.posterior
        d = post.diagnostics
        err = float(angles_deg(np.array(post.direction["mean"])[None], truth)[0])
        rec = dict(seed=seed, divergences=int(d.divergences), r_hat=float(d.max_r_hat),
                   ess_bulk=float(d.min_ess_bulk), converged=bool(d.converged), err_deg=err,
                   cone90_deg=float(post.direction["cone_deg"]["90"]),
                   windows=[list(w) for p in post.problem.pairs for w in p])
        out.append(rec)
        log(f"seed {seed:3d}: {rec['divergences']} divergences, R-hat {rec['r_hat']:.4f}, bulk "
            f"ESS {rec['ess_bulk']:.0f}, {'converged' if rec['converged'] else 'NOT converged'}; "
            f"axis error {err:.3f} deg, cone90 {rec['cone90_deg']:.3f} deg  "
            f"({time.perf_counter() - t0:.0f} s)")
    return out


def run_posterior(draws: int, log=print) -> dict:
    """Long fits of the shipped RCS scenarios (simulation key 21, fit key 5): the mean axis,
    cone radii and inertia means with their Monte Carlo standard errors."""
    import arviz as az
    import jax
    import numpy as np

    from cassini_bayes import setup_jax
    from cassini_bayes.inference.runner import SamplerSettings
    from cassini_bayes.inference.rwa4 import fit_rwa4
    from cassini_bayes.inference.sphere import CONE_LEVELS, angles_deg, mean_direction
    from cassini_bayes.names import INERTIA_NAMES, U4_NAMES
    from cassini_bayes.simulate import scenario_from_dict, simulate

    setup_jax()
    settings = SamplerSettings(chains=4, warmup=1000, draws=draws, target_accept=0.95)
    out = {}
    for name, prior in SHIPPED_RCS:
        path = ROOT / "experiments" / "scenarios" / f"{name}.toml"
        scenario = scenario_from_dict(tomllib.loads(path.read_text()), src=str(path))
        sim = simulate(jax.random.key(21), scenario)
        post = fit_rwa4(jax.random.key(5), sim.telemetry, scenario.prior, method="rcs",
                        prior=prior, settings=settings, prior_draws=0)
        p = post.idata.posterior
        u = np.stack([p[n].values for n in U4_NAMES], -1)               # (chains, draws, 3)
        mean = mean_direction(u)
        ang = angles_deg(u, mean).reshape(u.shape[:2])
        rec = {"divergences": int(post.diagnostics.divergences),
               "mean": mean.tolist(),
               "mean_mcse": [float(az.mcse(p[n].values, method="mean")) for n in U4_NAMES],
               "cone_deg": {}, "inertia": {}}
        for lv in CONE_LEVELS:
            rec["cone_deg"][str(lv)] = [float(np.percentile(ang, lv)),
                                        float(az.mcse(ang, method="quantile", prob=lv / 100))]
        for n in INERTIA_NAMES:
            v = p[n].values
            rec["inertia"][n] = [float(v.mean()), float(az.mcse(v, method="mean")),
                                 float(v.std())]
        out[f"{name} ({prior})"] = rec
        cones = ", ".join(f"{k}: {v[0]:.3f} ± {v[1]:.3f}" for k, v in rec["cone_deg"].items())
        log(f"{name} ({prior} prior): mean axis {np.round(mean, 5).tolist()} (mcse "
            f"{np.round(rec['mean_mcse'], 5).tolist()}), cones (deg) {cones}, "
            f"{rec['divergences']} divergences")
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("part", nargs="?", default="family", choices=("family", "posterior"))
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--long-draws", type=int, default=10_000)
    ap.add_argument("--json", default=None, help="write the records here (their manifest beside)")
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    t0 = time.perf_counter()
    if args.part == "family":
        records = run_family(range(args.first_seed, args.first_seed + args.seeds))
        ok = [r for r in records if r["converged"]]
        print(f"\n{len(ok)}/{len(records)} converged; divergences "
              f"{sum(r['divergences'] for r in records)} in all, "
              f"{sum(r['divergences'] for r in ok)} on the converged fits; max R-hat "
              f"{max(r['r_hat'] for r in records):.4f}, min bulk ESS "
              f"{min(r['ess_bulk'] for r in records):.0f}; {time.perf_counter() - t0:.0f} s")
    else:
        records = run_posterior(args.long_draws)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"part": args.part, "records": records}, fh, indent=1)


if __name__ == "__main__":
    main()
