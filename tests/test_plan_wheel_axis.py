"""Planning a wheel-axis calibration (RWA method): the prediction is the fit's own Laplace
approximation, planned manoeuvres stay within their limits on the simulated telemetry, the
commands (docs/planning.md)."""

from __future__ import annotations

import copy
import json
import tomllib

import jax
import numpy as np
import pytest

from cassini_bayes.errors import InputError
from cassini_bayes.plan import checks
from cassini_bayes.plan.limits import limits_path, load_limits
from cassini_bayes.simulate import scenario_from_dict, simulate
from cassini_bayes.simulate.open_world import base_scenario

ESPA = "models/espa_bus.toml"


def _short_espa() -> dict:
    """``wheel_axis_espa_bus`` cut to its first two slew pairs (1200 s): fast, two window
    pairs (Z, X)."""
    d = copy.deepcopy(base_scenario("wheel_axis_espa_bus"))
    d["run"]["duration_s"] = 1200.0
    d["slew"] = d["slew"][:4]
    d["name"] = "wheel_axis_espa_short"
    return d


def _short_limits(tmp_path) -> str:
    d = tomllib.loads(limits_path("wheel_axis_espa_bus").read_text())
    d["limits"]["duration_s"] = 1200.0
    p = tmp_path / "short_limits.toml"
    import tomli_w

    p.write_text(tomli_w.dumps(d))
    return str(p)


def test_prediction_equals_the_fits_laplace_sd():
    """On the same noisy telemetry and noise levels, the prediction's covariance is the fit's
    own Laplace approximation (prepare_rwa4's mode and whitening): JAX's exact Hessian against
    the fit's differenced one, so to 1e-4 and not to rounding; its direction sd is the fit's
    ``sd_direction_deg``."""
    from cassini_bayes.inference.rwa4 import prepare_rwa4
    from cassini_bayes.plan.wheel_axis import predict_axis

    s = scenario_from_dict(_short_espa())
    tel = simulate(jax.random.key(3), s).telemetry
    prob = prepare_rwa4(tel, s.prior, method="rwa", wheel="RW2")
    assert np.asarray(prob.data.n_s).shape[0] == 2 * len(prob.pairs)     # the slope rows
    lap = predict_axis(prob, prob.noise_hat)
    tril = np.asarray(prob.data.tril)
    fit_cov = tril @ tril.T
    np.testing.assert_allclose(np.sqrt(np.diag(lap.cov)), np.sqrt(np.diag(fit_cov)), rtol=1e-4)
    np.testing.assert_allclose(lap.centre, np.asarray(prob.data.centre), atol=1e-6)
    sd_dir = np.degrees(np.sqrt(np.linalg.eigvalsh(lap.tangent_cov)[-1]))
    assert sd_dir == pytest.approx(prob.sd_direction_deg, rel=1e-3)


def test_evaluate_predicts_every_site_of_the_fit():
    """``evaluate_wheel_axis`` on the noise-free flight: the solved wheel found from the truth,
    every posterior site (axis components, inertia) below its prior sd, the axis near the true
    one, the cones ordered."""
    from cassini_bayes.plan.wheel_axis import AXIS_SITES, evaluate_wheel_axis

    s = scenario_from_dict(_short_espa())
    p = evaluate_wheel_axis(s)
    assert p.wheel == "RW2" and p.sites == AXIS_SITES and len(p.pairs) == 2
    assert np.all(p.site_sd > 0) and np.all(p.site_sd < p.site_prior_sd)
    assert p.site_sd[0] < 0.05 * p.site_prior_sd[0]          # the axis is what the data inform
    err = np.degrees(np.arccos(np.clip(p.axis @ p.true_axis, -1, 1)))
    assert err < 0.2 * p.sd_direction_deg        # noise-free: the mode is the truth
    c = p.cone_deg
    assert 0 < c["50"] < c["90"] < c["95"] and p.sd_direction_deg < c["90"]


def test_the_prediction_carries_the_window_slopes():
    """``evaluate_wheel_axis`` predicts the fit with its quiet windows' momentum slopes (the RWA
    method's torque measurement): its covariance is the Laplace approximation of the fit's
    preparation of the noise-free flight, slope rows included, and the same problem with the
    slope rows removed (the means alone, where the torques limit the bus) predicts a cone
    several times wider: the failing case of a prediction that skipped them."""
    from cassini_bayes.inference.rwa4 import prepare_rwa4
    from cassini_bayes.plan.wheel_axis import (evaluate_wheel_axis, noise_free_telemetry,
                                               predict_axis, scenario_noise)

    s = scenario_from_dict(_short_espa())
    p = evaluate_wheel_axis(s, "RW2")
    _, tel = noise_free_telemetry(s)
    prob = prepare_rwa4(tel, s.prior, method="rwa", pairs=p.pairs, wheel="RW2")
    d = prob.data
    assert np.asarray(d.n_s).shape[0] == 2 * len(p.pairs)
    lap = predict_axis(prob, scenario_noise(s))
    np.testing.assert_allclose(lap.tangent_cov, p.tangent_cov, rtol=1e-6, atol=1e-18)
    means_only = prob._replace(data=d._replace(
        m_pi_s=d.m_pi_s[:0], r_u_s=d.r_u_s[:0], k_h_s=d.k_h_s[:0], n_s=d.n_s[:0],
        t_aa_s=d.t_aa_s[:0], nu_cols_s=d.nu_cols_s[:0], nu_pi_s=d.nu_pi_s[:0]))
    wide = predict_axis(means_only, scenario_noise(s))
    ratio = np.sqrt(np.trace(wide.tangent_cov) / np.trace(lap.tangent_cov))
    assert ratio > 3.0, ratio


def test_one_slew_pair_is_refused_and_unknown_wheels_are_one_line_errors():
    """The API's arguments: one pair cannot see the axis along its slew axis; a wheel that is
    not running; a wheel for an inertia evaluation."""
    from cassini_bayes.api import evaluate_plan, plan_wheel_axis

    with pytest.raises(InputError, match="from 2 to 12"):
        plan_wheel_axis("espa_bus", "wheel_axis_espa_bus", wheel="RW2", pairs=1)
    with pytest.raises(InputError, match="not a running wheel"):
        plan_wheel_axis("espa_bus", "wheel_axis_espa_bus", wheel="RW9")
    with pytest.raises(InputError, match="wheel-axis calibration only"):
        evaluate_plan("wheel_axis_espa_bus", calibration="inertia", wheel="RW2")
    with pytest.raises(InputError, match="choose one of"):
        evaluate_plan("wheel_axis_espa_bus", calibration="leak")
    with pytest.raises(InputError, match="no thruster fires"):
        evaluate_plan("wheel_axis_espa_bus", calibration="thrust")


def test_planned_manoeuvre_flies_within_its_limits(tmp_path):
    """A planned wheel-axis manoeuvre (every slew at the largest rate the limits allow, the
    wheel biased to half its limit) simulated with noise: every limit holds on the telemetry;
    the slews fit the duration with windows of at least the shortest allowed; the
    perpendicular family's axes are perpendicular to the wheel's axis."""
    from cassini_bayes.plan.axis_planner import AxisChoice, axis_scenario, min_window_s

    lim, base = load_limits("wheel_axis_espa_bus", ESPA)
    g = base.prior.wheel("RW2").axis
    perp = axis_scenario(lim, base, ESPA, "RW2", AxisChoice(3, 90.0, "perpendicular"))
    assert all(abs(np.dot(sl["axis"], g)) < 1e-9 for sl in perp["slew"])
    d = axis_scenario(lim, base, ESPA, "RW2", AxisChoice(6, 45.0, "body", wheel_fraction=0.5))
    assert d is not None and len(d["slew"]) == 11 and len(d["window"]) == 12
    s = scenario_from_dict(d)
    assert s.slews[0].t_start_s >= min_window_s(lim, base) - 1e-9
    assert s.slews[-1].t_end_s <= s.duration_s - min_window_s(lim, base) + 1e-6
    tel = simulate(jax.random.key(1), s).telemetry
    u = checks.largest_usage(tel.t, tel.omega, tel.wheel_rates, base.prior.wheel_axes,
                             base.prior.wheel_inertias, np.ones(4), lim)
    assert all(v <= 1.0 for v in u.values()), u
    assert u["wheel_speed"] > 0.45                  # the bias is what was asked
    # too many long slews for the duration: not a candidate
    assert axis_scenario(lim, base, ESPA, "RW2", AxisChoice(12, 180.0, "body")) is None


def test_plan_evaluate_wheel_axis_prints_the_cones(run_cli, tmp_path):
    """``plan evaluate --wheel`` (with ``--spacecraft``): the axis's cones beside Brown's 1°, a
    row per site, the windows; summary.json and report.html written."""
    import tomli_w

    p = tmp_path / "short.toml"
    p.write_text(tomli_w.dumps(_short_espa()))
    code, out, err = run_cli("plan", "evaluate", p, "--wheel", "RW2", "--spacecraft", "espa_bus",
                             "--limits", "wheel_axis_espa_bus", "--out", tmp_path / "ev")
    assert code == 0, err
    for word in ("RW2 axis", "90 %", "u4_x", "Iyz", "windows", "wheel_speed"):
        assert word in out
    s = json.loads((tmp_path / "ev" / "summary.json").read_text())
    assert s["calibration"] == "wheel-axis"
    pr = s["prediction"]
    assert pr["wheel"] == "RW2" and len(pr["windows_s"]) == 2 and "wheel_speed" in pr["usage"]
    # the quiet windows' slopes measure the torques (Euler dH/dt = T), so the bus is limited by
    # the known wheels' axis tilts (share 0.99; the torques carried 0.56-0.59 by the means alone)
    shares = pr["variance_shares"]
    assert shares["wheel_axes"] > 0.5 and shares["inertial_torque"] < 0.1, shares
    assert "--window-a" in pr["fit_windows"]
    assert "u4_x" in (tmp_path / "ev" / "report.html").read_text()


@pytest.mark.slow
def test_plan_wheel_axis_writes_a_scenario_that_flies_within_its_limits(run_cli, tmp_path):
    """``plan wheel-axis`` with a short search (two pairs, 20 minutes, the short shipped
    manoeuvre as the comparison: Brown's eight slews do not fit 20 minutes): the written
    scenario simulates within every limit, and it evaluates to the plan's prediction."""
    import tomli_w

    lim_file = _short_limits(tmp_path)
    short = tmp_path / "short.toml"
    short.write_text(tomli_w.dumps(_short_espa()))
    code, _, err = run_cli("plan", "wheel-axis", "--spacecraft", "espa_bus", "--wheel", "RW2",
                           "--limits", lim_file, "--pairs", "2", "--baseline", short,
                           "--out", tmp_path / "p")
    assert code == 0, err
    s = json.loads((tmp_path / "p" / "summary.json").read_text())
    assert s["plan"]["limits_ok"] and s["choice"]["pairs"] == 2
    assert s["baseline"]["name"] == "scenario wheel_axis_espa_short"
    assert np.isfinite(s["improvement"]["sd_direction"])
    code, _, err = run_cli("simulate", tmp_path / "p" / "scenario.toml", "--out",
                           tmp_path / "sim", "--seed", "3")
    assert code == 0, err
    from cassini_bayes.telemetry import read_telemetry

    lim, base = load_limits(lim_file, ESPA)
    tel = read_telemetry(tmp_path / "sim" / "telemetry.csv", spacecraft=base.prior)
    u = checks.largest_usage(tel.t, tel.omega, tel.wheel_rates, base.prior.wheel_axes,
                             base.prior.wheel_inertias, np.ones(4), lim)
    assert all(v <= 1.0 for v in u.values()), u
    code, out, err = run_cli("plan", "evaluate", tmp_path / "p" / "scenario.toml", "--wheel",
                             "RW2")
    assert code == 0, err
    assert f"{s['plan']['sd_direction_deg']:.4g}" in out


@pytest.mark.slow
def test_prediction_matches_a_nuts_fit_of_noisy_data():
    """One NUTS fit of the short ESPA manoeuvre (fixed keys) against the prediction made before
    it: each axis component's posterior sd within ±25 %. This fit is 1.01–1.03 of it; over 20
    open-world seeds of the full manoeuvre the medians are 0.88–0.93 and one fit of 20 is beyond
    ±25 % (docs/planning.md), so a false failure needs a nominal fit like the open world's
    worst. It can fail: the prediction with the wheel-tilt knowledge doubled (the short
    manoeuvre's limiting error, share 0.99) is 1.63–1.89× the fit's."""
    from cassini_bayes.inference.rwa4 import fit_rwa4
    from cassini_bayes.inference.runner import SamplerSettings
    from cassini_bayes.plan.wheel_axis import evaluate_wheel_axis

    s = scenario_from_dict(_short_espa())
    pred = evaluate_wheel_axis(s, "RW2")
    tel = simulate(jax.random.key(11), s).telemetry
    post = fit_rwa4(jax.random.key(12), tel, s.prior, method="rwa", wheel="RW2",
                    pairs=pred.pairs, prior_draws=0,
                    settings=SamplerSettings(chains=2, warmup=300, draws=500))
    sd = np.array([post.idata.posterior[n].values.std() for n in ("u4_x", "u4_y", "u4_z")])
    np.testing.assert_allclose(sd / pred.site_sd[:3], 1.0, atol=0.25)
