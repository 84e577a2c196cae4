"""The API's first example (docs/api.md) against the command that does the same fit.

Simulates the Post-Probe slews (``slews_post_probe``) into a temporary folder, then times, each
in a fresh process and alternating (API, CLI, API, CLI, …) so that both see the same load:

* ``python -c`` of the docs' example: ``cb.fit_inertia(cb.read_telemetry(path),
  cb.load_spacecraft("cassini_post_probe"), seed=0, chains=C, warmup=W, draws=D)`` then
  ``fit.save(out)``, nothing else (no ``request_host_devices``);
* ``cassini-bayes fit inertia --telemetry path --spacecraft cassini_post_probe --seed 0
  --chains C --warmup W --draws D --out out``.

One unmeasured run of each first fills the persistent compilation cache (both then load the
same programs). Prints per run the wall time, the CPU time (user + system, of the child) and
the 1-minute load average at its start, then the medians, the API/CLI ratio of the wall
medians and the chain method each used (config.toml); ``--json`` writes everything. Not a test:
the numbers are in docs/performance.md.

    python benchmarks/api_vs_cli.py [--chains 4] [--warmup 300] [--draws 500] [--pairs 3]
                                    [--json api_vs_cli.json]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path


def _timed(cmd: list[str]) -> dict:
    load = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if r.returncode != 0:
        raise SystemExit(f"{cmd[:3]} failed ({r.returncode}): {r.stderr[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall_s": wall, "cpu_s": cpu, "load_1min": load}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--warmup", type=int, default=300)
    ap.add_argument("--draws", type=int, default=500)
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    if args.json:
        from _provenance import start

        start(args.json, vars(args), None, replace=True)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        subprocess.run([sys.executable, "-m", "cassini_bayes.cli", "simulate", "slews_post_probe",
                        "--out", str(tmp / "sim")], check=True, capture_output=True)
        path = tmp / "sim" / "telemetry.csv"
        api = [sys.executable, "-c",
               "import sys, cassini_bayes as cb\n"
               "fit = cb.fit_inertia(cb.read_telemetry(sys.argv[1]), "
               "cb.load_spacecraft('cassini_post_probe'), seed=0, chains=int(sys.argv[2]), "
               "warmup=int(sys.argv[3]), draws=int(sys.argv[4]))\n"
               "fit.save(sys.argv[5], force=True)",
               str(path), str(args.chains), str(args.warmup), str(args.draws), str(tmp / "api")]
        cli = [sys.executable, "-m", "cassini_bayes.cli", "fit", "inertia", "--telemetry",
               str(path), "--spacecraft", "cassini_post_probe", "--seed", "0", "--chains",
               str(args.chains), "--warmup", str(args.warmup), "--draws", str(args.draws),
               "--out", str(tmp / "cli"), "--force"]
        _timed(api), _timed(cli)   # fill the compilation cache
        runs = {"api": [], "cli": []}
        for i in range(args.pairs):
            for name, cmd in (("api", api), ("cli", cli)):
                row = _timed(cmd)
                runs[name].append(row)
                print(f"{name} {i}: wall {row['wall_s']:6.1f} s  cpu {row['cpu_s']:6.1f} s  "
                      f"load {row['load_1min']:4.1f}", flush=True)
        methods = {name: tomllib.loads((tmp / name / "config.toml").read_text())["sampler"]
                   ["chain_method_used"] for name in runs}
    med = {name: {k: statistics.median(r[k] for r in rows) for k in ("wall_s", "cpu_s")}
           for name, rows in runs.items()}
    ratio = med["api"]["wall_s"] / med["cli"]["wall_s"]
    print(f"median wall: API {med['api']['wall_s']:.1f} s, CLI {med['cli']['wall_s']:.1f} s "
          f"(API/CLI {ratio:.2f}); median cpu: API {med['api']['cpu_s']:.1f} s, "
          f"CLI {med['cli']['cpu_s']:.1f} s; chains {methods}; {os.cpu_count()} CPUs")
    if args.json:
        args.json.write_text(json.dumps({"settings": vars(args) | {"json": str(args.json)},
                                         "cpu_count": os.cpu_count(), "runs": runs,
                                         "chain_method_used": methods,
                                         "median": med, "api_over_cli": ratio}, indent=1))


if __name__ == "__main__":
    main()
