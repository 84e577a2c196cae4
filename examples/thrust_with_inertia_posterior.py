"""
Thrust and pulse time constants, with the inertia's uncertainty carried along
=============================================================================

When Cassini biases its reaction wheels (spins them up or down under thruster control), the
wheels' reaction torque is cancelled by short attitude-control thruster pulses. Each pulse's
angular impulse is its thrust ``F`` times its moment arm times an effective on-time, which the
pulse dynamics (a delay ``τd``, a rise ``τr`` and a fall ``τf`` time constant) make shorter or
longer than the commanded width. Balancing the body's momentum change (``I Δω``) plus the wheels'
against the summed pulse impulses gives the thrust: Feldman & Lee (2006, AAS 06-102, Eqs 19-23,
Table 2), who held the inertia at its prediction.

Here the inertia is not held fixed: this example first fits the inertia tensor to simulated
slews (``slews_post_probe``), then fits the mean thrust ``F`` and the three time constants to a
simulated biasing event (``biasing_day028``, truth F = 0.699 N, 5/20/65 ms) with
``cb.fit_thrust(..., inertia_posterior=inertia_fit)``: the inertia posterior becomes the thrust
fit's inertia prior, so its uncertainty propagates into ``F``. It prints both posteriors against
the truth and the papers' least squares, and saves the thrust run.

Run ``python examples/thrust_with_inertia_posterior.py --help`` for the settings.
"""

import argparse

import cassini_bayes as cb


def main(args):
    sampler = dict(seed=args.seed, chains=args.chains, warmup=args.warmup, draws=args.draws)

    # 1. The inertia from RWA slews; the scenario's [prior] model is where the calibration starts.
    slews = cb.simulate_scenario(args.slews, seed=args.seed)
    inertia_fit = cb.fit_inertia(slews.telemetry, slews.prior, **sampler)
    inertia = inertia_fit.summary()["parameters"]
    true_inertia = slews.truth()["inertia_kgm2"]
    print("inertia posterior, kg m² (mean ± sd, truth)")
    cells = [f"{n} {inertia[n]['mean']:6.0f} ± {inertia[n]['sd']:3.0f} ({true_inertia[n]:.0f})"
             for n in true_inertia]
    print("  " + "   ".join(cells[:3]) + "\n  " + "   ".join(cells[3:]))

    # 2. The biasing event: telemetry plus the log of every commanded pulse (t_on, thruster,
    #    width). The inertia posterior replaces the model's inertia prior.
    event = cb.simulate_scenario(args.event, seed=args.seed)
    fit = cb.fit_thrust(event.telemetry, event.pulses, event.prior,
                        inertia_posterior=inertia_fit, **sampler)

    truth = event.truth()
    true_f = sum(truth["thrust_n"].values()) / len(truth["thrust_n"])  # mode "mean": one F
    rows = [("F", "N", 1.0, true_f),
            ("tau_delay", "ms", 1e3, truth["tau_delay_s"]),
            ("tau_rise", "ms", 1e3, truth["tau_rise_s"]),
            ("tau_fall", "ms", 1e3, truth["tau_fall_s"])]
    params = fit.summary()["parameters"]
    baseline = fit.baseline or {}
    print(f"thrust and pulse time constants ({event.pulses.t_on.size} pulses, "
          f"event {args.event!r})")
    print(f"{'':10} {'truth':>8} {'least sq':>9} {'post mean':>9} {'post sd':>8} "
          f"{'90 % interval':>19}")
    for name, unit, scale, true in rows:
        p = params[name]
        # the least squares estimates F only (at the model's nominal time constants)
        lsq = f"{scale * baseline[name]:9.3f}" if name in baseline else f"{'-':>9}"
        print(f"{name:10} {scale * true:8.3f} {lsq} {scale * p['mean']:9.3f} "
              f"{scale * p['sd']:8.3f} [{scale * p['q05']:8.3f}, {scale * p['q95']:8.3f}] {unit}")
    print(f"converged: inertia {inertia_fit.converged}, thrust {fit.converged}")
    for line in fit.warnings:
        print(f"warning: {line}")

    out = fit.save(args.out, force=True)  # replaces only a run this package wrote
    print(f"saved {out}")
    return fit


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description="Thrust from a simulated biasing event, "
                                     "with the inertia posterior from simulated slews")
    parser.add_argument("--slews", default="slews_post_probe",
                        help="inertia scenario (shipped name or TOML path)")
    parser.add_argument("--event", default="biasing_day028",
                        help="biasing-event scenario (shipped name or TOML path)")
    parser.add_argument("--chains", type=int, default=4, help="NUTS chains")
    parser.add_argument("--warmup", type=int, default=1000, help="warm-up iterations per chain")
    parser.add_argument("--draws", type=int, default=1000, help="kept draws per chain")
    parser.add_argument("--seed", type=int, default=0, help="seed of the noise and the sampler")
    parser.add_argument("--out", default="runs/thrust_with_inertia_posterior",
                        help="run directory of the thrust fit")
    main(parser.parse_args())
