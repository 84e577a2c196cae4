"""Is an SBC failure the model's or the sampler's? The ranks of a finished ``cassini-bayes sbc``
run split by the campaign's own convergence flag, each group tested as the run tests all.

Reads ``RUN/replicates.npz`` (written by every SBC run) and writes, for the converged replicates
and for the others, a JSON in the ``parameters`` schema of the run's ``summary.json`` (so
``benchmarks/docs_tables.py``'s ``sbc`` kind draws either), each with the replicates' count,
divergences and the truths' medians of the ranked parameters. A selection on convergence is
not itself a valid SBC (which truths fail to converge is part of the model's behaviour): it
says where the failure sits, and the run's own verdict stands.

    python benchmarks/sbc_by_convergence.py runs/sbc_thrust_robust_espa \
        --out docs/sbc/thrust_robust_espa/by_convergence
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _group(names, rank, truth, n_draws: int, n_div, alpha: float) -> dict:
    import numpy as np

    from cassini_bayes.analysis.sbc import sbc_result

    res = sbc_result(names, rank, n_draws, alpha_family=alpha)
    params = {n: {"chi2": {"p_value": float(p.chi2.p_value)},
                  "ecdf": {"p_value": float(p.ecdf.p_value)},
                  "passed": bool(p.chi2.p_value >= res.alpha and p.ecdf.p_value >= res.alpha),
                  "coverage": {f"{round(100 * c):d}": {"nominal": c, "observed": float(o)}
                               for c, o in zip(p.coverage.levels, p.coverage.observed)}}
              for n, p in res.parameters.items()}
    return {"replicates": int(rank.shape[0]), "divergent_transitions": int(np.sum(n_div)),
            "alpha_family": alpha, "alpha_per_parameter": float(res.alpha),
            "passed": bool(res.passed("both")), "parameters": params,
            "truth_median": {n: float(np.median(truth[:, j])) for j, n in enumerate(names)}}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", type=Path, help="a finished `cassini-bayes sbc` run directory")
    ap.add_argument("--out", type=Path, required=True, help="folder for the two JSON records")
    ap.add_argument("--alpha", type=float, default=0.01, help="family-wise level (the run's)")
    args = ap.parse_args(argv)

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import numpy as np

    from _provenance import start

    z = np.load(args.run / "replicates.npz")
    names = [str(n) for n in z["names"]]
    ok = ~z["failed"].astype(bool)
    conv = z["converged"].astype(bool)
    n_draws = int(json.loads((args.run / "summary.json").read_text())["draws_per_replicate"])
    args.out.mkdir(parents=True, exist_ok=True)
    for label, sel in (("converged", ok & conv), ("not_converged", ok & ~conv)):
        path = args.out / f"{label}.json"
        start(path, {"run": str(args.run), "group": label, "alpha": args.alpha}, replace=True)
        rec = _group(names, z["rank"][sel], z["truth"][sel], n_draws, z["n_divergent"][sel],
                     args.alpha)
        path.write_text(json.dumps(rec, indent=1) + "\n")
        print(f"{label}: {rec['replicates']} replicates, passed {rec['passed']}")


if __name__ == "__main__":
    main()
