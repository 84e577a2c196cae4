"""Benchmark: ``cassini-bayes fit inertia`` against the samplers a user would use instead.

    python benchmarks/bench_samplers.py [--scenario slew_2000_03_15] [--rounds 3]
        [--systems pkg_cold,pkg_warm,pkg_robust_warm,pymc_cold,pymc_warm,nutpie,numpyro]
        [--work DIR] [--json FILE]

Needs the optional extra ``pip install -e '.[bench]'`` (PyMC, nutpie). Not a test: nothing is
asserted; it prints a table and writes every run to ``--json``.

One simulated data set (``cassini-bayes simulate SCENARIO``), the same priors, 4 chains × 1000
warm-up + 1000 draws everywhere, every run a fresh process:

- ``pkg_cold`` / ``pkg_warm``: ``cassini-bayes fit inertia --idealised`` with an empty / a filled
  persistent compilation cache (``--jax-cache DIR``); ``pkg_robust_warm``: the default robust
  model, warm cache. The package's own model: whitened coordinates, per-sensor noise.
- ``pymc_cold`` / ``pymc_warm``: the plain PyMC model (``benchmarks/plain_inertia.py``: the
  Feldman & Lee momentum regression, ``H_N`` unknown, one Gaussian noise σ, the package's priors),
  default ``pm.sample``, with an empty / a filled pytensor compile directory.
- ``nutpie``: the same PyMC model compiled and sampled by nutpie (numba; nothing is kept between
  processes).
- ``numpyro``: the same plain model in NumPyro, default NUTS, without the package's whitening
  (no persistent compilation cache: what a plain script gets).
- ``pymc_same`` (warm), ``nutpie_same``, ``numpyro_same``: the same three with the noise model of
  the package's idealised fit instead of the single σ (``plain_inertia.py --noise package``: per
  sample the body residual's covariance ``s² B̂_t``, ``B̂_t`` computed by the package, ``log s ~
  N(0, 1)``): the same posterior as ``pkg_*``, so their means must agree with it within Monte Carlo
  error.

Interleaved: each round runs every system once, in an order rotated from round to round; an
untimed run first fills the warm caches. Per run: the wall time of the whole process (start-up,
imports, data, compilation, sampling, and for the package its run directory and report), the
sampling time with compilation excluded (PyMC's ``sampling_time``; nutpie's ``sample`` call;
NumPyro and the package: the sampler call minus the JAX trace/lower/compile(/cache-load)
durations inside it), the load average before and after (the machine is shared). Per system the
medians over rounds of: wall, sampling time, the smallest bulk ESS and largest R-hat over the six
inertia entries (ArviZ), ESS/s including everything (min ESS / wall) and excluding compilation
(min ESS / sampling time), and whether the posterior means agree with the PyMC runs'
(``max |Δ mean| / posterior sd`` over the six entries, ≤ 0.1 counts as agreeing), the plain
model's and the same model's.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NAMES = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")
SYSTEMS = ("pkg_cold", "pkg_warm", "pkg_robust_warm", "pymc_cold", "pymc_warm", "nutpie",
           "numpyro", "pymc_same", "nutpie_same", "numpyro_same")
SETTINGS = {"chains": 4, "warmup": 1000, "draws": 1000}

# ``cassini-bayes ARGS`` in-process as the console script runs it, timing the sampler
# (``run_nuts``) and the JAX trace, lower and compile/load durations that fall inside it
_PKG_CHILD = """
import json, sys, time
t_start = time.perf_counter()
from jax import monitoring
events = []
monitoring.register_event_duration_secs_listener(
    lambda event, secs, **kw: events.append((time.perf_counter(), event, secs)))
import cassini_bayes.inference.runner as runner
calls = []
_run_nuts = runner.run_nuts
def run_nuts(*a, **k):
    t = time.perf_counter()
    out = _run_nuts(*a, **k)
    calls.append((t, time.perf_counter()))
    return out
runner.run_nuts = run_nuts
from cassini_bayes.cli import _hide_dask, main
_hide_dask(sys.argv[2:])  # what the console script does before main
code = main(sys.argv[2:])
t0, t1 = calls[-1]
compile_s = sum(s for (t, e, s) in events if t0 <= t <= t1 and e in (
    "/jax/core/compile/backend_compile_duration", "/jax/core/compile/jaxpr_trace_duration",
    "/jax/core/compile/jaxpr_to_mlir_module_duration"))
json.dump({"code": code, "t_fit": t1 - t0, "t_sample": t1 - t0 - compile_s,
           "t_compile": compile_s, "t_process": time.perf_counter() - t_start},
          open(sys.argv[1], "w"))
"""


def _loadavg() -> float:
    return os.getloadavg()[0]


def simulate(scenario: str, work: Path) -> Path:
    out = work / "sim"
    if not (out / "telemetry.csv").exists():
        r = subprocess.run([sys.executable, "-m", "cassini_bayes.cli", "simulate",
                            str(ROOT / "experiments" / "scenarios" / f"{scenario}.toml"),
                            "--out", str(out)], capture_output=True, text=True,
                           env={**os.environ, "CASSINI_BAYES_JAX_CACHE": "off"})
        if r.returncode != 0:
            raise SystemExit(f"simulate {scenario} failed:\n{r.stderr}")
    return out


def plain_data(sim: Path, spacecraft: Path, work: Path) -> Path:
    """The plain models' arrays from the simulated telemetry, computed once with the package's
    readers (DCMs, wheel momentum in body axes) and the prior it states."""
    import numpy as np

    from cassini_bayes.frames import dcm, quat_continuous
    from cassini_bayes.inference.inertia import inertia_prior
    from cassini_bayes.physics.momentum import wheel_momentum_body
    from cassini_bayes.spacecraft import load_spacecraft
    from cassini_bayes.telemetry import read_telemetry

    tel = read_telemetry(sim / "telemetry.csv")
    sc = load_spacecraft(spacecraft)
    names = tel.active_wheels()
    rates = np.stack([np.nan_to_num(tel.wheel_rate(n)) for n in names], 1)
    axes = np.stack([sc.wheel(n).axis for n in names])
    js = np.array([sc.wheel(n).inertia for n in names])
    prior = inertia_prior(sc)
    out = work / "plain.npz"
    np.savez(out, a=np.asarray(dcm(quat_continuous(np.asarray(tel.q)))),
             omega=np.asarray(tel.omega), dt=tel.t - tel.t[0],
             h_wheels=np.asarray(wheel_momentum_body(rates, axes, js)),
             prior_mean=prior.mean, prior_sd=prior.sd, whiten=_package_whitening(tel, sc))
    return out


def _package_whitening(tel, sc):
    """``W_t = L_t⁻¹`` (n, 3, 3), ``L_t Lᵀ_t = B̂_t``: the idealised fit's noise covariance of the
    body residual per sample (errors in variables: gyro, wheel-rate and attitude noise at the
    empirical-Bayes levels, at the GLS mode), for the plain models' ``--noise package``."""
    import numpy as np

    from cassini_bayes.inference.inertia import noise_covariance, prepare_inertia

    problem = prepare_inertia([tel], sc, torque=True, robust=False)
    theta = np.asarray(problem.data.theta_star)
    if problem.t.size != tel.t.size or not np.allclose(problem.omega, tel.omega):
        raise SystemExit("the fit's samples are not the telemetry's: cannot whiten row by row")
    b = noise_covariance(problem, theta[:6], theta[None, 6:9], theta[None, 9:12],
                         problem.noise_eb)
    return np.linalg.inv(np.linalg.cholesky(b))


def _command(system: str, sim: Path, spacecraft: Path, data: Path, work: Path, seed: int,
             rnd: int) -> tuple[list[str], dict, Path]:
    rec = work / f"{system}_{rnd}.rec"
    env = dict(os.environ)
    if system.startswith("pkg"):
        cache = work / ("jax_warm" if "warm" in system else f"jax_cold_{rnd}")
        out = work / f"{system}_{rnd}_out"
        args = ["--jax-cache", str(cache), "fit", "inertia", "--telemetry",
                str(sim / "telemetry.csv"), "--spacecraft", str(spacecraft), "--out", str(out),
                "--seed", str(seed), "--force"]
        if system != "pkg_robust_warm":
            args.append("--idealised")
        return [sys.executable, "-c", _PKG_CHILD, str(rec), *args], env, rec
    framework = system.split("_")[0]
    if framework == "pymc":
        compiledir = work / ("pytensor_warm" if _warm(system) else f"pytensor_cold_{rnd}")
        env["PYTENSOR_FLAGS"] = f"compiledir={compiledir}"
    noise = "package" if system.endswith("_same") else "plain"
    return ([sys.executable, str(ROOT / "benchmarks" / "plain_inertia.py"), framework, str(data),
             str(rec) + ".npz", "--seed", str(seed), "--noise", noise], env,
            Path(str(rec) + ".npz"))


def _warm(system: str) -> bool:
    """Whether a system runs on a cache filled beforehand (``pymc_same``: PyMC warm)."""
    return "warm" in system or system == "pymc_same"


def _draws(system: str, rec: Path, work: Path, rnd: int):
    """``(6, chains, draws)`` inertia draws and the child's timings."""
    import numpy as np

    if system.startswith("pkg"):
        import arviz as az

        t = json.loads(rec.read_text())
        if t["code"] not in (0, 3):
            raise SystemExit(f"{system}: cassini-bayes exited {t['code']}")
        post = az.from_netcdf(work / f"{system}_{rnd}_out" / "posterior.nc").posterior
        return np.stack([post[n].values for n in NAMES]), t
    with np.load(rec) as z:
        return z["draws"], {k: float(z[k]) for k in ("t_fit", "t_sample", "t_import")}


def fill_cache(system: str, sim: Path, spacecraft: Path, data: Path, work: Path) -> None:
    """Fill a warm system's cache, untimed: a whole package fit (the sampler program depends
    on the numbers of steps), or a 20 + 20-step PyMC run (pytensor caches the compiled C of
    the model's graph, which does not)."""
    if system.startswith("pkg"):
        run_once(system, sim, spacecraft, data, work, 99, -1)
        return
    cmd, env, _ = _command(system, sim, spacecraft, data, work, 99, -1)
    subprocess.run(cmd + ["--warmup", "20", "--draws", "20"], env=env, capture_output=True,
                   cwd=work, check=True)


def run_once(system: str, sim: Path, spacecraft: Path, data: Path, work: Path, seed: int,
             rnd: int) -> dict:
    import arviz as az

    cmd, env, rec = _command(system, sim, spacecraft, data, work, seed, rnd)
    load0 = _loadavg()
    t0 = time.perf_counter()
    r = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=work)
    wall = time.perf_counter() - t0
    load1 = _loadavg()
    if r.returncode not in (0, 3) or not rec.exists():
        raise SystemExit(f"{system} failed ({r.returncode}):\n{r.stderr[-3000:]}")
    draws, timing = _draws(system, rec, work, rnd)
    ds = az.convert_to_dataset({n: draws[i] for i, n in enumerate(NAMES)})
    ess = az.ess(ds, method="bulk")
    rhat = az.rhat(ds)
    return {"system": system, "round": rnd, "wall_s": wall, "load_before": load0,
            "load_after": load1, **{k: timing[k] for k in ("t_fit", "t_sample")},
            "min_ess_bulk": float(min(ess[n].values for n in NAMES)),
            "max_rhat": float(max(rhat[n].values for n in NAMES)),
            "mean": [float(draws[i].mean()) for i in range(6)],
            "sd": [float(draws[i].std()) for i in range(6)]}


def _agreement(rs: list[dict], ref: list[dict]) -> float | None:
    """``max |Δ mean| / sd`` over the six entries and the runs ``rs``, against the mean of the
    runs ``ref``."""
    import numpy as np

    if not ref:
        return None
    ref_mean = np.mean([r["mean"] for r in ref], axis=0)
    return max(float(np.max(np.abs(np.asarray(r["mean"]) - ref_mean) / np.asarray(r["sd"])))
               for r in rs)


def summarise(runs: list[dict]) -> list[dict]:
    """Medians per system, and the posterior agreement with PyMC's means: with the plain model's
    (``pymc_cold``/``pymc_warm``) and with the same model as the package's idealised fit
    (``pymc_same``)."""
    by = {}
    for r in runs:
        by.setdefault(r["system"], []).append(r)
    plain = [r for r in runs if r["system"] in ("pymc_cold", "pymc_warm")]
    same = [r for r in runs if r["system"] == "pymc_same"]
    rows = []
    for system, rs in by.items():
        med = {k: statistics.median(r[k] for r in rs)
               for k in ("wall_s", "t_sample", "min_ess_bulk", "max_rhat")}
        ess_incl = statistics.median(r["min_ess_bulk"] / r["wall_s"] for r in rs)
        ess_excl = statistics.median(r["min_ess_bulk"] / r["t_sample"] for r in rs)
        loads = [r["load_before"] for r in rs] + [r["load_after"] for r in rs]
        rows.append({"system": system, "runs": len(rs), **med, "ess_per_s_incl": ess_incl,
                     "ess_per_s_excl": ess_excl,
                     "max_dmean_over_sd_vs_pymc": _agreement(rs, plain),
                     "max_dmean_over_sd_vs_pymc_same": _agreement(rs, same),
                     "load_min": min(loads), "load_max": max(loads)})
    return rows


LABELS = {"pkg_cold": "`fit inertia --idealised`, cold cache",
          "pkg_warm": "`fit inertia --idealised`, warm cache",
          "pkg_robust_warm": "`fit inertia` (robust), warm cache",
          "pymc_cold": "PyMC default NUTS, plain model, empty compile dir",
          "pymc_warm": "PyMC default NUTS, plain model, warm compile dir",
          "nutpie": "nutpie, plain model", "numpyro": "plain NumPyro, plain model",
          "pymc_same": "PyMC, package's model, warm compile dir",
          "nutpie_same": "nutpie, package's model",
          "numpyro_same": "plain NumPyro, package's model"}


def table(rows: list[dict]) -> str:
    """The medians of :func:`summarise` as a Markdown table, a row per system (the table kind
    ``bench_samplers_medians`` of docs_tables.py prints it from a record's ``medians``)."""
    def agree(x):
        return "–" if x is None else f"{x:.3f}"

    out = ["| system | runs | wall | sampling (no compile) | min bulk ESS | max R-hat | "
           "ESS/s, everything | ESS/s, sampling | Δmean/sd vs PyMC, plain model | "
           "vs PyMC, package's model | load |", "|" + "---|" * 11]
    for r in rows:
        out.append(f"| {LABELS.get(r['system'], r['system'])} | {r['runs']} | "
                   f"{r['wall_s']:.1f} s | {r['t_sample']:.2f} s | {r['min_ess_bulk']:.0f} | "
                   f"{r['max_rhat']:.3f} | {r['ess_per_s_incl']:.0f} | "
                   f"{r['ess_per_s_excl']:.0f} | {agree(r['max_dmean_over_sd_vs_pymc'])} | "
                   f"{agree(r['max_dmean_over_sd_vs_pymc_same'])} | "
                   f"{r['load_min']:.1f}–{r['load_max']:.1f} |")
    return "\n".join(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="slew_2000_03_15")
    ap.add_argument("--spacecraft", default=None,
                    help="prior model (default: the scenario's [prior] model)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--systems", default=",".join(SYSTEMS))
    ap.add_argument("--work", default=None, help="working folder (default: a new temporary one)")
    ap.add_argument("--json", default=None, help="write every run and the medians here")
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    import tempfile
    import tomllib

    work = Path(args.work or tempfile.mkdtemp(prefix="bench_samplers_")).resolve()
    work.mkdir(parents=True, exist_ok=True)
    scenario = ROOT / "experiments" / "scenarios" / f"{args.scenario}.toml"
    spacecraft = Path(args.spacecraft) if args.spacecraft else (
        ROOT / tomllib.loads(scenario.read_text())["prior"]["model"])
    systems = args.systems.split(",")
    sim = simulate(args.scenario, work)
    data = plain_data(sim, spacecraft, work)
    print(f"data: {sim / 'telemetry.csv'}; prior {spacecraft.name}; work {work}", flush=True)
    for system in systems:  # untimed: fill the warm caches
        if _warm(system):
            fill_cache(system, sim, spacecraft, data, work)
    runs = []
    for rnd in range(args.rounds):
        order = systems[rnd % len(systems):] + systems[:rnd % len(systems)]
        for system in order:
            run = run_once(system, sim, spacecraft, data, work, rnd, rnd)
            runs.append(run)
            print(json.dumps({k: (round(v, 4) if isinstance(v, float) else v)
                              for k, v in run.items() if k not in ("mean", "sd")}), flush=True)
            for p in work.glob(f"*_{rnd}_out"):
                shutil.rmtree(p, ignore_errors=True)
    rows = summarise(runs)
    print(table(rows))
    if args.json:
        Path(args.json).write_text(json.dumps({"settings": SETTINGS, "runs": runs,
                                               "medians": rows}, indent=1))
    return 0


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    sys.exit(main())
