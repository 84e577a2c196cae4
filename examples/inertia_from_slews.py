"""
Inertia tensor from reaction-wheel slews
========================================

Cassini's attitude is controlled by reaction wheels, and a slew made with them leaves the
spacecraft's total angular momentum unchanged: whatever momentum the wheels take, the body
gives back. Writing that balance at every telemetry sample, ``R(q) (I ω + h_wheels) = H0``,
turns gyro rates ``ω``, attitude ``q`` and wheel tach rates into a linear system for the six
entries of the inertia tensor ``I`` — Feldman & Lee (2006, AAS 06-102, Eq 11), who solved it by
least squares after slews about X, Y and Z (their Table 1, "Post-Probe").

This example simulates those slews from the shipped scenario ``slews_post_probe`` (truth: the
Table 1 Post-Probe estimate; the calibration starts from the Table 1 prediction), fits the
posterior of the six entries with :func:`cassini_bayes.fit_inertia` (NUTS; the robust model also
integrates out gyro bias/scale, wheel inertia and axis errors and a constant external torque),
prints the posterior beside the truth and the papers' least-squares estimate on the same data,
and saves the run directory (``posterior.nc``, ``summary.json``, ``config.toml``,
``report.html``) that ``cassini-bayes fit inertia`` would write.

Run ``python examples/inertia_from_slews.py --help`` for the settings.
"""

import argparse

import cassini_bayes as cb

NAMES = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")


def main(args):
    # Synthetic telemetry: the scenario's slews through the simulator (dynamics, controller,
    # gyro/star-tracker/tach noise). ``truth()`` is what truth.json records, SI units.
    sim = cb.simulate_scenario(args.scenario, seed=args.seed)
    truth = sim.truth()["inertia_kgm2"]

    # The spacecraft model the calibration starts from: the scenario's [prior] model (its
    # inertia prediction and stated uncertainty are the prior; its wheels map tach to momentum).
    spacecraft = sim.prior

    fit = cb.fit_inertia(sim.telemetry, spacecraft, seed=args.seed, chains=args.chains,
                         warmup=args.warmup, draws=args.draws)

    # summary() is the summary.json dict: every parameter's mean, sd and 5/50/95 % quantiles,
    # and the papers' least-squares baseline on the same data.
    params = fit.summary()["parameters"]
    baseline = fit.baseline or {}
    print(f"inertia tensor, kg m² (scenario {args.scenario!r}, seed {args.seed})")
    print(f"{'':4} {'truth':>9} {'least sq':>9} {'post mean':>10} {'post sd':>8} "
          f"{'90 % interval':>21}")
    for name in NAMES:
        p = params[name]
        lsq = f"{baseline[name]:9.1f}" if name in baseline else f"{'-':>9}"
        print(f"{name:4} {truth[name]:9.1f} {lsq} {p['mean']:10.1f} {p['sd']:8.1f} "
              f"[{p['q05']:9.1f}, {p['q95']:9.1f}]")

    d = fit.diagnostics  # R-hat, effective sample sizes, divergent transitions
    print(f"converged: {fit.converged} (max R-hat {d.max_r_hat:.3f}, min bulk ESS "
          f"{d.min_ess_bulk:.0f}, divergences {d.divergences})")
    for line in fit.warnings:
        print(f"warning: {line}")

    # The run directory the command writes. ``force=True`` replaces an earlier run of this
    # script; it never replaces a directory cassini-bayes did not write.
    out = fit.save(args.out, force=True)
    print(f"saved {out}")
    return fit


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description="Inertia tensor from simulated RWA slews")
    parser.add_argument("--scenario", default="slews_post_probe",
                        help="shipped scenario name or scenario TOML path")
    parser.add_argument("--chains", type=int, default=4, help="NUTS chains")
    parser.add_argument("--warmup", type=int, default=1000, help="warm-up iterations per chain")
    parser.add_argument("--draws", type=int, default=1000, help="kept draws per chain")
    parser.add_argument("--seed", type=int, default=0, help="seed of the noise and the sampler")
    parser.add_argument("--out", default="runs/inertia_from_slews", help="run directory to write")
    main(parser.parse_args())
