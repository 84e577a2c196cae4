"""
Inertia of an ESPA-class smallsat bus from its own wheel slews
==============================================================

Nothing in the momentum balance of Feldman & Lee (2006, AAS 06-102, Eqs 2-11) is Cassini's:
``R(q) (I ω + Σ_k J_k ρ_k g_k) = H0`` holds for any spacecraft and any set of wheels. This example
calibrates a 180 kg ESPA-class bus (``models/espa_bus.toml``: inertia ~20-27 kg m² with products
of a few tenths, four wheels in a pyramid about +Z, eight canted thrusters that the slews never
use) from six 30-degree slews flown by its four wheels (scenario ``slews_espa_bus``: the
simulator allocates the controller's torque with the pseudo-inverse of the wheel axes and holds
each wheel within the model file's speed and torque limits).

The model file names the wheels, so the telemetry's wheel columns are ``rw1 … rw4`` (rpm, signed
along each wheel's axis), and the robust model's per-wheel nuisance parameters
(``wheel_scale``, ``wheel_tilt``) carry those names. The script simulates the slews, fits the
posterior of the six entries with :func:`cassini_bayes.fit_inertia`, prints it beside the truth
(moments in per cent of the truth, against the papers' ±1 % budget) and the least-squares
baseline, and saves the run directory that ``cassini-bayes fit inertia`` would write.

Run ``python examples/inertia_espa_bus.py --help`` for the settings.
"""

import argparse

import cassini_bayes as cb

NAMES = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")


def main(args):
    # Synthetic telemetry of the bus's slews; ``truth()`` is what truth.json records (SI units).
    sim = cb.simulate_scenario(args.scenario, seed=args.seed)
    truth = sim.truth()["inertia_kgm2"]

    # The calibration starts from the scenario's [prior] model: models/espa_bus.toml.
    spacecraft = sim.prior
    print(f"{spacecraft.name}: wheels {', '.join(spacecraft.wheel_names)} (telemetry columns "
          f"{' '.join(n.lower() for n in spacecraft.wheel_names)}), "
          f"{len(spacecraft.thrusters)} thrusters")

    fit = cb.fit_inertia(sim.telemetry, spacecraft, seed=args.seed, chains=args.chains,
                         warmup=args.warmup, draws=args.draws)

    params = fit.summary()["parameters"]
    baseline = fit.baseline or {}
    print(f"inertia tensor, kg m² (scenario {args.scenario!r}, seed {args.seed})")
    print(f"{'':4} {'truth':>8} {'least sq':>9} {'post mean':>10} {'post sd':>8} "
          f"{'90 % interval':>19} {'error':>9}")
    for name in NAMES:
        p, t = params[name], truth[name]
        lsq = f"{baseline[name]:9.3f}" if name in baseline else f"{'-':>9}"
        err = (f"{100 * (p['mean'] / t - 1):+8.2f}%" if name in NAMES[:3]
               else f"{p['mean'] - t:+9.3f}")
        print(f"{name:4} {t:8.3f} {lsq} {p['mean']:10.3f} {p['sd']:8.3f} "
              f"[{p['q05']:8.3f}, {p['q95']:8.3f}] {err}")

    d = fit.diagnostics
    print(f"converged: {fit.converged} (max R-hat {d.max_r_hat:.3f}, min bulk ESS "
          f"{d.min_ess_bulk:.0f}, divergences {d.divergences})")
    for line in fit.warnings:
        print(f"warning: {line}")
    out = fit.save(args.out, force=True)
    print(f"saved {out}")
    return fit


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description="Inertia of an ESPA-class bus from its slews")
    parser.add_argument("--scenario", default="slews_espa_bus",
                        help="shipped scenario name or scenario TOML path")
    parser.add_argument("--chains", type=int, default=4, help="NUTS chains")
    parser.add_argument("--warmup", type=int, default=1000, help="warm-up iterations per chain")
    parser.add_argument("--draws", type=int, default=1000, help="kept draws per chain")
    parser.add_argument("--seed", type=int, default=0, help="seed of the noise and the sampler")
    parser.add_argument("--out", default="runs/inertia_espa_bus", help="run directory to write")
    args = parser.parse_args()
    cb.request_host_devices()   # one CPU device per chain, as the command line does
    main(args)
