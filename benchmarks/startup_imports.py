"""What the command's start-up spends in imports, by ``python -X importtime``.

Runs, each in a fresh process (``python -X importtime -m cassini_bayes.cli …``), with a warm
bytecode cache (one unmeasured run first):

* ``--help``;
* ``check FILE`` (the Post-Probe slews, simulated into a temporary folder);
* ``fit inertia`` on the same file up to the sampler: the process ends when the runner first
  compiles the sampler (a post-import hook replaces ``runner._build_sampler``), so only the
  imports of reading, checking and preparing the data count;
* ``import cassini_bayes`` then ``cassini_bayes.fit_inertia`` up to the sampler (the API).

Prints per case the wall time of the process, the summed self time of every import (the column
``self [us]`` of ``-X importtime``), the heaviest top-level packages (the self times of their
modules) and
whether ``jax``, ``numpyro``, ``arviz``, ``matplotlib`` were imported. ``--repeat N`` takes the
median of N runs (the machine is shared: compare rows of one run). Not a test: the numbers are
in docs/performance.md.

    python benchmarks/startup_imports.py [--repeat 3] [--top 8] [--json startup.json]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

WATCH = ("jax", "numpy", "scipy", "numpyro", "arviz", "xarray", "matplotlib", "rich", "typer")

# ends the process when the sampler is about to be compiled (before any sampling)
_STOP_AT_SAMPLER = """
import importlib.abc, importlib.util, os, sys
class _Hook(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name != "cassini_bayes.inference.runner":
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec(name)
        run = spec.loader.exec_module
        def exec_module(module):
            run(module)
            def stop(*a, **k):
                sys.stderr.write("STARTUP-SAMPLER-REACHED\\n"); sys.stderr.flush(); os._exit(0)
            module._build_sampler = stop
        spec.loader.exec_module = exec_module
        return spec
sys.meta_path.insert(0, _Hook())
"""


def _cases(telemetry: Path, out: Path) -> dict[str, str]:
    cli = "import sys; from cassini_bayes.cli import main; sys.exit(main(sys.argv[1:]))"
    api = ("import cassini_bayes as cb\n"
           f"cb.fit_inertia(cb.read_telemetry({str(telemetry)!r}), 'cassini_post_probe', "
           "seed=0, chains=2, warmup=300, draws=300)")
    return {
        "--help": f"{cli}\0--help",
        "check FILE": f"{cli}\0check\0{telemetry}",
        "fit inertia (to the sampler)": (f"{_STOP_AT_SAMPLER}\n{cli}\0fit\0inertia\0--telemetry"
                                         f"\0{telemetry}\0--spacecraft\0cassini_post_probe"
                                         f"\0--out\0{out}\0--force"),
        "API fit_inertia (to the sampler)": f"{_STOP_AT_SAMPLER}\n{api}",
        "import cassini_bayes": "import cassini_bayes",
    }


def _parse(stderr: str) -> tuple[float, dict[str, float], set[str]]:
    """(summed self seconds, self seconds per top-level package, modules imported)."""
    total, top, mods = 0.0, {}, set()
    for line in stderr.splitlines():
        if not line.startswith("import time:") or "self [us]" in line:
            continue
        self_us, _cum_us, name = line[len("import time:"):].split("|")
        mod = name.strip()
        mods.add(mod)
        total += int(self_us) / 1e6
        root = mod.split(".")[0]
        top[root] = top.get(root, 0.0) + int(self_us) / 1e6
    return total, top, mods


def _run(code: str) -> tuple[float, float, dict[str, float], set[str], bool]:
    src, *argv = code.split("\0")
    env = dict(os.environ, MPLBACKEND="Agg")
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-X", "importtime", "-c", src, *argv], env=env,
                       capture_output=True, text=True)
    wall = time.perf_counter() - t0
    total, top, mods = _parse(r.stderr)
    reached = "STARTUP-SAMPLER-REACHED" in r.stderr
    if r.returncode not in (0,) and not reached:
        tail = [ln for ln in r.stderr.splitlines() if not ln.startswith("import time:")]
        raise SystemExit(f"failed ({r.returncode}): {' | '.join(tail[-5:])}")
    return wall, total, top, mods, reached


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--top", type=int, default=8)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    if args.json:
        from _provenance import start

        start(args.json, vars(args), None, replace=True)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        subprocess.run([sys.executable, "-m", "cassini_bayes.cli", "simulate", "slews_post_probe",
                        "--out", str(tmp / "sim")], check=True, capture_output=True)
        telemetry = tmp / "sim" / "telemetry.csv"
        for name, code in _cases(telemetry, tmp / "fit").items():
            _run(code)  # warm the bytecode and file caches
            runs = [_run(code) for _ in range(args.repeat)]
            wall = statistics.median(r[0] for r in runs)
            imports = statistics.median(r[1] for r in runs)
            top = runs[-1][2]
            mods = runs[-1][3]
            heavy = sorted(top.items(), key=lambda kv: -kv[1])[: args.top]
            loaded = [w for w in WATCH if w in mods]
            rows.append({"case": name, "wall_s": wall, "imports_s": imports,
                         "top": dict(heavy), "imported": loaded,
                         "load_1min": os.getloadavg()[0]})
            print(f"{name:34s} wall {wall:5.2f} s  imports {imports:5.2f} s  "
                  f"load {os.getloadavg()[0]:4.1f}")
            print(f"{'':34s} heaviest: " + ", ".join(f"{k} {v:.2f}" for k, v in heavy))
            print(f"{'':34s} imported: {' '.join(loaded) or '-'}")
    if args.json:
        args.json.write_text(json.dumps({"cpu_count": os.cpu_count(), "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
