"""The report's sampler diagnostics: R-hat, bulk/tail ESS and energy BFMI of every judged
posterior component.

The numbers are the fit's own from ``summary.json`` (so a page and its summary never disagree);
a component ``summary.json`` lacks (an older or hand-made run) is computed with ArviZ from the
posterior file, the one path that imports it. Energy BFMI is ArviZ's formula (Betancourt 2016)
on ``sample_stats.energy``.
"""


from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from cassini_bayes.diagnostics import Diagnostics
from cassini_bayes.files import finite_or_none
from cassini_bayes.report.rundata import RunData, flatten_draws

BFMI_MIN = 0.3  # Betancourt (2016): E-BFMI below 0.3 indicates poor exploration


class DiagnosticRow(NamedTuple):
    """Diagnostics and posterior summary of one scalar component of the posterior."""

    label: str
    r_hat: float
    ess_bulk: float
    ess_tail: float
    role: str  # "parameter" or "nuisance" (both judged by the fit's verdict)
    mean: float | None = None
    sd: float | None = None
    contraction: float | None = None

    @property
    def of_interest(self) -> bool:
        """A calibration parameter."""
        return self.role == "parameter"

    @property
    def judged(self) -> bool:
        """In the fit's convergence verdict (``summary.json``'s parameters and nuisance)."""
        return self.role in ("parameter", "nuisance")


@dataclass(frozen=True)
class DiagnosticTable:
    """Sampler diagnostics of a run, per component and overall.

    Attributes
    ----------
    rows : tuple of DiagnosticRow
        Per scalar component the fit judges: parameters of interest first, then nuisance
        components by worst R-hat.
    sampler : dict
        The sampler's own coordinates (whitened ``z``, ``w``): name → number of components.
        Listed, not judged: every parameter is a function of them.
    chains, draws : int
        Posterior shape.
    divergences : int or None
        Divergent transitions after warm-up (``None``: ``sample_stats.diverging`` absent).
    bfmi : numpy.ndarray or None
        Energy BFMI per chain; ``None`` without ``sample_stats.energy``.
    overall : Diagnostics
        The extremes over :attr:`rows` (NaN when not computable, e.g. one chain) judged by the
        fit's rule (:mod:`cassini_bayes.diagnostics`; BFMI is reported, not judged).
    converged_summary : bool or None
        ``summary.json``'s ``diagnostics.converged`` (the fit's verdict).
    computed : tuple of str
        Components whose statistics ``summary.json`` lacked and ArviZ computed here.
    """

    rows: tuple[DiagnosticRow, ...]
    sampler: dict[str, int]
    chains: int
    draws: int
    divergences: int | None
    bfmi: np.ndarray | None
    overall: Diagnostics
    converged_summary: bool | None
    computed: tuple[str, ...] = ()

    @property
    def converged(self) -> bool:
        """The fit's verdict when it wrote one, else the recomputed one."""
        if self.converged_summary is None:
            return self.overall.converged
        return self.converged_summary



def _judged_names(run: RunData) -> set[str] | None:
    """Variables in the fit's verdict: ``summary.json``'s parameters and nuisance (base names);
    ``None`` for a run without a ``nuisance`` entry (then every variable is judged)."""
    if "nuisance" not in run.summary:
        return None
    keys = [*(run.summary.get("parameters") or {}), *(run.summary.get("nuisance") or {})]
    return {str(k).split("[")[0] for k in keys} or None


def _arviz_stats(draws: dict[str, np.ndarray]) -> dict[str, tuple[float, float, float]]:
    """R-hat, bulk and tail ESS of each (chain, draw) array, computed by ArviZ."""
    from cassini_bayes._arviz import load_arviz

    az = load_arviz()
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for label, x in draws.items():
            out[label] = (float(az.rhat(x)), float(az.ess(x, method="bulk")),
                          float(az.ess(x, method="tail")))
    return out


def _nan(x) -> float:
    """A summary.json number, NaN for ``null``."""
    v = finite_or_none(x)
    return float("nan") if v is None else v


def energy_bfmi(energy: np.ndarray) -> np.ndarray:
    """E-BFMI per chain of a (chain, draw) energy array (Betancourt 2016; ArviZ's formula)."""
    e = np.asarray(energy, float)
    return np.square(np.diff(e, axis=1)).mean(axis=1) / np.var(e, axis=1)


def diagnostics(run: RunData, param_names: list[str]) -> DiagnosticTable:
    """Diagnostics of every judged posterior component (``param_names``: the parameters of
    interest); the fit's numbers from ``summary.json``, ArviZ for any it lacks."""
    post = run.posterior
    sizes = post.sizes
    chains, draws = int(sizes.get("chain", 1)), int(sizes.get("draw", 0))
    judged = _judged_names(run)
    stats = {**(run.summary.get("nuisance") or {}), **(run.summary.get("parameters") or {})}
    interest = set(param_names)
    sampler: dict[str, int] = {}
    todo: dict[str, tuple[str, np.ndarray]] = {}    # label -> (role, draws) to compute
    rows = []
    for name, var in post.vars.items():
        if var.dims[:2] != ("chain", "draw"):
            continue
        role = ("parameter" if name in interest else
                "nuisance" if judged is None or name in judged else "sampler coordinate")
        if role == "sampler coordinate":
            sampler[name] = int(np.prod(var.values.shape[2:], dtype=int))
            continue
        for label, x in flatten_draws(post, [name]).items():
            s = stats.get(label)
            if isinstance(s, dict) and "r_hat" in s:      # (null: undefined, e.g. one chain)
                rows.append(DiagnosticRow(label, _nan(s.get("r_hat")), _nan(s.get("ess_bulk")),
                                          _nan(s.get("ess_tail")), role,
                                          finite_or_none(s.get("mean")),
                                          finite_or_none(s.get("sd")),
                                          finite_or_none(s.get("contraction"))))
            else:
                todo[label] = (role, x)
    if todo:
        computed = _arviz_stats({k: x for k, (_, x) in todo.items()})
        for label, (role, x) in todo.items():
            r, eb, et = computed[label]
            s = stats.get(label) if isinstance(stats.get(label), dict) else {}
            rows.append(DiagnosticRow(label, r, eb, et, role, float(np.mean(x)),
                                      float(np.std(x, ddof=1)) if x.size > 1 else None,
                                      finite_or_none(s.get("contraction"))))
    first = [r for r in rows if r.of_interest]
    rest = sorted((r for r in rows if not r.of_interest),  # worst R-hat first, NaN last
                  key=lambda r: -r.r_hat if np.isfinite(r.r_hat) else np.inf)
    rows = first + rest

    divergences = bfmi = None
    ss = run.groups.get("sample_stats")
    if ss is not None:
        if "diverging" in ss:
            divergences = int(np.asarray(ss["diverging"].values).astype(bool).sum())
        if "energy" in ss and ss["energy"].dims[:2] == ("chain", "draw"):
            with np.errstate(divide="ignore", invalid="ignore"):
                bfmi = energy_bfmi(ss["energy"].values)

    def _ext(f, xs):
        xs = [x for x in xs if np.isfinite(x)]
        return float(f(xs)) if xs else float("nan")

    conv = (run.summary.get("diagnostics") or {}).get("converged")
    worst = max((r for r in rows if np.isfinite(r.r_hat)), key=lambda r: r.r_hat, default=None)
    overall = Diagnostics.judge(divergences or 0, _ext(max, [r.r_hat for r in rows]),
                                _ext(min, [r.ess_bulk for r in rows]),
                                _ext(min, [r.ess_tail for r in rows]),
                                worst.label if worst is not None else "")
    return DiagnosticTable(
        rows=tuple(rows),
        sampler=sampler,
        chains=chains,
        draws=draws,
        divergences=divergences,
        bfmi=bfmi,
        overall=overall,
        converged_summary=None if conv is None else bool(conv),
        computed=tuple(todo),
    )


