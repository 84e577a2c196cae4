"""Planning a thrust calibration: the prediction is the Laplace approximation of the robust thrust
fit's own density (checked against a brute-force differenced Hessian), the planned biasing event
keeps its limits on the simulated telemetry, bad limits are one-line errors, the CLI
(docs/planning.md)."""

from __future__ import annotations

import copy
import json
import tomllib

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from cassini_bayes.errors import InputError
from cassini_bayes.plan.limits import limits_from_dict, limits_path
from cassini_bayes.simulate import scenario_from_dict
from cassini_bayes.simulate.open_world import base_scenario

ESPA = "models/espa_bus.toml"


def _small_event() -> dict:
    """``pulses_espa_bus`` cut to its first eight pulses (one per thruster, 250 ms) and 100 s."""
    d = copy.deepcopy(base_scenario("pulses_espa_bus"))
    d["run"]["duration_s"] = 100.0
    d["pulse"] = d["pulse"][:8]
    d["name"] = "pulses_espa_small"
    return d


def _limits(**change) -> dict:
    d = tomllib.loads(limits_path("thrust_espa_bus").read_text())
    d["limits"].update(change)
    return d


def test_prediction_matches_a_differenced_hessian():
    """The predicted covariance (``jax.hessian`` of the fit's density at the truth, noise scale
    held) equals the inverse of a brute-force Hessian from second differences of the density's
    values (step 1e-3 posterior sd along the predicted whitening), and the sites' sd its delta
    method with a differenced Jacobian of the fit's map to the physical parameters: to 1e-3 relative
    (the differences' truncation is ~1e-6 and their rounding ~1e-5 of the curvature)."""
    from cassini_bayes.inference.thrust.coords import physical
    from cassini_bayes.plan.thrust import (_held_density, _site_names, _truth, _truth_vector,
                                           noise_free_problem, predict_thrust, representable)

    s = scenario_from_dict(_small_event())
    _, problem, sig = noise_free_problem(s, "mean")
    s = representable(s, "mean")
    names = _site_names(problem)
    truth = _truth(s, problem, names)
    at = _truth_vector(problem, names, truth)
    lap = predict_thrust(problem, sig, at=at)
    kw = problem.data._replace(log_noise_hat=jnp.log(jnp.asarray(sig)[None]))
    n_f, n_c, n_ev = problem.n_f, problem.n_c, 1
    f = jax.jit(_held_density(n_f, n_c, True, n_ev))
    x0 = np.asarray(lap.centre)
    w = np.linalg.cholesky(lap.cov)
    h = 1e-3
    d = x0.size
    hw = np.zeros((d, d))
    for i in range(d):
        for j in range(i, d):
            ei, ej = h * w[:, i], h * w[:, j]
            v = (float(f(x0 + ei + ej, kw)) - float(f(x0 + ei - ej, kw))
                 - float(f(x0 - ei + ej, kw)) + float(f(x0 - ei - ej, kw))) / (4 * h * h)
            hw[i, j] = hw[j, i] = -v
    cov_fd = w @ np.linalg.inv(hw) @ w.T
    np.testing.assert_allclose(np.sqrt(np.diag(cov_fd)), np.sqrt(np.diag(lap.cov)), rtol=1e-3)
    k = n_f + n_c + 3

    def sites(x):
        theta = jnp.concatenate([x[:k], jnp.zeros(n_ev), x[k:]])
        p = physical(theta, kw, n_f, n_c, True)
        return np.asarray(jnp.concatenate([p.thrust, p.tau, p.inertia]))

    jac = np.stack([(sites(x0 + 1e-4 * w[:, i]) - sites(x0 - 1e-4 * w[:, i])) / 2e-4
                    for i in range(d)], 1) @ np.linalg.inv(w)
    # the fit's draws times 1 + u, u the wheels' common scale from its prior (ThrustProblem.
    # scale_free): the thrust and the inertia gain x² var(u)
    x = np.r_[truth[:n_f], np.zeros(3), truth[n_f + 3:]]
    u_cov = problem.layout.common_scale_sd**2 * np.outer(x, x)
    sd_fd = np.sqrt(np.diag(jac @ cov_fd @ jac.T + u_cov))
    np.testing.assert_allclose(sd_fd, np.sqrt(np.diag(lap.site_cov)), rtol=1e-3)
    # the point is the truth: the sites there are the scenario's true values
    np.testing.assert_allclose(lap.site_mean, truth, rtol=1e-9)
    # the check can fail: with the noise doubled the sites the noise limits (not F and the
    # inertia, which the wheels' common scale limits here) move by far more than the tolerance
    lap2 = predict_thrust(problem, 2 * sig, at=at)
    assert not np.allclose(np.sqrt(np.diag(lap2.site_cov)), sd_fd, rtol=0.2)


def test_evaluate_thrust_reports_every_site_beside_budget_and_prior():
    """Mode ``thruster`` on the small event: a thrust per thruster, the centre-of-mass offset,
    the time constants and the inertia, each narrower than its prior; thrust budgets ±10 %."""
    from cassini_bayes.plan.thrust import evaluate_thrust

    s = scenario_from_dict(_small_event())
    p = evaluate_thrust(s, "thruster")
    assert p.sites[:8] == tuple(f"F[{n}]" for n in s.prior.thruster_names)
    assert p.sites[8:11] == ("com_x", "com_y", "com_z")
    assert np.all(p.site_sd < p.site_prior_sd)
    np.testing.assert_allclose(p.budget[:8], 0.1 * s.prior.thrust_per_thruster)
    assert np.isnan(p.budget[8]) and p.n_pulses == 8
    assert p.max_ratio == max(x for x in p.ratio if np.isfinite(x))
    assert p.site_sd_mode is not None and p.non_gaussian == ()     # eight pulses: Gaussian


def test_sites_on_a_ridge_are_named_not_gaussian():
    """The rule of ``ThrustPrediction.non_gaussian``: one time-constant site's sd at the
    noise-free mode 30 % off the truth's (either way) names every thrust and time-constant site,
    the centre of mass and the inertia not; 20 % off names none; an inertia site 30 % off names
    itself alone; the table and summary.json say so."""
    from cassini_bayes.api._plan_format import format_thrust_table, thrust_block
    from cassini_bayes.plan.thrust import evaluate_thrust

    p = evaluate_thrust(scenario_from_dict(_small_event()), "thruster", check_mode=False)
    assert p.site_sd_mode is None and p.non_gaussian == ()
    ridge = p.sites[:8] + ("tau_delay", "tau_rise", "tau_fall")
    i = p.sites.index("tau_rise")
    for share, named in ((1.3, ridge), (1 / 1.3, ridge), (1.2, ()), (1 / 1.2, ())):
        q = p._replace(site_sd_mode=p.site_sd * np.where(np.arange(len(p.sites)) == i, share, 1))
        assert q.non_gaussian == named
    j = p.sites.index("Ixz")
    q = p._replace(site_sd_mode=p.site_sd * np.where(np.arange(len(p.sites)) == j, 1.3, 1))
    assert q.non_gaussian == ("Ixz",) and p.ridge_sites == ridge
    assert "Ixz 1.30: their predicted sd is indicative" in format_thrust_table(q, "t")
    q = p._replace(site_sd_mode=p.site_sd * np.where(np.arange(len(p.sites)) == i, 0.5, 1))
    assert "not Gaussian on this event" in format_thrust_table(q, "t") and "tau_rise 0.50" in \
        format_thrust_table(q, "t")
    block = thrust_block(q)
    assert block["non_gaussian"] == list(ridge)
    assert block["sites"]["tau_rise"]["sd_at_mode"] == pytest.approx(0.5 * q.site_sd[i])


@pytest.mark.parametrize("change, key", [
    ({"max_pulse_s": 0.1}, "max_pulse_s"),
    ({"min_pulse_s": 0.5, "max_pulse_s": 0.25}, "max_pulse_s"),
    ({"thrusters": ["A1", "Z9"]}, "thrusters"),
    ({"thrusters": []}, "thrusters"),
    ({"thrusters": "A1"}, "thrusters"),
    ({"duration_s": 120.0}, "duration_s"),
    ({"max_wheel_rpm": -1.0}, "max_wheel_rpm"),
    ({"min_pulse_s": 0.05}, "min_pulse_s"),
])
def test_bad_thrust_limits_are_one_line_errors(change, key):
    with pytest.raises(InputError) as e:
        limits_from_dict(_limits(**change), ESPA, "thrust_limits.toml", slews=False)
    msg = str(e.value)
    assert key in msg and "\n" not in msg


@pytest.mark.slow
def test_plan_thrust_flies_within_its_limits(run_cli, tmp_path):
    """``plan thrust`` on a 4-minute ESPA event with the longest pulse 250 ms and two thrusters
    forbidden: the written scenario simulates (noisy, ``simulate``) within every limit, on the
    telemetry and on the pulse log, and ``plan evaluate`` gives the plan's prediction; the
    search ranks, and both predict, over the nominal truth and one drawn from the model file's
    knowledge."""
    import tomli_w

    from cassini_bayes.plan import checks
    from cassini_bayes.plan.limits import load_limits
    from cassini_bayes.telemetry import read_pulses, read_telemetry

    d = _limits(duration_s=240.0, max_pulse_s=0.25)
    lim_file = tmp_path / "limits.toml"
    lim_file.write_text(tomli_w.dumps(d))
    code, out, err = run_cli("plan", "thrust", "--spacecraft", "espa_bus", "--limits", lim_file,
                             "--out", tmp_path / "p", "--truths", "1")
    assert code == 0, err
    s = json.loads((tmp_path / "p" / "summary.json").read_text())
    assert s["plan"]["limits_ok"]
    assert len(s["search"]) >= 4
    assert all(c["truths"] == 1 for c in s["search"])      # ranked over the truths too
    code, _, err = run_cli("simulate", tmp_path / "p" / "scenario.toml", "--out",
                           tmp_path / "sim", "--seed", "3")
    assert code == 0, err
    lim, base = load_limits(lim_file, ESPA, slews=False)
    tel = read_telemetry(tmp_path / "sim" / "telemetry.csv", spacecraft=base.prior)
    u = checks.largest_usage(tel.t, tel.omega, tel.wheel_rates, base.prior.wheel_axes,
                             base.prior.wheel_inertias, np.ones(4), lim)
    assert all(v <= 1.0 for v in u.values()), u
    log = read_pulses(tmp_path / "sim" / "pulses.csv", spacecraft=base.prior)
    assert lim.min_pulse_s - 1e-9 <= log.width.min() and log.width.max() <= lim.max_pulse_s + 1e-9
    code, out, err = run_cli("plan", "evaluate", tmp_path / "p" / "scenario.toml",
                             "--truths", "1")
    assert code == 0, err
    assert s["plan"]["truths"] == 1
    assert f"{s['plan']['sites']['F']['sd']:.4g}" in out


def test_plan_evaluate_cli_on_a_biasing_event(run_cli, tmp_path):
    """``plan evaluate`` recognises a scenario whose thrusters fire as a thrust calibration and
    prints each thrust site (``--truths 1``: the median over two truths, with its range); a
    spacecraft with other thrusters is refused in one line."""
    import tomli_w

    p = tmp_path / "small.toml"
    p.write_text(tomli_w.dumps(_small_event()))
    code, out, err = run_cli("plan", "evaluate", p, "--spacecraft", "espa_bus", "--out",
                             tmp_path / "ev", "--truths", "1")
    assert code == 0, err
    assert "robust thrust fit" in out and "tau_rise" in out and "sd/budget" in out
    assert "median over the nominal truth and 1 drawn" in out
    summary = json.loads((tmp_path / "ev" / "summary.json").read_text())
    assert summary["calibration"] == "thrust" and "F" in summary["prediction"]["sites"]
    site = summary["prediction"]["sites"]["F"]
    assert summary["prediction"]["truths"] == 1
    assert site["sd_range"][0] <= site["sd"] <= site["sd_range"][1]
    assert (tmp_path / "ev" / "report.html").stat().st_size > 1000
    code, _, err = run_cli("plan", "evaluate", p, "--spacecraft", "cassini_post_probe")
    assert code != 0 and "spacecraft" in err


def test_knowledge_truths_stay_inside_the_model_files_knowledge():
    """Each drawn truth has its inertia in the model file's knowledge box, its time constants in
    the manufacturer's ranges, wheel errors, torques and centre of mass at the stated sds (6 sd:
    a false failure ~1e-8 a draw); fixed per seed."""
    from cassini_bayes.plan.truths import knowledge_truths

    s = scenario_from_dict(_small_event())
    prior = s.prior
    ts = knowledge_truths(s, 6, seed=0)
    assert len(ts) == 6 and knowledge_truths(s, 0) == []
    i0 = np.asarray(prior.inertia)
    for t in ts:
        moments = np.diag(t.truth.inertia)
        assert np.all(np.abs(moments / np.diag(i0) - 1) <= prior.moi_uncertainty)
        assert not np.allclose(moments, np.diag(i0))
        for k in ("tau_delay", "tau_rise", "tau_fall"):
            lo, hi = getattr(prior.pulse, f"{k}_range")
            assert lo <= getattr(t.truth.pulse, k) <= hi
        assert len(t.wheel_inertia_errors) == len(s.truth.wheel_names)
        assert np.all(np.abs(t.external_torque_body_nm) < 6 * prior.knowledge.torque_sd_nm)
    com = np.array([t.truth.com_m - prior.com_m for t in ts])
    assert prior.com_sd_m > 0 and np.all(np.abs(com) < 6 * prior.com_sd_m)
    assert np.all(np.std(com, axis=0) > 0.2 * prior.com_sd_m)
    again = knowledge_truths(s, 6, seed=0)
    assert all(np.array_equal(a.truth.inertia, b.truth.inertia) for a, b in zip(ts, again))
    assert not np.array_equal(knowledge_truths(s, 1, seed=1)[0].truth.inertia,
                              ts[0].truth.inertia)


def test_evaluate_thrust_over_truths_is_the_median_beside_the_nominal():
    """``truths=2``: each site's sd is the median of three predictions, the nominal one kept
    beside it and inside the range; ``plan evaluate --truths`` prints and saves it."""
    from cassini_bayes.plan.thrust import evaluate_thrust

    s = scenario_from_dict(_small_event())
    nominal = evaluate_thrust(s, "mean", check_mode=False)
    p = evaluate_thrust(s, "mean", truths=2, check_mode=False)
    assert p.truths == 2 and nominal.truths == 0
    np.testing.assert_array_equal(nominal.site_sd_range[1], nominal.site_sd)
    np.testing.assert_allclose(p.site_sd_nominal, nominal.site_sd, rtol=1e-9)
    lo, hi = p.site_sd_range
    assert np.all(lo <= p.site_sd) and np.all(p.site_sd <= hi)
    assert np.all(lo <= p.site_sd_nominal) and np.all(p.site_sd_nominal <= hi)
    assert np.any(hi > 1.01 * lo)           # the truths' flights tell different amounts
    assert p.site_sd_truths.shape == (3, len(p.sites))
    assert np.isnan(p.site_sd_interval[0]).all()        # 3 truths: no interval reaches 90 %


def test_truths_are_refused_where_they_mean_nothing(tmp_path):
    from cassini_bayes.api import evaluate_plan

    with pytest.raises(InputError, match="truths"):
        evaluate_plan("slews_post_prm", truths=2)
    with pytest.raises(InputError, match="truths"):
        evaluate_plan("slews_post_prm", truths=-1)
    from cassini_bayes.api import plan_thrust

    with pytest.raises(InputError, match="truths"):
        plan_thrust("espa_bus", "thrust_espa_bus", truths=-2)


@pytest.mark.slow
def test_one_pulse_width_leaves_a_ridge_that_is_not_gaussian():
    """The ESPA bus's biasing event fires every pulse at 125 ms: its thrusts and time constants
    are named not Gaussian (each thrust's sd at the noise-free mode is about half that at the
    truth, docs/planning.md); Cassini's day 028, whose pulses have three widths, is Gaussian to
    a few per cent."""
    from cassini_bayes.plan.thrust import evaluate_thrust
    from cassini_bayes.simulate import load_scenario

    espa = evaluate_thrust(load_scenario("biasing_espa_bus"), "thruster")
    assert len(espa.pulse_widths_s) == 1 and "tau_fall" in espa.non_gaussian
    assert np.all(espa.sd_mode_ratio[:8] < 0.7)
    day028 = evaluate_thrust(load_scenario("biasing_day028"), "mean")
    assert len(day028.pulse_widths_s) > 1 and day028.non_gaussian == ()
    assert np.all(np.abs(day028.sd_mode_ratio - 1) < 0.1)


def test_the_median_interval_is_the_binomial_order_statistics():
    """Over 17 truths the ≥ 90 % interval of the median is the 5th to the 13th value (coverage
    1 − 2 P(Bin(17, ½) ≤ 4) = 0.951; the 6th–12th cover 0.857); over 9 the 2nd to the 8th;
    below 5 no interval reaches 90 % (NaN)."""
    from cassini_bayes.plan.truths import median_interval

    x = np.arange(17.0)[::-1, None] * np.array([1.0, 2.0])
    lo, hi = median_interval(x)
    np.testing.assert_array_equal(lo, [4.0, 8.0])
    np.testing.assert_array_equal(hi, [12.0, 24.0])
    lo, hi = median_interval(np.arange(9.0))
    assert (lo, hi) == (1.0, 7.0)
    assert np.isnan(median_interval(np.arange(4.0))[0])
    assert median_interval(np.arange(5.0)) == (0.0, 4.0)


def test_the_printed_prediction_gives_the_medians_interval_from_five_truths():
    """With 5 or more truths the table adds each site's ≥ 90 % interval of the median."""
    from cassini_bayes.api._plan_format import format_thrust_table
    from cassini_bayes.plan.thrust import ThrustPrediction

    sd = np.array([0.01, 0.001])
    p = ThrustPrediction(
        mode="mean", sites=("F", "tau_delay"), site_sd=sd, site_prior_sd=np.ones(2),
        budget=np.array([0.1, 0.003]), truth=np.ones(2), combinations={}, noise=np.ones(2),
        usage={}, n_pulses=3, pulse_widths_s=(0.125,), duration_s=1.0, t=np.zeros(1),
        omega=np.zeros((1, 3)), wheel_rpm=np.zeros((1, 1)), wheel_names=("RW1",),
        pulse_t=np.zeros(1), pulse_width=np.zeros(1), pulse_thruster=("A1",), truths=5,
        site_sd_truths=np.linspace(0.5, 1.5, 6)[:, None] * sd)
    text = format_thrust_table(p, "plan")
    assert "median, 90 % interval" in text and "0.005–0.015" in text
    short = format_thrust_table(p._replace(truths=3, site_sd_truths=p.site_sd_truths[:4]), "p")
    assert "interval" not in short
