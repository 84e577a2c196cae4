"""Feldman & Lee's weak-Z slews, predicted before any fit: the Post-PRM slews' predicted posterior
sd of each inertia entry over the Post-Probe slews' (docs/planning.md, "Weak Z").

Two :func:`cassini_bayes.plan.evaluate.evaluate_inertia` predictions (noise-free simulations, the
robust model's Laplace approximation), about a minute. Writes, with ``--json``, both scenarios'
predicted sd (the data part, the wheels' common scale held fixed, and as a fit reports it) and
their ratios; the table kind ``plan_weak_z`` (``_tables_planning.py``) reads it.

    python benchmarks/plan_weak_z.py [--weak slews_post_prm] [--strong slews_post_probe]
        [--json weak_z.json]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

ENTRIES = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")


def predict(name: str) -> dict:
    """One scenario's predicted sd (kg m²), the data part and as a fit reports it."""
    import cassini_bayes
    from cassini_bayes.plan.evaluate import evaluate_inertia
    from cassini_bayes.simulate.scenario import load_scenario, scenario_path

    cassini_bayes.setup_jax()
    t0 = time.perf_counter()
    p = evaluate_inertia(load_scenario(scenario_path(name)))
    return {"scenario": name, "sd_data": dict(zip(ENTRIES, p.sd_data.tolist())),
            "sd": dict(zip(ENTRIES, p.sd.tolist())), "seconds": time.perf_counter() - t0}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--weak", default="slews_post_prm")
    ap.add_argument("--strong", default="slews_post_probe")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    weak, strong = predict(args.weak), predict(args.strong)
    ratio = {part: {e: weak[part][e] / strong[part][e] for e in ENTRIES}
             for part in ("sd_data", "sd")}
    for part, label in (("sd_data", "data part"), ("sd", "as reported")):
        print(f"{label:12s} " + "  ".join(f"{e} {ratio[part][e]:.3g}" for e in ENTRIES))
    if args.json:
        from _provenance import write_json

        write_json(args.json, {"weak": weak, "strong": strong, "ratio": ratio})


if __name__ == "__main__":
    main()
