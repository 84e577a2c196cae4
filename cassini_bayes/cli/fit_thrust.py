"""``cassini-bayes fit thrust ...`` (docs/design.md §5): thrust and pulse time constants.

``--telemetry F.csv --pulses P.csv`` may be repeated (paired in order): the biasing events are
pooled, sharing the time constants and the thrust (:mod:`cassini_bayes.inference.thrust`).
"""

from __future__ import annotations

from pathlib import Path

import typer

from cassini_bayes.cli.fit import (CHAINS, DRAWS, FORCE, OUT, SEED, STRICT, TARGET_ACCEPT,
                                   WARMUP, WHEEL_ERRORS, collect_warnings, fit_config,
                                   sampler_settings, wheel_errors_name, write_fit_run)

ORDER = 21


def thrust_baseline(events, spacecraft, mode: str) -> tuple[dict | None, list[str]]:
    """Feldman & Lee's least squares (Eqs 19-23) with the pulse-dynamics correction at the
    spacecraft model's nominal time constants, all events stacked; ``None`` when unavailable."""
    import numpy as np

    from cassini_bayes.estimators import thrust as est
    from cassini_bayes.physics.impulse import moment_matrix

    th = spacecraft.thrusters
    q = np.asarray(moment_matrix(th.Lx, th.Ly, th.Lzy, th.Lzz, th.com))
    p = spacecraft.pulse
    vs, js = [], []
    try:
        for tel, log in events:
            rates = np.nan_to_num(np.asarray(tel.wheel_rates, float))
            h = np.zeros((tel.n, 3))
            for k, name in enumerate(tel.wheel_names):
                if name in tel.active_wheels():
                    w = spacecraft.wheel(name)
                    h += w.inertia * rates[:, k, None] * w.axis[None, :]
            v, j = est.regression_inputs(tel.t, tel.omega, h, spacecraft.inertia,
                                         pulses=(log.t_on, log.thruster, log.width),
                                         tau=(p.tau_delay, p.tau_rise, p.tau_fall))
            vs.append(v)
            js.append(j)
        v, j = np.concatenate(vs), np.concatenate(js)
    except Exception as e:  # the baseline must never sink the Bayesian fit
        return None, [f"baseline unavailable: {' '.join(str(e).split())}"]
    out, msgs = {}, []
    fits = {"mean": [("F", est.fit_mean, None)],
            "branch": [("F_Z", est.fit_z_thrusters, "mean"), ("F_Y", est.fit_y_mean, None)],
            "thruster": [("F_Z", est.fit_z_thrusters, "each"),
                         ("F_Y", est.fit_y_thrusters, "each")]}[mode]
    for name, fn, how in fits:
        try:
            f = fn(v, j, q)
        except Exception as e:
            msgs.append(f"baseline {name}: {' '.join(str(e).split())}")
            continue
        if how == "each":
            out.update({n: float(x) for n, x in zip(f.names, f.estimate)})
        elif how == "mean":
            out[name] = float(np.mean(f.estimate))
        else:
            out[name] = float(f.estimate[0])
    return (out or None), msgs


def thrust_sensitivity(post) -> dict:
    """``sensitivity`` block of a robust thrust fit: how far each nuisance effect of prior size
    would move the thrust and time constants if it were left out (posterior regression,
    :func:`cassini_bayes.inference.sensitivity.posterior_sensitivity`)."""
    import numpy as np

    from cassini_bayes.inference.nuisance import EFFECTS, site_prior_sd
    from cassini_bayes.inference.sensitivity import posterior_sensitivity
    from cassini_bayes.inference.thrust import TAU_NAMES

    post_ds = post.idata.posterior
    layout = post.problem.layout

    def flat(name):
        v = np.asarray(post_ds[name].values, float)
        return v.reshape(v.shape[0] * v.shape[1], -1)

    names = list(post.problem.names) + list(TAU_NAMES)
    targets = {n: flat(n)[:, 0] for n in names}
    prior_sd = site_prior_sd(layout)
    groups = {e: (flat(EFFECTS[e]), prior_sd[EFFECTS[e]])
              for e in layout.slices if EFFECTS[e] in post_ds}
    units = {n: ("N" if n.startswith("F") else "s") for n in names}
    return posterior_sensitivity(targets, groups, units)


def fit_thrust_cmd(
    telemetry: list[Path] = typer.Option(..., "--telemetry", help="Biasing-event telemetry CSV "
                                         "(repeat for several events)."),
    pulses: list[Path] = typer.Option(None, "--pulses", help="Pulse log CSV of each event "
                                      "(t_on, thruster, width), in the order of --telemetry."),
    spacecraft: str = typer.Option(..., "--spacecraft", help="Spacecraft model TOML."),
    out: Path = OUT,
    mode: str = typer.Option("mean", "--mode", help="mean (F), branch (F_Z, F_Y) or thruster "
                             "(F_Z1 ... F_Y4)."),
    inertia_posterior: Path = typer.Option(None, "--inertia-posterior", help="Run directory of "
                                           "an inertia fit: its posterior becomes the inertia "
                                           "prior (default: the spacecraft model's inertia and "
                                           "its stated uncertainty)."),
    fix_inertia: bool = typer.Option(False, "--fix-inertia", help="Hold the inertia at the "
                                     "spacecraft model's prediction (the papers' practice; the "
                                     "default with --idealised). A wrong fixed inertia biases "
                                     "the thrust."),
    seed: int = SEED,
    chains: int = CHAINS,
    warmup: int = WARMUP,
    draws: int = DRAWS,
    target_accept: float = TARGET_ACCEPT,
    strict: bool = STRICT,
    force: bool = FORCE,
    idealised: bool = typer.Option(False, "--idealised",
                                   help="The papers' idealised model: no gyro bias/scale factor, "
                                        "wheel inertia or axis errors, no external torque "
                                        "(default: the robust model with those as nuisance "
                                        "parameters, priors from the spacecraft model's [gyro] "
                                        "and [wheel_knowledge])."),
    wheel_errors: str = WHEEL_ERRORS,
) -> None:
    """Posterior of the thrust and the pulse time constants from biasing events."""
    import jax

    from cassini_bayes._paths import model_path
    from cassini_bayes.consistency import check_thrust_data
    from cassini_bayes.errors import InputError
    from cassini_bayes.inference.summary import build_summary
    from cassini_bayes.inference.thrust import (MODES, TAU_NAMES, fit_thrust, inertia_from_run,
                                                thrust_names)
    from cassini_bayes.rundir import check_out, file_record
    from cassini_bayes.spacecraft import load_spacecraft
    from cassini_bayes.telemetry import read_pulses, read_telemetry

    if mode not in MODES:
        raise InputError(f"--mode {mode!r}: choose one of {', '.join(MODES)}")
    pulses = list(pulses or [])
    if not pulses:
        raise InputError("fit thrust needs the pulse log of each event: --pulses P.csv "
                         "(columns t_on, thruster, width)")
    if len(pulses) != len(telemetry):
        raise InputError(f"{len(telemetry)} --telemetry file(s) but {len(pulses)} --pulses "
                         "file(s); give one pulse log per telemetry file, in the same order")
    check_out(out, force=force, inputs=[*telemetry, *pulses, model_path(spacecraft),
                                        *([inertia_posterior] if inertia_posterior else [])])
    sc = load_spacecraft(spacecraft)
    if fix_inertia and inertia_posterior is not None:
        raise InputError("--fix-inertia and --inertia-posterior exclude each other; give one")
    inertia = (inertia_from_run(inertia_posterior) if inertia_posterior is not None
               else "fixed" if fix_inertia else None)
    events = [(read_telemetry(t), read_pulses(p)) for t, p in zip(telemetry, pulses)]
    check_thrust_data(events, sc)  # units, conventions, pulse log vs on_*, by the physics
    settings = sampler_settings(chains, warmup, draws, target_accept)
    wheel_errors = wheel_errors_name(wheel_errors)
    key = jax.random.key(seed)  # the one place the seed becomes a key
    with collect_warnings() as warns:
        post = fit_thrust(key, events, sc, mode=mode, inertia=inertia, settings=settings,
                          robust=not idealised, wheel_errors=wheel_errors)
    baseline, base_warns = thrust_baseline(events, sc, mode)
    names = list(thrust_names(mode)) + list(TAU_NAMES)
    nuisance = ["sigma_omega", "sigma_rho"]
    if "Ixx" in post.idata.posterior:   # the inertia was sampled
        from cassini_bayes.physics.momentum import INERTIA_NAMES
        nuisance += list(INERTIA_NAMES)
    if not idealised:
        from cassini_bayes.inference.nuisance import EFFECTS
        nuisance += [EFFECTS[e] for e in post.problem.layout.slices]
    from cassini_bayes.inference.adequacy import thrust_adequacy

    priored = names + [n for n in nuisance if not n.startswith("sigma_")]
    summary = build_summary("thrust", post.idata, parameters=names,
                            diagnostics=post.diagnostics, baseline=baseline, seed=seed,
                            nuisance=nuisance, warnings=warns + base_warns,
                            adequacy=thrust_adequacy(post, priored))
    summary["mode"] = mode
    summary["model"] = "idealised" if idealised else "robust"
    summary["wheel_errors"] = None if idealised else wheel_errors
    if not idealised:
        summary["sensitivity"] = thrust_sensitivity(post)
    config = fit_config("fit thrust", seed=seed, spacecraft=sc, settings=settings,
                        inputs={"telemetry": [file_record(p) for p in telemetry],
                                "pulses": [file_record(p) for p in pulses],
                                "spacecraft": file_record(model_path(spacecraft)),
                                **({"inertia_posterior": str(Path(inertia_posterior).resolve())}
                                   if inertia_posterior is not None else {})},
                        options={"mode": mode, "model": "idealised" if idealised else "robust",
                                 "inertia": ("posterior" if inertia_posterior is not None
                                             else "sampled" if "Ixx" in post.idata.posterior
                                             else "fixed"),
                                 "wheel_errors": wheel_errors})
    write_fit_run(out, force=force, strict=strict, idata=post.idata, summary=summary,
                  config=config)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    """Add ``fit thrust`` to the ``fit`` group."""
    groups["fit"].command("thrust")(fit_thrust_cmd)
