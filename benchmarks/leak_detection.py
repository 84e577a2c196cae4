"""Leak-detection campaign: the Bayesian monitor against Lee's threshold monitor.

Simulated cruise stretches (``experiments/scenarios/leak_cruise.toml``: attitude held by the RCS
dead-band controller) of ``--hours`` each, every one with its own thruster-to-thruster variation
(true thrusts 0.699 N × (1 + 0.05 z), Lee's η), external body torque (N(0, 15 µN m) per axis)
and gyro/tach noise. Leak runs: every thruster Z1 … Y4 at three sizes — Lee's cruise requirement
(an average torque of 0.005 N m on the most affected axis), 10 % of thrust (Lee's Fig. 6 case)
and 0.1 % of thrust (his sensitivity claim) — with the onset drawn in [600, 3600] s. Control runs:
no leak. Both monitors see the same telemetry, pulse log and prior spacecraft model.

Decision rules, fixed before the runs: Bayesian — alarm (detection) at the first check (every
60 s, residual every 60 s) with P(leak) ≥ 0.99, isolation at the first with one thruster's
P ≥ 0.99, prior probability of a leak 0.01 per stretch; Lee — R_T = 50 N m s, T_limit = 10 h,
Eq 11 correction with η = 0.05, isolation by the polarities of R at the trigger. An alarm before
the onset, or on a control run, is a false alarm.

    python benchmarks/leak_detection.py [--hours 4] [--reps 2] [--controls 16] [--out FILE.json]
        [--open-world] [--sizes requirement 10 0.1 none]

Prints the campaign table (``_tables_leak.campaign_table``; docs/leak.md generates it from the
``--out`` records, kind ``leak_campaign``). Never a timed test.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time

import jax
import numpy as np

from _tables_leak import campaign_table
from cassini_bayes.estimators.leak import threshold_monitor
from cassini_bayes.inference.leak import leak_inputs, leak_posterior
from cassini_bayes.physics.impulse import THRUSTER_NAMES
from cassini_bayes.simulate import load_scenario, pulse_log, simulate_batch, truth_params
from cassini_bayes.simulate.scenario import Leak
from cassini_bayes.telemetry import Telemetry

ETA, TORQUE_SD_NM, REQUIREMENT_NM = 0.05, 15e-6, 0.005


def _truths(s, rng, b, open_world: bool = False):
    """``b`` true parameter sets: the scenario's, with thrusts and body torque drawn — from the
    monitor's own laws (Normal, η = 5 %; Normal, 15 µN m), or, ``open_world``, from other and
    wider ones: thrusts uniform within ±10 % (sd 5.8 %), torques Laplace with 1.5 × the sd."""
    base = truth_params(s)
    batch = base._make(np.broadcast_to(np.asarray(x), (b,) + np.shape(x)) for x in base)
    if open_world:
        err = rng.uniform(-0.10, 0.10, (b, 8))
        torque = rng.laplace(0.0, 1.5 * TORQUE_SD_NM / np.sqrt(2.0), (b, 3))
    else:
        err = ETA * rng.standard_normal((b, 8))
        torque = TORQUE_SD_NM * rng.standard_normal((b, 3))
    return batch._replace(thrust_n=s.prior.thrust * (1.0 + err), torque_body_nm=torque)


def _run(s, rng, b, seed, open_world: bool = False):
    arr = simulate_batch(jax.random.split(jax.random.PRNGKey(seed), b), s,
                         _truths(s, rng, b, open_world))
    arr = jax.tree_util.tree_map(np.asarray, arr)
    out = []
    for i in range(b):
        a = jax.tree_util.tree_map(lambda x: x[i], arr)
        tel = Telemetry(t=a.t_meas, q=a.q_meas, omega=a.omega_meas,
                        wheel_rates=a.wheel_rates_meas, wheel_names=s.wheel_names,
                        on_times=a.on_times, source=f"<{s.name}>")
        inp = leak_inputs(tel, pulse_log(a, s), s.prior)
        bay = leak_posterior(inp, check_step_s=60.0)
        lee = threshold_monitor(inp.t, inp.residual, inp.impulse, inp.q_matrix)
        out.append({"bayes": (bay.detection_time_s, bay.thruster, bay.isolation_time_s),
                    "lee": (lee.detection_time_s,
                            None if lee.thruster is None else THRUSTER_NAMES[lee.thruster],
                            lee.detection_time_s)})
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hours", type=float, default=4.0)
    ap.add_argument("--reps", type=int, default=2)
    ap.add_argument("--controls", type=int, default=16)
    ap.add_argument("--seed", type=int, default=17)
    ap.add_argument("--out", default=None)
    ap.add_argument("--open-world", action="store_true",
                    help="draw thrusts (uniform ±10 %%) and torques (Laplace, 1.5 × sd) from "
                         "laws other and wider than the monitor's priors")
    ap.add_argument("--sizes", nargs="+", default=None,
                    help="leak sizes to run (default: all three); 'none' runs controls only")
    args = ap.parse_args()
    if args.out:
        from _provenance import start

        start(args.out, vars(args), None, replace=True)
    rng = np.random.default_rng(args.seed)
    base = load_scenario("leak_cruise")
    base = dataclasses.replace(base, duration_s=args.hours * 3600.0)
    f_n = base.prior.thrust
    arms = np.max(np.abs(base.prior.moment_matrix), axis=0)
    sizes = {"requirement 0.005 N m": lambda k: REQUIREMENT_NM / (f_n * arms[k]),
             "10 % of thrust": lambda k: 0.1, "0.1 % of thrust": lambda k: 0.001}
    if args.sizes is not None:
        sizes = {k: v for k, v in sizes.items() if k.split()[0] in args.sizes}
    rows, t0 = [], time.time()
    for label, frac in sizes.items():
        for k, name in enumerate(THRUSTER_NAMES):
            onset = float(np.round(rng.uniform(600.0, 3600.0)))
            s = dataclasses.replace(base, leak=Leak(k, float(frac(k)), onset))
            for r in _run(s, rng, args.reps, int(rng.integers(2**31)), args.open_world):
                rows.append({"size": label, "thruster": name, "fraction": float(frac(k)),
                             "onset_s": onset, **r})
        print(f"{label}: done ({time.time() - t0:.0f} s)", flush=True)
    ctrl = dataclasses.replace(base, leak=None)
    controls = _run(ctrl, rng, args.controls, int(rng.integers(2**31)), args.open_world)
    print(f"controls: done ({time.time() - t0:.0f} s)", flush=True)
    print(campaign_table([(rows, controls, args.hours)]))
    if args.out:
        with open(args.out, "w") as f:
            json.dump({"args": vars(args), "leak_runs": rows, "controls": controls}, f, indent=1)


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    main()
