"""``cassini-bayes fit inertia ...`` (docs/design.md §5), and the pieces every ``fit`` shares.

Shared by ``fit thrust`` and ``fit rwa4`` (add them as their own ``register`` in a module of this
package, or beside ``inertia`` here):

* the common options as ready-made ``typer.Option`` defaults: :data:`SEED`, :data:`CHAINS`,
  :data:`WARMUP`, :data:`DRAWS`, :data:`TARGET_ACCEPT`, :data:`STRICT`, :data:`FORCE`, :data:`OUT`;
* :func:`sampler_settings` — options → :class:`~cassini_bayes.inference.runner.SamplerSettings`
  (progress bar only on a terminal);
* :func:`write_fit_run` — writes the run directory atomically (``posterior.nc``,
  ``summary.json``, ``config.toml``, ``report.html``), prints the result and the warnings, and
  under ``--strict`` raises :class:`~cassini_bayes.errors.NotConvergedError` (exit 3) *after*
  writing everything, or :class:`~cassini_bayes.errors.InadequateModelError` (also exit 3) when
  the summary's ``adequacy`` checks failed;
* :func:`collect_warnings` — turns Python warnings raised during a fit into lines for the summary.

The seed becomes a ``jax.random`` key exactly once, here, with ``jax.random.key(seed)``.
"""

from __future__ import annotations

import sys
import warnings
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

import typer

from cassini_bayes import __version__, _jax_cache
from cassini_bayes._devices import request_host_devices
from cassini_bayes.cli._options import seed_option

ORDER = 20


# one JAX CPU device per core and at least 4, before anything starts the backend (the CLI imports
# its command modules at start-up)
request_host_devices()

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
WHEEL_ERRORS = typer.Option("per-wheel", "--wheel-errors",
                            help="Robust model's wheel spin-inertia errors: per-wheel (one scale "
                                 "per wheel, the default) or common (one scale for all wheels).")


def wheel_errors_name(value: str) -> str:
    """The library's ``wheel_errors`` (``per_wheel``/``common``) of a ``--wheel-errors`` value."""
    from cassini_bayes.errors import InputError

    name = value.replace("-", "_")
    if name not in ("per_wheel", "common"):
        raise InputError(f"--wheel-errors {value!r}: choose per-wheel or common")
    return name


def sampler_settings(chains: int, warmup: int, draws: int, target_accept: float = 0.9):
    """The runner's settings from the common options; the progress bar only on a terminal."""
    from cassini_bayes.inference.runner import SamplerSettings

    return SamplerSettings(chains=chains, warmup=warmup, draws=draws,
                           target_accept=target_accept, progress=sys.stderr.isatty())


@contextmanager
def collect_warnings() -> Iterator[list[str]]:
    """Record ``warnings.warn`` messages raised inside the block as one-line strings."""
    lines: list[str] = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        yield lines
    for w in caught:
        if issubclass(w.category, (DeprecationWarning, FutureWarning)):
            continue
        msg = " ".join(str(w.message).split())
        if msg not in lines:
            lines.append(msg)


def _console():
    from rich.console import Console

    return Console(stderr=True, highlight=False)


def write_fit_run(out: Path, *, force: bool, strict: bool, idata, summary: dict,
                  config: dict) -> Path:
    """Write the run directory, report what happened, and enforce ``--strict``.

    Returns the final directory. Raises ``NotConvergedError`` under ``strict`` when
    ``summary["diagnostics"]["converged"]`` is false, ``InadequateModelError`` when
    ``summary["adequacy"]["ok"]`` is false — after the directory is complete.
    """
    from cassini_bayes.errors import InadequateModelError, NotConvergedError
    from cassini_bayes.rundir import (RunDir, write_config, write_posterior, write_report,
                                      write_summary)

    with RunDir(out, force=force) as rd:
        write_posterior(rd.path, idata)
        write_summary(rd.path, summary)
        write_config(rd.path, config)
        with collect_warnings() as report_warnings:
            write_report(rd.path, display_dir=rd.final, summary=summary)
    console = _console()
    for line in list(summary.get("warnings", [])) + report_warnings:
        console.print(f"[yellow]warning:[/yellow] {line}")
    d = summary["diagnostics"]
    status = "[green]converged[/green]" if d["converged"] else "[red]NOT converged[/red]"
    adequacy = summary.get("adequacy")
    failed = ([] if adequacy is None else
              [n for n, c in adequacy["checks"].items() if not c["ok"]])
    fit = ("" if adequacy is None else "; [green]adequacy ok[/green]" if not failed
           else f"; [red]ADEQUACY FAILED: {', '.join(failed)}[/red]")
    console.print(f"{summary['kind']}: {status} (max R-hat {d['max_r_hat']:.4f}, min bulk ESS "
                  f"{d['min_ess_bulk']:.0f}, {d['divergences']} divergences){fit} -> {rd.final}")
    typer.echo(str(rd.final))
    problems = []
    if not d["converged"]:
        msg = (f"{rd.final}: the sampler did not converge (max R-hat {d['max_r_hat']:.4f}, min "
               f"bulk ESS {d['min_ess_bulk']:.0f}, {d['divergences']} divergences); outputs "
               "written with converged = false — run longer (--warmup/--draws), raise "
               "--target-accept if it diverged, or check the data")
        if strict:
            problems.append(msg)
        else:
            console.print(f"[yellow]warning:[/yellow] {msg}")
    if failed and strict:
        problems.append(
            f"{rd.final}: the model does not fit the data: adequacy check(s) "
            f"{', '.join(failed)} failed (summary.json \"adequacy\", docs/adequacy.md); outputs "
            "written — look for an unmodelled error (a wheel's tachometer, the inertia, a "
            "thruster) or a bad file")
    if problems:
        raise (NotConvergedError if not d["converged"] else InadequateModelError)(
            "; ".join(problems))
    return rd.final


def _inertia_baseline(telemetries, spacecraft) -> tuple[dict | None, list[str]]:
    """The paper's all-axes least squares (Feldman & Lee Eq 11) on the same data, or ``None``.

    One file: :func:`cassini_bayes.estimators.inertia.fit_all_axes`. Several files: their Eq 11
    systems (each anchored on its own first sample) stacked into one least-squares problem.
    """
    import numpy as np

    from cassini_bayes.physics.momentum import INERTIA_NAMES, stacked_system, wheel_momentum_body

    try:
        from cassini_bayes.estimators.inertia import fit_all_axes

        parts, msgs = [], []
        for tel in telemetries:
            names = tel.active_wheels()
            rates = np.stack([np.nan_to_num(tel.wheel_rate(n)) for n in names], 1)
            axes = np.stack([spacecraft.wheel(n).axis for n in names])
            js = np.array([spacecraft.wheel(n).inertia for n in names])
            h = np.asarray(wheel_momentum_body(rates, axes, js))
            parts.append((tel.q, tel.omega, h))
        if len(parts) == 1:
            fit = fit_all_axes(*parts[0])
            pi, msgs = fit.pi, list(fit.warnings)
        else:
            systems = [stacked_system(*p) for p in parts]
            s = np.concatenate([np.asarray(a) for a, _ in systems])
            g = np.concatenate([np.asarray(b) for _, b in systems])
            pi = np.linalg.lstsq(s, g, rcond=None)[0]
        return {n: float(v) for n, v in zip(INERTIA_NAMES, pi)}, [f"baseline: {m}" for m in msgs]
    except Exception as e:  # the baseline must never sink the Bayesian fit
        return None, [f"baseline (Feldman & Lee Eq 11 least squares) unavailable: "
                      f"{' '.join(str(e).split())}"]


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
                                        "spacecraft model's [gyro] and [wheel_knowledge])."),
    wheel_errors: str = WHEEL_ERRORS,
    more: list[Path] = typer.Argument(None, hidden=True, help="More telemetry files, as in "
                                      "--telemetry A.csv B.csv."),
) -> None:
    """Posterior of the inertia tensor from RWA slews (shared I, per-file momentum)."""
    import jax

    from cassini_bayes.consistency import check_inertia_data
    from cassini_bayes.inference.adequacy import inertia_adequacy
    from cassini_bayes.inference.inertia import NOISE_NAMES, fit_inertia, robust_sites
    from cassini_bayes.inference.sensitivity import sensitivity_block
    from cassini_bayes.inference.summary import build_summary
    from cassini_bayes.physics.momentum import INERTIA_NAMES
    from cassini_bayes._paths import model_path
    from cassini_bayes.rundir import check_out, file_record
    from cassini_bayes.spacecraft import load_spacecraft
    from cassini_bayes.telemetry import read_telemetry_many

    telemetry = list(telemetry) + list(more or [])
    check_out(out, force=force, inputs=[*telemetry, model_path(spacecraft)])  # before any work
    sc = load_spacecraft(spacecraft)
    tels = read_telemetry_many(telemetry)
    check_inertia_data(tels, sc)  # units and conventions by the physics, before any sampling
    settings = sampler_settings(chains, warmup, draws, target_accept)
    wheel_errors = wheel_errors_name(wheel_errors)
    key = jax.random.key(seed)  # the one place the seed becomes a key
    with collect_warnings() as warns:
        post = fit_inertia(key, tels, sc, torque=torque, robust=not idealised, settings=settings,
                           wheel_errors=wheel_errors)
    baseline, base_warns = _inertia_baseline(tels, sc)
    robust = [] if idealised else robust_sites(post.problem.layout)
    priored = (["T_N"] if torque else []) + robust
    summary = build_summary(
        "inertia", post.idata, parameters=INERTIA_NAMES, diagnostics=post.diagnostics,
        baseline=baseline, seed=seed, warnings=warns + base_warns,
        nuisance=["H0"] + (["T_N"] if torque else []) + ["noise_scale", *NOISE_NAMES]
        + robust,
        adequacy=inertia_adequacy(post, list(INERTIA_NAMES) + priored))
    post_sd = {n: float(post.idata.posterior[n].std()) for n in INERTIA_NAMES}
    summary["model"] = "idealised" if idealised else "robust"
    summary["wheel_errors"] = None if idealised else wheel_errors
    summary["sensitivity"] = sensitivity_block(post.problem.sensitivity, post_sd)
    config = fit_config("fit inertia", seed=seed, spacecraft=sc, settings=settings,
                        inputs={"telemetry": [file_record(p) for p in telemetry],
                                "spacecraft": file_record(model_path(spacecraft))},
                        options={"torque": torque, "idealised": idealised,
                                 "wheel_errors": wheel_errors})
    write_fit_run(out, force=force, strict=strict, idata=post.idata, summary=summary,
                  config=config)


def fit_config(command: str, *, seed: int, spacecraft, settings, inputs: dict,
               options: dict) -> dict:
    """The resolved inputs of a fit, ``config.toml`` (docs/design.md §4.4): enough to re-run."""
    return {
        "command": command,
        "version": __version__,
        "seed": seed,
        "inputs": inputs,
        "options": options,
        "sampler": settings._asdict() | {"chain_method": settings.chain_method or "auto",
                                          "progress": False},
        "spacecraft": spacecraft.to_dict(),
        "jax_cache": _jax_cache.stats().to_dict(),  # did this fit load compiled programs?
    }


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    """Add ``fit inertia`` to the ``fit`` group."""
    groups["fit"].command("inertia")(fit_inertia_cmd)
