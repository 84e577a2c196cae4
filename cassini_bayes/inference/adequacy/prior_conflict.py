"""Adequacy check 1: prior-data conflict of the posterior sites.

See :mod:`cassini_bayes.inference.adequacy`.
"""

from __future__ import annotations

import math
from typing import Mapping, Sequence

import numpy as np

from cassini_bayes.inference.adequacy.check import PRIOR_CONFLICT_SD, Check, z_check, not_applicable


def _elements(da) -> dict[str, np.ndarray]:
    """``{label: flat draws}`` for every element of a (chain, draw, ...) DataArray."""
    extra = [d for d in da.dims if d not in ("chain", "draw")]
    if not extra:
        return {da.name: np.asarray(da.values).ravel()}
    st = da.stack(_e=extra).transpose(..., "_e")
    vals = np.asarray(st.values).reshape(-1, st.sizes["_e"])
    out = {}
    for j, idx in enumerate(st["_e"].values):
        idx = idx if isinstance(idx, tuple) else (idx,)
        out[f"{da.name}[{','.join(str(i) for i in idx)}]"] = vals[:, j]
    return out


def common_wheel_scale(idata, layout) -> dict[str, tuple[np.ndarray, float]]:
    """The wheel spin-inertia errors in the directions the data and the priors split them, as
    derived elements for :func:`prior_data_conflict` (``label → (draws, zero-mean prior sd)``):

    * ``wheel_scale_mean``, the wheels' mean error ``c = c_s + mean_k d_k``, prior sd
      ``√(σ_s² + Σ_k σ_k²/K²)``: the direction that trades with the inertia's (and the thrust's)
      overall scale, so a wrong fixed inertia pulls it first;
    * ``wheel_scale_rel[k]``, each wheel's error relative to that mean, ``c_k − c``, prior sd
      ``√(σ_k² (1 − 2/K) + Σ_j σ_j²/K²)``: what slews about several axes measure, so one wheel's
      tachometer (or spin inertia) off by several times its knowledge shows here, while its
      total ``c_k`` shares the error with the unidentified mean and stays nearer its prior.

    Empty for the common model (its one scale is already an element)."""
    if layout is None or layout.wheel_errors != "per_wheel" or "wheel_scale" not in idata.posterior:
        return {}
    sd = np.asarray(layout.sd)
    d_var = sd[layout.slices["wheel_inertia"]]**2
    k = d_var.size
    mean_var = float(np.sum(d_var)) / k**2
    draws = np.asarray(idata.posterior["wheel_scale"].transpose(..., "wheel").values)
    draws = draws.reshape(-1, k)
    c = draws.mean(-1)
    c_var = mean_var + (float(sd[layout.slices["wheel_inertia_common"]][0]**2)
                        if layout.has_common else 0.0)
    out = {"wheel_scale_mean": (c, math.sqrt(c_var))}
    if k > 1:
        names = idata.posterior["wheel"].values
        for j in range(k):
            out[f"wheel_scale_rel[{names[j]}]"] = (draws[:, j] - c,
                                                   math.sqrt(d_var[j] * (1 - 2 / k) + mean_var))
    return out


def prior_data_conflict(idata, sites: Sequence[str], threshold: float = PRIOR_CONFLICT_SD,
                        prior_sd: Mapping[str, np.ndarray] | None = None,
                        derived: Mapping[str, tuple[np.ndarray, float]] | None = None) -> Check:
    """``max |E[x | data] − E[x]| / sd(x)`` over every element of ``sites`` that has a prior.

    Works on any site shape (a scalar ``wheel_scale`` or one per wheel alike). ``prior_sd``:
    sites with a zero-mean Normal prior of these sds (flat, in the site's element order; e.g.
    :func:`nuisance_prior_sd`); the other sites' prior mean and sd come from the ``prior``
    group's draws, on the log scale when every draw is positive (the log-normal priors of thrust
    and time constants; moments of inertia). ``derived``: more elements, ``label → (posterior
    draws, zero-mean prior sd)`` (e.g. :func:`common_wheel_scale`).
    """
    name = "prior_data_conflict"
    prior_sd = dict(prior_sd or {})
    has_prior = "prior" in idata.groups()
    worst, worst_z = None, -1.0
    for label, (draws, sd) in (derived or {}).items():
        z = abs(float(np.mean(draws))) / sd if sd > 0 else -1.0
        if z > worst_z:
            worst, worst_z = label, z
    for site in sites:
        if site not in idata.posterior:
            continue
        post = _elements(idata.posterior[site])
        if site in prior_sd and np.size(prior_sd[site]) == len(post):
            ref = {label: (0.0, float(sd))
                   for label, sd in zip(post, np.ravel(prior_sd[site]))}
        elif has_prior and site in idata.prior:
            ref = {}
            for label, p in _elements(idata.prior[site]).items():
                if label in post and p.size > 1:
                    logs = bool(np.all(p > 0) and np.all(post[label] > 0))
                    p = np.log(p) if logs else p
                    ref[label] = (float(np.mean(p)), float(np.std(p, ddof=1)), logs)
        else:
            continue
        for label, r in ref.items():
            x = np.log(post[label]) if len(r) == 3 and r[2] else post[label]
            if not r[1] > 0:
                continue
            z = abs(float(np.mean(x)) - r[0]) / r[1]
            if z > worst_z:
                worst, worst_z = label, z
    if worst is None:
        return not_applicable(name, threshold, "no posterior site has a proper prior")
    return z_check(name, worst_z, threshold, worst)
