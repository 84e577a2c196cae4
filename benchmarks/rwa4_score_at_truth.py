"""Is the wheel-axis likelihood proper? The expected score of the inertia's overall scale at the
truth, over SBC truths (docs/sbc/rwa4_rwa_robust_espa/README.md; docs/robust/README.md, "RWA4
spin axis").

For a proper likelihood ``E[∂ log p(data | θ)/∂θ]`` at the true ``θ`` is 0 whatever the data.
Each replicate is drawn and flown exactly as the ``rwa4`` SBC adapter does (its truth from the
fit's priors, every robust nuisance effect drawn, replicate ``i``'s key ``fold_in(key(seed), i)``),
prepared as ``fit_wheel_axis`` prepares it, and the score of ``π → k π`` at ``k = 1`` (the other
coordinates at the truth) taken by central differences (±1 %) of

- ``fixed``: :func:`cassini_bayes.inference.rwa4.likelihood.loglik`, the white-noise part of
  its normalising determinant at the prior-mean inertia and the chart's centre axis;
- ``sampled``: the same Gaussian with the whole determinant at the sampled inertia and axis
  (the likelihood before bddbbf8).

    python benchmarks/rwa4_score_at_truth.py [--scenario wheel_axis_espa_bus] [--wheel RW2]
        [--replicates 64] [--seed 1] [--json score.json]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def scores(scenario: Path, wheel: str, n: int, seed: int) -> dict[str, list[float]]:
    """Per replicate, the two likelihoods' scores of the inertia scale at the truth."""
    import jax
    import jax.numpy as jnp

    from cassini_bayes.analysis._campaign_batch import _programs, replicate_keys
    from cassini_bayes.analysis.sbc_models._contract import ModelSpec, build_model
    from cassini_bayes.inference.rwa4.data import prepare_rwa4
    from cassini_bayes.inference.rwa4.likelihood import DATA_KEYS, loglik, rows
    from cassini_bayes.simulate.run import measured_telemetry

    spec = ModelSpec.make("rwa4", scenario.read_text(), scenario_source=scenario.name,
                          robust=True, wheel=wheel, method="rwa")
    adapter = build_model(spec).simulate_batch.__self__
    truth, arrays = _programs(spec)[1](replicate_keys(seed, np.arange(n)))
    out: dict[str, list[float]] = {"fixed": [], "sampled": []}
    for i in range(n):
        tel = measured_telemetry(jax.tree.map(lambda a, i=i: np.asarray(a[i]), arrays),
                                 adapter.scenario, f"<replicate {i}>")
        kw = prepare_rwa4(tel, adapter.scenario.prior, method="rwa", wheel=wheel,
                          robust=True).data
        data = {k: getattr(kw, k) for k in DATA_KEYS}
        u, pi = jnp.asarray(truth[i, :3]), truth[i, 3:]

        def fixed(k):
            return float(loglik(u, jnp.asarray(k * pi), kw.log_noise_hat, u_ref=kw.u0,
                                pi_ref=kw.pi_mean, **data))

        def sampled(k):
            d, cov, cols = (np.asarray(x) for x in rows(u, jnp.asarray(k * pi),
                                                          kw.log_noise_hat, **data))
            s = cov + cols @ cols.T
            return -0.5 * (d @ np.linalg.solve(s, d) + np.linalg.slogdet(s)[1])

        for name, f in (("fixed", fixed), ("sampled", sampled)):
            out[name].append((f(1.01) - f(0.99)) / 0.02)
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="wheel_axis_espa_bus",
                    help="a shipped scenario's name or a scenario TOML path")
    ap.add_argument("--wheel", default="RW2")
    ap.add_argument("--replicates", type=int, default=64)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    import cassini_bayes
    from cassini_bayes.simulate.scenario import scenario_path

    cassini_bayes.setup_jax()
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    t0 = time.perf_counter()
    s = scores(Path(scenario_path(args.scenario)), args.wheel, args.replicates, args.seed)
    summary = {name: {"mean": float(np.mean(v)), "se": float(np.std(v, ddof=1) / np.sqrt(len(v)))}
               for name, v in s.items()}
    for name, m in summary.items():
        print(f"{name:8s} score of the inertia scale at the truth: {m['mean']:+.2f} "
              f"± {m['se']:.2f} (mean ± se over {args.replicates} replicates)")
    if args.json:
        from _provenance import write_json

        write_json(args.json, {"scenario": args.scenario, "wheel": args.wheel,
                               "replicates": args.replicates, "seed": args.seed,
                               "summary": summary, "scores": s,
                               "seconds": time.perf_counter() - t0})


if __name__ == "__main__":
    main()
