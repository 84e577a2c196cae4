"""The leak monitor's onset quadrature: its error against a finer rule, and its cost.

Stretches: those of ``verdict_false_alarms.py leak`` (same seeds, same draws: per seed one 4 h
``leak_cruise`` stretch without a leak and one with a 10 % leak), monitored with
``cassini_post_probe`` and its residual every 60 s.

* ``accuracy`` — ``leak_posterior`` with its own rule against :data:`FINE` (no easy cells, 12
  nodes per part instead of 5, parts of at most 0.1 in ``w`` and 0.25 in ``y`` instead of 0.5
  and 1, pruning at 80 nats instead of 40), a check every 60 s. Per stretch the largest
  difference of any hypothesis' probability at any check, of its log (where either probability
  exceeds 1e-12), the fraction's mean and 90 % interval in the fine posterior's sd, its sd
  relative, the onset's mean in the fine onset sd.
* ``cost`` — CPU seconds (``time.process_time``) of ``leak_posterior`` per stretch with a check
  every 60 s and every 600 s; ``--grid-from COMMIT`` adds the leak module of that commit
  (``git show COMMIT:cassini_bayes/inference/leak.py``; 3924e41 has the 20 s onset grid).

Prints Markdown tables for docs/leak.md. Not a test.

    python benchmarks/leak_quadrature.py accuracy --seeds 6
    python benchmarks/leak_quadrature.py cost --seeds 3 --grid-from 3924e41 [--json cost.json]

``--json`` writes the cost record with a manifest; the table kind ``leak_quadrature_cost``
reads it.
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

MODEL = "cassini_post_probe"
HOURS = 4.0


def _fine():
    """The reference rule: 4-5x finer than the monitor's in every setting."""
    from cassini_bayes.inference.leak._onset import Rule

    return Rule(easy_nats=-1.0, part_w=0.1, part_y=0.25, part_nodes=12, prune_nats=80.0)


def _stretches(seeds):
    """Yield ``(seed, leak, LeakInputs)`` of :func:`verdict_false_alarms.leak_stretches`."""
    from verdict_false_alarms import leak_stretches

    from cassini_bayes.inference.leak import leak_inputs
    from cassini_bayes.spacecraft import load_spacecraft

    sc = load_spacecraft(MODEL)
    for seed in seeds:
        for leak, _, _, tel, pulses in leak_stretches(seed, HOURS, 2):
            yield seed, leak, leak_inputs(tel, pulses, sc)


def _grid_module(commit: str):
    """The leak module of ``commit``, imported from ``git show`` as ``_leak_<commit>``."""
    src = subprocess.run(["git", "-C", str(ROOT), "show",
                          f"{commit}:cassini_bayes/inference/leak.py"],
                         check=True, capture_output=True, text=True).stdout
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / f"_leak_{commit}.py"
        path.write_text(src)
        spec = importlib.util.spec_from_file_location(path.stem, path)
        mod = importlib.util.module_from_spec(spec)
        sys.modules[path.stem] = mod          # dataclasses look their module up while executing
        spec.loader.exec_module(mod)
    return mod


def accuracy(seeds) -> None:
    """Print, per stretch, the monitor's differences from the :func:`_fine` rule (module
    docstring) and the largest of each over all stretches."""
    from cassini_bayes.inference.leak import leak_posterior

    fine = _fine()
    rows = []
    print("| seed | stretch | max Δ P | max Δ log P | Δ fraction mean (sd) | Δ fraction sd "
          "(rel.) | Δ 90 % interval (sd) | Δ onset mean (onset sd) | CPU s own / fine |")
    print("|---|---|---|---|---|---|---|---|---|")
    for seed, leak, inp in _stretches(seeds):
        t0 = time.process_time()
        a = leak_posterior(inp, check_step_s=60.0)
        t1 = time.process_time()
        b = leak_posterior(inp, check_step_s=60.0, _rule=fine)
        t2 = time.process_time()
        big = (a.prob > 1e-12) | (b.prob > 1e-12)
        log_a, log_b = (np.log(np.clip(p.prob, 1e-300, None)) for p in (a, b))
        r = (float(np.abs(a.prob - b.prob).max()),
             float(np.abs(log_a - log_b)[big].max()),
             abs(a.fraction_mean - b.fraction_mean) / b.fraction_sd,
             abs(a.fraction_sd / b.fraction_sd - 1.0),
             float(np.abs(np.subtract(a.fraction_interval, b.fraction_interval)).max()
                   / b.fraction_sd),
             abs(a.onset_s - b.onset_s) / max(b.onset_sd_s, 1e-12))
        rows.append(r)
        print(f"| {seed} | {'10 % leak' if leak else 'no leak'} | "
              + " | ".join(f"{x:.1e}" for x in r) + f" | {t1 - t0:.1f} / {t2 - t1:.1f} |",
              flush=True)
    print(f"| all {len(rows)} | largest | "
          + " | ".join(f"**{x:.1e}**" for x in np.max(rows, axis=0)) + " | |")


def cost(seeds, grid_from: str | None) -> dict:
    """CPU seconds per stretch of each monitor and check step, with a leak and without: the
    record :func:`cost_table` prints."""
    from cassini_bayes.inference import leak

    monitors = {"continuous onset (this code)": lambda inp, cs: leak.leak_posterior(
        inp, check_step_s=cs)}
    if grid_from:
        grid = _grid_module(grid_from)
        monitors = {f"20 s onset grid ({grid_from})": lambda inp, cs: grid.leak_posterior(
            inp, check_step_s=cs), **monitors}
    fine = _fine()
    monitors["the finer rule of `accuracy`"] = lambda inp, cs: leak.leak_posterior(
        inp, check_step_s=cs, _rule=fine)
    steps = (60.0, 600.0)
    cpu = {}                                 # (monitor, check step, leak) -> [s]
    for _, leak_, inp in _stretches(seeds):
        for name, run in monitors.items():
            for cs in steps:
                t0 = time.process_time()
                run(inp, cs)
                cpu.setdefault((name, cs, leak_), []).append(time.process_time() - t0)
    return {"hours": HOURS, "seeds": list(seeds),
            "rows": [{"monitor": m, "check_step_s": cs, "leak": lk, "cpu_s": v}
                     for (m, cs, lk), v in cpu.items()]}


def cost_table(record: dict) -> str:
    """Median and range of the CPU seconds per stretch, a row per monitor and check step (the
    table kind ``leak_quadrature_cost`` of docs_tables.py prints it from the record)."""
    n = len(record["seeds"])
    out = [f"| monitor | checks every | {n} stretches with a 10 % leak: median (range) | "
           f"{n} without: median (range) |", "|---|---|---|---|"]
    by = {(r["monitor"], r["check_step_s"], r["leak"]): r["cpu_s"] for r in record["rows"]}
    for name, cs in dict.fromkeys((r["monitor"], r["check_step_s"]) for r in record["rows"]):
        cells = [f"{np.median(v):.2f} ({min(v):.2f}-{max(v):.2f})"
                 for v in (by[(name, cs, True)], by[(name, cs, False)])]
        out.append(f"| {name} | {cs:g} s | " + " | ".join(cells) + " |")
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("part", choices=("accuracy", "cost"))
    ap.add_argument("--seeds", type=int, default=3, help="seeds 0 … N-1, two stretches each")
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--grid-from", default=None,
                    help="cost: also time the leak module of this commit")
    ap.add_argument("--json", type=Path, help="cost: write the record here (with a manifest)")
    args = ap.parse_args()
    if args.json:
        from _provenance import start

        start(args.json, vars(args), None, replace=True)
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    t0 = time.time()
    if args.part == "accuracy":
        accuracy(seeds)
    else:
        record = cost(seeds, args.grid_from)
        print(cost_table(record))
        print(f"\n(CPU s of leak_posterior per {HOURS:g} h stretch)")
        if args.json:
            from _provenance import write_json

            write_json(args.json, record)
    print(f"\n{time.time() - t0:.0f} s wall")


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    main()
