"""``cassini-bayes fit inertia ...`` (docs/design.md §5), and the pieces every ``fit`` shares.

A ``fit`` command parses its options, calls one library function
(:func:`cassini_bayes.fit_inertia`, :func:`~cassini_bayes.fit_thrust`,
:func:`~cassini_bayes.fit_rwa4`) and hands the result to :func:`write_fit_run`. Shared by
``fit thrust`` and ``fit rwa4``:

* the common options as ready-made ``typer.Option`` defaults: :data:`SEED`, :data:`CHAINS`,
  :data:`WARMUP`, :data:`DRAWS`, :data:`TARGET_ACCEPT`, :data:`STRICT`, :data:`FORCE`, :data:`OUT`,
  :data:`WHEEL_ERRORS`;
* :func:`sampler_options` — the common options as the fit functions' keyword arguments
  (progress bar only on a terminal);
* :func:`write_fit_run` — writes the run directory (:meth:`cassini_bayes.FitResult.save`),
  prints the result and the warnings, and under ``--strict`` raises
  :class:`~cassini_bayes.errors.NotConvergedError` (exit 3) *after* writing everything, or
  :class:`~cassini_bayes.errors.InadequateModelError` (also exit 3) when the summary's
  ``adequacy`` checks failed.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import typer

from cassini_bayes.cli._console import escape, stderr_console
from cassini_bayes.cli._options import seed_option

ORDER = 20

SEED = seed_option(0, "Seed of the run's jax.random key.")
CHAINS = typer.Option(4, "--chains", min=1, help="Number of NUTS chains.")
WARMUP = typer.Option(1000, "--warmup", min=10, help="Warmup (adaptation) iterations per chain.")
DRAWS = typer.Option(1000, "--draws", min=10, help="Kept draws per chain.")
TARGET_ACCEPT = typer.Option(0.9, "--target-accept", min=0.5, max=0.999,
                             help="NUTS target acceptance probability: raise it (e.g. 0.95) "
                                  "when a fit reports divergent transitions; smaller steps, "
                                  "longer trees.")
STRICT = typer.Option(False, "--strict", help="Exit non-zero (3) when the sampler did not "
                                              "converge or an adequacy check failed (outputs "
                                              "are still written).")
FORCE = typer.Option(False, "--force", help="Replace --out if it is a run directory "
                                             "cassini-bayes wrote (never a user's folder).")
OUT = typer.Option(..., "--out", help="Run directory to write (atomically).")
WHEEL_ERRORS = typer.Option(None, "--wheel-errors", show_default=False,
                            help="Robust model's wheel spin-inertia errors: per-wheel (one scale "
                                 "per wheel, the default) or common (one scale for all wheels).")


def wheel_errors_name(value: str | None, idealised: bool = False) -> str:
    """The library's ``wheel_errors`` (``per_wheel``/``common``) of a ``--wheel-errors`` value
    (``None``: not given, ``per_wheel``); refused beside ``--idealised``, whose model has no
    wheel errors (it was accepted, and recorded, without effect)."""
    from cassini_bayes.errors import InputError

    if value is None:
        return "per_wheel"
    if idealised:
        raise InputError(f"--wheel-errors {value}: the idealised model has no wheel errors; drop "
                         "one of --wheel-errors and --idealised")
    name = value.replace("-", "_")
    if name not in ("per_wheel", "common"):
        raise InputError(f"--wheel-errors {value!r}: choose per-wheel or common")
    return name


def sampler_options(chains: int, warmup: int, draws: int, target_accept: float) -> dict:
    """The fit functions' sampler keyword arguments; the progress bar only on a terminal."""
    return {"chains": chains, "warmup": warmup, "draws": draws, "target_accept": target_accept,
            "progress": sys.stderr.isatty()}


def write_fit_run(result, out: Path, *, force: bool, strict: bool) -> Path:
    """Write the run directory of ``result`` (a :class:`cassini_bayes.FitResult`), report what
    happened, and enforce ``--strict``.

    Returns the final directory. Raises ``NotConvergedError`` under ``strict`` when the sampler
    did not converge, ``InadequateModelError`` when an adequacy check failed — after the
    directory is complete.
    """
    from cassini_bayes.api import collect_warnings
    from cassini_bayes.cli._verdict import failed_checks, verdict_text
    from cassini_bayes.errors import InadequateModelError, NotConvergedError

    with collect_warnings() as report_warnings:
        final = result.save(out, force=force, progress=sys.stderr.isatty())
    summary = result.summary()
    console = stderr_console()
    for line in list(summary.get("warnings", [])) + report_warnings:
        console.print(f"[yellow]warning:[/yellow] {escape(line)}")
    d = summary["diagnostics"]
    status = "[green]converged[/green]" if d["converged"] else "[red]NOT converged[/red]"
    failed = failed_checks(summary) or []
    fit = verdict_text(summary)
    r_hat = (f"{d['max_r_hat']:.4f}" if d["max_r_hat"] is not None
             and math.isfinite(d["max_r_hat"]) else "undefined (one chain)")
    console.print(f"{summary['kind']}: {status} (max R-hat {r_hat}, min bulk ESS "
                  f"{d['min_ess_bulk']:.0f}, {d['divergences']} divergences){fit} -> "
                  f"{escape(str(final))}")
    typer.echo(str(final))
    problems = []
    if not d["converged"]:
        msg = (f"{final}: the sampler did not converge (max R-hat {r_hat}, min "
               f"bulk ESS {d['min_ess_bulk']:.0f}, {d['divergences']} divergences); outputs "
               "written with converged = false — run longer (--warmup/--draws), raise "
               "--target-accept if it diverged, or check the data")
        if strict:  # (without --strict, summary.json's warnings above said it)
            problems.append(msg)
    if failed and strict:
        problems.append(
            f"{final}: the model does not fit the data: adequacy check(s) "
            f"{', '.join(failed)} failed (summary.json \"adequacy\", docs/adequacy.md); outputs "
            "written — look for an unmodelled error (a wheel's tachometer, the inertia, a "
            "thruster) or a bad file")
    if problems:
        raise (NotConvergedError if not d["converged"] else InadequateModelError)(
            "; ".join(problems))
    return final


def fit_inertia_cmd(
    telemetry: list[Path] = typer.Option(..., "--telemetry", help="RWA-slew telemetry CSV "
                                         "(repeat, or list several after one --telemetry)."),
    spacecraft: str = typer.Option(..., "--spacecraft", help="Spacecraft model TOML (prior)."),
    out: Path = OUT,
    seed: int = SEED,
    chains: int = CHAINS,
    warmup: int = WARMUP,
    draws: int = DRAWS,
    target_accept: float = TARGET_ACCEPT,
    strict: bool = STRICT,
    force: bool = FORCE,
    torque: bool = typer.Option(True, "--torque/--no-torque",
                                help="Include a constant inertial external torque per file."),
    idealised: bool = typer.Option(False, "--idealised",
                                   help="The papers' idealised model: no gyro bias/scale factor, "
                                        "wheel inertia or axis errors (default: the robust model "
                                        "with those as nuisance parameters, priors from the "
                                        "spacecraft model's \\[gyro] and \\[wheel_knowledge])."),
    wheel_errors: str = WHEEL_ERRORS,
    more: list[Path] = typer.Argument(None, hidden=True, help="More telemetry files, as in "
                                      "--telemetry A.csv B.csv."),
) -> None:
    """Posterior of the inertia tensor from RWA slews (shared I, per-file momentum)."""
    from cassini_bayes._paths import model_path
    from cassini_bayes.api import fit_inertia
    from cassini_bayes.rundir import check_out

    telemetry = list(telemetry) + list(more or [])
    check_out(out, force=force, inputs=[*telemetry, model_path(spacecraft)])  # before any work
    result = fit_inertia(telemetry, spacecraft, seed=seed, torque=torque, robust=not idealised,
                         wheel_errors=wheel_errors_name(wheel_errors, idealised),
                         **sampler_options(chains, warmup, draws, target_accept))
    write_fit_run(result, out, force=force, strict=strict)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    """Add ``fit inertia`` to the ``fit`` group."""
    groups["fit"].command("inertia")(fit_inertia_cmd)
