"""The adequacy verdict of a budget from posteriors: are its input runs fit to be combined?

A budget propagates the draws of independent fits (docs/budgets.md), so it inherits whatever is
wrong with them, and it assumes they describe one spacecraft. Four checks, each with the
``Check`` shape of the fits' verdicts (``summary["adequacy"]``, docs/adequacy.md):

* ``input_convergence`` — the number of input runs whose ``summary.json`` says the sampler did
  not converge (threshold 0);
* ``input_adequacy`` — the number of input runs whose own adequacy verdict failed (threshold 0;
  a run without a verdict is named in the note and not counted);
* ``spacecraft_models`` — the number of different spacecraft models the runs were fitted with
  (their ``config.toml``; threshold 1);
* ``shared_inertia`` — the budget's own consistency: every run that sampled the inertia (an
  inertia fit; a thrust or RWA4 fit with the inertia free) measured the same spacecraft, so
  their posterior means of each entry should agree within ``√(sd_a² + sd_b²)``; the statistic is
  the normal deviate of the smallest Bonferroni-adjusted two-sided tail probability over the
  pairs of runs and the six entries (threshold 4, as the fits' ``held_out``). Runs that share
  data (a thrust fit given the inertia run's posterior) agree by construction, so the check
  can only err on the safe side there.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
from scipy import stats

from cassini_bayes.inference.adequacy.check import (Z_THRESHOLD, Adequacy, Check, z_check,
                                                    normal_deviate, not_applicable)
from cassini_bayes.errors import InputError
from cassini_bayes.names import INERTIA_NAMES
from cassini_bayes.rundir import read_posterior, read_run_file

__all__ = ["budget_adequacy", "input_convergence", "input_adequacy", "spacecraft_models",
           "shared_inertia", "run_summaries", "run_models", "run_inertia_draws"]


def run_summaries(runs: dict) -> dict[str, dict]:
    """Each run's ``summary.json`` as a dict (runs without a readable one are left out); a run is
    a directory or an unsaved fit (its ``summary()``)."""
    out = {}
    for kind, run in runs.items():
        summary = run.summary() if hasattr(run, "summary") else read_run_file(run, "summary.json")
        if isinstance(summary, dict):
            out[kind] = summary
    return out


def run_models(runs: dict) -> dict[str, str]:
    """Each run's spacecraft model name from its ``config.toml`` (runs without one left out); a
    run is a directory or an unsaved fit (its ``config``)."""
    out = {}
    for kind, run in runs.items():
        cfg = run.config if hasattr(run, "config") else read_run_file(run, "config.toml")
        if cfg is None:
            continue
        name = (cfg.get("spacecraft") or {}).get("name")
        if isinstance(name, str):
            out[kind] = name
    return out


def run_inertia_draws(runs: dict) -> dict[str, np.ndarray]:
    """``(n, 6)`` draws of ``Ixx … Iyz`` (kg m²) of every run whose ``posterior.nc`` (or an
    unsaved fit's ``idata``) has them."""
    out = {}
    for kind, run in runs.items():
        try:
            post = (run.idata if hasattr(run, "idata") else read_posterior(run)).posterior
        except InputError:  # unreadable: load_posterior has already said so for the budget's own
            continue
        if all(n in post for n in INERTIA_NAMES):
            d = np.stack([np.asarray(post[n].values, float).reshape(-1) for n in INERTIA_NAMES],
                         -1)
            if d.shape[0] >= 10 and np.all(np.isfinite(d)):
                out[kind] = d
    return out


def _num(diag: dict, key: str, spec: str) -> str:
    x = diag.get(key)
    return format(x, spec) if isinstance(x, (int, float)) else "?"


def input_convergence(summaries: dict[str, dict], runs: dict[str, Path]) -> Check:
    """How many input runs did not converge (their ``diagnostics.converged`` is false)."""
    bad = {k: s.get("diagnostics") or {} for k, s in summaries.items()
           if (s.get("diagnostics") or {}).get("converged") is False}
    note = "; ".join(
        f"the {k} run {runs[k]} did not converge (max R-hat {_num(d, 'max_r_hat', '.4f')}, min "
        f"bulk ESS {_num(d, 'min_ess_bulk', '.0f')}, {_num(d, 'divergences', 'd')} divergences): "
        "its lines rest on draws that may not represent its posterior; re-fit it with more draws"
        for k, d in bad.items())
    return z_check("input_convergence", float(len(bad)), 0.0, ", ".join(bad) or None, note or None)


def input_adequacy(summaries: dict[str, dict], runs: dict[str, Path]) -> Check:
    """How many input runs failed their own adequacy checks (a run without a verdict is named
    in the note, not counted)."""
    bad, unchecked = {}, [k for k in runs if not isinstance(summaries.get(k, {}).get("adequacy"),
                                                             dict)]
    for k, s in summaries.items():
        block = s.get("adequacy")
        if isinstance(block, dict) and block.get("ok") is False:
            bad[k] = [n for n, c in (block.get("checks") or {}).items()
                      if isinstance(c, dict) and c.get("ok") is False]
    parts = [f"the {k} run {runs[k]} failed its adequacy checks ({', '.join(v)}): its model may "
             "not fit its data" for k, v in bad.items()]
    if unchecked:
        parts.append("no adequacy verdict in the " + ", ".join(unchecked) + " run(s)")
    return z_check("input_adequacy", float(len(bad)), 0.0, ", ".join(bad) or None,
                  "; ".join(parts) or None)


def spacecraft_models(models: dict[str, str]) -> Check:
    """How many different spacecraft models the runs were fitted with (threshold 1)."""
    n = len(set(models.values()))
    if n == 0:
        return not_applicable("spacecraft_models", 1.0, "no run's config.toml names its model")
    note = ", ".join(f"{k}: {v}" for k, v in models.items())
    if n > 1:
        note += ("; the budget combines parameters of different spacecraft or epochs; give runs "
                 "of one model")
    return z_check("spacecraft_models", float(n), 1.0, note=note)


def shared_inertia(draws: dict[str, np.ndarray], threshold: float = Z_THRESHOLD) -> Check:
    """Do the runs that sampled the inertia agree on it? (module docstring)"""
    name = "shared_inertia"
    if len(draws) < 2:
        return not_applicable(name, threshold, "fewer than two input runs sampled the inertia"
                              + (f" ({', '.join(draws)})" if draws else ""))
    worst, where, n_tests = -1.0, "", 0
    for (ka, a), (kb, b) in itertools.combinations(draws.items(), 2):
        sd = np.sqrt(a.var(axis=0, ddof=1) + b.var(axis=0, ddof=1))
        z = np.abs(a.mean(axis=0) - b.mean(axis=0)) / np.maximum(sd, 1e-300)
        n_tests += z.size
        j = int(np.argmax(z))
        if z[j] > worst:
            worst = float(z[j])
            where = (f"{INERTIA_NAMES[j]}: {ka} {a[:, j].mean():.6g} ± {a[:, j].std(ddof=1):.3g}"
                     f", {kb} {b[:, j].mean():.6g} ± {b[:, j].std(ddof=1):.3g} kg m^2")
    p = 2.0 * stats.norm.sf(worst)
    return z_check(name, normal_deviate(min(p * n_tests, 1.0)), threshold, where,
                  f"largest |z| {worst:.2f} over {n_tests} entries and pairs of runs; runs that "
                  "disagree describe different spacecraft (an epoch, a model) or one of them "
                  "does not fit its data")


def budget_adequacy(runs: dict) -> Adequacy:
    """The four checks of a budget whose inputs are ``runs`` (by kind): run directories or
    unsaved fits (objects with ``summary()``, ``config`` and ``idata``)."""
    summaries = run_summaries(runs)
    return Adequacy((input_convergence(summaries, runs), input_adequacy(summaries, runs),
                     spacecraft_models(run_models(runs)), shared_inertia(run_inertia_draws(runs))))
