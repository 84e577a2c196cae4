"""How the stated time-tag sd moves the per-thruster thrusts of a single-width biasing event.

``biasing_espa_bus`` (every pulse 125 ms) flown with the time tags' white error ``--flown`` (s;
the shipped scenario flies none) and fitted per thruster (``fit_thrust(..., mode="thruster")``)
with the model file's ``[telemetry_knowledge] time_tag_sd_s`` replaced by ``--stated`` (s; the
package's default is 10 ms; the prior median of the sd the fit learns), each pair once, one
noise seed, a small sampler. Per pair: the learned tag sd, every thrust's error, its sd and
coverage, the time constants' posterior. The table kind
``thrust_tag_statement`` reads the record. Not a test: nothing is asserted.

    python benchmarks/thrust_time_tag_statement.py --pairs 0.0001:0 0.01:0 0.01:0.01 \\
        [--seed 1] [--json out.json]
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
import time
import tomllib
from pathlib import Path

SCENARIO = "biasing_espa_bus"
TAU = ("tau_delay", "tau_rise", "tau_fall")


def fit_pair(stated_s: float, flown_s: float, seed: int, sampler: dict) -> dict:
    """Fly the event with tags of sd ``flown_s`` and fit it stating ``stated_s``."""
    import cassini_bayes as cb
    from cassini_bayes.files import toml_text
    from cassini_bayes.simulate.scenario import scenario_path

    d = tomllib.loads(scenario_path(SCENARIO).read_text())
    d["noise"]["time_tag_jitter_s"] = flown_s
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"{SCENARIO}.toml"
        path.write_text(toml_text(d))
        sim = cb.simulate_scenario(path, seed=seed)
    kn = dataclasses.replace(sim.prior.knowledge, time_tag_sd_s=stated_s)
    prior = dataclasses.replace(sim.prior, knowledge=kn)
    truth = sim.truth()
    t0 = time.perf_counter()
    fit = cb.fit_thrust(sim.telemetry, sim.pulses, prior, mode="thruster", seed=seed, **sampler)
    p = fit.summary()["parameters"]
    thrusts = {n: {"error_pct": 100 * (p[f"F[{n}]"]["mean"] / f - 1),
                   "sd_pct": 100 * p[f"F[{n}]"]["sd"] / f,
                   "covered_90": bool(p[f"F[{n}]"]["q05"] <= f <= p[f"F[{n}]"]["q95"])}
               for n, f in truth["thrust_n"].items()}
    tau = {n: {"truth_s": float(truth[f"{n}_s"]), "mean_s": p[n]["mean"], "sd_s": p[n]["sd"]}
           for n in TAU}
    learned = fit.summary()["nuisance"].get("time_tag_sd")
    return {"stated_s": stated_s, "flown_s": flown_s, "seed": seed,
            "time_tag_sd": None if learned is None else {
                k: learned[k] for k in ("mean", "sd", "q05", "q95")},
            "n_pulses": int(sim.pulses.width.size), "thrusts": thrusts, "tau": tau,
            "adequacy_ok": fit.summary()["adequacy"]["ok"], "seconds": time.perf_counter() - t0}


def table(rows: list[dict]) -> str:
    """One line per (stated, flown) pair."""
    lines = ["| stated tag sd | tags flown | tag sd learned (90 %) | thrust errors | thrust sd | "
             "thrusts covered (90 %) | `τd`, `τr`, `τf` (ms; truth 4, 15, 35) | adequacy |",
             "|" + "---|" * 8]
    for r in rows:
        e = [t["error_pct"] for t in r["thrusts"].values()]
        sd = sorted(t["sd_pct"] for t in r["thrusts"].values())[len(e) // 2]
        cov = sum(t["covered_90"] for t in r["thrusts"].values())
        taus = ", ".join(f"{1e3 * r['tau'][n]['mean_s']:.1f} ± {1e3 * r['tau'][n]['sd_s']:.1f}"
                         for n in TAU)
        tag = r.get("time_tag_sd")
        learned = ("held at the stated" if tag is None else
                   f"{1e3 * tag['mean']:.2g} ms ({1e3 * tag['q05']:.2g}–{1e3 * tag['q95']:.2g})")
        lines.append(f"| {1e3 * r['stated_s']:g} ms | {1e3 * r['flown_s']:g} ms | {learned} | "
                     f"{min(e):+.2f} … {max(e):+.2f} % | {sd:.2f} % | {cov}/{len(e)} | {taus} | "
                     f"{'ok' if r['adequacy_ok'] else 'FAILED'} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", nargs="+", required=True, metavar="STATED:FLOWN",
                    help="stated and flown time-tag sd, s")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--chains", type=int, default=2)
    ap.add_argument("--warmup", type=int, default=300)
    ap.add_argument("--draws", type=int, default=300)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    sampler = {k: getattr(args, k) for k in ("chains", "warmup", "draws")}
    rows = []
    for pair in args.pairs:
        stated, flown = (float(x) for x in pair.split(":"))
        rows.append(fit_pair(stated, flown, args.seed, sampler))
        print(table(rows[-1:]).splitlines()[-1], flush=True)
        if args.json:
            from _provenance import write_json

            write_json(args.json, rows)
    print(table(rows))


if __name__ == "__main__":
    main()
