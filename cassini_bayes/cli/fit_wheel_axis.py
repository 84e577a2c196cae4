"""``cassini-bayes fit wheel-axis TELEMETRY --spacecraft M --wheel NAME --method rcs|rwa ...``
(docs/cli.md): any wheel's spin axis on the sphere (Brown 2012 §III, for any spacecraft model).

``--window-a T0:T1 --window-b T0:T1`` may be repeated (paired in order: one A/B pair per slew
pair for the RWA method); without them the windows come from the quiet periods
(:func:`cassini_bayes.inference.rwa4.detect_windows`). ``fit rwa4`` (:mod:`.fit_rwa4`) is
Cassini's name for ``--wheel RWA4`` and shares these options.
"""

from __future__ import annotations

from pathlib import Path

import typer

from cassini_bayes.api._limits import RWA4_TARGET_ACCEPT
from cassini_bayes.cli.fit import (CHAINS, DRAWS, FORCE, OUT, SEED, STRICT, WARMUP,
                                   WHEEL_ERRORS, sampler_options, wheel_errors_name,
                                   write_fit_run)

ORDER = 23

METHOD = typer.Option(..., "--method", help="rcs (Brown Eq 1) or rwa (Brown Eq 3).")
SPACECRAFT = typer.Option(..., "--spacecraft", help="Spacecraft model TOML.")
WINDOW_A = typer.Option(None, "--window-a", help="Time A window T0:T1 (s); repeat, paired in "
                        "order with --window-b.")
WINDOW_B = typer.Option(None, "--window-b", help="Time B window T0:T1 (s).")
PRIOR = typer.Option("uniform", "--prior", help="uniform (on the sphere) or cone (the wheel's "
                     "articulation cone: the model file's cone_axis and "
                     "cone_deg of that wheel).")
INERTIA_POSTERIOR = typer.Option(None, "--inertia-posterior", help="Run directory of an inertia "
                                 "fit: its posterior becomes the inertia prior (default: the "
                                 "model's knowledge requirements).")
IDEALISED = typer.Option(False, "--idealised", help="Brown's idealised model: no gyro bias/scale "
                         "factor, wheel spin-inertia or known-wheel axis errors, no external "
                         "torque (default: the robust model with those integrated out).")
TELEMETRY_ARG = typer.Argument(None, metavar="TELEMETRY", show_default=False,
                               help="Calibration telemetry CSV (or --telemetry).")
TELEMETRY_OPT = typer.Option(None, "--telemetry", show_default=False,
                             help="Calibration telemetry CSV (as TELEMETRY).")
WHEEL = typer.Option(..., "--wheel", help="The wheel whose axis is calibrated, one of the "
                     "spacecraft model's wheel names.")
TARGET_ACCEPT = typer.Option(RWA4_TARGET_ACCEPT, "--target-accept", min=0.5, max=0.999,
                             help="NUTS target acceptance probability (0.95 for the spin axis: "
                                  "at 0.9 one fit in 80 diverged once).")


def run_axis_fit(*, wheel: str, telemetry: Path, spacecraft: str, method: str, out: Path,
                 window_a, window_b, prior: str, inertia_posterior: Path | None,
                 idealised: bool, wheel_errors: str | None, seed: int, chains: int, warmup: int,
                 draws: int, target_accept: float, strict: bool, force: bool,
                 rwa4: bool = False) -> None:
    """Parse the options, fit (:func:`cassini_bayes.fit_wheel_axis`, or with ``rwa4``
    :func:`cassini_bayes.fit_rwa4`) and write the run directory."""
    from cassini_bayes._paths import model_path
    from cassini_bayes.api import fit_rwa4, fit_wheel_axis
    from cassini_bayes.errors import InputError
    from cassini_bayes.names import AXIS_METHODS as METHODS, AXIS_PRIORS as PRIORS
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
    options = dict(method=method, windows=windows, prior=prior,
                   inertia_posterior=inertia_posterior, seed=seed, robust=not idealised,
                   wheel_errors=wheel_errors_name(wheel_errors, idealised),
                   **sampler_options(chains, warmup, draws, target_accept))
    result = (fit_rwa4(tel, spacecraft, **options) if rwa4
              else fit_wheel_axis(tel, spacecraft, wheel=wheel, **options))
    write_fit_run(result, out, force=force, strict=strict)


def fit_wheel_axis_cmd(
    telemetry_arg: Path = TELEMETRY_ARG,
    telemetry: Path = TELEMETRY_OPT,
    spacecraft: str = SPACECRAFT,
    wheel: str = WHEEL,
    method: str = METHOD,
    out: Path = OUT,
    window_a: list[str] = WINDOW_A,
    window_b: list[str] = WINDOW_B,
    prior: str = PRIOR,
    inertia_posterior: Path = INERTIA_POSTERIOR,
    idealised: bool = IDEALISED,
    wheel_errors: str = WHEEL_ERRORS,
    seed: int = SEED,
    chains: int = CHAINS,
    warmup: int = WARMUP,
    draws: int = DRAWS,
    target_accept: float = TARGET_ACCEPT,
    strict: bool = STRICT,
    force: bool = FORCE,
) -> None:
    """Posterior of a wheel's spin axis, with the inertia uncertainty sampled jointly."""
    from cassini_bayes.errors import InputError

    if telemetry_arg is not None and telemetry is not None and telemetry_arg != telemetry:
        raise InputError(f"two telemetry files, {telemetry_arg} and --telemetry {telemetry}; "
                         "the spin-axis calibration takes one")
    telemetry = telemetry_arg if telemetry is None else telemetry
    if telemetry is None:
        raise InputError("no telemetry: give the calibration telemetry CSV as TELEMETRY (or "
                         "--telemetry)")
    run_axis_fit(wheel=wheel, telemetry=telemetry, spacecraft=spacecraft, method=method, out=out,
                 window_a=window_a, window_b=window_b, prior=prior,
                 inertia_posterior=inertia_posterior, idealised=idealised,
                 wheel_errors=wheel_errors, seed=seed, chains=chains, warmup=warmup, draws=draws,
                 target_accept=target_accept, strict=strict, force=force)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    """Add ``fit wheel-axis`` to the ``fit`` group."""
    groups["fit"].command("wheel-axis")(fit_wheel_axis_cmd)
