"""Benchmark: Brown (2012) §III.B Monte Carlo mass-property analysis, 10⁵ draws.

Prints the compile time, the wall time per 10⁵ draws of the jitted JAX analysis
(:func:`cassini_bayes.analysis.mass_property.mass_property_mc`, median of repeats) and, as a
baseline in the same process, the same computation written directly in vectorised NumPy
(draws, tensors, ``numpy.linalg.solve``, angles). docs/design.md §8 target: 10⁵ draws in
under a second.

    python benchmarks/bench_mass_property.py [--draws 100000] [--repeats 7]
"""

from __future__ import annotations

import argparse
import time

import jax
import numpy as np

from cassini_bayes.analysis.mass_property import (
    mass_property_mc,
    requirement_box,
    summarise_errors,
)
from cassini_bayes.spacecraft import load_spacecraft

PHI = (np.radians(-30.0), np.radians(210.0))


def numpy_baseline(rng, inertia, n):
    """The same analysis in plain vectorised NumPy (Brown Eq 1, small drift: û ∝ Î I⁻¹ u)."""
    x = rng.uniform(-1.0, 1.0, (n, 6)) * np.array([0.1, 0.1, 0.1, 75.0, 75.0, 75.0])
    i_hat = np.broadcast_to(inertia, (n, 3, 3)).copy()
    i_hat[:, [0, 1, 2], [0, 1, 2]] *= 1.0 + x[:, :3]
    for k, (a, b) in enumerate(((0, 1), (0, 2), (1, 2))):
        i_hat[:, a, b] += x[:, 3 + k]
        i_hat[:, b, a] += x[:, 3 + k]
    phi = rng.uniform(*PHI, n)
    s, c = np.sqrt(2.0 / 3.0), np.sqrt(1.0 / 3.0)
    u = np.stack([s * np.cos(phi), s * np.sin(phi), np.full(n, c)], -1)
    u_hat = np.einsum("nij,nj->ni", i_hat, np.linalg.solve(inertia, u.T).T)
    return np.arctan2(np.linalg.norm(np.cross(u_hat, u), axis=-1), np.sum(u_hat * u, -1))


def _median_time(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--draws", type=int, default=100_000)
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args(argv)
    inertia = load_spacecraft("cassini_post_probe").inertia
    box = requirement_box()
    key = jax.random.key(0)

    def run_jax(k=key):
        return mass_property_mc(k, inertia, box, args.draws, phi_range_rad=PHI).error_rad \
            .block_until_ready()

    t0 = time.perf_counter()
    run_jax()
    compile_s = time.perf_counter() - t0
    jax_s = _median_time(run_jax, args.repeats)
    rng = np.random.default_rng(0)
    numpy_s = _median_time(lambda: numpy_baseline(rng, inertia, args.draws), args.repeats)
    p99_jax = summarise_errors(run_jax()).p99_deg
    p99_np = summarise_errors(numpy_baseline(rng, inertia, args.draws)).p99_deg
    print(f"mass-property Monte Carlo, {args.draws} draws (median of {args.repeats})")
    print(f"  first call (compile + run)  {compile_s:8.3f} s")
    print(f"  jax, jitted                 {jax_s * 1e3:8.2f} ms   "
          f"({args.draws / jax_s:,.0f} draws/s)")
    print(f"  numpy baseline              {numpy_s * 1e3:8.2f} ms   "
          f"({args.draws / numpy_s:,.0f} draws/s)")
    print(f"  speed-up vs numpy           {numpy_s / jax_s:8.2f} x")
    print(f"  target (< 1 s per 1e5)      {'met' if jax_s * 1e5 / args.draws < 1.0 else 'MISSED'}")
    print(f"  99th percentile: jax {p99_jax:.3f} deg, numpy {p99_np:.3f} deg (same model)")


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    main()
