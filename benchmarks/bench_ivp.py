"""Benchmark: vector evaluations per second of the inertial vector propagator (Lee §3.3).

Prints, for batches of N vectors, the compile time and the evaluations per second (median of
repeats, after compilation) of

* conic propagation by Goodyear's method (:func:`cassini_bayes.ivp.propagate_conic`) on random
  elliptic and hyperbolic states and times (each evaluation solves Kepler's equation);
* Chebyshev segment evaluation (:meth:`cassini_bayes.ivp.ChebyshevSegments.position`,
  Eq 16's recurrence to order 12) at random times over a 5-segment list;

and, as a baseline in the same process, the Chebyshev evaluation in vectorised NumPy
(``numpy.polynomial.chebyshev.chebval``). Names the CPU. ``--json`` writes the rates as a
record with its manifest (docs/ivp.md's table is generated from it).

    python benchmarks/bench_ivp.py [--n 100000] [--repeats 7] [--json FILE.json]
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import jax
import numpy as np

import cassini_bayes  # noqa: F401  (64-bit)
from cassini_bayes.files import json_text, write_text
from cassini_bayes.ivp import ChebyshevSegments, propagate_conic_unchecked
from _provenance import cpu_name, start


def timed(fn, repeats: int) -> tuple[float, float]:
    t0 = time.perf_counter()
    jax.block_until_ready(fn())
    first = time.perf_counter() - t0
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(fn())
        times.append(time.perf_counter() - t0)
    return first, float(np.median(times))


def main(args) -> None:
    if args.json:
        start(args.json, {"n": args.n, "repeats": args.repeats})
    rows = []
    rng = np.random.default_rng(0)
    n = args.n
    mu = 3.7931208e16
    r0 = rng.normal(size=(n, 3)) * 1.2e9
    v_esc = np.sqrt(2 * mu / np.linalg.norm(r0, axis=1))
    v0 = rng.normal(size=(n, 3)) / np.sqrt(3) * (v_esc * rng.uniform(0.3, 1.5, n))[:, None]
    dt = rng.uniform(-3e6, 3e6, n)
    mus = np.full(n, mu)
    first, med = timed(lambda: propagate_conic_unchecked(r0, v0, mus, dt).r, args.repeats)
    print(f"CPU: {cpu_name()} ({jax.device_count()} JAX device(s), {jax.default_backend()})")
    print(f"conic (Goodyear), N = {n}: first call {first:.2f} s, then {med * 1e3:.1f} ms "
          f"= {n / med:.3g} vectors/s")
    rows.append({"evaluation": "conic", "first_call_s": first, "median_s": med})

    bounds = np.cumsum(np.r_[0.0, rng.uniform(1e4, 1e6, 5)])
    coeffs = [rng.normal(size=(3, 13)) * 1e6 / (1 + np.arange(13)) ** 2 for _ in range(5)]
    seg = ChebyshevSegments.from_segments(bounds, coeffs)
    t = rng.uniform(bounds[0], bounds[-1], n)
    first, med = timed(lambda: seg.position(t), args.repeats)
    print(f"Chebyshev order 12, 5 segments, N = {n}: first call {first:.2f} s, then "
          f"{med * 1e3:.2f} ms = {n / med:.3g} vectors/s")
    rows.append({"evaluation": "chebyshev", "first_call_s": first, "median_s": med})
    k = np.clip(np.searchsorted(bounds, t, side="right") - 1, 0, 4)
    tau = (2 * t - bounds[k + 1] - bounds[k]) / (bounds[k + 1] - bounds[k])
    c = np.asarray(coeffs)

    def numpy_eval():
        out = np.empty((n, 3))
        for j in range(5):
            m = k == j
            out[m] = np.polynomial.chebyshev.chebval(tau[m], c[j].T).T
        return out

    _, med_np = timed(numpy_eval, args.repeats)
    print(f"  NumPy chebval baseline: {med_np * 1e3:.2f} ms = {n / med_np:.3g} vectors/s "
          f"(JAX/NumPy speed ratio {med_np / med:.2f})")
    rows.append({"evaluation": "numpy_chebval", "first_call_s": None, "median_s": med_np})
    if args.json:
        write_text(args.json, json_text({
            "cpu": cpu_name(), "jax_devices": jax.device_count(), "n": n,
            "repeats": args.repeats, "load_1min": os.getloadavg()[0], "rows": rows}))


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--n", type=int, default=100_000, help="vectors per batch")
    p.add_argument("--repeats", type=int, default=7)
    p.add_argument("--json", type=Path, default=None, help="write the record here")
    main(p.parse_args())
