"""Benchmark: a warm robust ``fit thrust`` of one long biasing event, split by phase.

Target: docs/performance.md ("Against the speed targets": a warm robust ``fit thrust`` of one
biasing event of about 800 samples and 450 pulses, <= 20 s on a 2-core machine).

Each fit runs in a fresh process, as ``cassini-bayes fit thrust`` does (the CLI's devices, the
persistent compilation cache in a folder of its own, filled by a first, cold run): the data read
and checked, the preparation (padding, nuisance columns, time-tag rates, data-only statistics),
the Laplace step, the sampler, the nuisance draws and residuals, the summaries (baseline,
adequacy checks), the run directory (``posterior.nc``, ``summary.json``, the report). Every phase
is timed twice: wall clock and CPU time of the whole process (``time.process_time``: all
threads, so four parallel chains on two cores count four chains' work; the measure to compare
on a shared machine, where the wall clock counts the other jobs too). After the fit the child
times the value and gradient of the event log density (the sampler's unit of work; min over
repeats of the mean over 200 calls) and reads the leapfrog steps per iteration from the draws.
Prints a table and, with ``--json``, writes every number. Not a test: nothing is asserted.

    python benchmarks/bench_thrust.py [--scenario biasing_long] [--runs 3] [--json out.json]

Data: ``cassini-bayes simulate SCENARIO`` (default ``biasing_long``: 821 samples at 1 s, 468
pulses of 125-375 ms; experiments/scenarios/biasing_long.toml), the scenario's prior model.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _provenance import cpu_name, start

_T0 = (time.perf_counter(), time.process_time())
ROOT = Path(__file__).resolve().parents[1]

PHASES = ("imports", "read and check", "preparation", "laplace", "sampler",
          "nuisance draws, residuals", "summaries", "writing")


class _Clock:
    """Wall and CPU seconds per phase; :meth:`wrap` times every call of a function."""

    def __init__(self):
        self.wall: dict[str, float] = {}
        self.cpu: dict[str, float] = {}
        self._stack: list[str] = []

    def add(self, phase, wall, cpu):
        self.wall[phase] = self.wall.get(phase, 0.0) + wall
        self.cpu[phase] = self.cpu.get(phase, 0.0) + cpu

    def wrap(self, owner, name: str, phase: str):
        fn = getattr(owner, name)

        def timed(*a, **k):
            w0, c0 = time.perf_counter(), time.process_time()
            self._stack.append(phase)
            try:
                return fn(*a, **k)
            finally:
                self._stack.pop()
                dw, dc = time.perf_counter() - w0, time.process_time() - c0
                self.add(phase, dw, dc)
                if self._stack:   # nested: not counted twice in the enclosing phase
                    self.add(self._stack[-1], -dw, -dc)

        setattr(owner, name, timed)


def child(args) -> dict:
    """One fit in this process (the CLI's set-up), its phases and the gradient's cost."""
    from cassini_bayes._devices import request_host_devices

    request_host_devices()
    import jax
    import numpy as np

    import cassini_bayes.api._thrust as api_thrust
    import cassini_bayes.consistency as consistency
    import cassini_bayes.inference.runner as runner
    import cassini_bayes.inference.thrust.data as tdata
    import cassini_bayes.inference.thrust.fit as tfit
    from cassini_bayes.api import fit_thrust
    from cassini_bayes.api._result import FitResult

    clock = _Clock()
    clock.add("imports", time.perf_counter() - _T0[0], time.process_time() - _T0[1])
    for owner, name, phase in [
            (api_thrust, "telemetry_inputs", "read and check"),
            (api_thrust, "pulse_inputs", "read and check"),
            (consistency, "check_thrust_data", "read and check"),
            (tfit, "prepare_thrust", "preparation"), (tdata, "laplace", "laplace"),
            (runner, "run_nuts", "sampler"),
            (tfit, "_add_nuisance_draws", "nuisance draws, residuals"),
            (tfit, "_posterior_mean_residuals", "nuisance draws, residuals"),
            (api_thrust, "thrust_baseline", "summaries"),
            (api_thrust, "thrust_summary", "summaries"), (FitResult, "save", "writing")]:
        clock.wrap(owner, name, phase)
    w0, c0 = time.perf_counter(), time.process_time()
    result = fit_thrust(Path(args.data) / "telemetry.csv", Path(args.data) / "pulses.csv",
                        args.spacecraft, seed=args.seed, chains=args.chains, warmup=args.warmup,
                        draws=args.draws)
    result.save(Path(args.out), force=True)
    fit_wall, fit_cpu = time.perf_counter() - w0, time.process_time() - c0
    out = {"wall": clock.wall, "cpu": clock.cpu,
           "total_wall": fit_wall + clock.wall["imports"],
           "total_cpu": fit_cpu + clock.cpu["imports"]}
    post = result.posterior
    idata = post.idata
    steps = np.asarray(idata.sample_stats["n_steps"], float)
    out["leapfrog_per_iteration"] = float(steps.mean())
    out["step_size"] = [float(x) for x in np.asarray(idata.sample_stats["step_size"])[:, 0]]
    out["divergences"] = int(np.asarray(idata.sample_stats["diverging"]).sum())
    # the cost of the sampler's unit of work, at the sampler's centre
    from cassini_bayes.inference.thrust.model import log_density

    problem = post.problem
    kw = problem.data
    n_f, n_c, sample_inertia = problem.n_f, problem.n_c, problem.inertia is not None
    vg = jax.jit(jax.value_and_grad(
        lambda w, kw: log_density(kw.centre + kw.tril @ w, kw, n_f, n_c, sample_inertia)))
    w = jax.device_put(np.zeros(kw.centre.shape[0]))
    jax.block_until_ready(vg(w, kw))
    best_c = best_w = float("inf")
    for _ in range(args.repeats):
        c0, w0 = time.process_time(), time.perf_counter()
        for _ in range(200):
            r = vg(w, kw)
        jax.block_until_ready(r)
        best_c = min(best_c, (time.process_time() - c0) / 200)
        best_w = min(best_w, (time.perf_counter() - w0) / 200)
    out["gradient_cpu_ms"], out["gradient_wall_ms"] = 1e3 * best_c, 1e3 * best_w
    out["n_samples"] = [int(x) for x in problem.n_samples]
    out["n_pulses"] = [int(x) for x in problem.n_pulses]
    out["dim"] = int(kw.centre.shape[0])
    out["n_nuisance"] = int(kw.nu_sd.shape[0])
    s = result.summary()
    out["summary_parameters"] = s["parameters"]
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="biasing_long")
    ap.add_argument("--sim-seed", type=int, default=None, help="sensor-noise seed of the "
                    "simulation (default: the scenario's)")
    ap.add_argument("--seed", type=int, default=0, help="the fit's seed")
    ap.add_argument("--runs", type=int, default=3, help="warm fits (after one cold)")
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--warmup", type=int, default=1000)
    ap.add_argument("--draws", type=int, default=1000)
    ap.add_argument("--repeats", type=int, default=5, help="gradient timing repeats")
    ap.add_argument("--cache", default=None, help="compilation cache folder (default: a fresh "
                    "temporary one, filled by the first run)")
    ap.add_argument("--json", default=None, help="write every number here")
    ap.add_argument("--workdir", default=None, help="keep the data, the cache and the run "
                    "directories here (default: a temporary folder, removed at the end)")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--data", default=None, help=argparse.SUPPRESS)
    ap.add_argument("--spacecraft", default=None, help=argparse.SUPPRESS)
    ap.add_argument("--out", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        print("BENCH " + json.dumps(child(args)))
        return
    if args.json:
        start(args.json, vars(args), argv, replace=True)

    sys.path.insert(0, str(ROOT))
    tmp = Path(args.workdir or tempfile.mkdtemp(prefix="bench_thrust_"))
    tmp.mkdir(parents=True, exist_ok=True)
    try:
        _parent(args, tmp)
    finally:
        if not args.workdir:
            shutil.rmtree(tmp, ignore_errors=True)


def _parent(args, tmp: Path) -> None:
    """Simulate, run the cold and the warm fits in child processes, print the table."""
    cache = Path(args.cache) if args.cache else tmp / "jax-cache"
    # this checkout's package, whatever the environment has installed
    env = dict(os.environ, CASSINI_BAYES_JAX_CACHE=str(cache),
               PYTHONPATH=os.pathsep.join([str(ROOT), *filter(None, [os.environ.get(
                   "PYTHONPATH")])]))
    cli = [sys.executable, "-m", "cassini_bayes.cli"]
    sim = [*cli, "simulate", args.scenario, "--out", str(tmp / "data"), "--force"]
    if args.sim_seed is not None:
        sim += ["--seed", str(args.sim_seed)]
    subprocess.run(sim, check=True, capture_output=True, cwd=ROOT, env=env)
    from cassini_bayes.simulate import load_scenario
    from cassini_bayes.simulate.scenario import scenario_path

    spacecraft = str(load_scenario(scenario_path(args.scenario)).prior_model_path)
    runs = []
    for i in range(args.runs + 1):
        load = os.getloadavg()[0]
        cmd = [sys.executable, __file__, "--child", "--data", str(tmp / "data"),
               "--spacecraft", spacecraft, "--out", str(tmp / f"fit{i}"),
               "--seed", str(args.seed), "--chains", str(args.chains),
               "--warmup", str(args.warmup), "--draws", str(args.draws),
               "--repeats", str(args.repeats)]
        p = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=ROOT)
        line = [x for x in p.stdout.splitlines() if x.startswith("BENCH ")]
        if p.returncode or not line:
            sys.exit(f"run {i} failed:\n{p.stderr[-3000:]}")
        r = json.loads(line[-1][6:])
        r["load_start"], r["load_end"] = load, os.getloadavg()[0]
        r["kind"] = "cold" if i == 0 and not args.cache else "warm"
        runs.append(r)
    r0 = runs[-1]
    print(f"cpu: {cpu_name()} ({os.cpu_count()} cores); scenario {args.scenario}: "
          f"{r0['n_samples']} samples, {r0['n_pulses']} pulses; sampler dim {r0['dim']}, "
          f"{r0['n_nuisance']} nuisance integrated out; {args.chains} chains x "
          f"({args.warmup} + {args.draws})")
    head = f"{'phase':28s}" + "".join(f"{r['kind'] + ' ' + str(i):>17s}"
                                      for i, r in enumerate(runs))
    print(head + "\n" + f"{'':28s}" + "   wall s   cpu s" * len(runs))
    for ph in PHASES + ("total",):
        cells = []
        for r in runs:
            wl = r["total_wall"] if ph == "total" else r["wall"].get(ph, 0.0)
            cp = r["total_cpu"] if ph == "total" else r["cpu"].get(ph, 0.0)
            cells.append(f"{wl:9.2f}{cp:8.2f}")
        print(f"{ph:28s}" + "".join(cells))
    for key, fmt in [("gradient_cpu_ms", "{:.3f}"), ("gradient_wall_ms", "{:.3f}"),
                     ("leapfrog_per_iteration", "{:.2f}"), ("divergences", "{}"),
                     ("load_start", "{:.1f}"), ("load_end", "{:.1f}")]:
        print(f"{key:28s}" + "".join(f"{fmt.format(r[key]):>17s}" for r in runs))
    if args.json:
        Path(args.json).write_text(json.dumps({"cpu": cpu_name(), "cores": os.cpu_count(),
                                               "scenario": args.scenario, "runs": runs},
                                              indent=1))


if __name__ == "__main__":
    main()
