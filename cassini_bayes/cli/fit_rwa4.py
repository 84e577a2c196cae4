"""``cassini-bayes fit rwa4 ...`` (docs/design.md §5): the RWA4 spin axis on the sphere.

``--window-a T0:T1 --window-b T0:T1`` may be repeated (paired in order: one A/B pair per slew
pair for the RWA method); without them the windows come from the quiet periods
(:func:`cassini_bayes.inference.rwa4.detect_windows`).
"""

from __future__ import annotations

from pathlib import Path

import typer

from cassini_bayes.api._limits import RWA4_TARGET_ACCEPT
from cassini_bayes.cli.fit import (CHAINS, DRAWS, FORCE, OUT, SEED, STRICT, WARMUP,
                                   WHEEL_ERRORS, sampler_options, wheel_errors_name,
                                   write_fit_run)

ORDER = 22


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
    target_accept: float = typer.Option(RWA4_TARGET_ACCEPT, "--target-accept", min=0.5,
                                        max=0.999, help="NUTS target acceptance probability "
                                        "(0.95 for RWA4: at 0.9 one fit in 80 diverged once)."),
    strict: bool = STRICT,
    force: bool = FORCE,
) -> None:
    """Posterior of the RWA4 spin axis, with the inertia uncertainty sampled jointly."""
    from cassini_bayes._paths import model_path
    from cassini_bayes.api import fit_rwa4
    from cassini_bayes.errors import InputError
    from cassini_bayes.inference.rwa4 import METHODS, PRIORS
    from cassini_bayes.rundir import check_out
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
    # the windows' open ends (":600") need its time span; its columns are the model's wheels
    tel = read_telemetry(telemetry, spacecraft=load_spacecraft(spacecraft))
    windows = [(parse_window(a, tel.t, option="window-a"),
                parse_window(b, tel.t, option="window-b"))
               for a, b in zip(window_a, window_b)] or None
    result = fit_rwa4(tel, spacecraft, method=method, windows=windows, prior=prior,
                      inertia_posterior=inertia_posterior, seed=seed, robust=not idealised,
                      wheel_errors=wheel_errors_name(wheel_errors, idealised),
                      **sampler_options(chains, warmup, draws, target_accept))
    write_fit_run(result, out, force=force, strict=strict)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    """Add ``fit rwa4`` to the ``fit`` group."""
    groups["fit"].command("rwa4")(fit_rwa4_cmd)
