"""Which short NUTS settings reach the package's convergence rule on clean simulated data.

For each clean shipped inertia scenario and seed (the seed of the noise and of the sampler, as
``examples/inertia_from_slews.py`` uses it), fits the robust inertia model (the
``cassini-bayes fit inertia`` default: per-wheel errors, external torque) with 4 chains ×
``W`` warm-up × ``D_max`` draws for each ``W`` of ``--warmups``, then judges every shorter run
those draws contain: the first ``C`` chains (``--chains``) and the first ``D`` draws
(``--draws``) of each, by the fit's own rule (:func:`cassini_bayes.inference.runner.diagnostics`
over the parameters the fit reports: max R-hat <= 1.01, min bulk ESS >= 400, no divergences).
The first ``C`` chains of a 4-chain run are a ``C``-chain run (each chain has its own key and
its own adaptation); the first ``D`` draws are the draws of a ``D``-draw run after the same
warm-up.

Prints one line per fit and setting, then per setting the fraction of fits that converged and
the worst R-hat and ESS; ``--json`` writes every row. Not a test: the numbers are in
docs/performance.md ("Quick settings"), whose table ``benchmarks/docs_tables.py`` makes from the
records in docs/quick_settings/ (:func:`table`).

    python benchmarks/quick_settings.py [--scenarios slews_post_probe slews_post_prm ...]
        [--seeds 0 1 2] [--warmups 300 500] [--chains 2 4] [--draws 300 500] [--json q.json]
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

CLEAN = ("slews_post_probe", "slews_post_prm", "slews_pre_soi", "slew_2000_03_15")


def _judge(post, names, chains: int, draws: int):
    import arviz as az

    from cassini_bayes.inference.runner import diagnostics

    idata = post.idata
    part = az.InferenceData(
        posterior=idata.posterior.isel(chain=slice(0, chains), draw=slice(0, draws)),
        sample_stats=idata.sample_stats.isel(chain=slice(0, chains), draw=slice(0, draws)))
    return diagnostics(part, names)


def table(paths: list[Path]) -> str:
    """The markdown table of docs/performance.md ("Quick settings") from the ``--json`` records:
    per setting, the fits that converged, the worst R-hat and the smallest bulk ESS."""
    rows = [r for p in paths for r in json.loads(Path(p).read_text())["rows"]]
    lines = ["| chains × warm-up + draws | converged | worst max R-hat | smallest min bulk ESS |",
             "|---|---|---|---|"]
    for key in sorted({(r["chains"], r["warmup"], r["draws"]) for r in rows}):
        sel = [r for r in rows if (r["chains"], r["warmup"], r["draws"]) == key]
        lines.append(f"| {key[0]} × {key[1]} + {key[2]} | {sum(r['converged'] for r in sel)} of "
                     f"{len(sel)} | {max(r['max_r_hat'] for r in sel):.4f} | "
                     f"{min(r['min_ess_bulk'] for r in sel):.0f} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenarios", nargs="+", default=list(CLEAN))
    ap.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    ap.add_argument("--warmups", nargs="+", type=int, default=[300, 500])
    ap.add_argument("--chains", nargs="+", type=int, default=[2, 4])
    ap.add_argument("--draws", nargs="+", type=int, default=[300, 500])
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    if args.json:
        from _provenance import start

        start(args.json, vars(args), None, replace=True)

    import jax

    import cassini_bayes as cb
    from cassini_bayes.inference.inertia import fit_inertia, robust_sites
    from cassini_bayes.inference.runner import SamplerSettings
    from cassini_bayes.names import INERTIA_NAMES

    rows = []
    for scenario in args.scenarios:
        for seed in args.seeds:
            sim = cb.simulate_scenario(scenario, seed=seed)
            for warmup in args.warmups:
                settings = SamplerSettings(chains=max(args.chains), warmup=warmup,
                                           draws=max(args.draws))
                t0 = time.perf_counter()
                post = fit_inertia(jax.random.key(seed), [sim.telemetry], sim.prior,
                                   settings=settings)
                wall = time.perf_counter() - t0
                names = (list(INERTIA_NAMES) + ["H0", "T_N", "noise_scale"]
                         + robust_sites(post.problem.layout))
                for chains in args.chains:
                    for draws in args.draws:
                        d = _judge(post, names, chains, draws)
                        row = {"scenario": scenario, "seed": seed, "chains": chains,
                               "warmup": warmup, "draws": draws, "max_r_hat": d.max_r_hat,
                               "min_ess_bulk": d.min_ess_bulk, "divergences": d.divergences,
                               "converged": d.converged, "worst": d.worst,
                               "fit_wall_s": wall, "load_1min": os.getloadavg()[0]}
                        rows.append(row)
                        print(f"{scenario:18s} seed {seed} {chains} x {warmup} + {draws}: "
                              f"R-hat {d.max_r_hat:.4f} ({d.worst}), ESS {d.min_ess_bulk:5.0f}, "
                              f"div {d.divergences}, {'ok' if d.converged else 'NOT converged'}",
                              flush=True)
    print()
    for chains in args.chains:
        for warmup in args.warmups:
            for draws in args.draws:
                sel = [r for r in rows if (r["chains"], r["warmup"], r["draws"])
                       == (chains, warmup, draws)]
                ok = sum(r["converged"] for r in sel)
                print(f"{chains} x {warmup} + {draws}: converged {ok}/{len(sel)}; worst R-hat "
                      f"{max(r['max_r_hat'] for r in sel):.4f}, min ESS "
                      f"{min(r['min_ess_bulk'] for r in sel):.0f}, divergences "
                      f"{sum(r['divergences'] for r in sel)}")
    if args.json:
        args.json.write_text(json.dumps({"args": {k: (str(v) if isinstance(v, Path) else v)
                                                  for k, v in vars(args).items()},
                                         "cpu_count": os.cpu_count(), "rows": rows}, indent=1))


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    main()
