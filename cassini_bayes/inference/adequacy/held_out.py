"""Adequacy check 2: held-out prediction (leave one telemetry file out).

See :mod:`cassini_bayes.inference.adequacy`.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from scipy import stats

from cassini_bayes.inference.adequacy.check import (Z_THRESHOLD, Check, z_check, normal_deviate,
                                                    not_applicable)


def gaussian_held_out(precisions: Sequence[np.ndarray], linears: Sequence[np.ndarray],
                      prior_precision: np.ndarray, prior_linear: np.ndarray,
                      rel_tol: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """Leave-one-block-out predictive test of a linear-Gaussian model, exact.

    Block ``f``'s log-likelihood in the shared parameters ``x`` (its own parameters already
    integrated out) is ``−½ xᵀ P_f x + b_fᵀ x``: as data, ``b_f ~ N(P_f x, P_f)``. The other
    blocks and the prior (canonical form ``Λ₀``, ``h₀``) give ``x ~ N(m, C)``, so
    ``b_f ~ N(P_f m, P_f + P_f C P_f)``; ``d² = rᵀ V⁺ r`` is χ² with ``rank(P_f)`` degrees of
    freedom.

    Returns ``d²`` and the degrees of freedom per block.
    """
    n = len(precisions)
    p_tot = sum(precisions)
    b_tot = sum(linears)
    d2, dof = np.zeros(n), np.zeros(n, int)
    for f in range(n):
        j = prior_precision + p_tot - precisions[f]
        h = prior_linear + b_tot - linears[f]
        m = np.linalg.solve(j, h)
        c = np.linalg.inv(j)
        r = linears[f] - precisions[f] @ m
        v = precisions[f] + precisions[f] @ c @ precisions[f]
        w, u = np.linalg.eigh(0.5 * (v + v.T))
        keep = w > rel_tol * max(w.max(), 0.0)
        proj = u[:, keep].T @ r
        d2[f] = float(np.sum(proj**2 / w[keep]))
        dof[f] = int(keep.sum())
    return d2, dof


def _profile(prec: np.ndarray, lin: np.ndarray, shared: np.ndarray, own: np.ndarray,
             own_prior_prec: np.ndarray, own_prior_lin: np.ndarray):
    """Integrate the ``own`` coordinates out of a canonical-form Gaussian (with their prior)."""
    j_oo = prec[np.ix_(own, own)] + np.diag(own_prior_prec)
    j_so = prec[np.ix_(shared, own)]
    k = np.linalg.solve(j_oo, np.c_[j_so.T, lin[own] + own_prior_lin])
    p = prec[np.ix_(shared, shared)] - j_so @ k[:, :-1]
    return 0.5 * (p + p.T), lin[shared] - j_so @ k[:, -1]


def inertia_held_out(problem, idata, threshold: float = Z_THRESHOLD) -> Check:
    """Leave-one-file-out check of an inertia fit (exact: the model is Gaussian in θ).

    Uses the per-file sufficient statistics of :func:`~cassini_bayes.inference.inertia.
    prepare_inertia` (``fmat``, ``gvec`` at ``theta_star``, log-likelihood
    ``−½ (δᵀ F_f δ + 2 g_fᵀ δ) / s_f²``, ``s_f`` the posterior-mean noise scale) and the stated
    priors (``π`` Normal(predicted, knowledge); ``H_0``, ``T_N``, ``ν`` zero-mean). The file's own
    parameters (``H_0``, ``T_N``, gyro bias, body torque: non-zero in its ``F_f`` only) are
    integrated out under their prior; the shared ones (``π``, gyro scale, wheel tilts) are tested
    with :func:`gaussian_held_out`.
    """
    name = "held_out"
    data = problem.data
    fmat = np.asarray(data.fmat)
    n_files = fmat.shape[0]
    if n_files < 2:
        return not_applicable(name, threshold, "one telemetry file: nothing to hold out")
    gvec = np.asarray(data.gvec)
    theta = np.asarray(data.theta_star)
    nu_sd = np.zeros(0) if data.nu_sd is None else np.asarray(data.nu_sd)
    per_file = np.asarray(data.file_sd)[:6 if problem.torque else 3]
    sd = np.r_[np.asarray(data.pi_sd), np.tile(per_file, n_files), nu_sd]
    if sd.size != fmat.shape[1]:
        return not_applicable(name, threshold, "the inertia model's parameter layout is not the "
                              "one this check knows (π, H_0/T_N per file, ν)")
    mean = np.r_[np.asarray(data.pi_mean), np.zeros(sd.size - 6)]
    prior_prec = 1.0 / sd**2
    prior_lin = prior_prec * (mean - theta)            # canonical form in δ = θ − θ*
    scale2 = np.asarray(idata.posterior["noise_scale"].mean(("chain", "draw"))).reshape(-1)**2
    touched = np.abs(fmat).sum(axis=2) > 0             # (F, P): which θ each file informs
    shared = np.flatnonzero(touched.sum(0) >= 2)
    precs, lins = [], []
    for f in range(n_files):
        own = np.flatnonzero(touched[f] & (touched.sum(0) == 1))
        p, b = _profile(fmat[f] / scale2[f], -gvec[f] / scale2[f], shared, own,
                        prior_prec[own], prior_lin[own])
        precs.append(p)
        lins.append(b)
    d2, dof = gaussian_held_out(precs, lins, np.diag(prior_prec[shared]), prior_lin[shared])
    p_val = np.array([stats.chi2.sf(d, k) if k else 1.0 for d, k in zip(d2, dof)])
    worst = int(np.argmin(p_val))
    z = normal_deviate(min(1.0, n_files * p_val[worst]))
    return z_check(name, z, threshold, problem.sources[worst],
                  note=f"χ² {d2[worst]:.1f} on {dof[worst]} dof")
