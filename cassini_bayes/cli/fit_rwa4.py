"""``cassini-bayes fit rwa4 ...`` (docs/design.md §5): the RWA4 spin axis on the sphere.

``--window-a T0:T1 --window-b T0:T1`` may be repeated (paired in order: one A/B pair per slew
pair for the RWA method); without them the windows come from the quiet periods
(:func:`cassini_bayes.inference.rwa4.detect_windows`).
"""

from __future__ import annotations

from pathlib import Path

import typer

from cassini_bayes.cli.fit import (CHAINS, DRAWS, FORCE, OUT, SEED, STRICT, TARGET_ACCEPT,
                                   WARMUP, WHEEL_ERRORS, collect_warnings, fit_config,
                                   sampler_settings, wheel_errors_name, write_fit_run)

ORDER = 22


def rwa4_sensitivity(post) -> dict:
    """``sensitivity`` block of an RWA4 fit: the RMS axis shift (deg) each nuisance effect of
    prior size causes in a model that leaves it out
    (:func:`cassini_bayes.inference.rwa4.axis_sensitivity`), and that shift over the posterior's
    RMS angle about its mean direction."""
    import numpy as np

    from cassini_bayes.inference.rwa4 import U4_NAMES, axis_sensitivity
    from cassini_bayes.inference.sphere import angles_deg

    draws = np.stack([post.idata.posterior[n].values.ravel() for n in U4_NAMES], -1)
    rms = float(np.sqrt(np.mean(angles_deg(draws, np.asarray(post.direction["mean"])) ** 2)))
    return {effect: {"modelled": post.problem.robust,
                     "parameters": {"axis": {"shift": shift,
                                             "shift_in_sd": shift / rms if rms > 0 else None,
                                             "units": "deg"}}}
            for effect, shift in axis_sensitivity(post.problem).items()}


def fit_rwa4_cmd(
    method: str = typer.Option(..., "--method", help="rcs (Brown Eq 1) or rwa (Brown Eq 3)."),
    telemetry: Path = typer.Option(..., "--telemetry", help="Calibration telemetry CSV."),
    spacecraft: str = typer.Option(..., "--spacecraft", help="Spacecraft model TOML."),
    out: Path = OUT,
    window_a: list[str] = typer.Option(None, "--window-a", help="Time A window T0:T1 (s); "
                                       "repeat, paired in order with --window-b."),
    window_b: list[str] = typer.Option(None, "--window-b", help="Time B window T0:T1 (s)."),
    prior: str = typer.Option("uniform", "--prior", help="uniform (on the sphere) or cone "
                              "(articulation cone, 54.7356 deg from +Z)."),
    inertia_posterior: Path = typer.Option(None, "--inertia-posterior", help="Run directory of "
                                           "an inertia fit: its posterior becomes the inertia "
                                           "prior (default: the model's knowledge requirements)."),
    idealised: bool = typer.Option(False, "--idealised",
                                   help="Brown's idealised model: no gyro bias/scale factor, "
                                        "wheel spin-inertia or known-wheel axis errors, no "
                                        "external torque (default: the robust model with those "
                                        "integrated out)."),
    wheel_errors: str = WHEEL_ERRORS,
    seed: int = SEED,
    chains: int = CHAINS,
    warmup: int = WARMUP,
    draws: int = DRAWS,
    target_accept: float = TARGET_ACCEPT,
    strict: bool = STRICT,
    force: bool = FORCE,
) -> None:
    """Posterior of the RWA4 spin axis, with the inertia uncertainty sampled jointly."""
    import jax

    from cassini_bayes._paths import model_path
    from cassini_bayes.consistency import check_rwa4_data
    from cassini_bayes.errors import InputError
    from cassini_bayes.inference.rwa4 import METHODS, PRIORS, U4_NAMES, fit_rwa4
    from cassini_bayes.inference.summary import build_summary
    from cassini_bayes.inference.thrust import inertia_from_run
    from cassini_bayes.physics.momentum import INERTIA_NAMES
    from cassini_bayes.rundir import check_out, file_record
    from cassini_bayes.spacecraft import load_spacecraft
    from cassini_bayes.telemetry import read_telemetry
    from cassini_bayes.windows import parse_window

    if method not in METHODS:
        raise InputError(f"--method {method!r}: choose one of {', '.join(METHODS)}")
    if prior not in PRIORS:
        raise InputError(f"--prior {prior!r}: choose one of {', '.join(PRIORS)}")
    window_a, window_b = list(window_a or []), list(window_b or [])
    if len(window_a) != len(window_b):
        raise InputError(f"{len(window_a)} --window-a but {len(window_b)} --window-b; give them "
                         "in pairs (Time A, Time B), paired in order")
    check_out(out, force=force, inputs=[telemetry, model_path(spacecraft),
                                        *([inertia_posterior] if inertia_posterior else [])])
    sc = load_spacecraft(spacecraft)
    inertia = inertia_from_run(inertia_posterior) if inertia_posterior is not None else None
    tel = read_telemetry(telemetry)
    check_rwa4_data(tel, sc, method)  # units, conventions, method vs data, by the physics
    pairs = None
    if window_a:
        pairs = [(parse_window(a, tel.t, option="window-a"),
                  parse_window(b, tel.t, option="window-b")) for a, b in zip(window_a, window_b)]
    settings = sampler_settings(chains, warmup, draws, target_accept)
    wheel_errors = wheel_errors_name(wheel_errors)
    key = jax.random.key(seed)  # the one place the seed becomes a key
    with collect_warnings() as warns:
        post = fit_rwa4(key, tel, sc, method=method, pairs=pairs, prior=prior, inertia=inertia,
                        settings=settings, robust=not idealised, wheel_errors=wheel_errors)
    from cassini_bayes.inference.adequacy import rwa4_adequacy

    pr = post.problem
    baseline = {n: float(v) for n, v in zip(U4_NAMES, pr.baseline)}
    summary = build_summary(
        "rwa4", post.idata, parameters=U4_NAMES, diagnostics=post.diagnostics,
        baseline=baseline, seed=seed, warnings=warns,
        nuisance=list(INERTIA_NAMES),
        extra={"direction": post.direction},
        adequacy=rwa4_adequacy(post, list(U4_NAMES) + list(INERTIA_NAMES)))
    summary["method"] = method
    summary["prior"] = prior
    summary["windows"] = [{"a": list(a), "b": list(b)} for a, b in pr.pairs]
    summary["model"] = "idealised" if idealised else "robust"
    summary["wheel_errors"] = None if idealised else wheel_errors
    summary["sensitivity"] = rwa4_sensitivity(post)
    config = fit_config("fit rwa4", seed=seed, spacecraft=sc, settings=settings,
                        inputs={"telemetry": file_record(telemetry),
                                "spacecraft": file_record(model_path(spacecraft)),
                                **({"inertia_posterior": str(Path(inertia_posterior).resolve())}
                                   if inertia_posterior is not None else {})},
                        options={"method": method, "prior": prior,
                                 "model": "idealised" if idealised else "robust",
                                 "wheel_errors": wheel_errors,
                                 "window_a": [f"{a[0]:.10g}:{a[1]:.10g}" for a, _ in pr.pairs],
                                 "window_b": [f"{b[0]:.10g}:{b[1]:.10g}" for _, b in pr.pairs],
                                 "windows_detected": pairs is None})
    write_fit_run(out, force=force, strict=strict, idata=post.idata, summary=summary,
                  config=config)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    """Add ``fit rwa4`` to the ``fit`` group."""
    groups["fit"].command("rwa4")(fit_rwa4_cmd)
