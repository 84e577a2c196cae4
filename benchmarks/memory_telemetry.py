"""Peak memory of reading a telemetry file, and of reading plus ``prepare_inertia``, by size.

A simulated ``slews_pre_soi`` record (2 Hz) is tiled with a continuing time base to each size
and written as CSV; each measurement runs in a fresh process and reports its peak resident
memory (``VmHWM`` of ``/proc/self/status``: the whole process, Python, NumPy and JAX included;
not ``ru_maxrss``, which a child inherits from its parent's size at the fork) and its wall time.
Stages: ``read`` (``read_telemetry``, unit heuristics on), ``prepare`` and ``prepare_robust``
(the read, then ``prepare_inertia`` with ``robust`` off and on). Not a test.

    python benchmarks/memory_telemetry.py [--rows 10000 100000 1000000]
        [--prepare-rows 10000 100000] [--json docs/performance/memory_telemetry.json]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

_CHILD = r"""
import sys, time, json
t0 = time.perf_counter()
import cassini_bayes
cassini_bayes.setup_jax()
from cassini_bayes import load_spacecraft
from cassini_bayes.telemetry import read_telemetry
stage, path = sys.argv[1], sys.argv[2]
tel = read_telemetry(path)
if stage != "read":
    from cassini_bayes.inference.inertia.data import prepare_inertia
    prepare_inertia([tel], load_spacecraft("cassini_pre_soi"), robust=stage == "prepare_robust")
hwm = next(line for line in open("/proc/self/status") if line.startswith("VmHWM"))
print(json.dumps({"peak_mb": int(hwm.split()[1]) / 1024,
                  "seconds": time.perf_counter() - t0}))
"""

STAGES = ("read", "prepare", "prepare_robust")


def tiled(rows: int, folder: Path) -> Path:
    """A CSV of ``rows`` rows: the simulated ``slews_pre_soi`` record repeated with a
    continuing time base."""
    import jax
    import numpy as np

    from cassini_bayes.simulate import load_scenario, simulate
    from cassini_bayes.telemetry import Telemetry, write_telemetry

    tel = simulate(jax.random.key(0), load_scenario("slews_pre_soi")).telemetry
    reps = -(-rows // tel.n)
    dt = float(tel.t[1] - tel.t[0])
    span = float(tel.t[-1] - tel.t[0]) + dt
    t = (tel.t[None, :] + span * np.arange(reps)[:, None]).ravel()[:rows]

    def tile(a):
        return np.concatenate([a] * reps)[:rows]

    big = Telemetry(t=t, q=tile(tel.q), omega=tile(tel.omega), wheel_rates=tile(tel.wheel_rates),
                    wheel_names=tel.wheel_names, thruster_names=tel.thruster_names,
                    on_times=None if tel.on_times is None else tile(tel.on_times))
    path = folder / f"tiled_{rows}.csv"
    write_telemetry(path, big)
    return path


def measure(stage: str, path: Path) -> dict:
    out = subprocess.run([sys.executable, "-c", _CHILD, stage, str(path)], capture_output=True,
                         text=True, cwd=ROOT)
    if out.returncode:
        sys.exit(f"{stage} {path.name}: {out.stderr.strip().splitlines()[-1]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, nargs="+", default=[10_000, 100_000, 1_000_000])
    ap.add_argument("--prepare-rows", type=int, nargs="+", default=[10_000, 100_000],
                    help="sizes at which prepare_inertia is measured too")
    ap.add_argument("--json", type=Path)
    a = ap.parse_args(argv)
    if a.json:
        from _provenance import start

        start(a.json, vars(a), argv, replace=True)
    sys.path.insert(0, str(ROOT))
    import cassini_bayes
    from cassini_bayes.files import write_text

    cassini_bayes.setup_jax()
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for rows in a.rows:
            path = tiled(rows, Path(tmp))
            for stage in STAGES:
                if stage != "read" and rows not in a.prepare_rows:
                    continue
                r = {"rows": rows, "stage": stage, **measure(stage, path)}
                results.append(r)
                print(f"{rows:>8d} rows  {stage:15s} {r['peak_mb']:7.0f} MB  "
                      f"{r['seconds']:6.1f} s", flush=True)
    if a.json:
        write_text(a.json, json.dumps({"results": results}, indent=1))


if __name__ == "__main__":
    main()
