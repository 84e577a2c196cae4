"""Simulator throughput: integration steps per second, one run and a vmapped batch.

Usage: ``python benchmarks/bench_simulate.py [--scenario NAME] [--batch 1000] [--repeat 3]``.

Prints compile time and steps/s (after compilation, best of ``--repeat``) for one run of the
scenario (telemetry as raw arrays, no file I/O) and for a vmapped batch of replicates with
different keys (one compiled call). A batch step counts once per replicate. Reference: Basilisk
integrates a comparable rigid-body-plus-wheels run at about 40 000 steps/s on this machine.
"""

from __future__ import annotations

import argparse
import time

import jax

import cassini_bayes  # noqa: F401  (x64)
from cassini_bayes.simulate import load_scenario, simulate_arrays, simulate_batch


def _time(fn, repeat):
    t0 = time.perf_counter()
    jax.block_until_ready(fn())
    first = time.perf_counter() - t0
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        jax.block_until_ready(fn())
        best = min(best, time.perf_counter() - t0)
    return first, best


def main(args) -> None:
    s = load_scenario(args.scenario)
    key = jax.random.key(0)
    print(f"scenario {s.name}: {s.n_steps} steps of {s.dt_s} s, {s.n_samples} samples, "
          f"control {s.control}, device {jax.devices()[0].platform}")
    first, best = _time(lambda: simulate_arrays(key, s), args.repeat)
    print(f"single run : first call {first:6.2f} s (incl. compile), run {best:7.3f} s, "
          f"{s.n_steps / best:12,.0f} steps/s")
    keys = jax.random.split(key, args.batch)
    first, best = _time(lambda: simulate_batch(keys, s), args.repeat)
    print(f"batch {args.batch:5d}: first call {first:6.2f} s (incl. compile), run {best:7.3f} s, "
          f"{args.batch * s.n_steps / best:12,.0f} steps/s")


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenario", default="slews_post_probe")
    p.add_argument("--batch", type=int, default=1000)
    p.add_argument("--repeat", type=int, default=3)
    main(p.parse_args())
