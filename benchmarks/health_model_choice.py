"""Change point or random walk? The marginal likelihood of both on the health campaigns.

For each seed the degradation and control campaigns' event summaries (as
``benchmarks/health_campaign.py``) are scored under

- the change-point model (:func:`cassini_bayes.inference.health.health_posterior`, its
  ``log_evidence``), and
- a Gaussian random walk per channel (local-level Kalman filter): ``x_e = x_{e−1} +
  N(0, q² Δt)``, ``y_ek = x_e + N(0, s_ek² + σ_k²)``, ``x_0 ~ N(log F, 0.5²)``, with ``q``
  log-uniform on 1e-4 … 1e-2 per √day (a 7 % drift takes ~50 … 500 000 days) and ``σ_k`` on the
  change-point model's grid, both marginalised exactly over their grids.

The log Bayes factor (change point − random walk) is printed per campaign and seed; ``--json``
writes them as a record with its manifest (docs/health/model_choice.md).

    python benchmarks/health_model_choice.py [--seeds 10] [--json FILE.json]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy.special import logsumexp

from cassini_bayes.api._health import campaign_summaries
from cassini_bayes.files import json_text, write_text
from cassini_bayes.inference.health import HealthPrior, health_posterior
from cassini_bayes.inference.health.changepoint import SCATTER_GRID

Q_GRID = np.geomspace(1e-4, 1e-2, 9)


def random_walk_log_evidence(t, y, s, prior: HealthPrior) -> float:
    """Σ over channels of log p(y_k) under the local-level model, grids marginalised."""
    total = 0.0
    for k in range(y.shape[1]):
        ll = np.zeros((Q_GRID.size, SCATTER_GRID.size))
        for a, q in enumerate(Q_GRID):
            for b, sig in enumerate(SCATTER_GRID):
                m, v, last, acc = np.log(prior.nominal_thrust_n), prior.baseline_sd ** 2, t[0], 0.0
                for e in range(t.size):
                    v += q * q * (t[e] - last)
                    last = t[e]
                    if not np.isfinite(y[e, k]):
                        continue
                    r2 = s[e, k] ** 2 + sig ** 2
                    f = v + r2
                    acc += -0.5 * (np.log(2 * np.pi * f) + (y[e, k] - m) ** 2 / f)
                    gain = v / f
                    m, v = m + gain * (y[e, k] - m), (1 - gain) * v
                ll[a, b] = acc
        total += logsumexp(ll) - np.log(ll.size)
    return float(total)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--first-seed", type=int, default=300)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args(argv)
    if args.json:
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    prior = HealthPrior()
    print("| campaign | seed | log BF (change point − random walk) |\n|---|---|---|")
    out: dict[str, list[float]] = {"health_degradation": [], "health_control": []}
    rows: list[dict] = []
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        for name in out:
            t, y, s = campaign_summaries(name, seed)
            bf = (health_posterior(t, y, s, prior).log_evidence
                  - random_walk_log_evidence(t, y, s, prior))
            out[name].append(bf)
            rows.append({"campaign": name, "seed": seed, "log_bf": bf})
            print(f"| {name} | {seed} | {bf:.2f} |", flush=True)
    for name, v in out.items():
        print(f"{name}: median log BF {np.median(v):.2f}, min {np.min(v):.2f}, "
              f"max {np.max(v):.2f}")
    if args.json:
        write_text(args.json, json_text({"p_change": prior.p_change, "rows": rows}))


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    main()
