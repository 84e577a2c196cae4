"""``cassini-bayes fit thrust ...`` (docs/design.md §5): thrust and pulse time constants.

``--telemetry F.csv --pulses P.csv`` may be repeated (paired in order): the biasing events are
pooled, sharing the time constants and the thrust (:mod:`cassini_bayes.inference.thrust`).
"""

from __future__ import annotations

from pathlib import Path

import typer

from cassini_bayes.cli.fit import (CHAINS, DRAWS, FORCE, OUT, SEED, STRICT, TARGET_ACCEPT,
                                   WARMUP, WHEEL_ERRORS, sampler_options, wheel_errors_name,
                                   write_fit_run)

ORDER = 21


def fit_thrust_cmd(
    telemetry: list[Path] = typer.Option(..., "--telemetry", help="Biasing-event telemetry CSV "
                                         "(repeat for several events)."),
    pulses: list[Path] = typer.Option(None, "--pulses", help="Pulse log CSV of each event "
                                      "(t_on, thruster, width), in the order of --telemetry."),
    spacecraft: str = typer.Option(..., "--spacecraft", help="Spacecraft model TOML."),
    out: Path = OUT,
    mode: str = typer.Option("mean", "--mode", help="mean (one F for all thrusters, the "
                             "papers' Eq 23), branch (F_Z, F_Y; Cassini's Eq 16 layout) or "
                             "thruster (F[<name>] per thruster of any layout, the centre-of-mass "
                             "offset com_x/y/z and the identified combinations)."),
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
                                        "parameters, priors from the spacecraft model's \\[gyro] "
                                        "and \\[wheel_knowledge])."),
    wheel_errors: str = WHEEL_ERRORS,
    flex: str = typer.Option("check", "--flex", help="check (search the events for a flexible "
                             "or slosh mode; the adequacy check flex_ringing fails where it "
                             "rings above the noise), model (also integrate out the momentum it "
                             "holds; docs/flex_mode.md) or off. Ranges and prior: the model's "
                             "\\[flex_knowledge]."),
) -> None:
    """Posterior of the thrust and the pulse time constants from biasing events."""
    from cassini_bayes._paths import model_path
    from cassini_bayes.api import fit_thrust
    from cassini_bayes.errors import InputError
    from cassini_bayes.names import THRUST_MODES as MODES
    from cassini_bayes.rundir import check_out

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
    result = fit_thrust(telemetry, pulses, spacecraft, mode=mode,
                        inertia_posterior=inertia_posterior, fix_inertia=fix_inertia, seed=seed,
                        robust=not idealised,
                        wheel_errors=wheel_errors_name(wheel_errors, idealised), flex=flex,
                        **sampler_options(chains, warmup, draws, target_accept))
    write_fit_run(result, out, force=force, strict=strict)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    """Add ``fit thrust`` to the ``fit`` group."""
    groups["fit"].command("thrust")(fit_thrust_cmd)
