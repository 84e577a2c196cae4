"""The fit-based experiments: inertia Table 1, thrust Table 2, RWA4 campaigns, error budgets.

Fast tests check the experiment files, the settings checks and the small helpers; one quick run
of the cheapest fit-free experiment (error budgets, thrust only) checks the sections and figures.
Quick runs of every fit-based experiment (each simulates and samples) are ``slow``; the
``reproduce --quick`` and ``experiment --quick`` tests run them too.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from cassini_bayes._paths import EXPERIMENTS_DIR
from cassini_bayes.errors import InputError
from cassini_bayes.experiments import experiment_from_dict, load_experiment, run_experiment

FIT_EXPERIMENTS = ("inertia_table1", "thrust_table2", "rwa4_rcs_campaign", "rwa4_rwa_campaign",
                   "error_budgets")


@pytest.mark.parametrize("name", FIT_EXPERIMENTS)
def test_experiment_files_are_shipped_and_valid(name):
    exp = load_experiment(EXPERIMENTS_DIR / f"{name}.toml")
    assert exp.kind.name == name
    assert exp.kind.quick, "every experiment has a quick mode"
    assert exp.resolved_settings(quick=True) != exp.resolved_settings(quick=False)


@pytest.mark.parametrize("kind, settings, words", [
    ("inertia_table1", {"epochs": ["mars"]}, "unknown epoch"),
    ("inertia_table1", {"draws": 1}, "draws"),
    ("thrust_table2", {"events": []}, "events"),
    ("rwa4_rcs_campaign", {"n_runs": 0}, "n_runs"),
    ("rwa4_rwa_campaign", {"max_from_rwa1_deg": 90.0}, "max_from_rwa1_deg"),
    ("error_budgets", {"calibrations": ["pointing"]}, "unknown calibration"),
    ("error_budgets", {"n_seeds": 0}, "n_seeds"),
])
def test_bad_settings_are_one_line_errors_naming_the_file(kind, settings, words, tmp_path):
    with pytest.raises(InputError) as e:  # at load (framework) or at run (the kind's own check)
        exp = experiment_from_dict({"kind": kind, "settings": settings}, src="bad.toml")
        run_experiment(exp, tmp_path / "out")
    assert words in str(e.value) and "bad.toml" in str(e.value)
    assert "\n" not in str(e.value)
    assert not (tmp_path / "out").exists()


def test_unknown_setting_and_wrong_type_are_rejected():
    with pytest.raises(InputError, match="settings.n_run"):
        experiment_from_dict({"kind": "rwa4_rcs_campaign", "settings": {"n_run": 3}})
    with pytest.raises(InputError, match="settings.scenarios.pointing"):
        experiment_from_dict({"kind": "error_budgets",
                              "settings": {"scenarios": {"pointing": "x"}}})


def test_tau_variance_share_recovers_a_known_split():
    from cassini_bayes.experiments.thrust_table2 import tau_variance_share

    rng = np.random.default_rng(0)
    tau = rng.normal(size=(20000, 3))
    # Var(F) = 0.5² (τ part) + 0.5² (noise): share 0.5, within 0.02 at n = 20000
    f = 0.5 * tau[:, 2] + 0.5 * rng.normal(size=20000)
    assert tau_variance_share(f, tau) == pytest.approx(0.5, abs=0.02)
    assert tau_variance_share(tau[:, 0], tau) == pytest.approx(1.0)
    assert tau_variance_share(np.ones(10), rng.normal(size=(10, 3))) == 0.0


def test_coverage_interval_is_clopper_pearson():
    from cassini_bayes.experiments.rwa4_campaign import coverage_interval

    # reference: scipy.stats.binomtest(9, 10).proportion_ci(method="exact") = (0.5550, 0.9975)
    lo, hi = coverage_interval(9, 10)
    assert lo == pytest.approx(0.5550, abs=1e-4) and hi == pytest.approx(0.9975, abs=1e-4)
    assert coverage_interval(10, 10)[1] == 1.0 and coverage_interval(0, 10)[0] == 0.0


def test_cone_axis_puts_rwa1_at_90_degrees():
    from cassini_bayes.experiments.rwa4_campaign import cone_axis
    from cassini_bayes.spacecraft import load_spacecraft

    rwa1 = load_spacecraft("cassini_pre_soi").wheel("RWA1").axis
    np.testing.assert_allclose(cone_axis(math.pi / 2), rwa1, atol=1e-9)
    assert np.degrees(np.arccos(cone_axis(0.3)[2])) == pytest.approx(54.7356, abs=1e-4)


def test_flight_test_scenario_flies_rwa1_with_rwa2_rwa3():
    from cassini_bayes.experiments.rwa4_campaign import flight_test_scenario

    s = flight_test_scenario("rwa4_rwa")
    on = dict(zip(s.wheel_names, s.wheels_on))
    assert on["RWA1"] and on["RWA2"] and on["RWA3"] and not on["RWA4"]
    np.testing.assert_allclose(s.truth.wheel("RWA1").axis, s.prior.wheel("RWA1").axis)


def test_flight_test_fits_rwa1_without_a_cone(tmp_path):
    """The full campaign's flight test (quick mode skips it): Cassini's RWA1 is a fixed wheel
    without an articulation cone, so its posterior takes the uniform prior, not an error."""
    settings = {"n_runs": 1, "posterior_runs": 1, "chains": 1, "warmup": 30, "draws": 30,
                "flight_test": True, "prior": "cone", "reports": 0}
    exp = experiment_from_dict({"kind": "rwa4_rwa_campaign", "settings": settings},
                               src="flight.toml")
    run_experiment(exp, tmp_path / "out", seed=0)
    ft = json.loads((tmp_path / "out" / "results.json").read_text())["results"]["flight_test"]
    assert ft["prior"] == "uniform"
    assert ft["post_error_deg"] < 5 * ft["cone_deg"]["90"]


@pytest.fixture(scope="module")
def budget_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("budgets") / "error_budgets"
    return run_experiment(EXPERIMENTS_DIR / "error_budgets.toml", out, quick=True, seed=1), out


def test_error_budget_quick_run_has_its_sections_and_figure(budget_run):
    rec, out = budget_run
    results = json.loads((out / "results.json").read_text())
    page = (out / "report.html").read_text()
    assert set(results["results"]) == set(rec.settings["calibrations"]) | {"from_posteriors"}
    # run alone (no fits beside it) the budgets from posteriors keep the papers' values
    assert results["results"]["from_posteriors"]["sources"] == {}
    assert "Budgets from posteriors, beside the papers" in page
    assert page.count("data:image/png;base64,") == len(results["figures"]) == 1
    for cal in rec.settings["calibrations"]:
        assert "error budget" in page
        b = results["results"][cal]
        assert b["rss"] >= max(v["rms"] for v in b["lines"].values())
        assert "sampling" in b["lines"] and "rate noise" in b["lines"]


def test_error_budget_numbers_are_sane(budget_run):
    rec, _ = budget_run
    s = rec.output.summary
    if "thrust" in s:
        t = s["thrust"]
        # attitude noise does not enter the thrust regression at all (rates and wheels only)
        assert t["lines"]["attitude noise"]["rms"] <= t["lines"]["sampling"]["rms"] * 1.01 + 1e-9
        # the pulse time constants dominate the thrust budget, as the paper says
        assert t["lines"]["pulse time constants"]["rms"] > t["lines"]["rate noise"]["rms"]
        # τ drawn over the manufacturer's ranges moves the τ-adjusted thrust by ~10 % (the
        # paper's budget): between 1 % and 30 % for any two keys
        assert 1.0 < t["rss"] < 30.0
    if "rwa4_rcs" in s:
        assert s["rwa4_rcs"]["rss"] < 3.0


@pytest.mark.slow
@pytest.mark.parametrize("name", FIT_EXPERIMENTS[:4])
def test_fit_experiments_quick_runs(name, tmp_path):
    rec = run_experiment(EXPERIMENTS_DIR / f"{name}.toml", tmp_path / name, quick=True, seed=2)
    results = json.loads((tmp_path / name / "results.json").read_text())
    page = (tmp_path / name / "report.html").read_text()
    assert page.count("data:image/png;base64,") == len(results["figures"]) >= 1
    for link in results["links"]:
        assert (tmp_path / name / link["path"]).exists()
        run_dir = (tmp_path / name / link["path"]).parent
        summary = json.loads((run_dir / "summary.json").read_text())
        assert (run_dir / "posterior.nc").exists() and (run_dir / "config.toml").exists()
        assert summary["kind"] in ("inertia", "thrust", "rwa4")
    s = rec.output.summary
    if name == "inertia_table1":
        for epoch in rec.settings["epochs"]:
            # posterior mean within 1 % of the truth on every moment, even with few draws
            assert np.max(np.abs(s[epoch]["errors_posterior_vs_truth"][:3])) < 1.0
    elif name == "thrust_table2":
        assert abs(s["pooled"]["thrust_mean_n"] / 0.699 - 1) < 0.10
    else:  # least squares on every run (quick mode skips the costly posteriors)
        budget = 3.0 if name == "rwa4_rcs_campaign" else 1.0
        assert max(r["ls_error_deg"] for r in s["runs"]) < budget
