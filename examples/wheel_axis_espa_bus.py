"""
The spin axis of one wheel of an ESPA-class bus
===============================================

Brown (2012) calibrated the axis of Cassini's re-articulated RWA4 from the momentum balance: the
spacecraft's total angular momentum is the same, in inertial axes, before ("Time A") and after
("Time B") a slew carried by the wheels, so the one unknown axis must make the two agree (Brown
Eq 3, the RWA method). Nothing in it is Cassini's: this example calibrates RW2 of a 180 kg
ESPA-class bus (``models/espa_bus.toml``, four wheels in a pyramid about +Z). In scenario
``wheel_axis_espa_bus`` RW2 is biased to 3000 rpm, its true axis 1.0° off the model file's, and
the four wheels fly four slew pairs (Z, X, Y and a multi-axis slew, out and back) with 200-s
pauses.

:func:`cassini_bayes.fit_wheel_axis` (what ``cassini-bayes fit wheel-axis`` runs) detects the
Time A / Time B windows from the quiet periods, samples the axis on the unit sphere with the
inertia's uncertainty and the robust model's gyro, wheel and torque errors, and reports the mean
axis and its cones. The bus's model gives RW2 no articulation cone, so the prior is uniform on the
sphere and the articulation-cone check is not run (a wheel entry with ``cone_axis`` and
``cone_deg`` allows ``prior="cone"``; docs/model_file.md). The parameters are named ``u4_x,
u4_y, u4_z`` for any wheel, Brown's notation; the summary's ``wheel`` block names the wheel.

Run ``python examples/wheel_axis_espa_bus.py --help`` for the settings.
"""

import argparse

import numpy as np

import cassini_bayes as cb


def angle_deg(u, v):
    """Angle between two directions, degrees."""
    u, v = np.asarray(u, float), np.asarray(v, float)
    cos = np.dot(u, v) / (np.linalg.norm(u) * np.linalg.norm(v))
    return float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))


def main(args):
    sim = cb.simulate_scenario(args.scenario, seed=args.seed)
    wheels = {w["name"]: w for w in sim.truth()["wheels"]}
    true_axis = wheels[args.wheel.upper()]["axis"]
    model_axis = sim.prior.wheel(args.wheel).axis

    fit = cb.fit_wheel_axis(sim.telemetry, sim.prior, wheel=args.wheel, method="rwa",
                            seed=args.seed, chains=args.chains, warmup=args.warmup,
                            draws=args.draws)

    summary = fit.summary()
    mean = summary["direction"]["mean"]
    cones = summary["direction"]["cone_deg"]
    print(f"{summary['wheel']['name']} spin axis, body frame (RWA method, scenario "
          f"{args.scenario!r}, {len(summary['windows'])} window pairs detected)")
    print(f"  model file      [{model_axis[0]: .5f}, {model_axis[1]: .5f}, {model_axis[2]: .5f}]  "
          f"{angle_deg(model_axis, true_axis):.3f} deg from the truth")
    print(f"  truth           [{true_axis[0]: .5f}, {true_axis[1]: .5f}, {true_axis[2]: .5f}]")
    print(f"  posterior mean  [{mean[0]: .5f}, {mean[1]: .5f}, {mean[2]: .5f}]  "
          f"{angle_deg(mean, true_axis):.3f} deg from the truth")
    ls = [fit.baseline[n] for n in ("u4_x", "u4_y", "u4_z")]
    print(f"  least squares   [{ls[0]: .5f}, {ls[1]: .5f}, {ls[2]: .5f}]  "
          f"{angle_deg(ls, true_axis):.3f} deg from the truth")
    print(f"  cone radius: 90 % {cones['90']:.3f} deg, 95 % {cones['95']:.3f} deg")
    d = fit.diagnostics
    print(f"converged: {fit.converged} (max R-hat {d.max_r_hat:.3f}, divergences "
          f"{d.divergences}); adequacy {'passed' if summary['adequacy']['ok'] else 'FAILED'}")
    for line in fit.warnings:
        print(f"warning: {line}")
    out = fit.save(args.out, force=True)  # replaces only a run this package wrote
    print(f"saved {out}")
    return fit


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description="A wheel's spin axis on an ESPA-class bus")
    parser.add_argument("--scenario", default="wheel_axis_espa_bus",
                        help="shipped scenario name or scenario TOML path")
    parser.add_argument("--wheel", default="RW2", help="the wheel whose axis is calibrated")
    parser.add_argument("--chains", type=int, default=4, help="NUTS chains")
    parser.add_argument("--warmup", type=int, default=1000, help="warm-up iterations per chain")
    parser.add_argument("--draws", type=int, default=1000, help="kept draws per chain")
    parser.add_argument("--seed", type=int, default=0, help="seed of the noise and the sampler")
    parser.add_argument("--out", default="runs/wheel_axis_espa_bus", help="run directory to write")
    args = parser.parse_args()
    cb.request_host_devices()   # one CPU device per chain, as the command line does
    main(args)
