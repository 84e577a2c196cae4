"""Benchmark: the CPU cost of a fit's report.html.

Prints, for each run directory given:

- ``report DIR`` alone: CPU seconds (user + system, ``getrusage`` of the child) and wall seconds
  of ``cassini-bayes report DIR`` in a fresh process, the median of ``--repeat`` runs;
- in this process, after the imports (what a warm ``fit`` pays): CPU seconds
  (``time.process_time``) of reading the run, the tables and each figure, and of the whole
  ``build_report``.

CPU time rather than wall time: the machine this project runs on is shared (2 cores, load ~15),
so wall times are inflated by the load; the load average is printed with the numbers, and
before/after comparisons must come from the same conditions. Not a test: nothing is asserted.

    python benchmarks/bench_report.py RUN_DIR [RUN_DIR ...] [--repeat 3] [--json report.json]

``--json`` writes one record per run directory (its name and ``summary.json`` kind, the
``report`` command's CPU and wall medians, the warm stages) with a manifest; the table kind
``bench_report`` reads it.

Make a run with ``cassini-bayes simulate experiments/scenarios/slews_post_probe.toml --out SIM``
and ``cassini-bayes fit inertia --telemetry SIM/telemetry.csv --spacecraft cassini_post_probe
--out RUN`` (4 chains × 1000 draws, the default).
"""

from __future__ import annotations

import argparse
import functools
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def cli_cost(run_dir: Path, repeat: int) -> tuple[float, float]:
    """Median (CPU s, wall s) of ``cassini-bayes report`` on a copy of ``run_dir``."""
    exe = shutil.which("cassini-bayes") or str(Path(sys.executable).parent / "cassini-bayes")
    cpu, wall = [], []
    with tempfile.TemporaryDirectory() as tmp:
        copy = Path(tmp) / run_dir.name
        shutil.copytree(run_dir, copy)
        for _ in range(repeat):
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            t0 = time.perf_counter()
            subprocess.run([exe, "report", str(copy)], check=True, stdout=subprocess.DEVNULL)
            wall.append(time.perf_counter() - t0)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    return statistics.median(cpu), statistics.median(wall)


def in_process(run_dir: Path) -> dict[str, float]:
    """CPU seconds of each stage of ``build_report`` after the imports (a warm fit's share)."""
    import matplotlib

    matplotlib.use("Agg")
    from cassini_bayes.report import build, figures

    times: dict[str, float] = {}

    def timed(name, f):
        @functools.wraps(f)
        def wrapper(*a, **k):
            t = time.process_time()
            try:
                return f(*a, **k)
            finally:
                times[name] = times.get(name, 0.0) + time.process_time() - t
        return wrapper

    saved = {}
    for mod, names in ((build, ("load_run", "diagnostics", "parameter_rows", "derived_rows")),
                       (figures, [n for n in figures.__all__ if n.endswith(("_figure", "_png"))]
                        + ["png_bytes"])):
        for n in names:
            if not hasattr(mod, n):     # (an older report module, for a before/after)
                continue
            saved[(mod, n)] = getattr(mod, n)
            setattr(mod, n, timed(n, getattr(mod, n)))
    try:
        with tempfile.TemporaryDirectory() as tmp:
            copy = Path(tmp) / run_dir.name
            shutil.copytree(run_dir, copy)
            t = time.process_time()
            build.build_report(copy)
            times["build_report (total)"] = time.process_time() - t
    finally:
        for (mod, n), f in saved.items():
            setattr(mod, n, f)
    return times


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path, help="fit run directories")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", type=Path, help="write the records here (with a manifest)")
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    records = []
    for run in args.runs:
        load = os.getloadavg()[0]
        cpu, wall = cli_cost(run, args.repeat)
        print(f"{run}: `cassini-bayes report` {cpu:.2f} s CPU, {wall:.2f} s wall "
              f"(median of {args.repeat})")
        summ = json.loads((run / "summary.json").read_text())
        records.append({"run": run.name, "kind": summ.get("kind"), "report_cpu_s": cpu,
                        "report_wall_s": wall, "repeat": args.repeat, "load": load})
    for run, rec in zip(args.runs, records):
        in_process(run)                  # first call: imports and first-use costs
        times = in_process(run)
        rec["warm_cpu_s"] = times
        print(f"{run}: in a warm process, CPU s: "
              + ", ".join(f"{k} {v:.3f}" for k, v in times.items()))
    if args.json:
        from _provenance import write_json

        write_json(args.json, records)


if __name__ == "__main__":
    main()
