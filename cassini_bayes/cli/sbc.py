"""``cassini-bayes sbc``: simulation-based calibration and coverage of a model, at scale.

::

    cassini-bayes sbc MODEL --replicates N --out DIR [--scenario FILE] [--seed N]
        [--executor local|dask] [--scheduler ADDR] [--workers W] [--batch B]
        [--set KEY=VALUE ...] [--alpha A] [--force] [--resume]

Runs an SBC campaign (:mod:`cassini_bayes.analysis.campaign`) of a registered model
(:mod:`cassini_bayes.analysis.sbc_models`) and writes the run directory ``DIR`` atomically:

- ``summary.json`` — per-parameter uniformity p-values (chi-square on binned ranks and the ECDF
  simultaneous-band test), coverage of the 50/80/90/95 % central intervals with binomial standard
  errors, number of replicates, failed and non-converged counts, seed, version;
- ``report.html`` — self-contained: tables, rank histograms, ECDF-difference plots;
- ``config.toml`` — model, scenario, settings, seed, batch size: enough to re-run it;
- ``replicates.npz`` — per replicate: truth, thinned draws, ranks, divergences, R-hat, and the
  effective sample size of the draws before thinning (``ess``; ``summary.json`` counts the
  replicates whose ESS is below the number of ranked draws).

While it runs, finished batches are checkpointed in the hidden sibling ``.DIR.sbc-work``; a
campaign that was interrupted continues from there with ``--resume`` (same seed and batch size
give exactly the replicates of an uninterrupted run). ``--force`` discards any checkpoints and
replaces a previous result — only a directory this package wrote
(:func:`cassini_bayes.rundir.check_out`), and only once the new result is complete.

``--set KEY=VALUE`` (repeatable) passes a model option: sampler sizes (``num_warmup``,
``num_draws``, ``num_chains``, ``thin``) or a model's mis-specification switch (e.g. ``thrust``:
``pulse_dynamics=false``; ``rwa4``: ``rwa4_inertia_factor=1.2``; ``inertia``:
``wheel_inertia_factor=1.05``) or a model variant (``inertia``: ``robust=true``, the robust model
``fit inertia`` uses by default, every nuisance truth drawn from its prior; docs/sbc/
inertia_robust/); ``VALUE`` is read as a TOML value (``300``, ``1.2``, ``false``,
``"cone"``) and falls back to a plain string. The campaigns of the issue's acceptance run on a
16-core machine as, e.g.::

    cassini-bayes sbc thrust -n 208 --batch 4 --executor dask --workers 16 --out sbc-thrust
    cassini-bayes sbc rwa4 -n 208 --batch 4 --executor dask --workers 16 --out sbc-rwa4
    cassini-bayes sbc inertia -n 208 --batch 16 --out sbc-inertia
    cassini-bayes sbc inertia -n 208 --batch 16 --set robust=true --out sbc-inertia-robust

(the inertia and toy models are fitted by one vmapped NUTS program per batch; the thrust and
RWA4 fits are not vectorised across replicates: a local Dask cluster of one single-threaded worker
per core is how they use the machine; the same seed gives the same ranks with either executor).
Measured throughput and the campaigns' results: ``docs/sbc/``.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import typer

from cassini_bayes._paths import text_file
from cassini_bayes.api._limits import MAX_CHAINS, MAX_DRAWS
from cassini_bayes.cli._options import seed_option
from cassini_bayes.errors import InputError, Interrupted
from cassini_bayes.rundir import check_out

ORDER = 60

__all__ = ["register", "parse_options"]


def _sbc_cmd(
    model: str = typer.Argument(..., help="Model to calibrate: toy, inertia, thrust or rwa4 "
                                "(whichever are registered)."),
    replicates: int = typer.Option(..., "--replicates", "-n", min=1,
                                   help="Number of replicates N."),
    out: Path = typer.Option(..., "--out", help="Run directory to write (atomically)."),
    scenario: Path | None = typer.Option(None, "--scenario",
                                         help="Scenario TOML for the simulator/model."),
    seed: int = seed_option(0, "Root seed; replicate i uses fold_in(key, i)."),
    executor: str = typer.Option("local", "--executor", help="local or dask."),
    scheduler: str | None = typer.Option(None, "--scheduler",
                                         help="Dask scheduler address (default: a local "
                                         "cluster)."),
    workers: int | None = typer.Option(None, "--workers", min=1,
                                       help="Workers of the local Dask "
                                       "cluster (default min(2, CPU count)); with "
                                       "--executor dask and no --scheduler."),
    batch: int = typer.Option(16, "--batch", min=1, help="Replicates per vectorised batch."),
    options: list[str] = typer.Option([], "--set", help="Model option KEY=VALUE (VALUE as "
                                      "TOML), repeatable: num_warmup, num_draws, num_chains, "
                                      "thin or a model's mis-specification switch."),
    alpha: float = typer.Option(0.01, "--alpha", help="Family-wise false-failure rate of "
                                "each uniformity statistic (Bonferroni over parameters)."),
    force: bool = typer.Option(False, "--force", help="Overwrite DIR and drop checkpoints."),
    resume: bool = typer.Option(False, "--resume", help="Continue an interrupted campaign."),
) -> None:
    """Simulation-based calibration (ranks, uniformity tests, coverage) of MODEL."""
    from cassini_bayes.analysis.sbc_models import ModelSpec, registered_models
    from cassini_bayes.analysis.sbc_run import work_dir, write_run

    if model not in registered_models():
        raise InputError(f"unknown model {model!r} for sbc; choose one of "
                         f"{', '.join(registered_models())}")
    if not 0 < alpha < 1:
        raise InputError(f"--alpha must be between 0 and 1, got {alpha}")
    if scenario is not None:   # a file, or a shipped scenario's bare name
        from cassini_bayes.simulate.scenario import scenario_path

        scenario = scenario_path(scenario)
    scenario_text = None if scenario is None else text_file(scenario, "scenario")
    out = Path(out)
    work = work_dir(out)
    check_out(out, force=force, inputs=[scenario] if scenario else [])
    _clear_or_keep_checkpoints(out, work, force=force, resume=resume)
    if workers is not None and (executor != "dask" or scheduler):
        raise InputError("--workers sets the size of a local Dask cluster: it needs "
                         "--executor dask and no --scheduler")
    spec = ModelSpec.make(model, scenario_text,
                          scenario_source=str(scenario) if scenario else "<scenario>",
                          **_check_sampler_options(parse_options(options)))
    result = _run_with_progress(spec, replicates, work, seed=seed, batch=batch,
                                executor=executor, scheduler=scheduler, workers=workers)
    summary = write_run(out, spec, result, alpha=alpha, executor=executor, force=force)
    shutil.rmtree(work, ignore_errors=True)
    _print_summary(summary, out)


def _clear_or_keep_checkpoints(out: Path, work: Path, *, force: bool, resume: bool) -> None:
    """Drop the checkpoint folder ``work`` with ``--force`` or when it holds no finished batch;
    keep it with ``--resume``; else it is an error that names both."""
    if not work.exists():
        return
    if force or not any(work.glob("batch_*.npz")):  # (no finished batch: nothing to keep)
        shutil.rmtree(work)
    elif not resume:
        raise InputError(f"an unfinished campaign for {out} is checkpointed in {work}; "
                         "pass --resume to continue it or --force to start over")


def _run_with_progress(spec, replicates: int, work: Path, *, seed: int, batch: int,
                       executor: str, scheduler: str | None, workers: int | None):
    """Run the campaign with a progress bar of its batches. An interrupted campaign with
    finished batches stops with a line on how to resume; one without any leaves no trace."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn

    from cassini_bayes.analysis.campaign import run_campaign

    with Progress("[progress.description]{task.description}", BarColumn(),
                  MofNCompleteColumn(), TimeElapsedColumn(), transient=True) as progress:
        task = progress.add_task(f"sbc {spec.name}: batches", total=None)

        def on_batch(b, n_done, n_total):
            progress.update(task, completed=n_done, total=n_total)

        try:
            return run_campaign(spec, replicates, work, seed=seed, batch_size=batch,
                                executor=executor, scheduler=scheduler, n_workers=workers,
                                on_batch=on_batch)
        except KeyboardInterrupt:
            n_done = len(list(work.glob("batch_*.npz")))
            if not n_done:
                shutil.rmtree(work, ignore_errors=True)
                raise
            raise Interrupted(f"{n_done} finished batch(es) are checkpointed in {work}; run "
                              "the same command with --resume to continue") from None
        except BaseException:
            if not any(work.glob("batch_*.npz")):  # nothing worth resuming: leave no trace
                shutil.rmtree(work, ignore_errors=True)
            raise


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    """Add ``sbc`` to the ``cassini-bayes`` command."""
    app.command("sbc")(_sbc_cmd)


def parse_options(items: list[str]) -> dict:
    """``["KEY=VALUE", ...]`` of ``--set`` as a dict; ``VALUE`` read as TOML, else a string."""
    from cassini_bayes._toml import toml_value

    out = {}
    for item in items:
        key, sep, raw = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise InputError(f"--set {item!r}: write KEY=VALUE, e.g. --set num_warmup=300")
        out[key] = toml_value(raw)
    return out


_SAMPLER_RANGE = {"num_warmup": (0, MAX_DRAWS), "num_draws": (1, MAX_DRAWS),
                  "num_chains": (1, MAX_CHAINS), "thin": (1, MAX_DRAWS)}


def _check_sampler_options(options: dict) -> dict:
    """``options`` after checking the sampler sizes every model takes (``num_warmup >= 0``,
    ``num_draws``, ``num_chains``, ``thin >= 1`` integers, ``thin <= num_draws``, and the
    fits' upper limits)."""
    for key, (low, high) in _SAMPLER_RANGE.items():
        v = options.get(key)
        if v is not None and (isinstance(v, bool) or not isinstance(v, int)
                              or not low <= v <= high):
            raise InputError(f"--set {key}={v!r}: must be an integer in {low} .. {high}")
    if options.get("thin", 1) > options.get("num_draws", options.get("thin", 1)):
        raise InputError(f"--set thin={options['thin']} keeps no draw of num_draws="
                         f"{options['num_draws']}; use thin <= num_draws")
    return options


def _print_summary(summary: dict, out: Path) -> None:
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    t = Table(title=f"SBC {summary['model']}: {summary['replicates']} replicates, "
              f"{summary['draws_per_replicate']} draws each")
    for col in ("parameter", "chi2 p", "ECDF p", "cov 50", "cov 80", "cov 90", "cov 95"):
        t.add_column(col, justify="left" if col == "parameter" else "right")
    for name, p in summary["parameters"].items():
        cov = p["coverage"]
        t.add_row(escape(name), f"{p['chi2']['p_value']:.3g}", f"{p['ecdf']['p_value']:.3g}",
                  *(f"{cov[k]['observed']:.3f}" for k in ("50", "80", "90", "95")))
    console = Console()
    console.print(t)
    verdict = "PASSED" if summary["passed"] else "FAILED"
    console.print(f"uniformity {verdict} at family-wise alpha={summary['alpha_family']}; "
                  f"failed replicates {summary['failures']}, not converged "
                  f"{summary['non_converged']}, ESS below the {summary['draws_per_replicate']} "
                  f"ranked draws {summary['ess']['below_draws']}; wrote {out}")
