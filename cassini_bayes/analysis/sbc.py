"""Simulation-based calibration: ranks, rank-uniformity tests, interval coverage, figures.

Simulation-based calibration (SBC, Talts et al. 2018, "Validating Bayesian inference algorithms
with simulation-based calibration", arXiv:1804.06788) checks a whole inference pipeline — prior,
simulator, likelihood, sampler — on synthetic truth. For replicate ``n``: draw ``θ̃ ~ p(θ)``,
simulate ``ỹ ~ p(y | θ̃)``, draw ``L`` (thinned, nearly independent) posterior draws
``θ_1..θ_L ~ p(θ | ỹ)`` and record the rank ``r = #{l : θ_l < θ̃} ∈ {0, …, L}``. If the posterior
is right, ``r`` is discrete-uniform on ``{0, …, L}`` for every parameter (Talts et al. 2018,
Theorem 1). This module is the statistics of that check, independent of any model:

- :func:`ranks` — the rank of the truth among the draws, ties broken at random with a key;
- :func:`chi2_uniformity` — Pearson's chi-square on ``B`` bins of ranks, ``p`` from
  :data:`scipy.stats.chi2` with ``B − 1`` degrees of freedom;
- :func:`ecdf_uniformity` — the ECDF simultaneous-band test of Säilynoja, Bürkner & Vehtari (2022,
  "Graphical test for discrete uniformity and its applications in goodness-of-fit evaluation and
  multiple sample comparison", Statistics and Computing 32:32): the statistic is the smallest
  pointwise binomial band level that still contains the whole rank ECDF; its null distribution is
  simulated exactly (discrete-uniform ranks), the simultaneous band itself comes from ArviZ
  (:func:`arviz.stats.ecdf_utils.ecdf_confidence_band`, "optimized" method of the same paper);
- :func:`coverage` — how often the truth falls inside the posterior's central 50/80/90/95 %
  intervals, with binomial standard errors ``sqrt(c (1 − c) / N)`` at the nominal level ``c``;
- :func:`sbc_result` — all of the above for every parameter, as one :class:`SbcResult`;
- :func:`plot_rank_histograms`, :func:`plot_ecdf_difference` — figures (the ECDF-difference panels
  are drawn by :func:`arviz.plot_ecdf`).

False-failure rate. With ``k`` parameters each tested at level ``α`` by one statistic, a correct
model fails at least one test with probability ``1 − (1 − α)^k ≤ k α`` (independent tests; the
parameters' ranks are dependent in general, and the union bound ``k α`` holds regardless).
:func:`sbc_result` tests each parameter at ``α / k`` by default (Bonferroni), so each statistic
falsely fails a correct model with probability at most ``alpha_family`` (default 1 %).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from scipy import stats

__all__ = [
    "COVERAGE_LEVELS",
    "ChiSquareTest",
    "EcdfTest",
    "Coverage",
    "ParameterSbc",
    "SbcResult",
    "ranks",
    "chi2_uniformity",
    "ecdf_uniformity",
    "coverage",
    "sbc_result",
    "plot_rank_histograms",
    "plot_ecdf_difference",
]

COVERAGE_LEVELS: tuple[float, ...] = (0.5, 0.8, 0.9, 0.95)
"""Nominal probabilities of the central posterior intervals whose coverage is reported."""

_ECDF_NULL_TRIALS = 3000
_ECDF_NULL_SEED = 20180412  # fixed: the same ranks always give the same p-value


class ChiSquareTest(NamedTuple):
    """Pearson chi-square test of discrete uniformity on binned ranks.

    Attributes
    ----------
    statistic : float
        ``Σ_b (O_b − E_b)² / E_b`` over the ``bins`` bins.
    df : int
        Degrees of freedom, ``bins − 1``.
    p_value : float
        Upper tail of the chi-square distribution with ``df`` degrees of freedom.
    bins : int
        Number of bins; each bin holds a contiguous run of rank values.
    observed : numpy.ndarray
        Counts per bin, shape ``(bins,)``.
    expected : numpy.ndarray
        Expected counts per bin under uniformity, shape ``(bins,)``.
    """

    statistic: float
    df: int
    p_value: float
    bins: int
    observed: np.ndarray
    expected: np.ndarray


class EcdfTest(NamedTuple):
    """ECDF simultaneous-band test of discrete uniformity (Säilynoja et al. 2022).

    Attributes
    ----------
    statistic : float
        ``1 − 2 min_i min(F_Bin(N·ECDF_i), 1 − F_Bin(N·ECDF_i − 1))``: the smallest pointwise
        (binomial) band level containing the whole ECDF; near 1 means some point is extreme.
    p_value : float
        Probability under discrete uniformity of a statistic at least as large, by simulation
        (``(1 + #{γ_sim ≥ γ}) / (1 + trials)``, a valid, slightly conservative p-value).

    Notes
    -----
    ``p_value < α`` is the same decision as "the ECDF leaves the ``1 − α`` simultaneous band" that
    ArviZ draws (:func:`arviz.stats.ecdf_utils.ecdf_confidence_band`, ``method="optimized"``, the
    band of :func:`plot_ecdf_difference`), up to the discreteness of the statistic; the test suite
    checks the two agree.
    """

    statistic: float
    p_value: float


class Coverage(NamedTuple):
    """Coverage of central posterior intervals.

    Attributes
    ----------
    levels : tuple of float
        Nominal probabilities ``c`` of the central intervals ``[q_{(1−c)/2}, q_{(1+c)/2}]``.
    observed : numpy.ndarray
        Fraction of replicates whose truth lies inside the interval, shape ``(len(levels),)``.
    se : numpy.ndarray
        Binomial standard error of that fraction at the nominal level, ``sqrt(c (1 − c) / N)``.
    n : int
        Number of replicates.
    """

    levels: tuple[float, ...]
    observed: np.ndarray
    se: np.ndarray
    n: int


class ParameterSbc(NamedTuple):
    """SBC results of one parameter."""

    name: str
    chi2: ChiSquareTest
    ecdf: EcdfTest
    coverage: Coverage


class SbcResult(NamedTuple):
    """SBC of a whole model.

    Attributes
    ----------
    names : tuple of str
        Parameter names, in column order of ``ranks``.
    ranks : numpy.ndarray
        Ranks of the truth, integers in ``0..n_draws``, shape ``(n_replicates, n_parameters)``.
    n_draws : int
        ``L``, the number of thinned posterior draws each rank was taken among.
    alpha : float
        Per-parameter test level (``alpha_family / n_parameters``).
    alpha_family : float
        Bound on the false-failure rate of each statistic over all parameters.
    parameters : dict
        ``name -> ParameterSbc``.
    """

    names: tuple[str, ...]
    ranks: np.ndarray
    n_draws: int
    alpha: float
    alpha_family: float
    parameters: dict[str, ParameterSbc]

    @property
    def n_replicates(self) -> int:
        """Number of replicates the ranks come from."""
        return int(self.ranks.shape[0])

    def passed(self, statistic: str = "both") -> bool:
        """Whether every parameter passes: ``"chi2"``, ``"ecdf"`` or ``"both"`` statistics."""
        ok = True
        for p in self.parameters.values():
            if statistic in ("chi2", "both"):
                ok &= p.chi2.p_value >= self.alpha
            if statistic in ("ecdf", "both"):
                ok &= p.ecdf.p_value >= self.alpha
        return bool(ok)


def ranks(key: jax.Array, draws: jax.Array, truth: jax.Array) -> jax.Array:
    """Rank of the truth among posterior draws, ties broken uniformly at random.

    Talts et al. (2018) Algorithm 1: ``r = #{l : θ_l < θ̃}``; with ``t`` draws equal to ``θ̃`` the
    rank is ``#{θ_l < θ̃} + U{0..t}`` so it stays exactly uniform for discrete or rounded draws.

    Parameters
    ----------
    key : jax.Array
        PRNG key for the tie-breaking.
    draws : jax.Array
        Posterior draws, shape ``(..., L)`` (the last axis are the draws).
    truth : jax.Array
        True values, shape ``(...)``.

    Returns
    -------
    jax.Array
        Integer ranks in ``0..L``, shape ``(...)``.
    """
    draws = jnp.asarray(draws)
    truth = jnp.asarray(truth)[..., None]
    below = jnp.sum(draws < truth, axis=-1)
    ties = jnp.sum(draws == truth, axis=-1)
    u = jax.random.uniform(key, below.shape)
    return (below + jnp.floor(u * (ties + 1)).astype(below.dtype)).astype(jnp.int32)


def _default_bins(n_replicates: int, n_draws: int) -> int:
    """Number of rank bins: about ``N / 10`` expected counts per bin, between 2 and 20, ``≤ L + 1``.

    Ten expected counts per bin keeps the chi-square approximation good (the usual rule is ≥ 5).
    """
    return int(max(2, min(20, n_replicates // 10, n_draws + 1)))


def _bin_edges(n_draws: int, bins: int) -> np.ndarray:
    """Edges splitting the rank values ``0..L`` into ``bins`` contiguous runs of near-equal size."""
    return np.round(np.linspace(0, n_draws + 1, bins + 1)).astype(int)


def chi2_uniformity(rank: np.ndarray, n_draws: int, bins: int | None = None) -> ChiSquareTest:
    """Pearson chi-square test that ranks are discrete-uniform on ``0..n_draws``.

    Parameters
    ----------
    rank : numpy.ndarray
        Integer ranks in ``0..n_draws``, shape ``(N,)``.
    n_draws : int
        ``L``, the number of posterior draws the ranks were taken among.
    bins : int, optional
        Number of bins ``B`` (default :func:`_default_bins`). Bin ``b`` holds the rank values
        ``[e_b, e_{b+1})``; its expected count is ``N (e_{b+1} − e_b) / (L + 1)``, exact even when
        ``B`` does not divide ``L + 1``.

    Returns
    -------
    ChiSquareTest
        Statistic, ``B − 1`` degrees of freedom, p-value from :data:`scipy.stats.chi2`.
    """
    rank = np.asarray(rank)
    n = rank.size
    bins = _default_bins(n, n_draws) if bins is None else int(bins)
    if not 2 <= bins <= n_draws + 1:
        raise ValueError(f"bins must be in 2..{n_draws + 1}, got {bins}")
    edges = _bin_edges(n_draws, bins)
    observed = np.histogram(rank, bins=edges)[0].astype(float)
    expected = n * np.diff(edges) / (n_draws + 1)
    statistic = float(np.sum((observed - expected) ** 2 / expected))
    df = bins - 1
    return ChiSquareTest(statistic, df, float(stats.chi2.sf(statistic, df)), bins, observed,
                         expected)


def _ecdf_gamma(counts: np.ndarray, n: int, cdf: np.ndarray) -> np.ndarray:
    """Säilynoja et al. (2022) statistic from ECDF counts ``N·ECDF`` at the evaluation points.

    ``counts`` has shape ``(..., K)``; returns shape ``(...)``. Same quantity as ArviZ's
    ``ecdf_utils._fit_pointwise_band_probability``, vectorised over many simulated ECDFs.
    """
    lower = stats.binom.cdf(counts, n, cdf).min(axis=-1)
    upper = stats.binom.sf(counts - 1, n, cdf).min(axis=-1)
    return 1.0 - 2.0 * np.minimum(lower, upper)


_NULL_CACHE: dict[tuple[int, int], np.ndarray] = {}


def _ecdf_null(n: int, n_draws: int) -> np.ndarray:
    """Simulated null distribution of the statistic for ``n`` uniform ranks on ``0..n_draws``."""
    if (n, n_draws) not in _NULL_CACHE:
        rng = np.random.default_rng(_ECDF_NULL_SEED)
        eval_points = np.arange(n_draws)
        cdf = (eval_points + 1) / (n_draws + 1)
        gammas = []
        for start in range(0, _ECDF_NULL_TRIALS, 500):
            m = min(500, _ECDF_NULL_TRIALS - start)
            sim = rng.integers(0, n_draws + 1, size=(m, n)) + (n_draws + 1) * np.arange(m)[:, None]
            hist = np.bincount(sim.ravel(), minlength=m * (n_draws + 1)).reshape(m, n_draws + 1)
            counts = np.cumsum(hist, axis=1)[:, :n_draws]
            gammas.append(_ecdf_gamma(counts, n, cdf))
        _NULL_CACHE[(n, n_draws)] = np.concatenate(gammas)
    return _NULL_CACHE[(n, n_draws)]


def ecdf_uniformity(rank: np.ndarray, n_draws: int) -> EcdfTest:
    """ECDF simultaneous-band test that ranks are discrete-uniform on ``0..n_draws``.

    The rank ECDF is evaluated at every rank value ``0..L−1`` (it is 1 at ``L``), where the
    uniform CDF is ``(r + 1) / (L + 1)``; evaluation points that do not depend on the data keep the
    band calibrated (Säilynoja et al. 2022, Sec. 2).

    Parameters
    ----------
    rank : numpy.ndarray
        Integer ranks in ``0..n_draws``, shape ``(N,)``.
    n_draws : int
        ``L``.

    Returns
    -------
    EcdfTest
    """
    rank = np.asarray(rank)
    n = rank.size
    cdf = (np.arange(n_draws) + 1) / (n_draws + 1)
    counts = np.cumsum(np.bincount(rank, minlength=n_draws + 1))[:n_draws]
    gamma = float(_ecdf_gamma(counts, n, cdf))
    null = _ecdf_null(n, n_draws)
    p_value = (1.0 + np.sum(null >= gamma - 1e-12)) / (1.0 + null.size)
    return EcdfTest(gamma, float(p_value))


def coverage(draws: np.ndarray, truth: np.ndarray,
             levels: Sequence[float] = COVERAGE_LEVELS) -> Coverage:
    """Coverage of central posterior intervals.

    Parameters
    ----------
    draws : numpy.ndarray
        Posterior draws, shape ``(N, L)``.
    truth : numpy.ndarray
        True values, shape ``(N,)``.
    levels : sequence of float
        Nominal central-interval probabilities.

    Returns
    -------
    Coverage
        Observed fraction inside ``[q_{(1−c)/2}, q_{(1+c)/2}]`` (sample quantiles of the draws)
        per level, with the binomial standard error at the nominal level.
    """
    draws = np.asarray(draws, dtype=float)
    truth = np.asarray(truth, dtype=float)
    n = truth.shape[0]
    observed, se = [], []
    for c in levels:
        lo, hi = np.quantile(draws, [(1 - c) / 2, (1 + c) / 2], axis=-1)
        observed.append(np.mean((truth >= lo) & (truth <= hi)))
        se.append(np.sqrt(c * (1 - c) / n))
    return Coverage(tuple(float(c) for c in levels), np.asarray(observed), np.asarray(se), n)


def sbc_result(names: Sequence[str], rank: np.ndarray, n_draws: int, *,
               draws: Mapping[str, np.ndarray] | None = None,
               truth: Mapping[str, np.ndarray] | None = None,
               alpha_family: float = 0.01, bins: int | None = None) -> SbcResult:
    """Uniformity tests and coverage for every parameter.

    Parameters
    ----------
    names : sequence of str
        Parameter names (columns of ``rank``).
    rank : numpy.ndarray
        Ranks, shape ``(N, P)``.
    n_draws : int
        ``L``.
    draws, truth : mapping, optional
        ``name -> (N, L)`` thinned draws and ``name -> (N,)`` truths for coverage. Without them the
        coverage is computed from the ranks (the truth is inside the central ``c`` interval of the
        draws when its rank is inside the central ``c`` fraction of ``0..L``).
    alpha_family : float
        Family-wise false-failure rate of each statistic; each parameter is tested at
        ``alpha_family / P``.
    bins : int, optional
        Chi-square bins (default :func:`_default_bins`).

    Returns
    -------
    SbcResult
    """
    rank = np.asarray(rank)
    names = tuple(names)
    if rank.ndim != 2 or rank.shape[1] != len(names):
        raise ValueError(f"ranks must have shape (N, {len(names)}), got {rank.shape}")
    alpha = alpha_family / len(names)
    out = {}
    for j, name in enumerate(names):
        r = rank[:, j]
        if draws is not None and truth is not None:
            cov = coverage(draws[name], truth[name])
        else:
            cov = _coverage_from_ranks(r, n_draws)
        out[name] = ParameterSbc(name, chi2_uniformity(r, n_draws, bins),
                                 ecdf_uniformity(r, n_draws), cov)
    return SbcResult(names, rank, int(n_draws), float(alpha), float(alpha_family), out)


def _coverage_from_ranks(rank: np.ndarray, n_draws: int,
                         levels: Sequence[float] = COVERAGE_LEVELS) -> Coverage:
    u = (rank + 0.5) / (n_draws + 1)
    n = rank.size
    obs = [np.mean(np.abs(u - 0.5) <= c / 2) for c in levels]
    se = [np.sqrt(c * (1 - c) / n) for c in levels]
    return Coverage(tuple(levels), np.asarray(obs), np.asarray(se), n)


# ---------------------------------------------------------------------------------- figures


def _grid(n: int):
    import matplotlib.pyplot as plt

    ncol = min(n, 3)
    nrow = -(-n // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(3.6 * ncol, 2.7 * nrow), squeeze=False)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    return fig, axes.flat


def plot_rank_histograms(result: SbcResult, bins: int | None = None, band: float = 0.99):
    """Histograms of the ranks with the pointwise binomial band of a uniform histogram.

    The grey band is the central ``band`` interval of ``Binomial(N, p_b)`` per bin (Talts et al.
    2018, Fig. 2 style); p-values of both statistics are in each title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = _grid(len(result.names))
    n, L = result.n_replicates, result.n_draws
    for ax, name, j in zip(axes, result.names, range(len(result.names))):
        test = chi2_uniformity(result.ranks[:, j], L, bins or result.parameters[name].chi2.bins)
        edges = _bin_edges(L, test.bins)
        p = np.diff(edges) / (L + 1)
        lo, hi = stats.binom.interval(band, n, p)
        ax.bar(edges[:-1], test.observed, width=np.diff(edges), align="edge", color="#5b7fb5",
               edgecolor="white", zorder=1)
        lo_s, hi_s = np.append(lo, lo[-1]), np.append(hi, hi[-1])
        ax.fill_between(edges, lo_s, hi_s, step="post", color="grey", alpha=0.25, lw=0,
                        zorder=0)
        for bound in (lo_s, hi_s):  # the band's edges stay visible over the bars
            ax.plot(edges, bound, drawstyle="steps-post", color="dimgrey", lw=0.8, ls="--",
                    zorder=3)
        ax.plot(edges, np.append(test.expected, test.expected[-1]), drawstyle="steps-post",
                color="black", lw=0.8, zorder=3)
        ps = result.parameters[name]
        ax.set_title(f"{name}: χ² p={ps.chi2.p_value:.3g}, ECDF p={ps.ecdf.p_value:.3g}",
                     fontsize=9)
        ax.set_xlabel(f"rank of truth among {L} draws")
        ax.set_xlim(0, L + 1)
    fig.tight_layout()
    return fig


def plot_ecdf_difference(result: SbcResult):
    """ECDF-difference plots of the ranks with ArviZ's simultaneous band at level ``1 − α``.

    Each panel is :func:`arviz.plot_ecdf` of the ranks against the discrete-uniform CDF on
    ``0..L``, ``difference=True``, ``confidence_bands="optimized"`` (Säilynoja et al. 2022).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from cassini_bayes._arviz import load_arviz

    az = load_arviz()

    fig, axes = _grid(len(result.names))
    L = result.n_draws

    def cdf(r):
        return np.clip((np.floor(r) + 1) / (L + 1), 0.0, 1.0)

    for ax, name, j in zip(axes, result.names, range(len(result.names))):
        az.plot_ecdf(result.ranks[:, j], eval_points=np.arange(L), cdf=cdf, difference=True,
                     confidence_bands="optimized", ci_prob=1 - result.alpha, ax=ax)
        ax.set_title(f"{name}: ECDF p={result.parameters[name].ecdf.p_value:.3g}", fontsize=9)
        ax.set_xlabel("rank")
    fig.tight_layout()
    return fig
