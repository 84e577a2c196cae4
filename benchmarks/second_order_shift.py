"""How far the rate steps' second-order terms move the least-squares estimators' answers on one
noisy flight: the leak monitor's probabilities and fraction
(:func:`~cassini_bayes.inference.leak.leak_posterior`) and a thrust-health event summary
(:func:`~cassini_bayes.inference.health.event_summary`), each with the term
(:func:`~cassini_bayes.estimators.leak.rate_step_second_order`) and with it zeroed in the
modules that use it. Printed: the largest change of any probability at any check, the fraction's
change in its posterior sd and the monitor's adequacy statistics, and the largest change of a
channel's log thrust in its sd::

    python benchmarks/second_order_shift.py leak_cruise --leak --key 1
    python benchmarks/second_order_shift.py leak_espa_bus --leak --key 200 --clean --duration 14400
    python benchmarks/second_order_shift.py health_event --health --key 0
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys

import numpy as np

import cassini_bayes
from cassini_bayes.files import write_text

_USERS = ("cassini_bayes.inference.leak._inputs", "cassini_bayes.inference.health.summary")


@contextlib.contextmanager
def first_order_only():
    """Within: the modules that add the second-order term add zero (the code before it)."""
    import importlib

    mods = [importlib.import_module(m) for m in _USERS]
    keep = [m.rate_step_second_order for m in mods]

    def zero(t_s, *args):
        return np.zeros((np.size(t_s), 3))

    for m in mods:
        m.rate_step_second_order = zero
    try:
        yield
    finally:
        for m, f in zip(mods, keep):
            m.rate_step_second_order = f


def run(name: str, key: int, leak: bool, health: bool, duration_s: float | None = None,
        clean: bool = False) -> dict:
    """The answers with and without the term on scenario ``name`` flown with key ``key`` (over
    ``duration_s`` when given; without its leak when ``clean``)."""
    import dataclasses

    import jax

    from cassini_bayes.inference.health import event_summary
    from cassini_bayes.estimators.leak import ETA
    from cassini_bayes.inference.leak import SAMPLE_STEP_S, leak_inputs, leak_posterior
    from cassini_bayes.inference.leak_adequacy import leak_adequacy
    from cassini_bayes.simulate import load_scenario, simulate

    s = load_scenario(name)
    if duration_s:
        s = dataclasses.replace(s, duration_s=float(duration_s))
    if clean:
        s = dataclasses.replace(s, leak=None)
    sim = simulate(jax.random.key(key), s)
    out: dict = {"scenario": name, "key": key, "duration_s": s.duration_s, "clean": clean,
                 "package": cassini_bayes.__file__}
    res = {}
    for label in ("first", "second"):
        with first_order_only() if label == "first" else contextlib.nullcontext():
            res[label] = {}
            if leak:
                inp = leak_inputs(sim.telemetry, sim.pulses, s.prior)
                post = leak_posterior(inp)
                res[label]["leak"] = post
                res[label]["adequacy"] = leak_adequacy(inp, post, eta=ETA,
                                                       sample_step_s=SAMPLE_STEP_S)
            if health:
                res[label]["health"] = event_summary(sim.telemetry, sim.pulses, s.prior)
    if leak:
        a, b = res["first"]["leak"], res["second"]["leak"]
        out["leak"] = {
            "max_abs_prob_change": float(np.max(np.abs(a.prob - b.prob))),
            "p_leak_last": [float(a.p_leak[-1]), float(b.p_leak[-1])],
            "p_leak_max": [float(a.p_leak.max()), float(b.p_leak.max())],
            "detection_time_s": [a.detection_time_s, b.detection_time_s],
            "thruster": [a.thruster, b.thruster],
            "fraction_mean": [a.fraction_mean, b.fraction_mean],
            "fraction_sd": [a.fraction_sd, b.fraction_sd],
            "fraction_change_in_sd": (b.fraction_mean - a.fraction_mean) / a.fraction_sd,
            "adequacy": [{c.name: c.statistic for c in res[x]["adequacy"].checks}
                         for x in ("first", "second")]}
    if health:
        a, b = res["first"]["health"], res["second"]["health"]
        ok = a.observed & b.observed
        sd = np.sqrt(np.diag(a.cov)[ok])
        out["health"] = {
            "channels": [n for n, k in zip(a.channels.names, ok) if k],
            "log_thrust_change_in_sd": ((b.log_thrust[ok] - a.log_thrust[ok]) / sd).tolist(),
            "sd_ratio": (np.sqrt(np.diag(b.cov)[ok]) / sd).tolist()}
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scenario")
    ap.add_argument("--key", type=int, default=0)
    ap.add_argument("--leak", action="store_true")
    ap.add_argument("--health", action="store_true")
    ap.add_argument("--duration", type=float, default=None, help="s (default the scenario's)")
    ap.add_argument("--clean", action="store_true", help="without the scenario's leak")
    ap.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    if a.json:
        from _provenance import start

        start(a.json, vars(a), argv, replace=True)
    row = run(a.scenario, a.key, a.leak, a.health, a.duration, a.clean)
    if "leak" in row:
        m = row["leak"]
        print(f"{a.scenario} key {a.key} leak: max |dP| {m['max_abs_prob_change']:.3g}; "
              f"P(leak) {m['p_leak_last'][0]:.6g} -> {m['p_leak_last'][1]:.6g} (largest "
              f"{m['p_leak_max'][0]:.3g} -> {m['p_leak_max'][1]:.3g}); detection "
              f"{m['detection_time_s'][0]} -> {m['detection_time_s'][1]} s "
              f"({m['thruster'][0]} -> {m['thruster'][1]}); fraction "
              f"{m['fraction_mean'][0]:.6g} -> {m['fraction_mean'][1]:.6g} "
              f"(sd {m['fraction_sd'][0]:.3g}: {m['fraction_change_in_sd']:+.3g} sd)")
        for label, ad in zip(("first", "second"), m["adequacy"]):
            print(f"  adequacy, {label} order: " + ", ".join(
                f"{k} {'n/a' if v is None else format(v, '.3g')}" for k, v in ad.items()))
    if "health" in row:
        m = row["health"]
        d = np.asarray(m["log_thrust_change_in_sd"])
        print(f"{a.scenario} key {a.key} health: log-thrust change, largest "
              f"{np.max(np.abs(d)):.3g} sd over {d.size} channels; sd ratio "
              f"{min(m['sd_ratio']):.4f}-{max(m['sd_ratio']):.4f}")
    if a.json:
        write_text(a.json, json.dumps(row, indent=1))
    return 0


if __name__ == "__main__":
    cassini_bayes.setup_jax()
    sys.exit(main())
