"""The ``summary.json`` of a run (docs/design.md §4.5 contract), built from InferenceData.

Contract keys: ``kind``, ``parameters`` (per parameter ``mean sd q05 q50 q95 r_hat ess_bulk
ess_tail``), ``baseline`` (the paper's least-squares estimate on the same data, or ``null`` with a
warning when it could not be computed), ``diagnostics`` (``divergences max_r_hat min_ess_bulk
converged``), ``seed``, ``version``.

Added here (free to add, docs/design.md §4.5): per parameter ``prior_sd`` and ``contraction``
(``1 − posterior variance / prior variance``, from the ``prior`` group: near 1 the data decide,
near 0 the prior does), ``weakly_identified`` (parameters with contraction < 0.5),
``diagnostics.min_ess_tail``, ``nuisance`` (the same statistics for nuisance parameters such as
``H0``, ``T_N`` and the noise scales, flattened as ``H0[0,x]``), ``warnings``, and ``adequacy``
(``{"ok": b, "checks": {NAME: {"statistic", "threshold", "ok", ...}}}``, the model's
self-checks of :mod:`cassini_bayes.inference.adequacy`; a warning line per failed check).
"""

from __future__ import annotations

import math
from typing import Mapping, Sequence

import numpy as np

from cassini_bayes import __version__
from cassini_bayes._arviz import load_arviz
from cassini_bayes.files import finite_or_none as _num
from cassini_bayes.files import json_clean

__all__ = ["CONTRACTION_WEAK", "build_summary"]

az = load_arviz()

CONTRACTION_WEAK = 0.5


def _flat(idata, group: str, name: str) -> dict[str, np.ndarray]:
    """``{label: (chain, draw) array}`` for every element of variable ``name``."""
    da = getattr(idata, group)[name]
    extra = [d for d in da.dims if d not in ("chain", "draw")]
    if not extra:
        return {name: np.asarray(da.values)}
    stacked = da.stack(_e=extra).transpose("chain", "draw", "_e")
    out = {}
    for j, idx in enumerate(stacked["_e"].values):
        idx = idx if isinstance(idx, tuple) else (idx,)
        out[f"{name}[{','.join(str(i) for i in idx)}]"] = np.asarray(stacked.values[..., j])
    return out


def _parameter_stats(idata: az.InferenceData, names: Sequence[str]) -> dict[str, dict]:
    """Per-element posterior statistics (ArviZ R-hat and ESS) of the variables ``names``."""
    out = {}
    for name in names:
        if name not in idata.posterior:
            continue
        draws = _flat(idata, "posterior", name)
        priors = _flat(idata, "prior", name) if ("prior" in idata.groups()
                                                  and name in idata.prior) else {}
        for label, x in draws.items():
            q05, q50, q95 = np.quantile(x, [0.05, 0.5, 0.95])
            entry = {"mean": _num(x.mean()), "sd": _num(x.std(ddof=1)), "q05": _num(q05),
                     "q50": _num(q50), "q95": _num(q95),
                     "r_hat": _num(az.rhat(x)), "ess_bulk": _num(az.ess(x, method="bulk")),
                     "ess_tail": _num(az.ess(x, method="tail"))}
            if label in priors:
                pv = float(np.var(priors[label], ddof=1))
                entry["prior_sd"] = _num(math.sqrt(pv))
                entry["contraction"] = _num(1.0 - float(np.var(x, ddof=1)) / pv) if pv > 0 else None
            out[label] = entry
    return out


def _convergence_warning(d) -> list[str]:
    """The line saying the sampler did not converge (``[]`` when it did)."""
    if d.converged:
        return []
    r_hat = f"{d.max_r_hat:.4f}" if np.isfinite(d.max_r_hat) else "undefined (one chain)"
    return [f"the sampler did not converge (max R-hat {r_hat}, min bulk ESS "
            f"{d.min_ess_bulk:.0f}, {d.divergences} divergences): run longer (more warm-up and "
            "draws), raise the target acceptance if it diverged, or check the data"]


def build_summary(kind: str, idata: az.InferenceData, *, parameters: Sequence[str],
                  diagnostics, baseline: Mapping[str, float] | None, seed: int,
                  nuisance: Sequence[str] = (), warnings: Sequence[str] = (),
                  extra: Mapping | None = None, adequacy=None) -> dict:
    """The ``summary.json`` dict (docs/design.md §4.5), JSON-ready (NaN/inf become ``null``).

    Parameters
    ----------
    kind : ``"inertia"``, ``"thrust"`` or ``"rwa4"``.
    idata : the run's InferenceData (``posterior``, and ``prior`` for the contraction).
    parameters : the calibrated parameters (e.g. ``Ixx … Iyz``), in order.
    diagnostics : :class:`cassini_bayes.diagnostics.Diagnostics`.
    baseline : least-squares estimate per parameter name, or ``None`` when unavailable.
    seed : the ``--seed`` the run's key was made from.
    nuisance : other variables to summarise under ``nuisance``.
    warnings : human-readable warnings (weak identification, baseline failure, ...).
    extra : more top-level keys (e.g. ``direction`` for rwa4).
    adequacy : :class:`cassini_bayes.inference.adequacy.Adequacy` of the fit, or ``None``.
    """
    params = _parameter_stats(idata, parameters)
    weak = [k for k, v in params.items()
            if v.get("contraction") is not None and v["contraction"] < CONTRACTION_WEAK]
    out = {
        "kind": kind,
        "parameters": params,
        "baseline": (None if baseline is None
                     else {k: _num(v) for k, v in baseline.items()}),
        "diagnostics": diagnostics.to_dict(),
        "seed": int(seed),
        "version": __version__,
        "weakly_identified": weak,
        "nuisance": _parameter_stats(idata, nuisance),
        "warnings": (_convergence_warning(diagnostics) + list(warnings)
                     + (adequacy.warnings() if adequacy is not None else [])),
    }
    if adequacy is not None:
        out["adequacy"] = json_clean(adequacy.to_dict())
    if extra:
        out.update(extra)
    return out
