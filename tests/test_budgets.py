"""Budgets propagated from posteriors: the propagation, each line's physics, Lee's and Brown's
numbers, the ``budget`` command and the experiments' posterior inputs."""

from __future__ import annotations

import csv
import json
import math
import re
from pathlib import Path

import jax
import numpy as np
import pytest

from cassini_bayes.analysis import budget_lines as bl
from cassini_bayes.analysis.mass_property import (
    RWA1_PHI_RAD,
    axis_on_cone,
    mass_property_mc_posterior,
)
from cassini_bayes.analysis.paper_facts import LEE_POINTING_TABLE2, TABLE1
from cassini_bayes.analysis.posterior_budgets import (
    DEFAULT_MANEUVER,
    LEE_CONTROL_LINE,
    Posterior,
    budget_csv,
    load_posterior,
    posterior_budget,
)
from cassini_bayes.analysis.propagation import credible_interval, propagate
from cassini_bayes.errors import InputError
from cassini_bayes.names import INERTIA_NAMES, U4_NAMES
from pages import first_table

Z90 = 1.6448536269514722  # standard-normal 95th percentile
EST = np.asarray(TABLE1["post_probe"]["est"], float)


# --- propagation -------------------------------------------------------------------------------


def test_a_linear_line_of_gaussians_gives_the_analytic_interval_and_shares():
    rng = np.random.default_rng(0)
    n = 400_000
    draws = {"x": rng.normal(1.0, 2.0, n), "y": rng.normal(-1.0, 1.0, n)}
    values, iv = propagate(lambda d: 3.0 * d["x"] - 2.0 * d["y"] + 1.0, draws)
    mean, sd = 6.0, math.sqrt(9 * 4 + 4 * 1)  # analytic: N(6, 40)
    assert values.shape == (n,)
    assert iv.median == pytest.approx(mean, abs=0.03)
    assert iv.low == pytest.approx(mean - Z90 * sd, abs=0.05)
    assert iv.high == pytest.approx(mean + Z90 * sd, abs=0.05)
    assert iv.shares["x"] == pytest.approx(36 / 40, abs=0.005)
    assert iv.shares["y"] == pytest.approx(4 / 40, abs=0.005)
    assert iv.share_sum == pytest.approx(1.0, abs=0.005)
    assert iv.level == 0.9 and iv.n_draws == n


def test_a_line_of_one_parameter_is_all_that_parameter():
    rng = np.random.default_rng(1)
    draws = {"a": rng.normal(size=5000), "b": rng.normal(size=5000),
             "v": rng.normal(size=(5000, 3))}
    _, iv = propagate(lambda d: np.exp(d["a"]) + 0.0 * d["b"], draws)
    assert iv.shares == {"a": 1.0, "b": 0.0, "v": 0.0} and iv.share_sum == 1.0
    _, iv = propagate(lambda d: np.linalg.norm(d["v"], axis=-1), draws)
    assert iv.shares["v"] == pytest.approx(1.0) and iv.shares["a"] == 0.0


def test_a_constant_line_has_no_shares_and_a_point_interval():
    _, iv = propagate(lambda d: np.full(d["a"].shape, 2.5), {"a": np.arange(20.0)})
    assert (iv.median, iv.low, iv.high) == (2.5, 2.5, 2.5)
    assert iv.shares == {"a": 0.0}


def test_credible_interval_levels():
    med, lo, hi = credible_interval(np.arange(101.0), 0.5)
    assert (med, lo, hi) == (50.0, 25.0, 75.0)
    with pytest.raises(ValueError):
        credible_interval([1.0], 1.0)
    with pytest.raises(ValueError, match="same number of draws"):
        propagate(lambda d: d["a"], {"a": np.ones(3), "b": np.ones(4)})


# --- the physics of the lines ------------------------------------------------------------------


def _inertia_draws(values):
    v = np.atleast_2d(np.asarray(values, float))
    return {k: v[:, i] for i, k in enumerate(INERTIA_NAMES)}


def test_inertia_line_is_feldman_lee_eq12_worst_moment():
    truth = EST.copy()
    truth[1] *= 1.02  # Iyy 2 % above the estimate: |Î − I| / I = 0.02 / 1.02
    out = bl.inertia_worst_moment_pct(_inertia_draws(truth), EST)
    assert out == pytest.approx([100 * 0.02 / 1.02])


def test_thrust_and_tau_lines():
    assert bl.thrust_error_pct({"F": np.array([0.7, 0.77])}, 0.7) == pytest.approx([0.0, 100 / 11])
    tau = np.array([0.005, 0.020, 0.065])
    same = {n: np.array([t]) for n, t in zip(("tau_delay", "tau_rise", "tau_fall"), tau)}
    assert bl.tau_thrust_error_pct(same, tau, [0.125]) == pytest.approx([0.0], abs=1e-12)
    # Feldman & Lee §V: R(125 ms) is 1.395 with τf = 65 ms and 1.195 with 40 ms (1.39462 and
    # 1.19501 unrounded): believing 65 ms when the truth is 40 ms overstates the impulse
    other = dict(same, tau_fall=np.array([0.040]))
    assert bl.tau_thrust_error_pct(other, tau, [0.125]) == pytest.approx(
        [100 * (1 - 1.19501 / 1.39462)], abs=1e-3)


def test_axis_line_measures_the_angle():
    e = np.array([0.0, 0.0, 1.0])
    a = np.radians(1.0)
    u = np.array([[np.sin(a), 0.0, np.cos(a)], [0.0, 0.0, 2.0]])
    assert bl.axis_error_deg({"u4": u}, e) == pytest.approx([1.0, 0.0], abs=1e-9)


def test_mass_property_line_is_zero_for_the_believed_inertia_and_grows_with_the_error():
    d = _inertia_draws(np.stack([EST, EST * np.array([1.05, 1, 1, 1, 1, 1])]))
    out = bl.rcs_mass_property_deg(d, EST, np.asarray(axis_on_cone(RWA1_PHI_RAD)))
    assert out[0] == pytest.approx(0.0, abs=1e-9) and out[1] > 0.01


def test_control_line_quasi_static_error_is_analytic():
    # no rate, no wheel momentum, inertia error only: θ = I⁻¹ (Î − I) α / ω_n²
    alpha = np.array([1e-4, -2e-4, 3e-4])
    m = DEFAULT_MANEUVER._replace(rate_rad_s=np.zeros(3), accel_rad_s2=alpha,
                                  wheel_momentum_nms=np.zeros(3), bandwidth_rad_s=0.2)
    truth = EST + np.array([30.0, -20.0, 10.0, 5.0, -4.0, 3.0])
    out = bl.rwa_control_error_mrad(_inertia_draws(truth), EST, np.asarray(
        axis_on_cone(RWA1_PHI_RAD)), m)
    i_true, i_hat = bl.inertia_of(truth), bl.inertia_of(EST)
    want = 1e3 * np.linalg.solve(i_true, (i_hat - i_true) @ alpha) / 0.04
    np.testing.assert_allclose(out[0], want, rtol=1e-10)
    # perfect knowledge: no error, and the maneuver's axes are not modified
    axes = m.wheel_axes.copy()
    zero = bl.rwa_control_error_mrad(_inertia_draws(EST), EST, [0.0, 0.0, 1.0], m)
    np.testing.assert_allclose(zero, 0.0, atol=1e-15)
    np.testing.assert_array_equal(m.wheel_axes, axes)


# --- the papers' numbers still reproduce -------------------------------------------------------


def _rows(budget, name):
    return [r for r in budget.rows if r.line == name]


def test_lee_table2_without_posteriors_keeps_the_papers_values():
    b = posterior_budget(jax.random.key(0))
    rss = _rows(b, "root-sum-square")
    assert [round(r.value, 3) for r in rss] == [1.186, 0.244]  # Lee Table 2 entries, RSS
    assert [r.paper for r in rss] == ["1.18 mrad", "0.23 mrad"]
    kept = [r for r in b.rows if r.interval is None]
    assert len(kept) == 2 * len(LEE_POINTING_TABLE2) + 2
    control = _rows(b, LEE_CONTROL_LINE)
    assert [r.value for r in control] == [0.04, 0.04]


def _posterior(kind, draws, method=None):
    return Posterior(kind, f"<{kind}>", draws, method)


def _fake(n=400, spread=1.0, seed=0):
    rng = np.random.default_rng(seed)
    inertia = _posterior("inertia", {k: EST[i] + spread * rng.normal(size=n)
                                     for i, k in enumerate(INERTIA_NAMES)})
    thrust = _posterior("thrust", {"F": 0.699 + 0.01 * spread * rng.normal(size=n),
                                   "tau_delay": 0.005 + 1e-4 * spread * rng.normal(size=n),
                                   "tau_rise": 0.020 + 1e-3 * spread * rng.normal(size=n),
                                   "tau_fall": 0.065 + 1e-3 * spread * rng.normal(size=n)})
    u = np.asarray(axis_on_cone(RWA1_PHI_RAD)) + 0.01 * spread * rng.normal(size=(n, 3))
    rwa4 = _posterior("rwa4", {"u4": u}, "rcs")
    return inertia, thrust, rwa4


def test_exact_knowledge_leaves_lee_rss_and_brown_line_at_the_papers():
    inertia, thrust, rwa4 = _fake(spread=0.0)
    b = posterior_budget(jax.random.key(1), inertia=inertia, thrust=thrust, rwa4=rwa4,
                         n_draws=50)
    for r in _rows(b, "root-sum-square"):
        assert r.interval.median == pytest.approx(1.186 if "X" in r.budget else 0.244, abs=5e-4)
    brown = _rows(b, "extra RCS-method error (Brown Eq 1)")[0].interval
    assert brown.high == pytest.approx(0.0, abs=1e-9)


def test_every_calibrated_line_has_an_interval_and_attribution():
    inertia, thrust, rwa4 = _fake()
    b = posterior_budget(jax.random.key(2), inertia=inertia, thrust=thrust, rwa4=rwa4,
                         n_draws=300)
    with_interval = [r for r in b.rows if r.interval is not None]
    assert {r.budget for r in with_interval} >= {"inertia", "thrust", "rwa4 (rcs)",
                                                 "rwa4 mass properties"}
    for r in with_interval:
        assert r.interval.low <= r.interval.median <= r.interval.high
        assert set(r.interval.shares) and r.interval.n_draws == 300
    thrust_line = _rows(b, "thrust knowledge")[0].interval
    assert thrust_line.shares == {"F": 1.0}
    axis_line = _rows(b, "RWA4 axis knowledge")[0].interval
    assert axis_line.shares == {"u4": 1.0}
    # same key, same numbers; another key, other resampling
    again = posterior_budget(jax.random.key(2), inertia=inertia, thrust=thrust, rwa4=rwa4,
                             n_draws=300)
    assert again.to_dict() == b.to_dict()
    rows = list(csv.DictReader(budget_csv(b).splitlines()))
    assert len(rows) == len(b.rows) and rows[0]["budget"] == "inertia"


def test_a_posterior_of_the_wrong_kind_is_refused():
    inertia, thrust, _ = _fake()
    with pytest.raises(InputError, match="thrust posterior given as the inertia"):
        posterior_budget(jax.random.key(0), inertia=thrust)


def test_brown_monte_carlo_from_a_posterior():
    i_hat = bl.inertia_of(EST)
    same = np.broadcast_to(i_hat, (10, 3, 3))
    d = mass_property_mc_posterior(jax.random.key(0), same, i_hat, 1000,
                                   phi_range_rad=(-0.5, 3.6))
    assert np.max(np.asarray(d.error_rad)) < 1e-9 and d.phi_rad.shape == (1000,)
    wide = i_hat + np.random.default_rng(0).normal(0, 50, (200, 3, 3))
    wide = 0.5 * (wide + np.swapaxes(wide, 1, 2))
    d = mass_property_mc_posterior(jax.random.key(0), wide, i_hat, 1000)
    assert 0.01 < np.degrees(np.percentile(np.asarray(d.error_rad), 99)) < 5


# --- run directories, the command and the experiments ------------------------------------------


def _write_run(path: Path, draws: dict, config: str = "") -> Path:
    import arviz as az

    path.mkdir(parents=True)
    az.from_dict(posterior={k: np.asarray(v).reshape(2, -1) for k, v in draws.items()}
                 ).to_netcdf(str(path / "posterior.nc"))
    if config:
        (path / "config.toml").write_text(config)
    return path


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("runs")
    inertia, thrust, rwa4 = _fake(n=200)
    u = rwa4.draws["u4"]
    return {
        "inertia": _write_run(root / "inertia", inertia.draws),
        "thrust": _write_run(root / "thrust", thrust.draws),
        "rwa4": _write_run(root / "rwa4", {n: u[:, i] for i, n in enumerate(U4_NAMES)},
                           '[options]\nmethod = "rwa"\n'),
    }


def test_load_posterior_reads_a_run_directory(runs):
    p = load_posterior(runs["rwa4"], "rwa4", option="--rwa4")
    assert p.method == "rwa" and p.draws["u4"].shape == (200, 3)
    assert set(load_posterior(runs["thrust"], "thrust").draws) == {
        "F", "tau_delay", "tau_rise", "tau_fall"}


def test_budget_command_end_to_end(runs, tmp_path, run_cli):
    out = tmp_path / "budget"
    code, stdout, err = run_cli("budget", "--inertia", runs["inertia"], "--thrust", runs["thrust"],
                                "--rwa4", runs["rwa4"], "--out", out, "--draws", 200)
    assert code == 0, err
    assert stdout.strip() == str(out / "report.html")
    assert {p.name for p in out.iterdir()} == {"summary.json", "budget.csv", "report.html",
                                               "config.toml", ".cassini-bayes-files"}
    s = json.loads((out / "summary.json").read_text())
    assert s["command"] == "budget" and s["n_draws"] == 200
    assert set(s["adequacy"]["checks"]) == {"input_convergence", "input_adequacy",
                                            "spacecraft_models", "shared_inertia"}
    assert set(s["sources"]) == {"inertia", "thrust", "rwa4"}
    budgets = {r["budget"] for r in s["rows"] if r["interval"]}
    assert {"inertia", "thrust", "rwa4 (rwa)", "rwa4 mass properties"} <= budgets
    page = (out / "report.html").read_text()
    assert "root-sum-square" in page and "1.18 mrad" in page
    # a pass/fail column against the papers' budgets; shares as percentages
    headers, rows = first_table(page)
    assert "verdict" in headers and "variance share, each parameter alone" in headers
    judged = {r[1].split("posterior:")[0].strip(): r[headers.index("verdict")] for r in rows
              if r[headers.index("verdict")] in ("pass", "FAIL")}
    assert {"thrust knowledge", "RWA4 axis knowledge"} <= set(judged)
    shares = [r[headers.index("variance share, each parameter alone")] for r in rows]
    assert any(re.search(r"\bF 100 %", x) for x in shares)
    # an existing --out is refused, --force replaces it
    code, _, err = run_cli("budget", "--thrust", runs["thrust"], "--out", out)
    assert code == 2 and "--force" in err
    code, _, err = run_cli("budget", "--thrust", runs["thrust"], "--out", out, "--force")
    assert code == 0, err
    assert set(json.loads((out / "summary.json").read_text())["sources"]) == {"thrust"}


def test_budget_verdict_warns_and_strict_exits_3(runs, tmp_path, run_cli):
    """An input run that did not converge fails the budget's verdict: a warning and
    ``ADEQUACY FAILED`` on the result line, exit 0; with ``--strict`` exit 3 after writing."""
    import shutil

    bad = tmp_path / "thrust_unconverged"
    shutil.copytree(runs["thrust"], bad)
    (bad / "summary.json").write_text(json.dumps({"kind": "thrust", "diagnostics": {
        "converged": False, "max_r_hat": 1.2, "min_ess_bulk": 40.0, "divergences": 3}}))
    code, _, err = run_cli("budget", "--thrust", bad, "--out", tmp_path / "b1", "--draws", 200)
    assert code == 0 and "ADEQUACY FAILED: input_convergence" in err and "warning:" in err, err
    s = json.loads((tmp_path / "b1" / "summary.json").read_text())
    assert s["adequacy"]["ok"] is False and s["warnings"]
    assert "ADEQUACY FAILED" in (tmp_path / "b1" / "report.html").read_text()
    code, _, err = run_cli("budget", "--thrust", bad, "--out", tmp_path / "b2", "--draws", 200,
                           "--strict")
    assert code == 3 and (tmp_path / "b2" / "summary.json").is_file(), err
    code, _, err = run_cli("budget", "--thrust", runs["thrust"], "--out", tmp_path / "b3",
                           "--draws", 200, "--strict")
    assert code == 0 and "adequacy ok" in err, err


def test_library_budget_is_what_the_command_writes(runs, tmp_path, run_cli):
    """``cassini_bayes.budget`` gives the command's summary; its errors name arguments."""
    import cassini_bayes as cb

    code, _, err = run_cli("budget", "--thrust", runs["thrust"], "--out", tmp_path / "cli",
                           "--draws", 200)
    assert code == 0, err
    res = cb.budget(thrust=runs["thrust"], n_draws=200)
    cli = json.loads((tmp_path / "cli" / "summary.json").read_text())
    api = json.loads((res.save(tmp_path / "api") / "summary.json").read_text())
    # the sources name the run as its caller spelled it: "--thrust RUN" or "thrust RUN"
    assert cli.pop("sources") == {"thrust": f"--thrust {runs['thrust']}"}
    assert api.pop("sources") == {"thrust": f"thrust {runs['thrust']}"}
    assert cli == api
    with pytest.raises(InputError, match="n_draws"):
        cb.budget(thrust=runs["thrust"], n_draws=3)


def _fit_result(run: Path, kind: str, method: str | None = None):
    """A :class:`~cassini_bayes.api.FitResult` (unsaved) holding ``run``'s draws."""
    from types import SimpleNamespace

    import arviz as az

    from cassini_bayes.api import FitResult

    config = {"command": f"fit {kind}", "seed": 7, "inputs": {"telemetry": [{"source": "x"}]},
              "options": {"method": method} if method else {}, "spacecraft": {"name": "m"}}
    summary = {"kind": kind, "diagnostics": {"converged": True}, "warnings": []}
    return FitResult(kind, SimpleNamespace(idata=az.from_netcdf(run / "posterior.nc")), None,
                     None, config, summary)


def test_budget_takes_fit_results(runs, tmp_path):
    """Issue 28: ``fit_thrust`` took an inertia fit's FitResult but ``budget`` refused one;
    ``budget`` takes FitResults as it takes run directories — the same lines from the same
    draws — records how to redo them in config.toml, and refuses one of another kind (a thrust
    fit carries inertia draws too: never taken as the inertia posterior)."""
    import cassini_bayes as cb

    fits = {k: _fit_result(runs[k], k, "rwa" if k == "rwa4" else None) for k in runs}
    by_dir = cb.budget(**runs, n_draws=200, seed=3)
    by_fit = cb.budget(**fits, n_draws=200, seed=3)
    assert by_fit.summary()["rows"] == by_dir.summary()["rows"]
    assert by_fit.config["inputs"]["thrust"] == {"command": "fit thrust", "seed": 7,
                                                 "inputs": {"telemetry": [{"source": "x"}]}}
    out = by_fit.save(tmp_path / "b")
    assert "&lt;fit thrust result, seed 7&gt;" in (out / "report.html").read_text()
    with pytest.raises(InputError, match=r"^inertia: a thrust fit; give an inertia fit's"):
        cb.budget(inertia=fits["thrust"])
    with pytest.raises(InputError, match=r"rwa4: give a FitResult or a run directory, not int"):
        cb.budget(rwa4=3)


@pytest.mark.parametrize("args, words", [
    ((), "give at least one run directory"),
    (("--inertia", "{thrust}"), "--inertia"),
    (("--rwa4", "{missing}"), "--rwa4"),
    (("--thrust", "{empty}"), "no posterior.nc"),
    (("--thrust", "{thrust}", "--draws", "3"), "--draws"),
])
def test_bad_budget_input_is_one_line(runs, tmp_path, run_cli, args, words):
    (tmp_path / "empty").mkdir()
    paths = {"thrust": runs["thrust"], "missing": tmp_path / "nope", "empty": tmp_path / "empty"}
    args = [a.format(**paths) for a in args]
    code, _, err = run_cli("budget", *args, "--out", tmp_path / "out")
    assert code == 2
    lines = [ln for ln in err.strip().splitlines() if ln.startswith("error:")]
    assert len(lines) == 1 and words in lines[0], err
    assert "Traceback" not in err and not (tmp_path / "out").exists()


class _Ctx:
    def __init__(self, workdir):
        self.workdir = workdir
        self.source = "experiments/x.toml"

    def error(self, message):
        return InputError(message, path=self.source)


def test_experiments_find_the_fits_of_the_same_reproduce_run(runs, tmp_path):
    import shutil

    from cassini_bayes.experiments._posteriors import AUTO_RUNS, find_posterior

    ctx = _Ctx(tmp_path / "error_budgets")
    assert find_posterior("auto", "inertia", "posteriors.inertia", ctx) is None  # no sibling
    assert find_posterior("", "inertia", "posteriors.inertia", ctx) is None
    shutil.copytree(runs["inertia"], tmp_path / AUTO_RUNS["inertia"][0])
    found = find_posterior("auto", "inertia", "posteriors.inertia", ctx)
    assert found.kind == "inertia" and found.draws["Ixx"].shape == (200,)
    assert found.source == "../inertia_table1/fits/post_probe"
    with pytest.raises(InputError, match=r"experiments/x.toml: settings.posteriors.thrust"):
        find_posterior(str(tmp_path / "nope"), "thrust", "posteriors.thrust", ctx)
    rwa = find_posterior(str(runs["inertia"].parent / "rwa4"), "rwa4_rcs", "p", ctx)
    assert rwa.method == "rwa"  # the run's own record wins over the setting's name


def test_error_budgets_posterior_section(runs):
    from cassini_bayes.experiments.error_budgets import _from_posteriors

    post = {"inertia": load_posterior(runs["inertia"], "inertia"),
            "thrust": load_posterior(runs["thrust"], "thrust"),
            "rwa4_rcs": None, "rwa4_rwa": load_posterior(runs["rwa4"], "rwa4")}
    checks, table, summary, note = _from_posteriors(jax.random.key(0), post, 200)
    ids = {c.fact_id for c in checks}
    assert {"inertia_accuracy_pct", "thrust_accuracy_pct", "rwa4_rwa_expected_deg",
            "rwa4_mass_property_deg", "lee_pointing_rss_x_mrad",
            "lee_pointing_rss_z_mrad"} <= ids
    lee = [c for c in checks if c.fact_id.startswith("lee_")]
    assert all(c.passed is None and c.paper for c in lee)
    assert table.columns[2] == "paper" and len(table.rows) == len(summary["rows"])
    # with no posterior at all: the papers' values, Lee's RSS from its own entries
    checks, table, summary, _ = _from_posteriors(
        jax.random.key(0), dict.fromkeys(post), 200)
    assert [round(c.ours, 3) for c in checks] == [1.186, 0.244]


def test_thrust_mass_property_line_is_linear_in_the_inertia_error():
    sens = np.array([1e-5, 2e-5, -3e-5, 0.0, 1e-4, 0.0])
    truth = EST + np.array([10.0, -5.0, 2.0, 7.0, -1.0, 3.0])
    out = bl.thrust_mass_property_pct(_inertia_draws(truth), EST, sens)
    assert out == pytest.approx([abs((EST - truth) @ sens)])


def test_thrust_sensitivity_to_the_assumed_inertia_is_exact():
    """The least-squares thrust (Feldman & Lee Eq 23) is linear in the assumed inertia: the
    one-difference sensitivity predicts a large perturbation to rounding."""
    from cassini_bayes.estimators.baseline import fit_thrust_baseline
    from cassini_bayes.experiments.error_budgets import thrust_inertia_sensitivity
    from cassini_bayes.simulate import load_scenario, simulate, truth_params

    key = jax.random.key(0)
    sens = thrust_inertia_sensitivity(key, "biasing_day028")
    sc = load_scenario("biasing_day028")
    sim, tp = simulate(key, sc), truth_params(sc)
    p = sc.prior.pulse
    entries = np.asarray(tp.inertia, float)
    f_true = float(np.mean(np.asarray(tp.thrust_n)))

    def thrust(e):
        return float(fit_thrust_baseline(sim.truth, sc.prior, sim.pulses, inertia=bl.inertia_of(e),
                                         tau=(p.tau_delay, p.tau_rise, p.tau_fall)).estimate[0])

    step = np.array([300.0, -200.0, 100.0, 50.0, -40.0, 30.0])
    change = 100 * (thrust(entries + step) - thrust(entries)) / f_true
    assert change == pytest.approx(step @ sens, rel=1e-6)


def test_runs_of_different_spacecraft_models_fail_the_verdict(tmp_path):
    """The budget's verdict fails (spacecraft_models) when its runs were fitted with different
    spacecraft models, and names them."""
    from cassini_bayes.analysis.budget_adequacy import run_models, spacecraft_models

    runs = {}
    for kind, model in (("inertia", "fsds"), ("thrust", "cassini-post-probe")):
        runs[kind] = tmp_path / kind
        runs[kind].mkdir()
        (runs[kind] / "config.toml").write_text(f'[spacecraft]\nname = "{model}"\n')
    c = spacecraft_models(run_models(runs))
    assert not c.ok and c.statistic == 2 and "inertia: fsds, thrust: cassini-post-probe" in c.note
    assert spacecraft_models(run_models({"inertia": runs["inertia"]})).ok


def test_input_runs_that_did_not_converge_or_fit_fail_the_verdict(tmp_path):
    """A budget inherits its inputs' problems: a run whose summary.json says it did not converge,
    or failed its adequacy checks, fails input_convergence or input_adequacy (a warning in the
    CLI, summary.json and the report); a clean or unreadable summary counts for nothing."""
    from cassini_bayes.analysis.budget_adequacy import (input_adequacy, input_convergence,
                                                        run_summaries)

    summaries = {
        "thrust": {"diagnostics": {"converged": False, "max_r_hat": 1.0104661,
                                   "min_ess_bulk": 487.9, "divergences": 0}},
        "rwa4": {"diagnostics": {"converged": True},
                 "adequacy": {"ok": False, "checks": {"balance_fit": {"ok": False},
                                                      "held_out": {"ok": True}}}},
        "inertia": {"diagnostics": {"converged": True}, "adequacy": {"ok": True}},
    }
    runs = {}
    for kind, summary in summaries.items():
        runs[kind] = tmp_path / kind
        runs[kind].mkdir()
        (runs[kind] / "summary.json").write_text(json.dumps(summary))
    runs["bad"] = tmp_path / "bad"
    runs["bad"].mkdir()
    (runs["bad"] / "summary.json").write_text("{not json")
    read = run_summaries(runs)
    conv, adeq = input_convergence(read, runs), input_adequacy(read, runs)
    assert (conv.statistic, conv.ok, conv.parameter) == (1.0, False, "thrust")
    assert "did not converge (max R-hat 1.0105, min bulk ESS 488, 0 divergences)" in conv.note
    assert (adeq.statistic, adeq.ok, adeq.parameter) == (1.0, False, "rwa4")
    assert "failed its adequacy checks (balance_fit)" in adeq.note
    assert "no adequacy verdict in the thrust, bad run(s)" in adeq.note
    del runs["thrust"], runs["rwa4"]
    read = run_summaries(runs)
    assert input_convergence(read, runs).ok and input_adequacy(read, runs).ok


def test_runs_that_disagree_on_the_inertia_fail_shared_inertia():
    """shared_inertia: two runs' inertia draws from one law pass (fixed key: z 0.0 here); a
    shift of 6 combined sd in Iyy fails it and is named; one run is not applicable. Under the
    null the statistic exceeds 4 with probability 6e-5 (Bonferroni over the 6 entries)."""
    from cassini_bayes.analysis.budget_adequacy import shared_inertia

    rng = np.random.default_rng(4)
    mean = np.array([7400.0, 6170.0, 3730.0, -130.0, -12.0, 147.0])
    sd = np.array([8.0, 7.0, 5.0, 3.0, 3.0, 3.0])
    a = mean + sd * rng.standard_normal((4000, 6))
    b = mean + 2 * sd * rng.standard_normal((4000, 6))
    assert shared_inertia({"inertia": a, "thrust": b}).ok
    shifted = b + np.array([0.0, 6 * np.hypot(7.0, 14.0), 0, 0, 0, 0])
    c = shared_inertia({"inertia": a, "thrust": shifted})
    assert not c.ok and c.statistic > 4.0 and c.parameter.startswith("Iyy")
    assert shared_inertia({"inertia": a}).statistic is None
