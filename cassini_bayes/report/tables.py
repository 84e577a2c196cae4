"""The numbers of the report: sampler diagnostics and the parameter table.

Diagnostics (R-hat, bulk/tail ESS, MCSE, energy BFMI) are computed with ArviZ from the posterior
file, never by hand, so a rebuilt report always matches ``posterior.nc``.

Posterior/prior **contraction** is ``1 − Var_post / Var_prior`` (Betancourt 2018, "Calibrating
model-based inferences and decisions", §2): 1 when the data pin a parameter down, 0 when the
posterior is the prior. A parameter is flagged *weakly identified* below 0.5 (its posterior sd is
still more than 70 % of the prior sd) and *prior-dominated* below 0.1.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from cassini_bayes import names
from cassini_bayes.names import F_NAMES, INERTIA_NAMES, TAU_NAMES, U4_NAMES
from cassini_bayes.report.rundata import RunData, finite_or_none, flatten_draws

__all__ = [
    "RHAT_MAX",
    "ESS_MIN",
    "BFMI_MIN",
    "WEAK_CONTRACTION",
    "PRIOR_DOMINATED_CONTRACTION",
    "DiagnosticRow",
    "Diagnostics",
    "ParameterRow",
    "parameter_names",
    "diagnostics",
    "parameter_rows",
    "unit_of",
    "lookup",
]

RHAT_MAX = 1.01  # Vehtari et al. (2021) recommendation
ESS_MIN = 400.0  # min bulk ESS >= 400: 100 per chain for 4 chains, Vehtari et al. (2021)
BFMI_MIN = 0.3  # Betancourt (2016): E-BFMI below 0.3 indicates poor exploration
WEAK_CONTRACTION = 0.5
PRIOR_DOMINATED_CONTRACTION = 0.1


class DiagnosticRow(NamedTuple):
    """ArviZ diagnostics of one scalar component of the posterior."""

    label: str
    r_hat: float
    ess_bulk: float
    ess_tail: float
    mcse_mean: float
    role: str  # "parameter", "nuisance" (both judged by the fit's verdict) or "sampler coordinate"

    @property
    def of_interest(self) -> bool:
        """A calibration parameter."""
        return self.role == "parameter"

    @property
    def judged(self) -> bool:
        """In the fit's convergence verdict (``summary.json``'s parameters and nuisance)."""
        return self.role != "sampler coordinate"


@dataclass(frozen=True)
class Diagnostics:
    """Sampler diagnostics of a run.

    Attributes
    ----------
    rows : tuple of DiagnosticRow
        Per scalar component; parameters of interest first, then nuisance variables by worst R-hat.
    chains, draws : int
        Posterior shape.
    divergences : int or None
        Divergent transitions after warm-up (``None``: ``sample_stats.diverging`` absent).
    bfmi : numpy.ndarray or None
        Energy BFMI per chain (``arviz.bfmi``); ``None`` without ``sample_stats.energy``.
    max_r_hat, min_ess_bulk, min_ess_tail : float
        Extremes over the components the fit's verdict judges: ``summary.json``'s parameters and
        nuisance, as the fit computed them (all components for a run without them); NaN when
        not computable, e.g. one chain. The sampler's own coordinates (whitened ``z``, ``w``)
        are listed in :attr:`rows` but not judged.
    converged_summary : bool or None
        ``summary.json``'s ``diagnostics.converged`` (the fit's verdict).
    """

    rows: tuple[DiagnosticRow, ...]
    chains: int
    draws: int
    divergences: int | None
    bfmi: np.ndarray | None
    max_r_hat: float
    min_ess_bulk: float
    min_ess_tail: float
    converged_summary: bool | None

    @property
    def converged_recomputed(self) -> bool:
        """The same rule as the fit: R-hat, bulk ESS, no divergences (BFMI reported, not gating)."""
        return (
            (self.divergences or 0) == 0
            and _le(self.max_r_hat, RHAT_MAX)
            and _ge(self.min_ess_bulk, ESS_MIN)
        )

    @property
    def converged(self) -> bool:
        """The fit's verdict when it wrote one, else the recomputed one."""
        if self.converged_summary is None:
            return self.converged_recomputed
        return self.converged_summary


class ParameterRow(NamedTuple):
    """One row of the parameter table (SI units, see ``unit``)."""

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


def _le(x: float, lim: float) -> bool:
    return bool(np.isfinite(x) and x <= lim)


def _ge(x: float, lim: float) -> bool:
    return bool(np.isfinite(x) and x >= lim)


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
    post = set(run.idata.posterior.data_vars)
    names: list[str] = []
    for key in (run.summary.get("parameters") or {}):
        base = str(key).split("[")[0]
        if base in post and base not in names:
            names.append(base)
    if names:
        return names
    candidates = {
        "inertia": INERTIA_NAMES,
        "thrust": F_NAMES + TAU_NAMES,
        "rwa4": U4_NAMES,
    }.get(run.kind, INERTIA_NAMES + F_NAMES + TAU_NAMES + U4_NAMES)
    names = [n for n in candidates if n in post]
    if not names:  # unknown naming: every posterior variable is "of interest"
        names = list(run.idata.posterior.data_vars)
    return names


def _judged_names(run: RunData) -> set[str] | None:
    """Variables in the fit's verdict: ``summary.json``'s parameters and nuisance (base names);
    ``None`` for a run without a ``nuisance`` entry (then every variable is judged)."""
    if "nuisance" not in run.summary:
        return None
    keys = [*(run.summary.get("parameters") or {}), *(run.summary.get("nuisance") or {})]
    return {str(k).split("[")[0] for k in keys} or None


def diagnostics(run: RunData, names: list[str]) -> Diagnostics:
    """ArviZ diagnostics of every posterior variable (``names``: the parameters of interest)."""
    import arviz as az

    post = run.idata.posterior
    chains, draws = int(post.sizes.get("chain", 1)), int(post.sizes.get("draw", 0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        table = az.summary(run.idata, kind="diagnostics", round_to="none")
    interest = set(flatten_draws(post, names))
    judged = _judged_names(run)

    def role(label: str) -> str:
        if label in interest:
            return "parameter"
        if judged is None or label.split("[")[0] in judged:
            return "nuisance"
        return "sampler coordinate"

    rows = [
        DiagnosticRow(
            str(label),
            float(r["r_hat"]),
            float(r["ess_bulk"]),
            float(r["ess_tail"]),
            float(r["mcse_mean"]),
            role(str(label)),
        )
        for label, r in table.iterrows()
    ]
    first = [r for r in rows if r.of_interest]
    rest = sorted((r for r in rows if not r.of_interest),  # judged first, worst R-hat, NaN last
                  key=lambda r: (not r.judged, -r.r_hat if np.isfinite(r.r_hat) else np.inf))
    rows = first + rest

    divergences = None
    bfmi = None
    if run.has_group("sample_stats"):
        ss = run.idata.sample_stats
        if "diverging" in ss.data_vars:
            divergences = int(np.asarray(ss["diverging"].values).astype(bool).sum())
        if "energy" in ss.data_vars:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                bfmi = np.asarray(az.bfmi(run.idata), dtype=float)

    def _ext(f, xs):
        xs = [x for x in xs if np.isfinite(x)]
        return float(f(xs)) if xs else float("nan")

    conv = (run.summary.get("diagnostics") or {}).get("converged")
    return Diagnostics(
        rows=tuple(rows),
        chains=chains,
        draws=draws,
        divergences=divergences,
        bfmi=bfmi,
        max_r_hat=_ext(max, [r.r_hat for r in rows if r.judged]),
        min_ess_bulk=_ext(min, [r.ess_bulk for r in rows if r.judged]),
        min_ess_tail=_ext(min, [r.ess_tail for r in rows if r.judged]),
        converged_summary=None if conv is None else bool(conv),
    )


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


def _stated_prior_sd(run: RunData) -> dict[str, float]:
    """Prior sd per parameter stated by the fit in ``constant_data.prior_sd`` (coordinate
    ``param``), used when the prior group has no draws of that parameter."""
    if not run.has_group("constant_data") or "prior_sd" not in run.idata.constant_data:
        return {}
    da = run.idata.constant_data["prior_sd"]
    if da.ndim != 1 or da.dims[0] not in da.coords:
        return {}
    out = {}
    for name, value in zip(da.coords[da.dims[0]].values, np.asarray(da.values, float)):
        v = finite_or_none(value)
        if v is not None:
            out[str(name)] = v
    return out


def _contraction(sd_post: float | None, sd_prior: float | None) -> float | None:
    if sd_post is None or sd_prior is None or not sd_prior > 0:
        return None
    return 1.0 - (sd_post / sd_prior) ** 2


def parameter_rows(run: RunData, names: list[str], diag: Diagnostics) -> list[ParameterRow]:
    """The parameter table: posterior summary, baseline, truth, prior sd and contraction."""
    post = flatten_draws(run.idata.posterior, names)
    prior = flatten_draws(run.idata.prior, names) if run.has_group("prior") else {}
    by_label = {r.label: r for r in diag.rows}
    summ = run.summary.get("parameters") or {}
    baseline = run.summary.get("baseline")
    truth = run.summary.get("truth")

    stated_sd = _stated_prior_sd(run)
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
            mean, sd = finite_or_none(s.get("mean")), finite_or_none(s.get("sd"))
            q05, q95 = finite_or_none(s.get("q05")), finite_or_none(s.get("q95"))
        if label in prior:
            p = prior[label].ravel()
            prior_sd = float(np.std(p, ddof=1)) if p.size > 1 else None
        else:
            prior_sd = stated_sd.get(label, finite_or_none(s.get("prior_sd")))
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
