"""
Inertia of a 12U CubeSat with a skew wheel and a MEMS gyro
==========================================================

A 12U CubeSat (``models/cubesat_12u.toml``: inertia 0.17-0.27 kg m², products of a few
thousandths, three wheels on the body axes plus a skew wheel along (1, 1, 1)/√3, no thrusters)
turns by 40 degrees about each axis and back on its wheels (scenario ``slews_cubesat_12u``). Its
sensors are a CubeSat's: a MEMS gyro with 1e-4 rad/s of white noise, a turn-on bias of ~2e-4
rad/s and a 0.1-0.2 % scale-factor error; wheel speeds from hall sensors in whole rpm. The momentum
balance of Feldman & Lee (2006, Eqs 2-11) is the same as Cassini's; what changes is the scale —
the wheels hold 50 mN m s, the slews exchange ~10 mN m s — and how well the sensors are known,
which the model file states (``[gyro] bias_sd_rad_s = 3e-4``, ``scale_factor_sd = 3e-3``,
``[torque_knowledge] sd_nm = 1e-6``): the robust inertia model integrates those errors out.

A spacecraft without thrusters has no ``on_*`` columns and no pulse log; its telemetry holds
``rwx rwy rwz rws`` (rpm). The script simulates the slews, fits the posterior of the six entries
with :func:`cassini_bayes.fit_inertia`, prints it beside the truth (moments in per cent of the
truth, products in kg m²) and saves the run directory.

Run ``python examples/inertia_cubesat.py --help`` for the settings.
"""

import argparse

import cassini_bayes as cb

NAMES = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")


def main(args):
    sim = cb.simulate_scenario(args.scenario, seed=args.seed)
    truth = sim.truth()["inertia_kgm2"]
    spacecraft = sim.prior          # models/cubesat_12u.toml, the scenario's [prior] model
    print(f"{spacecraft.name}: wheels {', '.join(spacecraft.wheel_names)}, "
          f"{'no thrusters' if not spacecraft.thrusters else 'thrusters'}")

    fit = cb.fit_inertia(sim.telemetry, spacecraft, seed=args.seed, chains=args.chains,
                         warmup=args.warmup, draws=args.draws)

    params = fit.summary()["parameters"]
    print(f"inertia tensor, kg m² (scenario {args.scenario!r}, seed {args.seed})")
    print(f"{'':4} {'truth':>9} {'post mean':>10} {'post sd':>9} {'90 % interval':>21} "
          f"{'error':>10}")
    for name in NAMES:
        p, t = params[name], truth[name]
        err = (f"{100 * (p['mean'] / t - 1):+9.2f}%" if name in NAMES[:3]
               else f"{p['mean'] - t:+10.5f}")
        print(f"{name:4} {t:9.5f} {p['mean']:10.5f} {p['sd']:9.5f} "
              f"[{p['q05']:9.5f}, {p['q95']:9.5f}] {err}")

    # The robust model's gyro bias per file and axis (rad/s), beside the scenario's truth.
    bias = fit.idata.posterior["gyro_bias"].mean(("chain", "draw")).values[0]
    print("gyro bias, rad/s: posterior mean " + " ".join(f"{b:+.2e}" for b in bias)
          + "; truth " + " ".join(f"{b:+.2e}" for b in sim.truth()["noise"]["gyro_bias_rad_s"]))
    d = fit.diagnostics
    print(f"converged: {fit.converged} (max R-hat {d.max_r_hat:.3f}, min bulk ESS "
          f"{d.min_ess_bulk:.0f}, divergences {d.divergences})")
    for line in fit.warnings:
        print(f"warning: {line}")
    out = fit.save(args.out, force=True)
    print(f"saved {out}")
    return fit


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description="Inertia of a 12U CubeSat from its slews")
    parser.add_argument("--scenario", default="slews_cubesat_12u",
                        help="shipped scenario name or scenario TOML path")
    parser.add_argument("--chains", type=int, default=4, help="NUTS chains")
    parser.add_argument("--warmup", type=int, default=1000, help="warm-up iterations per chain")
    parser.add_argument("--draws", type=int, default=1000, help="kept draws per chain")
    parser.add_argument("--seed", type=int, default=0, help="seed of the noise and the sampler")
    parser.add_argument("--out", default="runs/inertia_cubesat", help="run directory to write")
    args = parser.parse_args()
    cb.request_host_devices()   # one CPU device per chain, as the command line does
    main(args)
