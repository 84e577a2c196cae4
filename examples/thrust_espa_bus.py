"""
Each thruster's thrust, and the centre of mass, of an ESPA-class bus
====================================================================

Feldman & Lee (2006, Eqs 14-23) calibrated Cassini's thrust from the momentum each pulse gives the
spacecraft: its angular impulse is the thrust times the moment arm ``r × d`` of the thruster's
position ``r`` and direction ``d``, times an effective on-time set by the valve's delay, rise and
fall. Cassini fitted one common thrust. The eight canted thrusters of a 180 kg ESPA-class bus
(``models/espa_bus.toml``) differ by a few per cent and fire against each other, so one common
thrust is no model for them: this example fits one thrust per thruster, ``F[<name>]``, and the
centre of mass's offset from the model file's (``com_x, com_y, com_z``, m), which moves every
moment arm.

Scenario ``pulses_espa_bus``: each thruster fires six open-loop pulses of its own (125-500 ms)
while the four pyramid wheels hold the attitude; the true thrusts are within ±4 % of the nominal
1 N, the valve time constants off the model's nominal ones, the centre of mass 1 cm from the
prediction. :func:`cassini_bayes.fit_thrust` with ``mode="thruster"`` (what ``cassini-bayes fit
thrust --mode thruster`` runs) samples them with the inertia's uncertainty and the robust model's
gyro, wheel and torque errors, and prints each thrust beside the truth.

Run ``python examples/thrust_espa_bus.py --help`` for the settings.
"""

import argparse

import numpy as np

import cassini_bayes as cb


def main(args):
    sim = cb.simulate_scenario(args.scenario, seed=args.seed)
    truth = sim.truth()
    fit = cb.fit_thrust(sim.telemetry, sim.pulses, sim.prior, mode="thruster", seed=args.seed,
                        chains=args.chains, warmup=args.warmup, draws=args.draws)

    summary = fit.summary()
    params = summary["parameters"]
    print(f"thrust per thruster, scenario {args.scenario!r} (90 % interval; truth)")
    covered = []
    for name, f_true in truth["thrust_n"].items():
        p = params[f"F[{name}]"]
        hit = p["q05"] <= f_true <= p["q95"]
        covered.append(hit)
        print(f"  F[{name}]  {p['mean']:.4f} N  [{p['q05']:.4f}, {p['q95']:.4f}]  truth "
              f"{f_true:.4f}  error {100 * (p['mean'] / f_true - 1):+.2f} %"
              f"{'' if hit else '  (not covered)'}")
    com_true = np.asarray(truth["center_of_mass_offset_m"], float)
    for axis, c_true in zip("xyz", com_true):
        p = params[f"com_{axis}"]
        print(f"  com_{axis}    {1e3 * p['mean']:+.2f} mm  [{1e3 * p['q05']:+.2f}, "
              f"{1e3 * p['q95']:+.2f}]  truth {1e3 * c_true:+.2f} mm")
    print(f"{sum(covered)} of {len(covered)} thrusts inside their 90 % interval")
    d = fit.diagnostics
    print(f"converged: {fit.converged} (max R-hat {d.max_r_hat:.3f}, divergences "
          f"{d.divergences}); adequacy {'passed' if summary['adequacy']['ok'] else 'FAILED'}")
    for line in fit.warnings:
        print(f"warning: {line}")
    out = fit.save(args.out, force=True)  # replaces only a run this package wrote
    print(f"saved {out}")
    return fit


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description="Per-thruster thrust of an ESPA-class bus")
    parser.add_argument("--scenario", default="pulses_espa_bus",
                        help="shipped scenario name or scenario TOML path")
    parser.add_argument("--chains", type=int, default=4, help="NUTS chains")
    parser.add_argument("--warmup", type=int, default=1000, help="warm-up iterations per chain")
    parser.add_argument("--draws", type=int, default=1000, help="kept draws per chain")
    parser.add_argument("--seed", type=int, default=0, help="seed of the noise and the sampler")
    parser.add_argument("--out", default="runs/thrust_espa_bus", help="run directory to write")
    args = parser.parse_args()
    cb.request_host_devices()   # one CPU device per chain, as the command line does
    main(args)
