"""Benchmark: inertia posterior, 4 chains × 1000 draws on 3600 telemetry samples.

Target: docs/design.md §8.

Prints, for one process: wall time of the first fit (with XLA compilation), of a second fit on new
data of the same shapes (no compilation), of the sampler alone, min bulk ESS over the six inertia
entries and over all sampled quantities, and ESS/s. Not a test: nothing is asserted.

Data: noisy synthetic RWA slews (tests/kinematics.py generators; Y, X, Y, Z and a skew slew at
2 Hz, truth = Feldman & Lee Eq 8), the cassini_2000_03_15 spacecraft model as prior.

    python benchmarks/bench_inertia.py [--chains 4] [--draws 1000] [--warmup 1000]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--warmup", type=int, default=1000)
    ap.add_argument("--draws", type=int, default=1000)
    ap.add_argument("--chain-method", default=None)
    ap.add_argument("--robust", action="store_true",
                    help="the robust model (gyro/wheel nuisance parameters, docs/design.md §7.5)")
    args = ap.parse_args(argv)

    import jax

    # one CPU device per core, before anything initialises the backend (parallel chains)
    jax.config.update("jax_num_cpu_devices", os.cpu_count() or 1)
    import arviz as az
    import numpy as np

    from cassini_bayes.inference.inertia import fit_inertia, inertia_model, prepare_inertia
    from cassini_bayes.inference.runner import SamplerSettings, run_nuts
    from cassini_bayes.physics.momentum import INERTIA_NAMES
    from cassini_bayes.spacecraft import load_spacecraft
    from slews import make_slews

    sc = load_spacecraft("cassini_2000_03_15")
    tel_a = make_slews(jax.random.key(1), sc, dt=0.5, rest=50.0)
    tel_b = make_slews(jax.random.key(2), sc, dt=0.5, rest=50.0)
    s = SamplerSettings(chains=args.chains, warmup=args.warmup, draws=args.draws,
                        chain_method=args.chain_method)
    print(f"samples {tel_a.n}, chains {s.chains} × ({s.warmup} warmup + {s.draws} draws), "
          f"{jax.local_device_count()} host devices, cpu count {os.cpu_count()}, "
          f"{'robust' if args.robust else 'idealised'} model")

    t0 = time.perf_counter()
    fit_inertia(jax.random.key(0), [tel_a], sc, settings=s, robust=args.robust)
    t_first = time.perf_counter() - t0

    t0 = time.perf_counter()
    res = fit_inertia(jax.random.key(1), [tel_b], sc, settings=s, robust=args.robust)
    t_second = time.perf_counter() - t0

    problem = prepare_inertia([tel_b], sc, robust=args.robust)
    t0 = time.perf_counter()
    idata = run_nuts(jax.random.key(2), inertia_model(True, args.robust),
                     model_kwargs={"data": problem.data},
                     settings=s, prior_draws=0)
    t_sampler = time.perf_counter() - t0

    ess_i = min(float(az.ess(res.idata, var_names=[n], method="bulk")[n]) for n in INERTIA_NAMES)
    d = res.diagnostics
    steps = float(np.mean(idata.sample_stats["n_steps"]))
    print(f"first fit (with compilation)     {t_first:8.2f} s")
    print(f"second fit (no compilation)      {t_second:8.2f} s   (data prep, sampler, prior, "
          "residuals, diagnostics)")
    print(f"sampler alone (no compilation)   {t_sampler:8.2f} s   mean leapfrog steps {steps:.1f}")
    print(f"min bulk ESS, inertia entries    {ess_i:8.0f}")
    print(f"min bulk ESS, all / min tail ESS {d.min_ess_bulk:8.0f} / {d.min_ess_tail:.0f}")
    print(f"max R-hat {d.max_r_hat:.4f}, divergences {d.divergences}, converged {d.converged}")
    print(f"ESS/s (inertia, second fit)      {ess_i / t_second:8.0f}")
    print(f"ESS/s (inertia, sampler alone)   {ess_i / t_sampler:8.0f}")


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    main()
