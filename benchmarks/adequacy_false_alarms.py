"""Adequacy checks: false-alarm rates on correctly specified data, and hits on mis-specified data.

Cases (each seed simulates fresh data and fits the robust model with small sampler settings):

* ``inertia_clean`` — ``slew_2000_03_15_real`` (3600 samples at 0.25 Hz), gyro bias/scale,
  wheel spin-inertia scale and axis tilts drawn from the prior model's knowledge (as
  ``coverage_robust_inertia.py --errors drawn``), two telemetry files per seed (same errors, fresh
  noise), so the held-out check runs; the robust model is correctly specified here.
* ``inertia_tach`` — the same with RWA1's tachometer 3 % off (its ``rwa1`` column × 1.03 in both
  files, the spacecraft model unchanged).
* ``thrust_clean`` — ``biasing_day028`` (one event), the spacecraft model's inertia set to the
  truth, fitted with the default robust model (the inertia sampled from the model file's
  knowledge).
* ``thrust_inertia`` — the same with the model file's inertia 3 % above the truth, held fixed
  there (``inertia="fixed"``, the papers' practice, ``--fix-inertia``).

Prints, per case, each check's failure rate with its binomial sd and the overall rate (any check
failed). Not a test; the numbers go to ``docs/adequacy.md``.

    python benchmarks/adequacy_false_alarms.py [--seeds 20] [--cases inertia_clean ...]
        [--chains 2] [--warmup 200] [--draws 200] [--json out.json]
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

CASES = ("inertia_clean", "inertia_tach", "thrust_clean", "thrust_inertia")
TACH_SCALE = 1.03       # case inertia_tach: RWA1's tachometer reads 3 % high
INERTIA_SCALE = 1.03    # case thrust_inertia: the model file's inertia 3 % above the truth


def _inertia_case(seed: int, tach: float, settings) -> dict:
    import jax
    import numpy as np

    from coverage_robust_inertia import _errors
    from cassini_bayes.inference.adequacy import inertia_adequacy
    from cassini_bayes.inference.inertia import ROBUST_SITES, fit_inertia
    from cassini_bayes.physics.momentum import INERTIA_NAMES
    from cassini_bayes.simulate import load_scenario, simulate_arrays
    from cassini_bayes.telemetry import Telemetry

    scenario = load_scenario("slew_2000_03_15_real")
    k_err, k_a, k_b, k_fit = jax.random.split(jax.random.key(1000 + seed), 4)
    tp, nz = _errors(k_err, scenario, True)
    tels = []
    for i, k in enumerate((k_a, k_b)):
        a = jax.tree_util.tree_map(np.asarray, simulate_arrays(k, scenario, tp, nz))
        rates = np.array(a.wheel_rates_meas)
        rates[:, scenario.wheel_names.index("RWA1")] *= tach
        tels.append(Telemetry(t=a.t_meas, q=a.q_meas, omega=a.omega_meas, wheel_rates=rates,
                              wheel_names=scenario.wheel_names, on_times=None,
                              source=f"file{i}"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = fit_inertia(k_fit, tels, scenario.prior, robust=True, settings=settings)
    return inertia_adequacy(post, list(INERTIA_NAMES) + ["T_N", *ROBUST_SITES]).to_dict()


def _thrust_case(seed: int, inertia_scale: float, settings) -> dict:
    from dataclasses import replace

    import jax
    import numpy as np

    from cassini_bayes.inference.adequacy import thrust_adequacy
    from cassini_bayes.inference.nuisance import EFFECTS
    from cassini_bayes.inference.thrust import TAU_NAMES, fit_thrust
    from cassini_bayes.simulate import load_scenario, pulse_log, simulate_arrays, truth_params
    from cassini_bayes.simulate.run import noise_params
    from cassini_bayes.physics.momentum import inertia_matrix
    from cassini_bayes.telemetry import Telemetry

    scenario = load_scenario("biasing_day028")
    k_sim, k_fit = jax.random.split(jax.random.key(2000 + seed))
    tp, nz = truth_params(scenario), noise_params(scenario)
    a = jax.tree_util.tree_map(np.asarray, simulate_arrays(k_sim, scenario, tp, nz))
    tel = Telemetry(t=a.t_meas, q=a.q_meas, omega=a.omega_meas, wheel_rates=a.wheel_rates_meas,
                    wheel_names=scenario.wheel_names, on_times=None, source="event")
    model = replace(scenario.prior,
                    inertia=inertia_scale * np.asarray(inertia_matrix(np.asarray(tp.inertia))))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = fit_thrust(k_fit, [(tel, pulse_log(a, scenario))], model, settings=settings,
                          inertia="fixed" if inertia_scale != 1.0 else None)
    return thrust_adequacy(post, ["F", *TAU_NAMES, *EFFECTS.values()]).to_dict()


def run_case(case: str, seed: int, settings) -> dict:
    if case.startswith("inertia"):
        return _inertia_case(seed, TACH_SCALE if case == "inertia_tach" else 1.0, settings)
    return _thrust_case(seed, INERTIA_SCALE if case == "thrust_inertia" else 1.0, settings)


def rates(results: list[dict]) -> dict:
    """Per check (and ``any``): failure rate, its binomial sd and, with no failure, the 95 %
    upper bound ``3/n`` (rule of three) over the seeds."""
    import numpy as np

    n = len(results)
    names = list(results[0]["checks"])
    out = {}
    for name in names + ["any"]:
        fails = [not (r["ok"] if name == "any" else r["checks"][name]["ok"]) for r in results]
        p = float(np.mean(fails))
        out[name] = {"rate": p, "sd": float(np.sqrt(p * (1 - p) / n)), "n": n,
                     "upper95": 3.0 / n if p == 0 else None,
                     "max_statistic": max((r["checks"][name]["statistic"] or 0.0)
                                          for r in results) if name != "any" else None}
    return out


CHECKS = ("prior_data_conflict", "held_out", "residual_autocorrelation", "residual_regression")


def check_cell(results: list[dict], name: str) -> str:
    """``k/n (median, largest statistic)`` of one check over ``results`` (adequacy blocks), with
    the parameter a failing check names when every failure names the same one; ``n/a`` where
    the check did not run."""
    import numpy as np

    checks = [r["checks"][name] for r in results if name in r["checks"]]
    stats = [c["statistic"] for c in checks if c["statistic"] is not None]
    if not stats:
        return "n/a"
    fails = [c for c in checks if not c["ok"]]
    named = {c.get("parameter") for c in fails}
    where = f", always `{named.pop()}`" if fails and len(named) == 1 and None not in named else ""
    return f"{len(fails)}/{len(results)} ({np.median(stats):.2g}, {max(stats):.2g}){where}"


def any_cell(results: list[dict]) -> str:
    """Fits failing any check, with the rule-of-three 95 % bound when none of ten or more did,
    else the rate and its binomial sd."""
    n, k = len(results), sum(not r["ok"] for r in results)
    if k == 0:
        return f"**0/{n}**" + (f" (≤ {3.0 / n:.2f} at 95 %)" if n >= 10 else "")
    if k == n:
        return f"**{k}/{n}**"
    p = k / n
    return f"**{k}/{n} = {p:.2f} ± {(p * (1 - p) / n) ** 0.5:.2f}**"


def table(records: list[dict]) -> str:
    """Per case of the records (``--json``): each check's failures (every check any fit ran)
    and the fits failing any."""
    cases = [(c, res) for rec in records for c, res in rec["results"].items()]
    names = list(dict.fromkeys(n for _, res in cases for r in res for n in r["checks"]))
    lines = ["| case | seeds | " + " | ".join(f"`{n}`" for n in names) + " | any check |",
             "|---|---|" + "---|" * (len(names) + 1)]
    for case, results in cases:
        lines.append(f"| `{case}` | {len(results)} | "
                     + " | ".join(check_cell(results, n) for n in names)
                     + f" | {any_cell(results)} |")
    return "\n".join(lines)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--cases", nargs="+", default=list(CASES), choices=CASES)
    ap.add_argument("--chains", type=int, default=2)
    ap.add_argument("--warmup", type=int, default=200)
    ap.add_argument("--draws", type=int, default=200)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    sys.path.insert(0, str(ROOT))
    from cassini_bayes.inference.runner import SamplerSettings

    settings = SamplerSettings(chains=args.chains, warmup=args.warmup, draws=args.draws,
                               chain_method="vectorized")
    t0 = time.perf_counter()
    table, per_seed = {}, {}
    for case in args.cases:
        results = []
        for seed in range(args.seeds):
            r = run_case(case, seed, settings)
            results.append(r)
            print(f"{case:15s} seed {seed:3d} ok {int(r['ok'])}  " + "  ".join(
                f"{k} {'-' if c['statistic'] is None else format(c['statistic'], '.2f')}"
                for k, c in r["checks"].items()) + f"  ({time.perf_counter() - t0:.0f} s)",
                flush=True)
        per_seed[case] = results
        table[case] = rates(results)
        print(f"{case}: " + "  ".join(
            f"{k} {v['rate']:.2f} ± {v['sd']:.2f}"
            + (f" (≤ {v['upper95']:.2f} at 95 %)" if v["upper95"] is not None else "")
            for k, v in table[case].items()), flush=True)
    if args.json is not None:
        args.json.write_text(json.dumps({"options": vars(args) | {"json": str(args.json)},
                                         "summary": table, "results": per_seed}, indent=1))


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    main()
