"""The Bayesian leak monitor on the ESPA bus: each thruster leaking at three sizes, and clean
stretches.

``experiments/scenarios/leak_espa_bus.toml`` (30 min holding attitude on the RCS dead-band
controller, the leak from 630 s) with its leak moved to each of the model's thrusters in turn at
10 %, 1 % and 0.1 % of its thrust (noise seed ``100 + k`` for thruster ``k``), and the same
scenario without the leak over ``--clean-hours`` (seeds 200, 201, …). Each stretch goes through
the public API (``simulate_scenario``, ``monitor_leak`` at its defaults, the model file as the
prior). The record holds, per run, the truth (thruster, fraction of its true thrust, onset, the
fraction in the monitor's units: of the model file's thrust) and the monitor's answer (detection,
isolation, fraction and onset with their sd, the largest ``P(leak)`` before the onset, the
adequacy verdict); the table kind ``leak_espa`` reads it. Not a test: nothing is asserted.

    python benchmarks/leak_espa.py [--json leak_espa.json] [--clean 3] [--clean-hours 4]
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np

SCENARIO = "leak_espa_bus"
FRACTIONS = (0.1, 0.01, 0.001)
LEAK_SEED, CLEAN_SEED = 100, 200


def _run(scenario, seed: int) -> dict:
    """One stretch simulated and monitored: the monitor's answer and its P(leak) by check."""
    import cassini_bayes as cb

    sim = cb.simulate_scenario(scenario, seed=seed)
    t0 = time.perf_counter()
    res = cb.monitor_leak(sim.telemetry, scenario.prior, pulses=sim.pulses)
    post, s = res.posterior, res.summary()
    return {"seed": seed, "monitor_s": time.perf_counter() - t0,
            "bayes": s["bayes"], "adequacy_ok": s["adequacy"]["ok"],
            "adequacy": {k: c["statistic"] for k, c in s["adequacy"]["checks"].items()},
            "t_check_s": post.t_check.tolist(), "p_leak": post.p_leak.tolist()}


def leak_runs(base) -> list[dict]:
    """Every thruster at every size of :data:`FRACTIONS`."""
    from cassini_bayes.simulate import truth_params
    from cassini_bayes.simulate.scenario import Leak

    true_f = np.asarray(truth_params(base).thrust_n, float)
    model_f = np.asarray(base.prior.thrust_per_thruster, float)
    onset = base.leak.t_start_s
    rows = []
    for frac in FRACTIONS:
        for k, name in enumerate(base.prior.thruster_names):
            s = dataclasses.replace(base, leak=Leak(k, frac, onset))
            r = _run(s, LEAK_SEED + k)
            rows.append({"fraction": frac, "thruster": name, "onset_s": onset,
                         "fraction_model_units": frac * true_f[k] / model_f[k], **r})
            b = r["bayes"]
            print(f"{frac:6.3f} {name}: detected {b['detection_time_s']}, isolated "
                  f"{b['thruster']} at {b['isolation_time_s']}, fraction "
                  f"{b['fraction_mean']:.5f} ± {b['fraction_sd']:.5f}", flush=True)
    return rows


def clean_runs(base, n: int, hours: float) -> list[dict]:
    """``n`` stretches of ``hours`` without the leak."""
    s = dataclasses.replace(base, leak=None, duration_s=hours * 3600.0)
    rows = []
    for i in range(n):
        r = _run(s, CLEAN_SEED + i)
        rows.append({"hours": hours, **r})
        print(f"clean {i}: detected {r['bayes']['detection_time_s']}, largest P(leak) "
              f"{max(r['p_leak']):.4f}", flush=True)
    return rows


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", type=Path, help="write the record here (with a manifest)")
    ap.add_argument("--clean", type=int, default=3, help="clean stretches")
    ap.add_argument("--clean-hours", type=float, default=4.0)
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    from cassini_bayes.simulate import load_scenario

    base = load_scenario(SCENARIO)
    record = {"scenario": SCENARIO, "leaks": leak_runs(base),
              "clean": clean_runs(base, args.clean, args.clean_hours)}
    from _tables_leak import leak_espa_table

    print(leak_espa_table(record))
    if args.json:
        from _provenance import write_json

        write_json(args.json, record)


if __name__ == "__main__":
    main()
