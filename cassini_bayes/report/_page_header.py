"""The top of a fit's report: the verdicts as badges, the run's identity, the warnings.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from cassini_bayes.diagnostics import ESS_BULK_MIN, R_HAT_MAX
from cassini_bayes.report.adequacy import adequacy_badge
from cassini_bayes.report.html import (
    badge,
    esc,
    page_header,
)
from cassini_bayes.report._answer import _wheel
from cassini_bayes.report.rundata import RunData
from cassini_bayes.report.tables import (
    BFMI_MIN,
    BudgetCheck,
    DiagnosticTable,
    ParameterRow,
)

KIND_TITLES = {
    "inertia": "inertia tensor from reaction-wheel slews (momentum model, Feldman & Lee Eqs 2-11)",
    "thrust": "thrust and pulse time constants from wheel-biasing events "
              "(impulse model, Feldman & Lee Eqs 14-23)",
    "rwa4": "RWA4 spin axis (Brown 2012)",
}


def verdict_badges(summary: dict, *, converged: bool | None = None,
                   checks: list[BudgetCheck] | None = None) -> str:
    """The verdict badges that open every report: converged (a sampled fit), adequate (from
    ``summary["adequacy"]``: a fit always, any other run when it has the block), within the
    papers' budgets (``checks``)."""
    out = []
    if converged is not None:
        out.append(badge("CONVERGED" if converged else "NOT CONVERGED", converged))
    if converged is not None or isinstance(summary.get("adequacy"), dict):
        out.append(adequacy_badge(summary))
    if checks:
        failed = [c for c in checks if not c.passed]
        out.append(badge("WITHIN THE PAPERS' BUDGETS" if not failed else
                         f"OUTSIDE THE PAPERS' BUDGETS ({len(failed)} of {len(checks)})",
                         not failed))
    return " ".join(out)


def report_header(run: RunData, diag: DiagnosticTable, rows: list[ParameterRow],
            checks: list[BudgetCheck], problems: list[str], shown: Path) -> str:
    cfg = run.config
    seed = run.summary.get("seed", cfg.get("seed", "–"))
    version = run.summary.get("version", cfg.get("version", "–"))
    src = "fit" if diag.converged_summary is not None else "recomputed"
    title = KIND_TITLES.get(run.kind, "unknown kind")
    name = _wheel(run).get("name")
    if run.kind == "rwa4" and name not in (None, "RWA4"):
        title = f"{name} spin axis (Brown 2012's method)"
    meta = (f"{run.kind} — {title} · {shown} · seed {seed} · "
            f"cassini-bayes {version} · {diag.chains} chains × {diag.draws} draws")
    badges = (f"{verdict_badges(run.summary, converged=diag.converged, checks=checks)}"
              f' <span class="na">({esc(src)} verdict: max R-hat ≤ {R_HAT_MAX}, min bulk ESS ≥ '
              f"{ESS_BULK_MIN:g}, no divergences)</span>")
    return page_header(badges, meta, _warnings(run, diag, rows) + problems)


def _warnings(run: RunData, diag: DiagnosticTable, rows: list[ParameterRow]) -> list[str]:
    w = [str(x) for x in (run.summary.get("warnings") or [])]
    w += list(run.notes)
    if diag.divergences:
        w.append(f"{diag.divergences} divergent transitions: the posterior may be biased")
    if np.isfinite(diag.overall.max_r_hat) and diag.overall.max_r_hat > R_HAT_MAX:
        w.append(f"max R-hat {diag.overall.max_r_hat:.4f} > {R_HAT_MAX}: chains disagree")
    if np.isfinite(diag.overall.min_ess_bulk) and diag.overall.min_ess_bulk < ESS_BULK_MIN:
        w.append(f"min bulk ESS {diag.overall.min_ess_bulk:.0f} < {ESS_BULK_MIN:g}")
    if diag.bfmi is not None and np.any(diag.bfmi < BFMI_MIN):
        w.append(f"energy BFMI below {BFMI_MIN} in chain(s) "
                 f"{', '.join(str(i) for i in np.flatnonzero(diag.bfmi < BFMI_MIN))}")
    if diag.converged_summary is not None and diag.converged_summary != diag.overall.converged:
        w.append(f"the fit's verdict (converged = {diag.converged_summary}) differs from this "
                 f"report's check on posterior.nc (R-hat ≤ {R_HAT_MAX}, bulk ESS ≥ "
                 f"{ESS_BULK_MIN:g}, no divergences)")
    weak = [r.label for r in rows if r.flag]
    if weak:
        w.append("weakly identified (posterior/prior contraction < 0.5): " + ", ".join(weak))
    # keep order, drop repeats
    return list(dict.fromkeys(w))
