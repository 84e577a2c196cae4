"""Per-wheel vs common wheel spin-inertia errors in the robust inertia model (docs/robust/
per_wheel.md).

Data: the multi-axis noisy slews of ``tests/test_inference_inertia.py`` (``make_slews``: Y, X,
Y, Z and a skew axis, wheels RWA1-3), once with every wheel's true spin inertia off by its own
fraction (``--errors``, the telemetry's wheel rates made with the true inertias, the fit given the
model file's) and once clean. Each case is fitted with the robust model twice,
``wheel_errors="per_wheel"`` and ``"common"``, and the script prints per entry the posterior mean's
distance from the truth in posterior sd, the posterior sd, whether the 90 % and 99 % intervals
cover, and per fit the largest R-hat, the divergences and the wall time. Not a test.

    python benchmarks/per_wheel_inertia.py [--errors 0.008 -0.009 0.006] [--chains 4]
        [--warmup 500] [--draws 500] [--seed 0] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--errors", type=float, nargs="+", default=[0.008, -0.009, 0.006],
                    help="true spin-inertia error of RWA1, RWA2, RWA3 (fractions)")
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--warmup", type=int, default=500)
    ap.add_argument("--draws", type=int, default=500)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    sys.path.insert(0, str(ROOT / "tests"))

    import jax
    import numpy as np

    from cassini_bayes.inference.inertia import fit_inertia
    from cassini_bayes.inference.runner import SamplerSettings
    from cassini_bayes.physics.momentum import INERTIA_NAMES, inertia_vector
    from cassini_bayes.spacecraft import load_spacecraft
    from slews import TRUTH, make_slews

    truth = np.asarray(inertia_vector(TRUTH))
    sc = load_spacecraft("cassini_2000_03_15")
    err = np.zeros(len(sc.wheels))
    err[:len(args.errors)] = args.errors
    true_sc = replace(sc, wheels=tuple(replace(w, inertia=w.inertia * (1.0 + e))
                                       for w, e in zip(sc.wheels, err)))
    cases = {"per-wheel errors": make_slews(jax.random.key(11), true_sc),
             "clean": make_slews(jax.random.key(11), sc)}
    settings = SamplerSettings(chains=args.chains, warmup=args.warmup, draws=args.draws)
    out = {"errors": list(err), "settings": settings._asdict(), "fits": []}
    for case, tel in cases.items():
        for model in ("per_wheel", "common"):
            t0 = time.perf_counter()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                post = fit_inertia(jax.random.key(args.seed), [tel], sc, robust=True,
                                   wheel_errors=model, settings=settings, prior_draws=100)
            wall = time.perf_counter() - t0
            p = post.idata.posterior
            rows = {}
            for i, n in enumerate(INERTIA_NAMES):
                x = p[n].values.ravel()
                q = np.quantile(x, [0.005, 0.05, 0.95, 0.995])
                rows[n] = {"z": float((x.mean() - truth[i]) / x.std()), "sd": float(x.std()),
                           "in90": bool(q[1] <= truth[i] <= q[2]),
                           "in99": bool(q[0] <= truth[i] <= q[3])}
            d = post.diagnostics
            scale = p["wheel_scale"].values.reshape(-1, *p["wheel_scale"].shape[2:])
            rec = {"case": case, "model": model, "entries": rows, "max_r_hat": d.max_r_hat,
                   "divergences": d.divergences, "wall_s": wall,
                   "wheel_scale_mean": np.atleast_1d(scale.mean(0)).tolist(),
                   "wheel_scale_sd": np.atleast_1d(scale.std(0)).tolist()}
            out["fits"].append(rec)
            print(f"{case:17s} {model:9s} R-hat {d.max_r_hat:.4f} div {d.divergences} "
                  f"{wall:6.1f} s  wheel_scale {np.round(rec['wheel_scale_mean'], 4)} "
                  f"± {np.round(rec['wheel_scale_sd'], 4)}")
            for n, r in rows.items():
                print(f"    {n}: z {r['z']:+6.2f}  sd {r['sd']:7.2f}  "
                      f"90% {'in ' if r['in90'] else 'OUT'}"
                      f"  99% {'in ' if r['in99'] else 'OUT'}")
    if args.json:
        args.json.write_text(json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    main()
