"""The run directory of an SBC campaign: its ``summary.json``, ``config.toml``,
``replicates.npz`` and ``report.html`` (the contract is ``cassini-bayes sbc``'s, docs/cli.md),
and the checkpoint folder of a campaign under way."""

from __future__ import annotations

import datetime as _dt
from pathlib import Path

import numpy as np

from cassini_bayes import __version__
from cassini_bayes.errors import InputError
from cassini_bayes.rundir import RunDir, write_config, write_summary

__all__ = ["write_run", "work_dir"]


def work_dir(out: Path) -> Path:
    """Checkpoint directory of the campaign whose result goes to ``out``."""
    return out.parent / f".{out.name}.sbc-work"


def _summarize(spec, result, *, alpha: float = 0.01, executor: str = "local"):
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
    from cassini_bayes.report.sbc import sbc_report_html

    sbc, summary = _summarize(spec, result, alpha=alpha, executor=executor)
    with RunDir(out, force=force) as rd:
        tmp = rd.path
        write_summary(tmp, summary)
        config = {"command": "sbc", "model": spec.name, "replicates": summary["replicates"],
                  "seed": summary["seed"], "batch": summary["batch_size"], "alpha": alpha,
                  "executor": executor, "version": __version__,
                  "created": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
                  "settings": _toml_safe(result.settings),
                  "options": _toml_safe(dict(spec.options))}
        if spec.scenario_text:
            config["scenario"] = spec.scenario_text
        write_config(tmp, config)
        np.savez(tmp / "replicates.npz", names=np.asarray(result.names), truth=result.truth,
                 draws=result.draws, rank=result.rank, n_divergent=result.n_divergent,
                 rhat=result.rhat, ess=result.ess, failed=result.failed,
                 converged=result.converged)
        (tmp / "report.html").write_text(sbc_report_html(sbc, summary))
    return summary


def _toml_safe(d: dict) -> dict:
    return {k: (v if isinstance(v, (int, float, str, bool)) else str(v)) for k, v in d.items()
            if v is not None}
