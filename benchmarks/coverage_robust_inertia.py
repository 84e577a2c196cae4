"""Coverage campaign: robust vs idealised inertia posteriors on slews with real-world errors.

For each seed: draw the truth's sensor and actuator errors at the scale of the robust model's
prior (the spacecraft model's default :class:`~cassini_bayes.spacecraft.Knowledge`: gyro bias
5e-7 rad/s and scale factor 5e-4 per axis, wheel spin inertias off by a common 0.5 %, each wheel
axis tilted by 0.2° per component, and a constant inertial torque of 15 µN m per axis, the T_N
prior), make noisy slews (tests/kinematics.py generators: Y, X, Y, Z and a skew slew) whose wheel
rates follow the *true* wheels, let the gyro read ``(1 + s) ω + b``, and fit both models with the
nominal spacecraft model. Prints the 90 % coverage of the six inertia entries per model with its
binomial standard error, and the median posterior sd. Not a test.

    python benchmarks/coverage_robust_inertia.py [--seeds 20] [--chains 2] [--draws 300]
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--chains", type=int, default=2)
    ap.add_argument("--warmup", type=int, default=300)
    ap.add_argument("--draws", type=int, default=300)
    args = ap.parse_args(argv)

    import jax
    import numpy as np

    from cassini_bayes.inference.inertia import TORQUE_PRIOR_SD_NM, fit_inertia
    from cassini_bayes.inference.nuisance import tilt_basis
    from cassini_bayes.inference.runner import SamplerSettings
    from cassini_bayes.physics.momentum import INERTIA_NAMES, inertia_vector
    from cassini_bayes.spacecraft import load_spacecraft
    from test_inference_inertia import TRUTH, make_slews

    sc = load_spacecraft("cassini_2000_03_15")
    k = sc.knowledge
    pi_true = np.asarray(inertia_vector(TRUTH))
    s = SamplerSettings(chains=args.chains, warmup=args.warmup, draws=args.draws)
    hits = {"idealised": [], "robust": []}
    sds = {"idealised": [], "robust": []}
    conv = {"idealised": [], "robust": []}
    t0 = time.perf_counter()
    for seed in range(args.seeds):
        key = jax.random.key(1000 + seed)
        k_b, k_s, k_c, k_a, k_t, k_n = jax.random.split(key, 6)
        bias = k.gyro_bias_sd_rad_s * np.asarray(jax.random.normal(k_b, (3,)))
        scale = k.gyro_scale_factor_sd * np.asarray(jax.random.normal(k_s, (3,)))
        c = k.wheel_inertia_sd_frac * float(jax.random.normal(k_c, ()))
        tilt = np.deg2rad(k.wheel_axis_sd_deg) * np.asarray(jax.random.normal(k_a, (4, 2)))
        torque = TORQUE_PRIOR_SD_NM * np.asarray(jax.random.normal(k_t, (3,)))
        wheels = []
        for w, a in zip(sc.wheels, tilt):
            axis = w.axis + a @ tilt_basis(w.axis)
            wheels.append(replace(w, axis=axis / np.linalg.norm(axis), inertia=w.inertia * (1 + c)))
        sc_true = replace(sc, wheels=tuple(wheels))
        tel = make_slews(k_n, sc_true, torque=torque)
        tel = replace(tel, omega=(1 + scale) * np.asarray(tel.omega) + bias)
        for name, robust in (("idealised", False), ("robust", True)):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                post = fit_inertia(jax.random.key(seed), [tel], sc, robust=robust, settings=s,
                                   prior_draws=0)
            p = post.idata.posterior
            q05 = np.array([np.quantile(p[n].values, 0.05) for n in INERTIA_NAMES])
            q95 = np.array([np.quantile(p[n].values, 0.95) for n in INERTIA_NAMES])
            hits[name].append((q05 <= pi_true) & (pi_true <= q95))
            sds[name].append([float(p[n].std()) for n in INERTIA_NAMES])
            conv[name].append((post.diagnostics.max_r_hat, post.diagnostics.divergences))
        print(f"seed {seed:2d}  idealised {hits['idealised'][-1].astype(int)}  robust "
              f"{hits['robust'][-1].astype(int)}  ({time.perf_counter() - t0:.0f} s)", flush=True)
    for name in hits:
        h = np.array(hits[name], float)
        n = h.size
        cov = h.mean()
        print(f"{name:9s} 90 % coverage {cov:.3f} ± {np.sqrt(cov * (1 - cov) / n):.3f} "
              f"(binomial se, {n} intervals = {h.shape[0]} seeds × 6)")
        print("          per entry " + "  ".join(f"{nm} {v:.2f}" for nm, v in
                                                zip(INERTIA_NAMES, h.mean(0))))
        print("          median sd " + "  ".join(f"{nm} {v:.2f}" for nm, v in
                                                zip(INERTIA_NAMES, np.median(sds[name], 0))))
        rh = np.array(conv[name])
        print(f"          max R-hat {rh[:, 0].max():.4f}, divergences {int(rh[:, 1].sum())}")


if __name__ == "__main__":
    main()
