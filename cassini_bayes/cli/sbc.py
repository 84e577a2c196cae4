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
``wheel_inertia_factor=1.05``); ``VALUE`` is read as a TOML value (``300``, ``1.2``, ``false``,
``"cone"``) and falls back to a plain string. The campaigns of the issue's acceptance run on a
16-core machine as, e.g.::

    cassini-bayes sbc thrust -n 208 --batch 4 --executor dask --workers 16 --out sbc-thrust
    cassini-bayes sbc rwa4 -n 208 --batch 4 --executor dask --workers 16 --out sbc-rwa4
    cassini-bayes sbc inertia -n 208 --batch 16 --out sbc-inertia

(the inertia and toy models are fitted by one vmapped NUTS program per batch; the thrust and
RWA4 fits are not vectorised across replicates: a local Dask cluster of one single-threaded worker
per core is how they use the machine; the same seed gives the same ranks with either executor).
Measured throughput and the campaigns' results: ``docs/sbc/``.
"""

from __future__ import annotations

import datetime as _dt
import json
import shutil
from pathlib import Path

import numpy as np
import typer

from cassini_bayes import __version__
from cassini_bayes._paths import text_file
from cassini_bayes.cli._options import seed_option
from cassini_bayes.errors import InputError, Interrupted
from cassini_bayes.rundir import RunDir, check_out

ORDER = 60

__all__ = ["register", "write_run", "work_dir", "parse_options", "check_sampler_options"]


def work_dir(out: Path) -> Path:
    """Checkpoint directory of the campaign whose result goes to ``out``."""
    return out.parent / f".{out.name}.sbc-work"


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    """Add ``sbc`` to the ``cassini-bayes`` command."""

    @app.command("sbc")
    def sbc(
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
        from cassini_bayes.analysis.campaign import run_campaign
        from cassini_bayes.analysis.sbc_models import ModelSpec, registered_models

        if model not in registered_models():
            raise InputError(f"unknown model {model!r} for sbc; choose one of "
                             f"{', '.join(registered_models())}")
        if not 0 < alpha < 1:
            raise InputError(f"--alpha must be between 0 and 1, got {alpha}")
        scenario_text = None if scenario is None else text_file(scenario, "scenario")
        out = Path(out)
        work = work_dir(out)
        check_out(out, force=force, inputs=[scenario] if scenario else [])
        if work.exists():
            if force:
                shutil.rmtree(work)
            elif not resume:
                raise InputError(f"an unfinished campaign for {out} is checkpointed in {work}; "
                                 "pass --resume to continue it or --force to start over")
        if workers is not None and (executor != "dask" or scheduler):
            raise InputError("--workers sets the size of a local Dask cluster: it needs "
                             "--executor dask and no --scheduler")
        spec = ModelSpec.make(model, scenario_text,
                              scenario_source=str(scenario) if scenario else "<scenario>",
                              **check_sampler_options(parse_options(options)))

        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn

        with Progress("[progress.description]{task.description}", BarColumn(),
                      MofNCompleteColumn(), TimeElapsedColumn(), transient=True) as progress:
            task = progress.add_task(f"sbc {model}: batches", total=None)

            def on_batch(b, n_done, n_total):
                progress.update(task, completed=n_done, total=n_total)

            try:
                result = run_campaign(spec, replicates, work, seed=seed, batch_size=batch,
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
        summary = write_run(out, spec, result, alpha=alpha, executor=executor, force=force)
        shutil.rmtree(work, ignore_errors=True)
        _print_summary(summary, out)


def parse_options(items: list[str]) -> dict:
    """``["KEY=VALUE", ...]`` of ``--set`` as a dict; ``VALUE`` read as TOML, else a string."""
    import tomllib

    out = {}
    for item in items:
        key, sep, raw = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise InputError(f"--set {item!r}: write KEY=VALUE, e.g. --set num_warmup=300")
        try:
            value = tomllib.loads(f"v = {raw.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            value = raw.strip()
        out[key] = value
    return out


_SAMPLER_MIN = {"num_warmup": 0, "num_draws": 1, "num_chains": 1, "thin": 1}


def check_sampler_options(options: dict) -> dict:
    """``options`` after checking the sampler sizes every model takes (``num_warmup >= 0``,
    ``num_draws``, ``num_chains``, ``thin >= 1`` integers, ``thin <= num_draws``)."""
    for key, low in _SAMPLER_MIN.items():
        v = options.get(key)
        if v is not None and (isinstance(v, bool) or not isinstance(v, int) or v < low):
            raise InputError(f"--set {key}={v!r}: must be an integer >= {low}")
    if options.get("thin", 1) > options.get("num_draws", options.get("thin", 1)):
        raise InputError(f"--set thin={options['thin']} keeps no draw of num_draws="
                         f"{options['num_draws']}; use thin <= num_draws")
    return options


def _print_summary(summary: dict, out: Path) -> None:
    from rich.console import Console
    from rich.table import Table

    t = Table(title=f"SBC {summary['model']}: {summary['replicates']} replicates, "
              f"{summary['draws_per_replicate']} draws each")
    for col in ("parameter", "chi2 p", "ECDF p", "cov 50", "cov 80", "cov 90", "cov 95"):
        t.add_column(col, justify="left" if col == "parameter" else "right")
    for name, p in summary["parameters"].items():
        cov = p["coverage"]
        t.add_row(name, f"{p['chi2']['p_value']:.3g}", f"{p['ecdf']['p_value']:.3g}",
                  *(f"{cov[k]['observed']:.3f}" for k in ("50", "80", "90", "95")))
    console = Console()
    console.print(t)
    verdict = "PASSED" if summary["passed"] else "FAILED"
    console.print(f"uniformity {verdict} at family-wise alpha={summary['alpha_family']}; "
                  f"failed replicates {summary['failures']}, not converged "
                  f"{summary['non_converged']}, ESS below the {summary['draws_per_replicate']} "
                  f"ranked draws {summary['ess']['below_draws']}; wrote {out}")


# -------------------------------------------------------------------------------- run dir


def summarize(spec, result, *, alpha: float = 0.01, executor: str = "local"):
    """``(SbcResult, summary dict)`` of a finished campaign (failed replicates left out)."""
    from cassini_bayes.analysis.sbc import sbc_result

    ok = ~result.failed
    names = result.names
    draws = {n: result.draws[ok, j] for j, n in enumerate(names)}
    truth = {n: result.truth[ok, j] for j, n in enumerate(names)}
    if ok.sum() < 2:
        raise InputError(f"only {int(ok.sum())} of {len(ok)} replicates produced finite draws; "
                         "check the model and scenario")
    sbc = sbc_result(names, result.rank[ok], result.n_draws, draws=draws, truth=truth,
                     alpha_family=alpha)
    params = {}
    for n, p in sbc.parameters.items():
        params[n] = {
            "chi2": {"statistic": p.chi2.statistic, "df": p.chi2.df, "bins": p.chi2.bins,
                     "p_value": p.chi2.p_value},
            "ecdf": {"statistic": p.ecdf.statistic, "p_value": p.ecdf.p_value},
            "passed": bool(p.chi2.p_value >= sbc.alpha and p.ecdf.p_value >= sbc.alpha),
            "coverage": {f"{round(100 * c):d}": {"nominal": c, "observed": float(o), "se": float(s)}
                         for c, o, s in zip(p.coverage.levels, p.coverage.observed,
                                            p.coverage.se)},
        }
    summary = {
        "kind": "sbc",
        "model": spec.name,
        "replicates": len(result.failed),
        "replicates_used": int(ok.sum()),
        "draws_per_replicate": int(result.n_draws),
        "failures": int(result.failed.sum()),
        "non_converged": int((~result.converged & ~result.failed).sum()),
        "divergent_transitions": int(result.n_divergent.sum()),
        "ess": _ess_summary(result, ok),
        "statistics": {
            "chi2": "Pearson chi-square on binned ranks, p from scipy.stats.chi2 (bins - 1 df)",
            "ecdf": "Saeilynoja et al. (2022) ECDF simultaneous-band statistic, simulated null",
        },
        "alpha_family": float(alpha),
        "alpha_per_parameter": float(sbc.alpha),
        "passed": sbc.passed("both"),
        "parameters": params,
        "settings": result.settings,
        "seed": int(result.seed),
        "batch_size": int(result.batch_size),
        "executor": executor,
        "version": __version__,
    }
    return sbc, summary


def _ess_summary(result, ok) -> dict:
    """Effective sample sizes of the replicates' draws before thinning, against the ``L`` ranked
    draws: ``below_draws`` replicates have ``ESS < L`` (their ranked draws are autocorrelated)."""
    ess = result.ess[ok]
    finite = ess[np.isfinite(ess)]
    return {"description": "smallest effective sample size over the parameters of each "
                           "replicate's draws before thinning (NumPyro estimator)",
            "min": float(finite.min()) if finite.size else None,
            "median": float(np.median(finite)) if finite.size else None,
            "below_draws": int(np.sum(~(ess >= result.n_draws)))}


def write_run(out: Path, spec, result, *, alpha: float = 0.01, executor: str = "local",
              force: bool = False) -> dict:
    """Write the run directory ``out`` atomically (:class:`cassini_bayes.rundir.RunDir`).

    Returns the ``summary.json`` content.
    """
    import tomli_w

    sbc, summary = summarize(spec, result, alpha=alpha, executor=executor)
    with RunDir(out, force=force) as rd:
        tmp = rd.path
        (tmp / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
        config = {"command": "sbc", "model": spec.name, "replicates": summary["replicates"],
                  "seed": summary["seed"], "batch": summary["batch_size"], "alpha": alpha,
                  "executor": executor, "version": __version__,
                  "created": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
                  "settings": _toml_safe(result.settings),
                  "options": _toml_safe(dict(spec.options))}
        if spec.scenario_text:
            config["scenario"] = spec.scenario_text
        (tmp / "config.toml").write_text(tomli_w.dumps(config))
        np.savez(tmp / "replicates.npz", names=np.asarray(result.names), truth=result.truth,
                 draws=result.draws, rank=result.rank, n_divergent=result.n_divergent,
                 rhat=result.rhat, ess=result.ess, failed=result.failed,
                 converged=result.converged)
        (tmp / "report.html").write_text(_report_html(sbc, summary))
    return summary


def _toml_safe(d: dict) -> dict:
    return {k: (v if isinstance(v, (int, float, str, bool)) else str(v)) for k, v in d.items()
            if v is not None}


def _png(fig) -> bytes:
    import io

    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    return buf.getvalue()


def _report_html(sbc, summary: dict) -> str:
    import matplotlib

    matplotlib.use("Agg", force=False)
    from cassini_bayes.analysis.sbc import plot_ecdf_difference, plot_rank_histograms
    from cassini_bayes.report.html import badge, figure, html_page, paragraph, section, table

    a = summary["alpha_per_parameter"]
    rows, cls = [], []
    for n, p in summary["parameters"].items():
        rows.append([n, f"{p['chi2']['statistic']:.2f}", p["chi2"]["bins"],
                     f"{p['chi2']['p_value']:.3g}", f"{p['ecdf']['statistic']:.4f}",
                     f"{p['ecdf']['p_value']:.3g}", "pass" if p["passed"] else "FAIL"])
        cls.append(["", "", "", "bad" if p["chi2"]["p_value"] < a else "good", "",
                    "bad" if p["ecdf"]["p_value"] < a else "good",
                    "good" if p["passed"] else "bad"])
    uni = table(["parameter", "χ²", "bins", "χ² p", "ECDF γ", "ECDF p", "verdict"], rows,
                classes=cls)
    crow, ccls = [], []
    for n, p in summary["parameters"].items():
        row, rc = [n], [""]
        for k in ("50", "80", "90", "95"):
            c = p["coverage"][k]
            row.append(f"{c['observed']:.3f} ± {c['se']:.3f}")
            z = abs(c["observed"] - c["nominal"]) / c["se"]
            rc.append("bad" if z > 3 else ("warn" if z > 2 else "good"))
        crow.append(row)
        ccls.append(rc)
    cov = table(["parameter", "50 %", "80 %", "90 %", "95 %"], crow, classes=ccls)
    header = (badge("uniformity passed" if summary["passed"] else "uniformity FAILED",
                    summary["passed"])
              + paragraph(f"model {summary['model']}, {summary['replicates']} replicates "
                          f"({summary['failures']} failed, {summary['non_converged']} not "
                          f"converged, {summary['ess']['below_draws']} with an effective sample "
                          "size below the ranked draws), "
                          f"{summary['draws_per_replicate']} thinned draws each, "
                          f"seed {summary['seed']}, cassini-bayes {summary['version']}"))
    sections = [
        section("Uniformity of ranks", [
            uni,
            paragraph("Ranks of the true parameter among the thinned posterior draws are "
                      "discrete-uniform when the posterior is calibrated (Talts et al. 2018). "
                      f"Each parameter is tested at alpha = {a:.3g} (family-wise "
                      f"{summary['alpha_family']} per statistic, Bonferroni): Pearson chi-square "
                      "on binned ranks, and the ECDF simultaneous-band statistic of Säilynoja et "
                      "al. (2022) with a simulated null.", note=True)]),
        section("Coverage of central intervals", [
            cov,
            paragraph("Fraction of replicates whose truth lies in the posterior's central "
                      "interval, ± the binomial standard error at the nominal level; red beyond "
                      "3 standard errors, amber beyond 2.", note=True)]),
        section("Rank histograms", figure(
            _png(plot_rank_histograms(sbc)),
            "Rank histograms; grey: 99 % pointwise binomial band of a uniform histogram.")),
        section("ECDF difference", figure(
            _png(plot_ecdf_difference(sbc)),
            f"ECDF of the ranks minus the uniform CDF, with ArviZ's simultaneous "
            f"{100 * (1 - a):.2f} % band (Säilynoja et al. 2022).")),
    ]
    return html_page(f"SBC: {summary['model']}", sections, header=header)
