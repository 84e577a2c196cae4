"""Does the model fit? Self-checks of a posterior that need no truth (flight data has none).

Each check returns one number, ``statistic``, compared with a ``threshold`` (``ok`` when
``statistic ≤ threshold``); every statistic is on the scale of a standard normal deviate, so the
thresholds read alike. The false-alarm rates on correctly specified data are measured by
``benchmarks/adequacy_false_alarms.py`` and stated in ``docs/adequacy.md``.

* ``prior_data_conflict`` — for every element ``x`` of the named posterior sites that has a
  proper prior (the ``prior`` group's draws), ``|E[x | data] − E[x]| / sd(x)`` with the prior's
  mean and sd, on the log scale when every prior draw is positive (thrust, time constants,
  moments). A nuisance parameter pulled several prior sd from its prior is how an unmodelled
  error reaches the answer; the worst element is named (``parameter``).
* ``held_out`` — leave one telemetry file out: the posterior of the shared parameters from the
  other files (and the prior) predicts the held-out file's information-weighted estimate, exactly
  where the model is linear-Gaussian in its parameters (the inertia model's sufficient
  statistics, :func:`gaussian_held_out`); the statistic is the normal deviate of the smallest
  Bonferroni-adjusted χ² tail probability over the files. Not applicable to one file.
* ``residual_autocorrelation`` — whiteness against time: per block (file, event) and axis the
  lag-1 autocorrelation ``ρ̂₁`` of the posterior-mean residuals, ``|ρ̂₁| √n`` (≈ N(0, 1) for
  white residuals); the maximum over blocks and axes.
* ``residual_regression`` — whiteness against the regressors the model uses (body rate ω and
  wheel momentum): per block and axis the F-test of the residual regressed on them, as the
  normal deviate of its Bonferroni-adjusted tail probability.
"""

from __future__ import annotations

import math
from typing import Mapping, NamedTuple, Sequence

import numpy as np
from scipy import stats

__all__ = ["Check", "Adequacy", "PRIOR_CONFLICT_SD", "Z_THRESHOLD", "normal_deviate",
           "prior_data_conflict", "gaussian_held_out", "inertia_held_out",
           "residual_autocorrelation", "residual_regression", "not_applicable",
           "inertia_adequacy", "thrust_adequacy", "rwa4_adequacy"]

PRIOR_CONFLICT_SD = 4.0   # prior sd between the posterior mean and the prior mean
Z_THRESHOLD = 4.0         # normal deviate of the residual and held-out checks (two-sided 6e-5)


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


def prior_data_conflict(idata, sites: Sequence[str],
                        threshold: float = PRIOR_CONFLICT_SD) -> Check:
    """``max |E[x | data] − E[x]| / sd(x)`` over every element of ``sites`` that has prior draws.

    Works on any site shape (a scalar ``wheel_scale`` or one per wheel alike). Prior mean and sd
    come from the ``prior`` group's draws; sites whose prior draws are all positive are compared
    on the log scale (log-normal priors of thrust and time constants; moments of inertia).
    """
    name = "prior_data_conflict"
    if "prior" not in idata.groups():
        return not_applicable(name, threshold, "no prior draws in the run")
    worst, worst_z = None, -1.0
    for site in sites:
        if site not in idata.posterior or site not in idata.prior:
            continue
        post, prior = _elements(idata.posterior[site]), _elements(idata.prior[site])
        for label, x in post.items():
            p = prior.get(label)
            if p is None or p.size < 2:
                continue
            if np.all(p > 0) and np.all(x > 0):
                p, x = np.log(p), np.log(x)
            sd = float(np.std(p, ddof=1))
            if not sd > 0:
                continue
            z = abs(float(np.mean(x)) - float(np.mean(p))) / sd
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

def _blocks(block: np.ndarray) -> list[np.ndarray]:
    return [np.flatnonzero(block == b) for b in np.unique(block)]


def residual_autocorrelation(residual: np.ndarray, block: np.ndarray,
                             threshold: float = Z_THRESHOLD) -> Check:
    """``max |ρ̂₁| √n`` over blocks and axes of ``residual`` (N, 3) in time order per block.

    ``ρ̂₁`` is the lag-1 autocorrelation of the block's centred residual on one axis; for white
    residuals ``ρ̂₁ √n`` is ≈ N(0, 1).
    """
    worst, worst_z = None, -1.0
    for b, idx in enumerate(_blocks(np.asarray(block))):
        x = np.asarray(residual, float)[idx]
        if x.shape[0] < 10:
            continue
        x = x - x.mean(0)
        den = np.sum(x**2, 0)
        rho = np.where(den > 0, np.sum(x[1:] * x[:-1], 0) / np.where(den > 0, den, 1.0), 0.0)
        z = np.abs(rho) * math.sqrt(x.shape[0])
        k = int(np.argmax(z))
        if z[k] > worst_z:
            worst, worst_z = f"block {b} axis {'xyz'[k]} (lag-1 autocorrelation {rho[k]:+.3f})", \
                float(z[k])
    if worst is None:
        return not_applicable("residual_autocorrelation", threshold, "too few residuals")
    return _check("residual_autocorrelation", worst_z, threshold, worst)


def residual_regression(residual: np.ndarray, covariates: np.ndarray, block: np.ndarray,
                        threshold: float = Z_THRESHOLD,
                        names: Sequence[str] | None = None) -> Check:
    """F-test of each block's residual axis regressed on ``covariates`` (N, K) plus a constant.

    Statistic: the normal deviate of the smallest Bonferroni-adjusted p-value over blocks and
    axes. ``parameter`` names the block, axis and the covariate with the largest |t|.
    """
    residual = np.asarray(residual, float)
    covariates = np.asarray(covariates, float)
    names = list(names) if names is not None else [f"x{k}" for k in range(covariates.shape[1])]
    tests = []
    for b, idx in enumerate(_blocks(np.asarray(block))):
        x = covariates[idx]
        x = x - x.mean(0)
        keep = np.std(x, 0) > 0
        x = x[:, keep]
        n, k = x.shape
        if k == 0 or n <= k + 2:
            continue
        q, rr = np.linalg.qr(x)
        good = np.abs(np.diag(rr)) > 1e-10 * np.abs(np.diag(rr)).max()
        q = q[:, good]
        k = q.shape[1]
        for a in range(residual.shape[1]):
            y = residual[idx, a] - residual[idx, a].mean()
            fit = q.T @ y
            ss_reg, ss_res = float(fit @ fit), float(y @ y - fit @ fit)
            if ss_res <= 0:
                continue
            f_stat = (ss_reg / k) / (ss_res / (n - k - 1))
            coef = np.linalg.lstsq(x, y, rcond=None)[0]
            resid_var = ss_res / (n - k - 1)
            se = np.sqrt(resid_var * np.diag(np.linalg.pinv(x.T @ x)))
            tv = np.abs(coef) / np.where(se > 0, se, np.inf)
            top = np.array(names)[keep][int(np.argmax(tv))]
            tests.append((stats.f.sf(f_stat, k, n - k - 1), f"block {b} axis {'xyz'[a]} ~ {top}"))
    if not tests:
        return not_applicable("residual_regression", threshold, "too few residuals")
    p, where = min(tests, key=lambda t: t[0])
    z = normal_deviate(min(1.0, len(tests) * p))
    return _check("residual_regression", z, threshold, where)


# --------------------------------------------------------------------------------------------
# Per kind
# --------------------------------------------------------------------------------------------

def _residual_checks(idata, covariates: np.ndarray | None, names: Sequence[str] | None,
                     block_coord: str) -> list[Check]:
    if "residuals" not in idata.groups():
        note = "the run has no per-sample residuals"
        return [not_applicable("residual_autocorrelation", Z_THRESHOLD, note),
                not_applicable("residual_regression", Z_THRESHOLD, note)]
    res = idata["residuals"]
    r = np.asarray(res["residual_std"] if "residual_std" in res else res["residual"])
    block = (np.asarray(res[block_coord]) if block_coord in res.coords
             else np.zeros(r.shape[0], int))
    checks = [residual_autocorrelation(r, block)]
    if covariates is None:
        checks.append(not_applicable("residual_regression", Z_THRESHOLD,
                                     "no regressors stored with the residuals"))
    else:
        checks.append(residual_regression(r, covariates, block, names=names))
    return checks


def inertia_adequacy(post, sites: Sequence[str]) -> Adequacy:
    """The checks of :func:`~cassini_bayes.inference.inertia.fit_inertia`'s result ``post``.

    ``sites``: the posterior sites with proper priors (the inertia entries and the robust
    nuisance sites). Residual regressors: body rate and wheel momentum (body axes).
    """
    pb = post.problem
    cov = np.c_[pb.omega, pb.h_wheels]
    names = ["wx", "wy", "wz", "hwx", "hwy", "hwz"]
    return Adequacy((prior_data_conflict(post.idata, sites), inertia_held_out(pb, post.idata),
                     *_residual_checks(post.idata, cov, names, "file")))


def thrust_adequacy(post, sites: Sequence[str]) -> Adequacy:
    """The checks of :func:`~cassini_bayes.inference.thrust.fit_thrust`'s result ``post``.

    Residual regressors: the body-rate change since the event's first sample (``I Δω`` is the
    left side of Feldman & Lee Eq 17, so a wrong inertia shows here) and the wheel momentum.
    """
    kw = post.problem.model_kwargs
    m = np.asarray(kw["mask"]) > 0
    omega, hw = np.asarray(kw["omega"]), np.asarray(kw["h_wheels"])
    cov = np.concatenate([np.c_[omega[e][m[e]] - omega[e][m[e]][0], hw[e][m[e]]]
                          for e in range(m.shape[0])])
    names = ["dwx", "dwy", "dwz", "hwx", "hwy", "hwz"]
    n_ev = m.shape[0]
    held = not_applicable("held_out", Z_THRESHOLD,
                          "one event: nothing to hold out" if n_ev < 2 else
                          "not implemented for the thrust model (its nuisance parameters are "
                          "integrated out jointly over the events)")
    return Adequacy((prior_data_conflict(post.idata, sites), held,
                     *_residual_checks(post.idata, cov, names, "event")))


def rwa4_adequacy(post, sites: Sequence[str]) -> Adequacy:
    """The checks of :func:`~cassini_bayes.inference.rwa4.fit_rwa4`'s result ``post``: prior-data
    conflict only (the likelihood uses window means, so there are no per-sample residuals; the
    pairs share integrated-out nuisance parameters)."""
    n_pairs = len(post.problem.pairs)
    held = not_applicable("held_out", Z_THRESHOLD,
                          "one window pair: nothing to hold out" if n_pairs < 2 else
                          "not implemented for the RWA4 model (its nuisance parameters are "
                          "integrated out jointly over the pairs)")
    return Adequacy((prior_data_conflict(post.idata, sites), held,
                     *_residual_checks(post.idata, None, None, "pair")))
