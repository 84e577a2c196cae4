"""Benchmark: what the budgets from posteriors add to ``cassini-bayes reproduce``.

In one warm process (after the imports, ArviZ's included), on the fits of a ``reproduce`` run
directory: the wall seconds of reading each posterior, of propagating every budget line
(:func:`~cassini_bayes.analysis.posterior_budgets.posterior_budget`, 4000 joint draws), of the
thrust's inertia sensitivity (a noise-free ``biasing_day028`` simulated and solved) and of
Brown's analysis 3 (:func:`~cassini_bayes.analysis.mass_property.mass_property_mc_posterior`,
10⁵ draws): the first call (with compilation) and the median of ``--repeat`` calls after it.
Not a test: nothing is asserted; the load average is recorded beside the numbers.

    python benchmarks/bench_budget.py RUN_DIR [--repeat 5] [--json budget.json]

``--json`` writes the record with a manifest; the table kind ``bench_budget`` reads it.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

FITS = {"inertia": ("inertia", "inertia_table1/fits/post_probe"),
        "thrust": ("thrust", "thrust_table2/fits/pooled"),
        "rwa4 (rwa)": ("rwa4", "rwa4_rwa_campaign/fits/run00"),
        "rwa4 (rcs)": ("rwa4", "rwa4_rcs_campaign/fits/run00")}
"""Per posterior: its kind and its run directory under the ``reproduce`` run."""


def timed(fn, repeat: int) -> dict[str, float]:
    """Wall seconds of the first call of ``fn`` and the median of ``repeat`` calls after it."""
    t0 = time.perf_counter()
    fn()
    first = time.perf_counter() - t0
    after = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        after.append(time.perf_counter() - t0)
    return {"first_s": first, "after_s": statistics.median(after)}


def measure(run: Path, repeat: int) -> dict:
    import arviz  # noqa: F401  (the import is not the budget's cost)
    import jax
    import numpy as np

    from cassini_bayes.analysis.budget_lines import inertia_of
    from cassini_bayes.analysis.mass_property import mass_property_mc_posterior
    from cassini_bayes.analysis.posterior_budgets import load_posterior, posterior_budget
    from cassini_bayes.experiments.error_budgets import thrust_inertia_sensitivity
    from cassini_bayes.names import INERTIA_NAMES

    post, steps = {}, {}
    for name, (kind, sub) in FITS.items():
        steps[f"read the {name} posterior"] = timed(
            lambda n=name, k=kind, s=sub: post.__setitem__(n, load_posterior(run / s, k)), repeat)
    key = jax.random.PRNGKey(0)
    steps["thrust sensitivity (biasing_day028 simulated and solved)"] = timed(
        lambda: thrust_inertia_sensitivity(key, "biasing_day028"), repeat)
    steps["every budget line, 4000 joint draws"] = timed(
        lambda: posterior_budget(key, inertia=post["inertia"], thrust=post["thrust"],
                                 rwa4=post["rwa4 (rwa)"], extra_axes=(post["rwa4 (rcs)"],),
                                 n_draws=4000), repeat)
    entries = np.stack([post["inertia"].draws[k] for k in INERTIA_NAMES], -1)
    i_draws, i_mean = inertia_of(entries), inertia_of(entries.mean(0))
    steps["Brown's analysis 3, 10^5 draws"] = timed(
        lambda: np.asarray(mass_property_mc_posterior(key, i_draws, i_mean, 100_000).error_rad),
        repeat)
    return {"run": str(run), "repeat": repeat, "steps": steps,
            "load_average": os.getloadavg()[0]}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", type=Path, help="a cassini-bayes reproduce run directory")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--json", type=Path, help="write the record here (with a manifest)")
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    record = measure(args.run, args.repeat)
    for step, t in record["steps"].items():
        print(f"{step:60s} first {t['first_s']:7.3f} s, after {t['after_s']:7.3f} s")
    if args.json:
        from _provenance import write_json

        write_json(args.json, record)


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache: this script uses modules directly
    main()
