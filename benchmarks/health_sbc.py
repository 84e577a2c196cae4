"""SBC of the thruster-health change-point model and of the Bayesian leak monitor.

    python benchmarks/health_sbc.py [--reps 400] [--leak-reps 1000] [--seed 1] [--out docs/sbc]

Writes ``OUT/health/`` and ``OUT/leak/``: ``summary.json`` (ranks' uniformity tests, coverage,
and for the leak monitor the calibration table of ``P(leak)``), ``rank_histograms.png``,
``ecdf_difference.png``. The statistics are :mod:`cassini_bayes.analysis.sbc`'s, the replicates
:mod:`cassini_bayes.analysis.health_sbc`'s. The change-point design is the control campaign's
(seed 0) event dates, standard errors and missing channels. Never a timed test.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import matplotlib
import numpy as np

matplotlib.use("Agg")

from cassini_bayes.analysis.health_sbc import (calibration_table, changepoint_sbc,  # noqa: E402
                                               leak_sbc)
from cassini_bayes.analysis.sbc import plot_ecdf_difference, plot_rank_histograms  # noqa: E402
from cassini_bayes.api._health import campaign_summaries  # noqa: E402


def _record(res, extra: dict) -> dict:
    return {"replicates": res.n_replicates, "draws": res.n_draws, "alpha_family":
            res.alpha_family, "alpha_per_parameter": res.alpha,
            "passed": res.passed("both"),
            "parameters": {n: {"chi2_p": p.chi2.p_value, "ecdf_p": p.ecdf.p_value,
                               "coverage": dict(zip(map(str, p.coverage.levels),
                                                    p.coverage.observed.tolist()))}
                           for n, p in res.parameters.items()}, **extra}


def _write(out: Path, res, extra: dict, options: dict, argv) -> dict:
    from _provenance import start

    out.mkdir(parents=True, exist_ok=True)
    start(out, options, argv, replace=True)
    plot_rank_histograms(res).savefig(out / "rank_histograms.png", dpi=100)
    plot_ecdf_difference(res).savefig(out / "ecdf_difference.png", dpi=100)
    rec = _record(res, extra)
    (out / "summary.json").write_text(json.dumps(rec, indent=1) + "\n")
    return rec


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=400)
    ap.add_argument("--leak-reps", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", default="docs/sbc")
    args = ap.parse_args(argv)
    t0 = time.time()
    dates, _, se = campaign_summaries("health_control", 0)
    cp = changepoint_sbc(args.seed, args.reps, dates, se)
    rec = _write(Path(args.out) / "health", cp, {"wall_s": time.time() - t0,
                                                 "design": "health_control seed 0"},
                 vars(args), argv)
    print(json.dumps({k: v for k, v in rec.items() if k != "parameters"}),
          {n: (round(p["chi2_p"], 3), round(p["ecdf_p"], 3))
           for n, p in rec["parameters"].items()})
    t0 = time.time()
    lk = leak_sbc(args.seed, args.leak_reps)
    table = calibration_table(lk.p_leak, lk.leak)
    every = calibration_table(lk.prob.ravel(),
                              (lk.truth[:, None] == np.arange(9)[None, :]).ravel())
    rec = _write(Path(args.out) / "leak", lk.result,
                 {"wall_s": time.time() - t0, "leak_replicates": int(lk.leak.sum()),
                  "p_leak_calibration": table, "p_hypothesis_calibration": every},
                 vars(args), argv)
    print(json.dumps({k: v for k, v in rec.items() if k != "parameters"}),
          {n: (round(p["chi2_p"], 3), round(p["ecdf_p"], 3))
           for n, p in rec["parameters"].items()})


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    main()
