"""Simulation-based calibration statistics (``cassini_bayes.analysis.sbc``) and SBC of the toy
model.

Statistical tests here use fixed keys/seeds, so each is deterministic; the false-failure rate (FFR)
stated with each is the probability, over the choice of key, that a correct implementation fails.
"""

from __future__ import annotations

import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import stats

from cassini_bayes.analysis import sbc
from cassini_bayes.analysis.campaign import run_campaign
from cassini_bayes.analysis.sbc_models import ModelSpec
from pages import first_table

BATCH = 16  # the same batch size in every test: one compiled sampler for the whole session


# ------------------------------------------------------------------------------- statistics


def test_ranks_count_draws_below_truth(key):
    draws = jnp.array([[0.1, 0.5, 0.9, 0.3], [1.0, 2.0, 3.0, 4.0]])
    truth = jnp.array([0.4, 0.5])
    np.testing.assert_array_equal(sbc.ranks(key, draws, truth), [2, 0])


def test_ranks_break_ties_uniformly(key):
    # All L = 9 draws equal the truth: the rank must be uniform on 0..9.
    # FFR: chi-square at alpha = 1e-3 -> 0.1 %.
    n, L = 5000, 9
    r = np.asarray(sbc.ranks(key, jnp.ones((n, L)), jnp.ones(n)))
    assert r.min() == 0 and r.max() == L
    assert sbc.chi2_uniformity(r, L, bins=10).p_value > 1e-3


def test_chi2_matches_scipy_chisquare():
    rng = np.random.default_rng(0)
    L = 99
    r = rng.integers(0, L + 1, 200)
    t = sbc.chi2_uniformity(r, L, bins=10)
    ref = stats.chisquare(np.bincount(r // 10, minlength=10))
    assert t.df == 9
    np.testing.assert_allclose([t.statistic, t.p_value], [ref.statistic, ref.pvalue], rtol=1e-12)


def test_chi2_unequal_bins_have_exact_expected_counts():
    t = sbc.chi2_uniformity(np.arange(101), 100, bins=4)  # 101 rank values, 4 bins
    np.testing.assert_allclose(t.expected.sum(), 101)
    np.testing.assert_allclose(t.statistic, 0.0, atol=1e-12)


def test_ecdf_statistic_matches_arviz():
    from arviz.stats.ecdf_utils import _fit_pointwise_band_probability

    rng = np.random.default_rng(1)
    L, n = 49, 80
    r = rng.integers(0, L + 1, n)
    cdf = (np.arange(L) + 1) / (L + 1)
    counts = np.cumsum(np.bincount(r, minlength=L + 1))[:L]
    # ArviZ casts N*ECDF to int; the +0.25/N keeps that cast exact.
    ref = _fit_pointwise_band_probability(n, (counts + 0.25) / n, cdf)
    assert sbc.ecdf_uniformity(r, L).statistic == pytest.approx(ref, rel=1e-12)


def test_ecdf_decision_agrees_with_arviz_simultaneous_band():
    """p < alpha exactly when the ECDF leaves ArviZ's optimized 1 - alpha simultaneous band."""
    from arviz.stats.ecdf_utils import ecdf_confidence_band

    rng = np.random.default_rng(2)
    L, n, alpha = 19, 60, 0.05
    cdf = (np.arange(L) + 1) / (L + 1)
    lower, upper = ecdf_confidence_band(n, np.arange(L), cdf, prob=1 - alpha, method="optimized")
    agree = 0
    for i in range(40):
        p_skew = np.linspace(1.0, 1.0 + 0.05 * i, L + 1)  # from uniform to increasingly tilted
        r = rng.choice(L + 1, size=n, p=p_skew / p_skew.sum())
        ecdf = np.cumsum(np.bincount(r, minlength=L + 1))[:L] / n
        inside = np.all((ecdf >= lower - 0.5 / n) & (ecdf <= upper + 0.5 / n))
        agree += inside == (sbc.ecdf_uniformity(r, L).p_value >= alpha)
    # The two calibrate the same band (one by simulation, one by ArviZ's exact recursion); they
    # may differ only for an ECDF sitting on the band's edge.
    assert agree >= 38


def test_uniformity_p_values_are_calibrated():
    # 400 sets of uniform ranks: the fraction of p < 0.1 is Binomial(400, 0.1)/400 (sd 0.015);
    # tolerance 0.05 (> 3.3 sd) per statistic -> FFR < 0.2 %.
    rng = np.random.default_rng(3)
    L, n = 39, 100
    p_chi, p_ecdf = [], []
    for _ in range(400):
        r = rng.integers(0, L + 1, n)
        p_chi.append(sbc.chi2_uniformity(r, L).p_value)
        p_ecdf.append(sbc.ecdf_uniformity(r, L).p_value)
    assert abs(np.mean(np.array(p_chi) < 0.1) - 0.1) < 0.05
    assert abs(np.mean(np.array(p_ecdf) < 0.1) - 0.1) < 0.05


def test_uniformity_tests_reject_a_u_shaped_histogram():
    # Over-confident posterior: truth too often in the tails.
    rng = np.random.default_rng(4)
    L, n = 99, 200
    u = rng.beta(0.6, 0.6, n)
    r = np.minimum((u * (L + 1)).astype(int), L)
    assert sbc.chi2_uniformity(r, L).p_value < 1e-4
    assert sbc.ecdf_uniformity(r, L).p_value < 1e-3


def test_sbc_of_exact_posteriors():
    # Conjugate normal: theta ~ N(0,1), y ~ N(theta, 1) -> posterior N(y/2, 1/2), drawn exactly.
    # Coverage ~ Binomial(n, c)/n: tolerance 4 se per level (8 checks) -> FFR < 0.1 %;
    # uniformity at alpha_family 0.005 per statistic, two statistics -> FFR <= 1 %.
    n, L = 2000, 199
    k1, k2, k3, k4 = jax.random.split(jax.random.key(1), 4)
    theta = jax.random.normal(k1, (n,))
    y = theta + jax.random.normal(k2, (n,))
    draws = y[:, None] / 2 + jnp.sqrt(0.5) * jax.random.normal(k3, (n, L))
    cov = sbc.coverage(np.asarray(draws), np.asarray(theta))
    assert cov.levels == sbc.COVERAGE_LEVELS
    np.testing.assert_allclose(cov.se, np.sqrt(np.array(cov.levels) * (1 - np.array(cov.levels))
                                               / n))
    assert np.all(np.abs(cov.observed - np.array(cov.levels)) < 4 * cov.se)
    res = sbc.sbc_result(["theta"], np.asarray(sbc.ranks(k4, draws, theta))[:, None], L,
                         alpha_family=0.005)
    c = res.parameters["theta"].coverage  # coverage from ranks alone
    assert np.all(np.abs(c.observed - np.array(c.levels)) < 4 * c.se)
    assert res.passed("both")


def test_figures_have_one_panel_per_parameter():
    import matplotlib

    matplotlib.use("Agg")
    rng = np.random.default_rng(5)
    L = 49
    res = sbc.sbc_result(["a", "b", "c", "d"], rng.integers(0, L + 1, (60, 4)), L)
    for fig in (sbc.plot_rank_histograms(res), sbc.plot_ecdf_difference(res)):
        assert sum(ax.get_visible() for ax in fig.axes) == 4


# ------------------------------------------------------------------------ SBC on the toy model


def _campaign(tmp_path, spec, n, seed):
    res = run_campaign(spec, n, tmp_path, seed=seed, batch_size=BATCH)
    names = res.names
    return sbc.sbc_result(names, res.rank, res.n_draws, alpha_family=0.005,
                          draws={nm: res.draws[:, j] for j, nm in enumerate(names)},
                          truth={nm: res.truth[:, j] for j, nm in enumerate(names)}), res


def test_sbc_passes_on_the_toy_model(tmp_path):
    """64 replicates of the correctly specified toy model pass both uniformity statistics.

    Each statistic is tested at alpha_family = 0.005 over the 3 parameters (Bonferroni, 0.0017
    each); two statistics -> FFR <= 1 %. Coverage: within 4 binomial se at every level and
    parameter (12 checks, normal approximation) -> FFR < 0.1 %.
    """
    result, res = _campaign(tmp_path, ModelSpec.make("toy"), 64, seed=11)
    assert res.failed.sum() == 0
    assert res.converged.mean() > 0.9
    assert result.passed("both"), {n: (p.chi2.p_value, p.ecdf.p_value)
                                   for n, p in result.parameters.items()}
    for p in result.parameters.values():
        assert np.all(np.abs(p.coverage.observed - np.array(p.coverage.levels))
                      < 4 * p.coverage.se)


def test_sbc_detects_a_misspecified_likelihood(tmp_path):
    """The likelihood's noise scale is half the data's (simulator noise doubled): SBC fails.

    Same machinery and thresholds as the passing test. sigma's posterior sits near twice the
    truth, so its ranks pile up at 0; the statistics fail by orders of magnitude.
    """
    result, _ = _campaign(tmp_path, ModelSpec.make("toy", simulator_noise_factor=2.0), 32,
                          seed=11)
    p = result.parameters["sigma"]
    assert p.chi2.p_value < 1e-6 and p.ecdf.p_value < result.alpha
    assert np.median(result.ranks[:, 2]) < 0.1 * result.n_draws
    assert p.coverage.observed[-1] < 0.5  # 95 % intervals cover the truth far less than 95 %
    assert not result.passed("chi2") and not result.passed("ecdf")


@pytest.mark.slow
def test_sbc_toy_campaign_200_replicates(tmp_path):
    """256 replicates pass both statistics (FFR <= 1 %) with coverage within 3 se (FFR ~3 %)."""
    result, _ = _campaign(tmp_path, ModelSpec.make("toy"), 256, seed=2026)
    assert result.passed("both")
    for p in result.parameters.values():
        assert np.all(np.abs(p.coverage.observed - np.array(p.coverage.levels))
                      < 3 * p.coverage.se)


@pytest.mark.slow
def test_sbc_detects_halved_likelihood_noise(tmp_path):
    result, _ = _campaign(tmp_path, ModelSpec.make("toy", likelihood_noise_factor=0.5), 64,
                          seed=11)
    assert not result.passed("chi2") and not result.passed("ecdf")


# ------------------------------------------------------------------ SBC of the inertia model
# The inertia adapter compiles the slew simulator and the inertia sampler (about a minute on the
# 2-core machine before any replicate runs), so its campaigns are marked slow.


@pytest.mark.slow
def test_sbc_inertia_small_campaign_passes_and_detects_wrong_wheel_inertia(tmp_path):
    """32 replicates pass; wheel inertias 5 % larger in the simulator than in the model fail.

    Uniformity at alpha_family = 0.005 per statistic over the 6 entries, two statistics ->
    FFR <= 1 %. The mis-specified scale biases every moment by far more than its posterior sd,
    so the truth sits below or above all draws and both statistics fail.
    """
    pytest.importorskip("cassini_bayes.inference.inertia")
    result, res = _campaign(tmp_path / "ok", ModelSpec.make("inertia"), 32, seed=3)
    assert res.failed.sum() == 0
    assert result.passed("both")
    bad, _ = _campaign(tmp_path / "bad", ModelSpec.make("inertia", wheel_inertia_factor=1.05),
                       16, seed=3)
    assert not bad.passed("chi2") and not bad.passed("ecdf")
    assert bad.parameters["Izz"].coverage.observed[-1] < 0.5


@pytest.mark.slow
def test_sbc_inertia_campaign_200_replicates(tmp_path):
    """208 replicates: both statistics pass (FFR <= 1 %), coverage within 3.5 se (24 checks)."""
    pytest.importorskip("cassini_bayes.inference.inertia")
    result, _ = _campaign(tmp_path, ModelSpec.make("inertia"), 208, seed=2026)
    assert result.passed("both")
    for p in result.parameters.values():
        assert np.all(np.abs(p.coverage.observed - np.array(p.coverage.levels))
                      < 3.5 * p.coverage.se)


# ---------------------------------------------------------------------------------- the CLI


def test_cli_writes_the_run_directory(run_cli, tmp_path):
    out = tmp_path / "sbc-toy"
    code, _, stderr = run_cli("sbc", "toy", "--replicates", 20, "--batch", BATCH,
                                   "--out", out, "--seed", 5)
    assert code == 0, stderr
    assert sorted(p.name for p in out.iterdir()) == [".cassini-bayes-files", "config.toml",
                                                     "replicates.npz", "report.html",
                                                     "summary.json"]
    s = json.loads((out / "summary.json").read_text())
    assert s["kind"] == "sbc" and s["model"] == "toy" and s["seed"] == 5
    assert s["replicates"] == 20 and s["failures"] == 0 and "non_converged" in s
    assert set(s["parameters"]) == {"alpha", "beta", "sigma"}
    for p in s["parameters"].values():
        assert 0 <= p["chi2"]["p_value"] <= 1 and 0 < p["ecdf"]["p_value"] <= 1
        assert set(p["coverage"]) == {"50", "80", "90", "95"}
    html = (out / "report.html").read_text()
    assert html.count("data:image/png;base64,") == 2 and "http://" not in html
    headers, rows = first_table(html)      # the answer first: calibrated or not, per parameter
    assert headers[:2] == ["parameter", "unit"] and headers[-1] == "verdict"
    assert "90 % interval coverage" in headers and {r[0] for r in rows} == set(s["parameters"])
    assert not any(p.name.startswith(".") for p in tmp_path.iterdir())  # work dir cleaned up

    code, _, stderr = run_cli("sbc", "toy", "--replicates", 20, "--out", out)
    assert code == 2 and "--force" in stderr and len(stderr.strip().splitlines()) == 1


def test_cli_rejects_unknown_model_and_bad_scenario(run_cli, tmp_path):
    code, _, stderr = run_cli("sbc", "nosuch", "--replicates", 4, "--out", tmp_path / "x")
    assert code == 2 and "toy" in stderr
    bad = tmp_path / "bad.toml"
    bad.write_text("n_obs = 20\nbogus = 1\n")
    code, _, stderr = run_cli("sbc", "toy", "--replicates", 4, "--out", tmp_path / "y",
                              "--scenario", bad)
    assert code == 2 and "bogus" in stderr
    code, _, stderr = run_cli("sbc", "toy", "--replicates", 4, "--out", tmp_path / "z",
                              "--scenario", tmp_path / "missing.toml")
    assert code == 2 and "missing.toml" in stderr
