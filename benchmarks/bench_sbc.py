"""Benchmark: SBC replicates per minute, per model and batch size, on this machine.

    python benchmarks/bench_sbc.py [--models toy,inertia,thrust,rwa4] [--batches 1,8,16,32]
        [--fit-batch 4] [--repeat 1] [--mcmc-loop 4] [--json bench_sbc.json]

For each model and batch size ``B`` it runs :func:`cassini_bayes.analysis.campaign.run_batch`
(the unit of work of every executor: prior draws, vmapped simulation, fits, ranks) once to compile,
then ``--repeat`` more batches, and reports the warm throughput ``60 B / seconds-per-batch``
(compilation excluded and reported separately). For the toy model it also times the obvious
alternative, a loop of ``numpyro.infer.MCMC`` (same NUTS settings, chains vectorised,
``jit_model_args=True``) over replicates, as the baseline of the ratio. The vectorised adapters
(``toy``, ``inertia``: one vmapped NUTS program per batch) run at each of ``--batches``; the
thrust and RWA4 adapters fit their replicates one after the other (``vectorized=False``), with
batches of ``--fit-batch`` replicates. Every adapter runs at its default sampler settings (for
the simulator models 300 warm-up, 300 draws, 2 chains), the ones a campaign uses. Projected time
of a campaign: ``N / rate`` minutes on this machine; with a Dask cluster of ``W`` workers on
``W`` free cores roughly ``W`` times faster. The load average is printed beside each figure (the
machine may be shared), and the process's CPU seconds per replicate: on a loaded machine
``60 / CPU-seconds`` is about the rate the process reaches with a core of its own. ``--json``
writes one record per setting (the table kind ``bench_sbc`` reads it) with its manifest.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings

os.environ.setdefault("MPLBACKEND", "Agg")

import jax  # noqa: E402
import numpy as np  # noqa: E402

import cassini_bayes  # noqa: E402,F401
from cassini_bayes.analysis.campaign import run_batch  # noqa: E402
from cassini_bayes.analysis.sbc_models import ModelSpec, build_model  # noqa: E402


def time_batches(spec: ModelSpec, batch: int, repeat: int) -> tuple[float, float, float]:
    """(compile-and-first-batch seconds, warm wall seconds per batch, warm CPU seconds per batch
    of this process, all its threads)."""
    t0 = time.perf_counter()
    run_batch(spec, 0, 0, batch)
    first = time.perf_counter() - t0
    t0, c0 = time.perf_counter(), time.process_time()
    for b in range(1, repeat + 1):
        run_batch(spec, 0, b, batch)
    return (first, (time.perf_counter() - t0) / repeat, (time.process_time() - c0) / repeat)


def mcmc_loop_baseline(n: int) -> tuple[float, float]:
    """Toy model fitted by a loop of numpyro.infer.MCMC: (first run s, warm s per replicate)."""
    import jax.numpy as jnp
    import numpyro
    import numpyro.distributions as dist
    from numpyro.infer import MCMC, NUTS

    model_cfg = build_model(ModelSpec.make("toy")).settings
    x = jnp.linspace(-1.0, 1.0, model_cfg["n_obs"])

    def model(y):
        a = numpyro.sample("alpha", dist.Normal(0.0, 1.0))
        b = numpyro.sample("beta", dist.Normal(0.0, 1.0))
        s = numpyro.sample("sigma", dist.LogNormal(jnp.log(0.5), 0.3))
        numpyro.sample("y", dist.Normal(a + b * x, s), obs=y)

    mcmc = MCMC(NUTS(model), num_warmup=model_cfg["num_warmup"],
                num_samples=model_cfg["num_draws"], num_chains=model_cfg["num_chains"],
                chain_method="vectorized", progress_bar=False, jit_model_args=True)
    ys = np.random.default_rng(0).normal(size=(n + 1, model_cfg["n_obs"]))
    t0 = time.perf_counter()
    mcmc.run(jax.random.key(0), jnp.asarray(ys[0]))
    jax.block_until_ready(mcmc.get_samples())
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    for i in range(1, n + 1):
        mcmc.run(jax.random.key(i), jnp.asarray(ys[i]))
        jax.block_until_ready(mcmc.get_samples())
    return first, (time.perf_counter() - t0) / n


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", default="toy,inertia,thrust,rwa4",
                    help="comma-separated: toy, inertia, thrust, rwa4")
    ap.add_argument("--batches", default="1,8,16,32", help="batch sizes for the toy model")
    ap.add_argument("--fit-batch", type=int, default=4,
                    help="batch size of the models fitted one replicate at a time")
    ap.add_argument("--repeat", type=int, default=1, help="warm batches timed per setting")
    ap.add_argument("--mcmc-loop", type=int, default=4,
                    help="replicates timed for the MCMC-loop baseline (0: skip)")
    ap.add_argument("--json", help="write the records here (with a manifest)")
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    records = []
    warnings.simplefilter("ignore")
    print(f"jax {jax.__version__}, devices {jax.devices()}, cpu count {os.cpu_count()}")
    rows = []
    for name in args.models.split(","):
        spec = ModelSpec.make(name)
        sizes = ([int(b) for b in args.batches.split(",")] if build_model(spec).vectorized
                 else [args.fit_batch])
        for b in sizes:
            load = os.getloadavg()[0]
            first, warm, cpu = time_batches(spec, b, args.repeat)
            how = "vmapped batch" if build_model(spec).vectorized else "batch (fits one by one)"
            rows.append((name, f"{how} B={b}", first, warm / b, 60 * b / warm))
            records.append({"model": name, "batch": b,
                            "vectorized": bool(build_model(spec).vectorized),
                            "first_s": first, "wall_s_per_replicate": warm / b,
                            "cpu_s_per_replicate": cpu / b, "load": [load, os.getloadavg()[0]]})
            print(f"{rows[-1][0]:8s} {rows[-1][1]:28s} first {first:7.1f} s   "
                  f"{warm / b:7.3f} s/replicate   {60 * b / warm:8.1f} replicates/min   "
                  f"CPU {cpu / b:6.3f} s/replicate ({60 * b / cpu:7.1f} per CPU-minute)   "
                  f"(200 replicates: {200 * warm / b / 60:6.1f} min)   load "
                  f"{load:.1f}-{os.getloadavg()[0]:.1f}", flush=True)
        if name == "toy" and args.mcmc_loop:
            first, per = mcmc_loop_baseline(args.mcmc_loop)
            rows.append((name, "loop of numpyro MCMC", first, per, 60 / per))
            print(f"{name:8s} {'loop of numpyro MCMC':28s} first {first:7.1f} s   "
                  f"{per:7.3f} s/replicate   {60 / per:8.1f} replicates/min", flush=True)
    best = {}
    for name, how, _, per, rate in rows:
        if "batch" in how:
            best[name] = max(best.get(name, 0.0), rate)
    for name, how, _, per, rate in rows:
        if how.startswith("loop") and name in best:
            print(f"{name}: best vmapped batch / MCMC loop = {best[name] / rate:.1f}x")
    if args.json:
        from _provenance import write_json

        write_json(args.json, records)
    return 0


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    sys.exit(main())
