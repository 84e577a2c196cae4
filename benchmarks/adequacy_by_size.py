"""Adequacy checks of the inertia fit against the number of samples: false alarms on correctly
specified files of 2 000, 20 000 and 200 000 rows, and hits on deliberately wrong ones.

The files are the Post-Probe slews (``slews_post_probe``: six 30° slews about X, Y, Z) run for
19 990 s (the slews and then a long rest; integration step 0.1 s) and sampled every 10 s, 1 s and
0.1 s: 2 000, 19 991 and 199 901 rows of the same motion, so only the number of samples changes.
Per seed the gyro bias and scale factor, the wheels' spin-inertia errors and axis tilts are drawn
from the prior model's knowledge (as ``adequacy_false_alarms.py``), with fresh sensor noise.

Cases:

* ``clean`` — one file, the robust model (the CLI's default): correctly specified.
* ``clean2`` — two files of the same errors and fresh noise, so ``held_out`` runs as well.
* ``sign`` — RWA2's column negated in the file (``check`` refuses that file; the fit is called
  directly), the robust model.
* ``tach`` — RWA1's tachometer 3 % high, the papers' idealised model (no wheel-scale nuisance
  to absorb it): a misfit that only the residual checks can see.

The adequacy statistics use the posterior means (and sd) of the fit and the residuals at the
posterior mean, so a small sampler run gives them (default 2 chains × 200 warm-up × 200 draws;
their Monte Carlo error is ~0.1 posterior sd); at 200 000 rows the fit's cost is the
preparation (noise levels and iterated least squares, O(N)), a few minutes per file on the
shared 2-core machine. Results are saved after every fit to ``--json`` (rerun with the same
file to resume; the manifest beside it lists every run). The table kind ``adequacy_by_size``
reads the records.

    python benchmarks/adequacy_by_size.py --seeds 20 --cases clean --json by_size.json
    python benchmarks/adequacy_by_size.py --seeds 3 --cases sign tach clean2 \\
        --json misfit.json
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
sys.path.insert(0, str(ROOT))

DURATION_S = 19_990.0
DT_S = 0.1
PERIODS_S = {2000: 10.0, 20000: 1.0, 200000: 0.1}   # nominal rows -> sample period
CASES = ("clean", "clean2", "sign", "tach")
TACH_SCALE = 1.03


def scenario(rows: int):
    from dataclasses import replace

    from cassini_bayes.simulate import load_scenario

    return replace(load_scenario("slews_post_probe"), duration_s=DURATION_S, dt_s=DT_S,
                   sample_period_s=PERIODS_S[rows])


def run_one(case: str, rows: int, seed: int, settings, save: Path | None = None) -> dict:
    """Simulate and fit one (case, size, seed); the adequacy block and the inertia."""
    import jax
    import numpy as np
    from coverage_robust_inertia import _errors

    from cassini_bayes import setup_jax
    from cassini_bayes.inference.adequacy import inertia_adequacy
    from cassini_bayes.inference.inertia import fit_inertia, robust_sites
    from cassini_bayes.physics.momentum import INERTIA_NAMES
    from cassini_bayes.simulate import simulate_arrays
    from cassini_bayes.telemetry import Telemetry

    setup_jax()
    sc = scenario(rows)
    k_err, k_fit, *k_files = jax.random.split(jax.random.key(7000 + seed), 4)
    tp, nz = _errors(k_err, sc, True)
    tels = []
    for i, k in enumerate(k_files[:2 if case == "clean2" else 1]):
        a = jax.tree_util.tree_map(np.asarray, simulate_arrays(k, sc, tp, nz))
        rates = np.array(a.wheel_rates_meas)
        if case == "sign":
            rates[:, sc.wheel_names.index("RWA2")] *= -1.0
        if case == "tach":
            rates[:, sc.wheel_names.index("RWA1")] *= TACH_SCALE
        tels.append(Telemetry(t=a.t_meas, q=a.q_meas, omega=a.omega_meas, wheel_rates=rates,
                              wheel_names=sc.wheel_names, on_times=None, source=f"file{i}"))
    robust = case != "tach"
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = fit_inertia(k_fit, tels, sc.prior, robust=robust, settings=settings)
    sites = list(INERTIA_NAMES) + ["T_N"] + (robust_sites(post.problem.layout) if robust else [])
    out = inertia_adequacy(post, sites).to_dict()
    p = post.idata.posterior
    truth = np.asarray(tp.inertia, float)
    out["inertia_z"] = {n: float((p[n].mean() - truth[i]) / p[n].std())
                        for i, n in enumerate(INERTIA_NAMES)}
    out["rows"] = int(sum(t.n for t in tels) // len(tels))
    out["seconds"] = time.perf_counter() - t0
    if save is not None:
        pb = post.problem
        save.mkdir(parents=True, exist_ok=True)
        np.savez(save / f"{case}_{rows}_{seed}.npz",
                 residual_std=post.idata["residuals"]["residual_std"].values,
                 omega=pb.omega, h_wheels=pb.h_wheels, t=pb.t, file_idx=pb.file_idx)
    return out


def table(records: list[dict]) -> str:
    """Markdown table of the records (``--json``, pooled): per case and size, each check's
    failures (median and largest statistic) and the fits failing any check."""
    from adequacy_false_alarms import CHECKS, any_cell, check_cell

    results: dict = {}
    for rec in records:
        for case, by_rows in rec["results"].items():
            for rows, seeds in by_rows.items():
                results.setdefault(case, {}).setdefault(rows, {}).update(seeds)
    lines = ["| case | rows | fits | " + " | ".join(f"`{n}`" for n in CHECKS) + " | any check |",
             "|---|---|---|" + "---|" * (len(CHECKS) + 1)]
    for case in CASES:
        for rows in PERIODS_S:
            rs = results.get(case, {}).get(str(rows), {})
            if not rs:
                continue
            res = [rs[k] for k in sorted(rs, key=int)]
            lines.append(f"| `{case}` | {res[0]['rows']} | {len(res)} | "
                         + " | ".join(check_cell(res, n) for n in CHECKS)
                         + f" | {any_cell(res)} |")
    return "\n".join(lines)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--sizes", nargs="+", type=int, default=list(PERIODS_S),
                    choices=list(PERIODS_S))
    ap.add_argument("--cases", nargs="+", default=["clean"], choices=CASES)
    ap.add_argument("--chains", type=int, default=2)
    ap.add_argument("--warmup", type=int, default=200)
    ap.add_argument("--draws", type=int, default=200)
    ap.add_argument("--json", type=Path, default=None, help="results, saved after every fit; "
                    "an existing file is resumed")
    ap.add_argument("--save-residuals", type=Path, default=None,
                    help="folder for each fit's residuals and regressors (.npz)")
    args = ap.parse_args(argv)
    from cassini_bayes.inference.runner import SamplerSettings
    from cassini_bayes.files import write_text

    settings = SamplerSettings(chains=args.chains, warmup=args.warmup, draws=args.draws,
                               chain_method="vectorized")
    if args.json is not None and args.seeds:
        from _provenance import start

        # seeds and cases grow over resumed runs; the sampler settings may not change
        start(args.json, {k: getattr(args, k) for k in ("chains", "warmup", "draws")}, argv)
    saved = json.loads(args.json.read_text()) if args.json and args.json.exists() else {}
    results = saved.get("results", {})
    t0 = time.perf_counter()
    for case in args.cases:
        for rows in args.sizes:
            done = results.setdefault(case, {}).setdefault(str(rows), {})
            for seed in range(args.seeds):
                if str(seed) in done:
                    continue
                r = run_one(case, rows, seed, settings, args.save_residuals)
                done[str(seed)] = r
                stats = "  ".join(
                    f"{k} " + ("-" if c["statistic"] is None else f"{c['statistic']:.2f}")
                    for k, c in r["checks"].items())
                print(f"{case:6s} {r['rows']:6d} rows seed {seed:2d} ok {int(r['ok'])}  {stats}"
                      f"  ({r['seconds']:.0f} s; {time.perf_counter() - t0:.0f} s)", flush=True)
                if args.json is not None:
                    write_text(args.json, json.dumps({"results": results}, indent=1) + "\n")
    print(table([{"results": results}]))

if __name__ == "__main__":
    main()
