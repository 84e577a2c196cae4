"""A few replicates of the per-thruster robust thrust SBC on the ESPA bus, looked at closely.

The ``thrust`` SBC adapter (``--set robust=true --set mode=thruster``, its ESPA scenario
``sbc/sbc_thrust_espa_bus.toml``) draws each replicate's truth from the fit's prior and flies it
(public :func:`cassini_bayes.analysis.sbc_models.build_model`). For each replicate this records
what the campaign's ranks do not show:

* the noise centre: pulses and samples, the second differences free of pulses (the noise
  estimate's input, :func:`cassini_bayes.inference.noise.pulse_bent`), and the estimated white
  noise ``σ̂_ω``, ``σ̂_ρ`` over the scenario's sensors';
* the common scale of inertia, wheel inertias and thrust, which one event cannot see: the drawn
  wheels' mean spin-inertia scale ``mean c_k`` and its z under the prior (``c_s + mean d_k``),
  and, with ``--fit``, the fraction of posterior draws below the truth for the moments and
  the wheel scales (a calibrated posterior puts a truth drawn z sd out along an unidentified
  direction at rank ``Φ(z)``).

Keys: the truths and flights from ``split(key(--key), 2 n)`` (the first ``n`` draw, the last
``n`` fly), the fits from ``key(0) … key(n − 1)``. Not a test: nothing is asserted.

    python benchmarks/sbc_thrust_trial.py [--replicates 3] [--key 1] [--fit]
        [--chains 2 --warmup 300 --draws 300] [--json out.json]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "cassini_bayes/data/experiments/scenarios/sbc/sbc_thrust_espa_bus.toml"
MOMENTS = ("Ixx", "Iyy", "Izz")


def _noise_centre(arrays, scenario) -> dict:
    """Pulses, samples, unbent second differences and the noise estimate over the sensors'."""
    import numpy as np

    from cassini_bayes.inference.noise import pulse_bent, rate_noise_levels
    from cassini_bayes.plan.wheel_axis import scenario_noise
    from cassini_bayes.simulate.run import measured_telemetry, pulse_log

    tel = measured_telemetry(arrays, scenario, "<sbc thrust trial>")
    log = pulse_log(arrays, scenario)
    bent = pulse_bent(np.asarray(tel.t, float), log.t_on, log.width)
    hat = rate_noise_levels(tel, bent)
    sensor = np.asarray(scenario_noise(scenario)[:2], float)
    return {"pulses": int(len(log.t_on)), "samples": int(len(tel.t)),
            "differences": int(bent.size), "unbent": int(np.count_nonzero(~bent)),
            "noise_over_sensor": (hat / sensor).tolist()}


def _common_scale(truth: dict, scenario, wheels: tuple[str, ...]) -> dict:
    """The drawn wheels' common scale ``u`` (``NuisanceLayout.common_scale_weights``: their
    precision-weighted mean scale, the plain mean where their knowledge is equal) and its z
    under its prior."""
    import numpy as np

    from cassini_bayes.inference.nuisance import nuisance_layout

    layout = nuisance_layout(scenario.prior, 1, wheels, wheel_errors="per_wheel")
    weights = layout.common_scale_weights[:layout.n_scales]
    mean = float(weights @ np.array([truth[f"wheel_scale[{w}]"] for w in wheels]))
    return {"mean_wheel_scale": mean, "z_common": mean / layout.common_scale_sd}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--replicates", type=int, default=3)
    ap.add_argument("--key", type=int, default=1)
    ap.add_argument("--fit", action="store_true", help="fit each replicate (NUTS)")
    ap.add_argument("--chains", type=int, default=2)
    ap.add_argument("--warmup", type=int, default=300)
    ap.add_argument("--draws", type=int, default=300)
    ap.add_argument("--json", type=Path, help="write the record here (with a manifest)")
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)

    import jax
    import numpy as np
    from statistics import NormalDist

    import cassini_bayes as cb
    from cassini_bayes.analysis.sbc_models import ModelSpec, build_model
    from cassini_bayes.simulate.scenario import load_scenario

    cb.setup_jax()
    path = SCENARIO
    opts = (("mode", "thruster"), ("num_chains", args.chains), ("num_draws", args.draws),
            ("num_warmup", args.warmup), ("robust", True), ("thin", 1))
    model = build_model(ModelSpec("thrust", path.read_text(), opts, str(path)))
    scenario = load_scenario(str(path))
    wheels = tuple(n[len("wheel_scale["):-1] for n in model.parameter_names
                   if n.startswith("wheel_scale["))
    n = args.replicates
    keys = jax.random.split(jax.random.key(args.key), 2 * n)
    truths, arrays = model.simulate_batch(keys[:n], keys[n:])
    rows = []
    for i in range(n):
        one = jax.tree.map(lambda x, i=i: x[i], arrays)
        truth = {k: float(v[i]) for k, v in truths.items()}
        row = {"replicate": i, **_noise_centre(one, scenario),
               **_common_scale(truth, scenario, wheels)}
        row["phi_z_common"] = NormalDist().cdf(row["z_common"])
        if args.fit:
            t0 = time.perf_counter()
            fit = model.fit(jax.random.key(i), one)
            below = {k: float(np.mean(np.asarray(fit.draws[k]) < truth[k]))
                     for k in MOMENTS + tuple(f"wheel_scale[{w}]" for w in wheels)}
            row.update(fraction_below=below, divergences=int(fit.n_divergent),
                       fit_seconds=time.perf_counter() - t0)
        rows.append(row)
        print(f"replicate {i}: {row['pulses']} pulses / {row['samples']} samples, "
              f"{row['unbent']} of {row['differences']} unbent, noise/sensor "
              + "/".join(f"{x:.2f}" for x in row["noise_over_sensor"])
              + f", mean c_k {100 * row['mean_wheel_scale']:+.2f} % (z {row['z_common']:+.2f})"
              + (f", below truth {min(row['fraction_below'].values()):.2f}–"
                 f"{max(row['fraction_below'].values()):.2f}" if args.fit else ""),
              file=sys.stderr, flush=True)
    if args.json:
        from _provenance import write_json

        write_json(args.json, {"scenario": scenario.name, "wheels": list(wheels),
                               "replicates": rows})


if __name__ == "__main__":
    main()
