"""The numbers of the report: the answer table, the papers' budgets and the sampler diagnostics.

**Diagnostics** (R-hat, bulk/tail ESS) are the fit's own: ``summary.json`` holds ArviZ's values
for every parameter and nuisance component, and the report shows those, so a page and its
summary never disagree. A component ``summary.json`` lacks (an older or hand-made run) is computed
with ArviZ from the posterior file, the one path that imports it. Energy BFMI is ArviZ's formula
(Betancourt 2016) on ``sample_stats.energy``.

Posterior/prior **contraction** is ``1 − Var_post / Var_prior`` (Betancourt 2018, "Calibrating
model-based inferences and decisions", §2): 1 when the data pin a parameter down, 0 when the
posterior is the prior. A parameter is flagged *weakly identified* below 0.5 (its posterior sd is
still more than 70 % of the prior sd) and *prior-dominated* below 0.1.

**Budgets**: a calibrated quantity with a budget in the papers
(:data:`~cassini_bayes.analysis.paper_facts.PAPER_FACTS`) is judged as ``cassini-bayes budget``
judges its line (docs/budgets.md): each posterior draw read as the truth and the posterior mean
as the estimate, the error's 95th percentile must lie within the paper's bound.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from cassini_bayes import names
from cassini_bayes.files import finite_or_none
from cassini_bayes.names import F_NAMES, INERTIA_NAMES, TAU_NAMES, U4_NAMES
from cassini_bayes.report._diagnostics_table import (  # noqa: F401 - re-exported
    BFMI_MIN as BFMI_MIN,
    DiagnosticRow as DiagnosticRow,
    DiagnosticTable as DiagnosticTable,
    diagnostics as diagnostics,
    energy_bfmi as energy_bfmi,
)
from cassini_bayes.report.rundata import RunData, flatten_draws

__all__ = [
    "BFMI_MIN",
    "WEAK_CONTRACTION",
    "PRIOR_DOMINATED_CONTRACTION",
    "BUDGET_QUANTILE",
    "DiagnosticRow",
    "DiagnosticTable",
    "BudgetCheck",
    "ParameterRow",
    "parameter_names",
    "diagnostics",
    "parameter_rows",
    "derived_rows",
    "budget_check",
    "unit_of",
    "lookup",
]

WEAK_CONTRACTION = 0.5
PRIOR_DOMINATED_CONTRACTION = 0.1
BUDGET_QUANTILE = 0.95  # a budget passes when this quantile of the error is within the bound


class BudgetCheck(NamedTuple):
    """A calibrated quantity against the papers' budget (module docstring).

    Attributes
    ----------
    fact_id : the :data:`~cassini_bayes.analysis.paper_facts.PAPER_FACTS` row.
    bound : the paper's bound as printed (``"≤ 1 %"``).
    source : where the paper states it (``"Feldman & Lee §VI"``).
    error_q95 : the error's 95th percentile over the posterior draws, in the bound's unit.
    unit : that unit.
    passed : whether ``error_q95`` is within the bound.
    """

    fact_id: str
    bound: str
    source: str
    error_q95: float
    unit: str
    passed: bool


class ParameterRow(NamedTuple):
    """One row of the answer table (SI units, see ``unit``)."""

    label: str
    unit: str
    mean: float | None
    sd: float | None
    q05: float | None
    q95: float | None
    baseline: float | None
    truth: float | None
    prior_sd: float | None
    contraction: float | None
    flag: str  # "", "weakly identified" or "prior-dominated"
    r_hat: float | None
    ess_bulk: float | None
    prior_mean: float | None = None  # the model file's prediction (the prior's centre)
    budget: BudgetCheck | None = None


def unit_of(label: str) -> str:
    """SI unit of a parameter for display, from :func:`cassini_bayes.names.unit_of` of its base
    name (``""`` when unknown)."""
    unit = names.unit_of(label.split("[")[0])
    return {None: "", "kg m^2": "kg m²", "1": "–"}.get(unit, unit)


def parameter_names(run: RunData) -> list[str]:
    """Calibration parameters of the run, in table order (posterior variable names).

    The keys of ``summary.json``'s ``parameters`` when given (stripped of ``[...]`` components),
    else the docs/design.md §3 names present in the posterior for the run's kind.
    """
    post = set(run.posterior.vars)
    out: list[str] = []
    for key in (run.summary.get("parameters") or {}):
        base = str(key).split("[")[0]
        if base in post and base not in out:
            out.append(base)
    if out:
        return out
    candidates = {
        "inertia": INERTIA_NAMES,
        "thrust": F_NAMES + TAU_NAMES,
        "rwa4": U4_NAMES,
    }.get(run.kind, INERTIA_NAMES + F_NAMES + TAU_NAMES + U4_NAMES)
    out = [n for n in candidates if n in post]
    if not out:  # unknown naming: every posterior variable is "of interest"
        out = list(run.posterior.vars)
    return out


def lookup(mapping: Any, label: str) -> float | None:
    """Find a parameter's value in a ``baseline``/``truth`` mapping of ``summary.json``.

    Accepts the label itself (``"Ixx"``, ``"F[Z1]"``), a vector under the base name for the
    components of RWA4's axis (``"u4": [x, y, z]``), and one level of nesting
    (``{"inertia": {"Ixx": ...}}``).
    """
    if not isinstance(mapping, dict):
        return None
    if label in mapping:
        return finite_or_none(mapping[label])
    if label in U4_NAMES:
        for key in ("u4", "axis", "direction"):
            vec = mapping.get(key)
            if isinstance(vec, dict):
                vec = vec.get("mean")
            if isinstance(vec, (list, tuple)) and len(vec) == 3:
                return finite_or_none(vec[U4_NAMES.index(label)])
    for v in mapping.values():
        if isinstance(v, dict) and label in v:
            return finite_or_none(v[label])
    return None


def _stated(run: RunData, var: str) -> dict[str, float]:
    """A per-parameter value the fit stated in ``constant_data`` (``prior_sd``, ``prior_mean``
    along a ``param`` coordinate)."""
    cd = run.groups.get("constant_data")
    if cd is None or var not in cd:
        return {}
    v = cd[var]
    if len(v.dims) != 1:
        return {}
    out = {}
    for name, value in zip(cd.labels(v.dims[0]), np.asarray(v.values, float)):
        x = finite_or_none(value)
        if x is not None:
            out[str(name)] = x
    return out


def _find_key(tree: Any, key: str) -> float | None:
    """The number stored under ``key`` anywhere in a nested TOML table (the spacecraft model)."""
    if isinstance(tree, dict):
        if key in tree and finite_or_none(tree[key]) is not None and \
                not isinstance(tree[key], bool):
            return float(tree[key])
        for v in tree.values():
            found = _find_key(v, key)
            if found is not None:
                return found
    return None


def _model_value(label: str, stated: dict[str, float], model: Any) -> float | None:
    """The spacecraft model file's prediction of a parameter: the prior mean the fit stated
    (``constant_data.prior_mean``), else the model's entry of that name in ``config.toml``'s
    ``[spacecraft]`` (a per-thruster ``F_…`` falls back to the model's ``F``); ``None`` when
    the model predicts none (an axis under a uniform prior)."""
    if label in stated:
        return stated[label]
    value = _find_key(model, label)
    if value is None and names.unit_of(label.split("[")[0]) == "N":
        value = _find_key(model, label.split("_")[0].split("[")[0])
    return value


def _contraction(sd_post: float | None, sd_prior: float | None) -> float | None:
    if sd_post is None or sd_prior is None or not sd_prior > 0:
        return None
    return 1.0 - (sd_post / sd_prior) ** 2


def budget_check(label: str, draws: np.ndarray) -> BudgetCheck | None:
    """The papers' budget of one calibrated quantity, judged on its posterior draws (module
    docstring); ``None`` for a quantity the papers give no budget for.

    A moment of inertia: Feldman & Lee Eq 12, ``100 |Î − I| / I`` against ±1 % (Feldman & Lee
    §VI); a thrust (any parameter in newtons): ``100 |F̂ − F| / F`` against ±10 % (Feldman & Lee
    §V, §VI).
    """
    from cassini_bayes.analysis import budget_lines as bl

    x = np.asarray(draws, float).ravel()
    if x.size < 2:
        return None
    est = float(np.mean(x))
    if label in INERTIA_NAMES[:3]:
        err = 100.0 * np.abs(est - x) / x                   # Feldman & Lee Eq 12, truth = draw
        return _check("inertia_accuracy_pct", err)
    if names.unit_of(label.split("[")[0]) == "N":
        return _check("thrust_accuracy_pct", bl.thrust_error_pct({"F": x}, est))
    return None


def _check(fact_id: str, err: np.ndarray) -> BudgetCheck:
    from cassini_bayes.analysis.paper_facts import fact

    f = fact(fact_id)
    q = float(np.quantile(err, BUDGET_QUANTILE))
    bound = f.printed
    if f.unit == "%":
        bound = f"±{f.value:g} %"
    elif f.unit == "deg":
        bound = bound.replace(" deg", "°")
    return BudgetCheck(f.id, bound, f.source, q, "°" if f.unit == "deg" else f.unit,
                       bool(f.passes(q)))


def derived_rows(run: RunData) -> list[tuple[str, str, np.ndarray, BudgetCheck | None]]:
    """Quantities the papers judge that are functions of several parameters: ``(label, unit,
    draws of the error, budget)`` — an inertia fit's worst moment (Feldman & Lee Eq 12, the
    ``budget`` command's line), an RWA4 fit's axis knowledge (Brown: ≤ 1° by the RWA method,
    < 3° by the RCS method)."""
    from cassini_bayes.analysis import budget_lines as bl

    post = run.posterior
    out = []
    moments = INERTIA_NAMES[:3]
    if run.kind == "inertia" and all(n in post for n in moments):
        d = {n: np.asarray(post[n].values, float).ravel() for n in moments}
        est = np.array([d[n].mean() for n in moments] + [0.0, 0.0, 0.0])
        err = bl.inertia_worst_moment_pct(d, est)
        out.append(("worst moment's error (Feldman & Lee Eq 12)", "%", err,
                    _check("inertia_accuracy_pct", err)))
    if run.kind == "rwa4" and all(n in post for n in U4_NAMES):
        u = np.stack([np.asarray(post[n].values, float).ravel() for n in U4_NAMES], -1)
        mean = u.mean(0)
        err = bl.axis_error_deg({"u4": u}, mean / np.linalg.norm(mean))
        method = run.summary.get("method") or (run.config.get("options") or {}).get("method")
        fid = "rwa4_rwa_expected_deg" if method == "rwa" else "rwa4_rcs_total_deg"
        name = {"rwa": "RWA method", "rcs": "RCS method"}.get(method, "method not recorded")
        out.append((f"spin-axis error, angle from the mean ({name})", "°", err,
                    _check(fid, err)))
    return out


def parameter_rows(run: RunData, param_names: list[str], diag: DiagnosticTable
                   ) -> list[ParameterRow]:
    """The answer table: posterior summary, the model file's prediction and the prior sd, the
    papers' least squares (``baseline``), truth when known, contraction and budget."""
    post = flatten_draws(run.posterior, param_names)
    prior = flatten_draws(run.groups.get("prior"), param_names)
    by_label = {r.label: r for r in diag.rows}
    summ = run.summary.get("parameters") or {}
    baseline = run.summary.get("baseline")
    truth = run.summary.get("truth")
    model = run.config.get("spacecraft")

    stated_sd, stated_mean = _stated(run, "prior_sd"), _stated(run, "prior_mean")
    labels = list(post)
    labels += [k for k in summ if k not in post]  # in the summary but not the file
    rows = []
    for label in labels:
        s = summ.get(label) if isinstance(summ.get(label), dict) else {}
        if label in post:
            x = post[label].ravel()
            mean, sd = float(np.mean(x)), float(np.std(x, ddof=1)) if x.size > 1 else float("nan")
            q05, q95 = (float(v) for v in np.quantile(x, [0.05, 0.95]))
        else:
            x = None
            mean, sd = finite_or_none(s.get("mean")), finite_or_none(s.get("sd"))
            q05, q95 = finite_or_none(s.get("q05")), finite_or_none(s.get("q95"))
        p = prior[label].ravel() if label in prior else None
        if p is not None and p.size > 1:
            prior_sd = float(np.std(p, ddof=1))
        else:
            prior_sd = stated_sd.get(label, finite_or_none(s.get("prior_sd")))
        prior_mean = _model_value(label, stated_mean, model)
        contraction = _contraction(sd, prior_sd)
        if contraction is None:
            contraction = finite_or_none(s.get("contraction"))
        flag = ""
        if contraction is not None and contraction < WEAK_CONTRACTION:
            flag = ("prior-dominated" if contraction < PRIOR_DOMINATED_CONTRACTION
                    else "weakly identified")
        if s.get("prior_dominated") is True:
            flag = "prior-dominated"
        elif s.get("weakly_identified") is True and not flag:
            flag = "weakly identified"
        d = by_label.get(label)
        rows.append(
            ParameterRow(
                label=label,
                unit=unit_of(label),
                mean=mean,
                sd=sd,
                q05=q05,
                q95=q95,
                baseline=lookup(baseline, label),
                truth=lookup(truth, label),
                prior_sd=prior_sd,
                contraction=contraction,
                flag=flag,
                r_hat=d.r_hat if d else finite_or_none(s.get("r_hat")),
                ess_bulk=d.ess_bulk if d else finite_or_none(s.get("ess_bulk")),
                prior_mean=prior_mean,
                budget=budget_check(label, x) if x is not None else None,
            )
        )
    return rows


def decimals_for(sd: float | None, *, digits: int = 2) -> int:
    """Decimal places that show ``digits`` significant digits of an uncertainty ``sd``."""
    if sd is None or not math.isfinite(sd) or sd <= 0:
        return 4
    return max(0, digits - 1 - int(math.floor(math.log10(sd))))


def fmt(x: float | None, decimals: int = 3) -> str:
    """Fixed-point number, ``"–"`` for missing values."""
    if x is None or not math.isfinite(x):
        return "–"
    if abs(x) >= 1e6 or (x != 0 and abs(x) < 10.0 ** (-decimals) and decimals > 6):
        return f"{x:.3e}"
    return f"{x:.{decimals}f}"
