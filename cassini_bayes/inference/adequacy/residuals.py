"""Adequacy check 3: residual structure (autocorrelation, regression on the model's regressors).

See :mod:`cassini_bayes.inference.adequacy`.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from scipy import stats

from cassini_bayes.inference.adequacy.check import (AUTOCORR_MAX, Z_THRESHOLD, Check, z_check,
                                                    normal_deviate, not_applicable)


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
    return z_check("residual_autocorrelation", worst_z, threshold, worst)


def _lag1(x: np.ndarray) -> np.ndarray:
    """Lag-1 autocorrelation of each column of ``x`` (n, k), centred."""
    x = x - x.mean(0)
    den = np.sum(x**2, 0)
    return np.where(den > 0, np.sum(x[1:] * x[:-1], 0) / np.where(den > 0, den, 1.0), 0.0)


def _neighbour_split(idx: np.ndarray, times: np.ndarray | None):
    """Every other sample of a block and its two neighbours: ``mid`` (the samples whose residual
    is tested), ``left``, ``right`` (indices) and the weight ``w`` of ``right`` in the linear
    interpolation at ``mid`` (in time when ``times`` is given, else ½)."""
    m = (idx.size - 1) // 2
    left, mid, right = idx[0:2 * m:2], idx[1:2 * m:2], idx[2:2 * m + 1:2]
    w = np.full(m, 0.5)
    if times is not None:
        t = np.asarray(times, float)
        span = t[right] - t[left]
        w = np.where(span > 0, (t[mid] - t[left]) / np.where(span > 0, span, 1.0), 0.5)
    return mid, left, right, w


def residual_regression(residual: np.ndarray, covariates: np.ndarray, block: np.ndarray,
                        threshold: float = Z_THRESHOLD, names: Sequence[str] | None = None,
                        labels: Sequence[str] | None = None,
                        times: np.ndarray | None = None) -> Check:
    """F-test of each block's residual axis regressed on ``covariates`` (N, K) and a constant.

    The regressors at a tested sample are interpolated from its two neighbours (linearly in
    ``times`` when given), and only every other sample is tested, so no regressor value holds
    the measurement noise of a tested sample. Why: the residual is made of the same measured
    quantities as the regressors (the inertia balance ``I ω + H_w − A H_N``), so a regressor
    taken at its own sample carries the noise that makes up the residual, and a combination of
    them (``I ω + H_w``, whose signal is only the slowly turning ``A H_N``) reproduces it: a
    fixed correlation at the noise level, whose F-statistic grows in proportion to the number
    of samples (docs/adequacy.md, "The number of samples"). For noise that is white from
    sample to sample the interpolated regressors are
    independent of the tested residual, whatever the number of samples; a misfit (a residual
    that follows the slowly varying signal of the regressors) is kept, since interpolating a
    smooth signal between neighbours changes it little.

    Both sides are then prewhitened with the tested residual's own lag-1 autocorrelation ``ρ̂``
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
        if idx.size < 2 * (3 * covariates.shape[1] + 10) + 1:
            continue
        mid, left, right, w = _neighbour_split(idx, times)
        x_mid = (1.0 - w)[:, None] * covariates[left] + w[:, None] * covariates[right]
        for a in range(residual.shape[1]):
            y0 = residual[mid, a]
            rho = float(_lag1(y0[:, None])[0])
            y = y0[1:] - rho * y0[:-1]
            x = x_mid[1:] - rho * x_mid[:-1]
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
    return z_check("residual_regression", normal_deviate(min(1.0, len(tests) * p)), threshold,
                  where)
