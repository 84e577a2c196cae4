"""Does the model fit? Self-checks of a posterior that need no truth (flight data has none).

Each check returns one number, ``statistic``, compared with a ``threshold`` (``ok`` when
``statistic ≤ threshold``). The false-alarm rates on correctly specified data are measured by
``benchmarks/adequacy_false_alarms.py`` and stated in ``docs/adequacy.md``.

* ``prior_data_conflict`` — for every element ``x`` of the named posterior sites that has a
  proper prior, ``|E[x | data] − E[x]| / sd(x)`` in prior sd (nuisance parameters: their stated
  zero-mean Normal priors; others: the ``prior`` group's draws, on the log scale when every draw
  is positive — thrust, time constants, moments). A nuisance parameter pulled several prior sd
  from its prior is how an unmodelled error reaches the answer; the worst element is named
  (``parameter``). Per-wheel robust fits add the wheels' mean spin-inertia error and each
  wheel's error relative to it (:func:`common_wheel_scale`): the directions a wrong inertia and
  a wrong tachometer pull.
* ``held_out`` — leave one telemetry file out: the posterior of the shared parameters from the
  other files (and the prior) predicts the held-out file's information-weighted estimate, exactly
  where the model is linear-Gaussian in its parameters (the inertia model's sufficient
  statistics, :func:`gaussian_held_out`); the statistic is the normal deviate of the smallest
  Bonferroni-adjusted χ² tail probability over the files. Not applicable to one file.
* ``residual_autocorrelation`` — whiteness against time: per block (file, event) and axis the
  lag-1 autocorrelation ``ρ̂₁`` of the posterior-mean residuals; the largest ``|ρ̂₁|``.
* ``residual_regression`` — whiteness against the regressors of the model (inertia fits: body
  rate and wheel momentum; not used for thrust fits, see :func:`thrust_adequacy`): per block and
  axis the F-test of the (AR(1)-prewhitened) residual regressed on them, as the normal deviate
  of the smallest Bonferroni-adjusted p-value.
* ``balance_fit`` (RWA4 fits) — the window-mean momentum balances at the posterior mean against
  the likelihood's own covariance (noise plus the integrated-out nuisance effects): ``χ²`` on
  ``3G − 2`` degrees of freedom (G window pairs), as the normal deviate of its upper tail.

Statistics expressed as normal deviates (held-out, regression, balance) fail beyond 4
(two-sided 6e-5 after the Bonferroni correction); the prior–data conflict beyond 4 prior sd; the
autocorrelation beyond 0.5.
"""

from __future__ import annotations

import math
from typing import Mapping, NamedTuple, Sequence

import numpy as np
from scipy import stats

from cassini_bayes.inference.nuisance import site_prior_sd as nuisance_prior_sd

__all__ = ["Check", "Adequacy", "PRIOR_CONFLICT_SD", "Z_THRESHOLD", "AUTOCORR_MAX",
           "normal_deviate", "nuisance_prior_sd", "prior_data_conflict", "common_wheel_scale",
           "gaussian_held_out",
           "inertia_held_out", "residual_autocorrelation", "residual_regression", "not_applicable",
           "inertia_adequacy", "thrust_adequacy", "rwa4_adequacy", "balance_fit"]

PRIOR_CONFLICT_SD = 4.0   # prior sd between the posterior mean and the prior mean
Z_THRESHOLD = 4.0         # normal deviate of the regression and held-out checks (two-sided 6e-5)
AUTOCORR_MAX = 0.5        # largest lag-1 autocorrelation of the residuals


class Check(NamedTuple):
    """One adequacy check: ``ok`` when ``statistic ≤ threshold`` (``statistic`` ``None``:
    not applicable, ``ok`` true, ``note`` says why); ``parameter`` names the worst element."""

    name: str
    statistic: float | None
    threshold: float
    ok: bool
    parameter: str | None = None
    note: str | None = None

    def to_dict(self) -> dict:
        out = {"statistic": self.statistic, "threshold": self.threshold, "ok": bool(self.ok)}
        if self.parameter is not None:
            out["parameter"] = self.parameter
        if self.note is not None:
            out["note"] = self.note
        return out

    def warning(self) -> str:
        """The one-line warning of a failed check."""
        where = f" ({self.parameter})" if self.parameter else ""
        return (f"adequacy check {self.name} failed{where}: statistic {self.statistic:.3g} > "
                f"threshold {self.threshold:g}" + (f"; {self.note}" if self.note else ""))


class Adequacy(NamedTuple):
    """The checks of one fit; ``ok`` when every check is."""

    checks: tuple[Check, ...]

    @property
    def ok(self) -> bool:
        return all(c.ok for c in self.checks)

    @property
    def failed(self) -> list[str]:
        return [c.name for c in self.checks if not c.ok]

    def to_dict(self) -> dict:
        """The ``summary.json`` block: ``{"ok": b, "checks": {NAME: {...}}}``."""
        return {"ok": self.ok, "checks": {c.name: c.to_dict() for c in self.checks}}

    def warnings(self) -> list[str]:
        return [c.warning() for c in self.checks if not c.ok]


def normal_deviate(p: float) -> float:
    """``z`` with two-sided standard-normal tail probability ``p`` (capped at 40)."""
    p = min(max(float(p), 0.0), 1.0)
    return 40.0 if p <= 0.0 else float(min(stats.norm.isf(p / 2.0), 40.0))


def not_applicable(name: str, threshold: float, note: str) -> Check:
    return Check(name, None, threshold, True, note=note)


def _check(name: str, z: float, threshold: float, parameter: str | None = None,
           note: str | None = None) -> Check:
    z = float(z)
    return Check(name, z, threshold, bool(z <= threshold), parameter, note)


# --------------------------------------------------------------------------------------------
# 1. Prior-data conflict
# --------------------------------------------------------------------------------------------

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
    return _check(name, worst_z, threshold, worst)


# --------------------------------------------------------------------------------------------
# 2. Held-out prediction
# --------------------------------------------------------------------------------------------

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
    from cassini_bayes.inference.inertia import H0_PRIOR_SD_NMS, TORQUE_PRIOR_SD_NM

    name = "held_out"
    kw = problem.model_kwargs
    fmat = np.asarray(kw["fmat"])
    n_files = fmat.shape[0]
    if n_files < 2:
        return not_applicable(name, threshold, "one telemetry file: nothing to hold out")
    gvec = np.asarray(kw["gvec"])
    theta = np.asarray(kw["theta_star"])
    nu_sd = np.asarray(kw["nu_sd"]) if "nu_sd" in kw else np.zeros(0)
    per_file = np.r_[np.full(3, H0_PRIOR_SD_NMS),
                     np.full(3, TORQUE_PRIOR_SD_NM)][:6 if problem.torque else 3]
    sd = np.r_[np.asarray(kw["pi_sd"]), np.tile(per_file, n_files), nu_sd]
    if sd.size != fmat.shape[1]:
        return not_applicable(name, threshold, "the inertia model's parameter layout is not the "
                              "one this check knows (π, H_0/T_N per file, ν)")
    mean = np.r_[np.asarray(kw["pi_mean"]), np.zeros(sd.size - 6)]
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
    return _check(name, z, threshold, problem.sources[worst],
                  note=f"χ² {d2[worst]:.1f} on {dof[worst]} dof")


# --------------------------------------------------------------------------------------------
# 3. Residual structure
# --------------------------------------------------------------------------------------------

def _blocks(block: np.ndarray, labels: Sequence[str] | None = None):
    """``(label, indices)`` per distinct value of ``block``."""
    return [(labels[int(b)] if labels is not None and 0 <= int(b) < len(labels) else f"block {b}",
             np.flatnonzero(block == b)) for b in np.unique(block)]


def residual_autocorrelation(residual: np.ndarray, block: np.ndarray,
                             threshold: float = AUTOCORR_MAX,
                             labels: Sequence[str] | None = None) -> Check:
    """``max |ρ̂₁|`` over blocks and axes of ``residual`` (N, 3), in time order per block.

    ``ρ̂₁`` is the lag-1 autocorrelation of a block's centred residual on one axis: 0 for white
    residuals (sd ``1/√n``), near 1 for a smooth misfit. An effect size rather than a test, so a
    long block with a small known correlation (the thrust model's neglected random walk of the
    gyroscopic term, ``ρ̂₁`` ≈ 0.15) does not fail it; blocks of fewer than ``(4/threshold)²``
    samples (≈ 64) are skipped, where white noise alone can reach it.
    """
    worst, worst_z = None, -1.0
    for label, idx in _blocks(np.asarray(block), labels):
        x = np.asarray(residual, float)[idx]
        if x.shape[0] < (4.0 / threshold)**2:
            continue
        rho = _lag1(x)
        k = int(np.argmax(np.abs(rho)))
        if abs(rho[k]) > worst_z:
            worst, worst_z = f"{label} axis {'xyz'[k]} (ρ̂₁ {rho[k]:+.3f})", float(abs(rho[k]))
    if worst is None:
        return not_applicable("residual_autocorrelation", threshold, "too few residuals")
    return _check("residual_autocorrelation", worst_z, threshold, worst)


def _lag1(x: np.ndarray) -> np.ndarray:
    """Lag-1 autocorrelation of each column of ``x`` (n, k), centred."""
    x = x - x.mean(0)
    den = np.sum(x**2, 0)
    return np.where(den > 0, np.sum(x[1:] * x[:-1], 0) / np.where(den > 0, den, 1.0), 0.0)


def residual_regression(residual: np.ndarray, covariates: np.ndarray, block: np.ndarray,
                        threshold: float = Z_THRESHOLD, names: Sequence[str] | None = None,
                        labels: Sequence[str] | None = None) -> Check:
    """F-test of each block's residual axis regressed on ``covariates`` (N, K) and a constant.

    Both sides are first prewhitened with the residual's own lag-1 autocorrelation ``ρ̂``
    (Cochrane–Orcutt: ``y_t − ρ̂ y_{t−1}``), so the test stays valid when the residuals carry a
    mild AR(1) correlation and asks only whether the regressors explain them. Statistic: the
    normal deviate of the smallest Bonferroni-adjusted p-value over blocks and axes; ``parameter``
    names the block, axis and the regressor with the largest |t|.
    """
    residual = np.asarray(residual, float)
    covariates = np.asarray(covariates, float)
    names = np.array(list(names) if names is not None
                     else [f"x{k}" for k in range(covariates.shape[1])])
    tests = []
    for label, idx in _blocks(np.asarray(block), labels):
        if idx.size < 3 * covariates.shape[1] + 10:
            continue
        for a in range(residual.shape[1]):
            y0 = residual[idx, a]
            rho = float(_lag1(y0[:, None])[0])
            y = y0[1:] - rho * y0[:-1]
            x = covariates[idx][1:] - rho * covariates[idx][:-1]
            x, y = x - x.mean(0), y - y.mean()
            keep = np.std(x, 0) > 0
            if not keep.any():
                continue
            q, rr = np.linalg.qr(x[:, keep])
            good = np.abs(np.diag(rr)) > 1e-10 * np.abs(np.diag(rr)).max()
            k, n = int(good.sum()), y.size
            fit = q[:, good].T @ y
            ss_reg, ss_res = float(fit @ fit), float(y @ y - fit @ fit)
            if ss_res <= 0:
                continue
            dof = n - k - 1
            f_stat = (ss_reg / k) / (ss_res / dof)
            coef, *_ = np.linalg.lstsq(x[:, keep], y, rcond=None)
            se = np.sqrt(ss_res / dof * np.diag(np.linalg.pinv(x[:, keep].T @ x[:, keep])))
            top = names[keep][int(np.argmax(np.abs(coef) / np.where(se > 0, se, np.inf)))]
            tests.append((float(stats.f.sf(f_stat, k, dof)), f"{label} axis {'xyz'[a]} ~ {top}"))
    if not tests:
        return not_applicable("residual_regression", threshold, "too few residuals")
    p, where = min(tests, key=lambda t: t[0])
    return _check("residual_regression", normal_deviate(min(1.0, len(tests) * p)), threshold,
                  where)


# --------------------------------------------------------------------------------------------
# Per kind
# --------------------------------------------------------------------------------------------

def _residual_checks(idata, covariates: np.ndarray | None, names: Sequence[str] | None,
                     block_coord: str, labels: Sequence[str],
                     no_regression: str = "no regressors stored with the residuals"
                     ) -> list[Check]:
    if "residuals" not in idata.groups():
        note = "the run has no per-sample residuals"
        return [not_applicable("residual_autocorrelation", AUTOCORR_MAX, note),
                not_applicable("residual_regression", Z_THRESHOLD, note)]
    res = idata["residuals"]
    r = np.asarray(res["residual_std"] if "residual_std" in res else res["residual"])
    block = (np.asarray(res[block_coord]) if block_coord in res.coords
             else np.zeros(r.shape[0], int))
    checks = [residual_autocorrelation(r, block, labels=labels)]
    if covariates is None:
        checks.append(not_applicable("residual_regression", Z_THRESHOLD, no_regression))
    else:
        checks.append(residual_regression(r, covariates, block, names=names, labels=labels))
    return checks


def inertia_adequacy(post, sites: Sequence[str]) -> Adequacy:
    """The checks of :func:`~cassini_bayes.inference.inertia.fit_inertia`'s result ``post``.

    ``sites``: the posterior sites with proper priors (the inertia entries and the robust
    nuisance sites). Residual regressors: body rate and wheel momentum (body axes).
    """
    pb = post.problem
    cov = np.c_[pb.omega, pb.h_wheels]
    names = ["wx", "wy", "wz", "hwx", "hwy", "hwz"]
    sd = nuisance_prior_sd(pb.layout) if pb.robust else {}
    derived = common_wheel_scale(post.idata, pb.layout) if pb.robust else {}
    return Adequacy((prior_data_conflict(post.idata, sites, prior_sd=sd, derived=derived),
                     inertia_held_out(pb, post.idata),
                     *_residual_checks(post.idata, cov, names, "file", pb.sources)))


def thrust_adequacy(post, sites: Sequence[str]) -> Adequacy:
    """The checks of :func:`~cassini_bayes.inference.thrust.fit_thrust`'s result ``post``.

    No residual regression: on correctly specified simulations (``biasing_day028``, the model
    file's inertia equal to the truth) the Z-axis impulse residual correlates with the wheel
    momentum and the body-rate change at a normal deviate of 3–5.5 (47 % of 30 seeds beyond 4;
    ``benchmarks/adequacy_false_alarms.py``), a structure of the model's own approximations (the
    neglected random walk of the integrated gyroscopic term, Feldman & Lee Eq 17), not of the
    data; a wrong inertia shows instead as the wheel spin-inertia scale pulled from its prior.
    """
    pb = post.problem
    n_ev = len(pb.sources)
    held = not_applicable("held_out", Z_THRESHOLD,
                          "one event: nothing to hold out" if n_ev < 2 else
                          "not implemented for the thrust model (its nuisance parameters are "
                          "integrated out jointly over the events)")
    sd = nuisance_prior_sd(pb.layout) if pb.layout is not None else {}
    derived = common_wheel_scale(post.idata, pb.layout)
    return Adequacy((prior_data_conflict(post.idata, sites, prior_sd=sd, derived=derived), held,
                     *_residual_checks(post.idata, None, None, "event",
                                       [f"{t} + {p}" for t, p in pb.sources],
                                       no_regression="not used for thrust fits: the model's "
                                       "own approximations correlate the residuals with the "
                                       "wheel momentum (docs/adequacy.md)")))


def balance_fit(post, threshold: float = Z_THRESHOLD) -> Check:
    """Does the RWA4 model fit its own window balances? ``χ²`` of the balances at the posterior
    mean (:func:`~cassini_bayes.inference.rwa4.balance_misfit`) as the normal deviate of its
    upper χ² tail probability."""
    from cassini_bayes.inference.rwa4 import U4_NAMES, balance_misfit
    from cassini_bayes.physics.momentum import INERTIA_NAMES

    p = post.idata.posterior
    u = np.array([float(p[n].mean()) for n in U4_NAMES])
    pi = np.array([float(p[n].mean()) for n in INERTIA_NAMES])
    chi2, dof = balance_misfit(post.problem, u, pi)
    z = normal_deviate(min(2.0 * float(stats.chi2.sf(chi2, dof)), 1.0))   # one-sided tail
    return _check("balance_fit", z, threshold, note=f"chi2 {chi2:.3g} on {dof} dof")


def rwa4_adequacy(post, sites: Sequence[str]) -> Adequacy:
    """The checks of :func:`~cassini_bayes.inference.rwa4.fit_rwa4`'s result ``post``:
    prior-data conflict and the fit of the window balances (:func:`balance_fit`; the likelihood
    uses window means, so there are no per-sample residuals; the pairs share integrated-out
    nuisance parameters)."""
    n_pairs = len(post.problem.pairs)
    held = not_applicable("held_out", Z_THRESHOLD,
                          "one window pair: nothing to hold out" if n_pairs < 2 else
                          "not implemented for the RWA4 model (its nuisance parameters are "
                          "integrated out jointly over the pairs)")
    return Adequacy((prior_data_conflict(post.idata, sites), held, balance_fit(post),
                     *_residual_checks(post.idata, None, None, "pair", [])))
