"""What the persistent compilation cache saves, and what a fit compiles.

Simulates the Post-Probe slews (``slews_post_probe``, 3 001 samples) and the 2004 day-028
biasing event (``biasing_day028``), then runs each ``cassini-bayes fit`` (default settings:
4 chains × 1000 warm-up + 1000 draws; the thrust fit robust) in fresh processes:

* ``fit inertia``: cache off twice (first and second call), then a fresh cache folder twice
  (cold: compiles and writes; warm: loads);
* ``fit thrust``: cache off, then cold and warm.

Each run records, through ``jax.monitoring`` duration events, every XLA program it compiled (or
loaded from the cache) with the seconds it took, and the seconds spent tracing and lowering to
MLIR (which the cache does not save), plus the cache's hits and misses (the fit's config.toml).
Prints per run the wall time (of it, the start-up before the command runs: imports), the XLA
compile (or cache-load) seconds, tracing, lowering and the rest (sampling, files, the report),
then the slowest programs of the cache-off runs; ``--json`` writes everything. Every row carries
the 1-minute load average at its start (the machine is shared: compare rows of one run, and
ratios). ``--where`` also lists, per run, the package lines that caused the programs to be built
(the stack at each lowering), to find eager array operations worth putting under ``jit``.

``--reproduce`` instead times ``cassini-bayes reproduce`` (the full settings; ``--quick`` for the
small ones) twice in fresh processes on one fresh cache folder: cold (compiles and writes) and
warm (loads). Not a test: the numbers are in docs/performance.md.

    python benchmarks/compile_cache.py [--only inertia|thrust] [--top 12] [--where]
                                       [--reproduce [--quick]] [--json cache.json]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
import tomllib
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COMPILE = "/jax/core/compile/backend_compile_duration"
TRACE = "/jax/core/compile/jaxpr_trace_duration"
LOWER = "/jax/core/compile/jaxpr_to_mlir_module_duration"

# run in the child: ``cassini-bayes ARGS`` in-process, with JAX's duration events recorded and,
# with WHERE set, the package lines on the stack at each XLA lowering
_CHILD = """
import collections, json, os, sys, time, traceback
from jax import monitoring
events = []
monitoring.register_event_duration_secs_listener(
    lambda event, secs, **kw: events.append((event, kw.get("fun_name", ""), secs)))
where = collections.Counter()
if os.environ.get("WHERE"):
    from jax._src.interpreters import pxla
    lower = pxla.lower_sharding_computation
    def traced_lower(*args, **kwargs):
        own = [f for f in traceback.extract_stack() if "cassini_bayes" in f.filename]
        where[" <- ".join(f"{f.filename.split('cassini_bayes/')[-1]}:{f.lineno}"
                          for f in own[-2:][::-1])] += 1
        return lower(*args, **kwargs)
    pxla.lower_sharding_computation = traced_lower
from cassini_bayes.cli import main
t0 = time.perf_counter()
code = main(sys.argv[2:])
json.dump({"code": code, "cli_s": time.perf_counter() - t0, "events": events,
           "where": where.most_common()}, open(sys.argv[1], "w"))
"""


def _run(args: list[str], cache: str, record: Path, where: bool = False) -> dict:
    """One ``cassini-bayes ARGS`` in a fresh process with ``CASSINI_BAYES_JAX_CACHE=cache``."""
    env = {**os.environ, "CASSINI_BAYES_JAX_CACHE": cache, "WHERE": "1" if where else ""}
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-c", _CHILD, str(record), *args], env=env,
                       capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0 or not record.exists():
        raise SystemExit(f"cassini-bayes {' '.join(args)} failed:\n{r.stderr}")
    rec = json.loads(record.read_text())
    if rec["code"] not in (0, 3):
        raise SystemExit(f"cassini-bayes {' '.join(args)} exited {rec['code']}:\n{r.stderr}")
    return {"wall_s": wall, "load_1min": load, **rec}


def _summary(name: str, rec: dict, config: Path | None) -> dict:
    by_event = defaultdict(float)
    programs = defaultdict(lambda: [0, 0.0])
    for event, fun, secs in rec["events"]:
        by_event[event] += secs
        if event == COMPILE:
            programs[fun][0] += 1
            programs[fun][1] += secs
    cache = tomllib.loads(config.read_text()).get("jax_cache", {}) if config else {}
    return {"run": name, "wall_s": rec["wall_s"], "cli_s": rec["cli_s"],
            "load_1min": rec["load_1min"], "where": rec.get("where", []),
            "programs": sum(n for n, _ in programs.values()),
            "compile_s": by_event[COMPILE], "trace_s": by_event[TRACE],
            "lower_s": by_event[LOWER], "hits": cache.get("hits"),
            "misses": cache.get("misses"),
            "per_program": sorted(([f, n, s] for f, (n, s) in programs.items()),
                                  key=lambda x: -x[2])}


def _simulate(scenario: str, out: Path) -> Path:
    r = subprocess.run([sys.executable, "-m", "cassini_bayes.cli", "simulate",
                        str(ROOT / "experiments" / "scenarios" / f"{scenario}.toml"), "--out",
                        str(out)], capture_output=True, text=True,
                       env={**os.environ, "CASSINI_BAYES_JAX_CACHE": "off"})
    if r.returncode != 0:
        raise SystemExit(f"simulate {scenario} failed:\n{r.stderr}")
    return out


def _fit_args(kind: str, data: Path, out: Path) -> list[str]:
    model = str(ROOT / "models" / "cassini_post_probe.toml")
    args = ["fit", kind, "--telemetry", str(data / "telemetry.csv"), "--spacecraft", model,
            "--out", str(out)]
    return args + (["--pulses", str(data / "pulses.csv")] if kind == "thrust" else [])


def _print(row: dict) -> None:
    hm = "" if row["hits"] is None else f"  hits {row['hits']:4d}  misses {row['misses']:4d}"
    other = row["cli_s"] - row["compile_s"] - row["trace_s"] - row["lower_s"]
    print(f"{row['run']:<20} wall {row['wall_s']:5.1f} s (start-up "
          f"{row['wall_s'] - row['cli_s']:4.1f} s)  programs {row['programs']:4d}  compile/load "
          f"{row['compile_s']:5.1f} s  trace {row['trace_s']:4.1f} s  lower {row['lower_s']:4.1f} "
          f"s  rest {other:5.1f} s{hm}  (load {row['load_1min']:.1f})", flush=True)


def _reproduce(quick: bool) -> list[dict]:
    """``cassini-bayes reproduce`` cold then warm on one fresh cache folder, each a fresh
    process: wall seconds and the load average at the start."""
    rows = []
    with tempfile.TemporaryDirectory(prefix="compile_cache_reproduce_") as tmp:
        env = {**os.environ, "CASSINI_BAYES_JAX_CACHE": str(Path(tmp) / "jax")}
        for run in ("cold", "warm"):
            out = Path(tmp) / f"reproduce-{run}"
            cmd = [sys.executable, "-m", "cassini_bayes.cli", "reproduce", "--out", str(out)]
            load = os.getloadavg()[0]
            t0 = time.perf_counter()
            r = subprocess.run(cmd + (["--quick"] if quick else []), env=env,
                               capture_output=True, text=True)
            wall = time.perf_counter() - t0
            if r.returncode not in (0, 3):
                raise SystemExit(f"reproduce ({run}) exited {r.returncode}:\n{r.stderr}")
            rows.append({"run": f"reproduce {run}", "wall_s": wall, "load_1min": load,
                         "exit": r.returncode})
            print(f"reproduce{' --quick' if quick else ''} {run:<5} wall {wall:6.1f} s  "
                  f"(exit {r.returncode}, load {load:.1f})", flush=True)
    return rows


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", choices=["inertia", "thrust"], default=None)
    ap.add_argument("--top", type=int, default=12, help="slowest programs listed per fit")
    ap.add_argument("--where", action="store_true",
                    help="list the package lines that built the programs, per run")
    ap.add_argument("--reproduce", action="store_true",
                    help="time `cassini-bayes reproduce`, cold and warm, instead of the fits")
    ap.add_argument("--quick", action="store_true", help="with --reproduce: its --quick")
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    if args.reproduce:
        result = {"cpu_count": os.cpu_count(), "runs": _reproduce(args.quick)}
        if args.json:
            args.json.write_text(json.dumps(result, indent=1) + "\n")
        return result
    plans = {"inertia": ("slews_post_probe", ["off 1st", "off 2nd", "cold", "warm"]),
             "thrust": ("biasing_day028", ["off", "cold", "warm"])}
    rows: list[dict] = []
    with tempfile.TemporaryDirectory(prefix="compile_cache_") as tmp:
        tmp = Path(tmp)
        cache = str(tmp / "jax")
        for kind, (scenario, runs) in plans.items():
            if args.only not in (None, kind):
                continue
            data = _simulate(scenario, tmp / scenario)
            for i, run in enumerate(runs):
                out = tmp / f"{kind}-{i}"
                rec = _run(_fit_args(kind, data, out), "off" if run.startswith("off") else cache,
                           tmp / f"{kind}-{i}.json", where=args.where)
                row = _summary(f"fit {kind} {run}", rec, out / "config.toml")
                rows.append(row)
                _print(row)
    for row in rows if args.where else []:
        print(f"\n{row['run']}: programs built, by package line (count, innermost first):")
        for line, n in row["where"][:args.top]:
            print(f"  {n:4d}  {line}")
    for row in rows:
        if not row["run"].endswith(("off 1st", "off")):
            continue
        print(f"\n{row['run']}: {row['programs']} programs, {row['compile_s']:.1f} s of XLA "
              f"compilation; the {args.top} slowest (name, count, seconds):")
        for fun, n, secs in row["per_program"][:args.top]:
            print(f"  {secs:7.2f} s  {n:3d} x  {fun}")
    result = {"cpu_count": os.cpu_count(), "load_avg": os.getloadavg(), "runs": rows}
    if args.json:
        args.json.write_text(json.dumps(result, indent=1) + "\n")
    return result


if __name__ == "__main__":
    main()
