"""Scenario files: loading and validation, the ``simulate`` CLI, momentum conservation of the RWA
slew scenarios, least-squares recovery on noise-free telemetry (inertia, RWA4 axis) and the
post-PRM conditioning."""

from __future__ import annotations

import json
import tomllib

import jax
import numpy as np
import pytest

from cassini_bayes.errors import InputError
from cassini_bayes.estimators import fit_axis_rwa, fit_inertia_baseline
from cassini_bayes.physics.momentum import (inertial_momentum, stacked_system,
                                            wheel_momentum_body)
from cassini_bayes.simulate import load_scenario, scenario_from_dict, simulate
from cassini_bayes.simulate.controllers import slew_duration
from cassini_bayes.simulate.scenario import scenario_path

REQUIRED = ["slew_2000_03_15", "slews_pre_soi", "slews_post_prm", "slews_post_probe",
            "fsds_biasing", "biasing_day028", "biasing_day049", "biasing_day061",
            "biasing_day071", "biasing_day094", "rwa4_rcs", "rwa4_rwa"]
SHORT_S = 2700.0   # common truncated length: one compiled program per wheel set


def _dict(name):
    return tomllib.loads(scenario_path(name).read_text())


def _truncated(name, duration=SHORT_S):
    """The scenario cut to ``duration`` s (slews that would not finish are dropped)."""
    d = _dict(name)
    d["run"]["duration_s"] = duration
    d["slew"] = [s for s in d.get("slew", []) if s["t_start_s"] + slew_duration(
        np.deg2rad(s["angle_deg"]), s["rate_mrad_s"] * 1e-3, s["accel_mrad_s2"] * 1e-3)
        <= duration]
    return scenario_from_dict(d, f"{name}[:{duration:g} s]")


def _h_rel_drift(res):
    s, tr = res.scenario, res.truth
    hw = wheel_momentum_body(np.nan_to_num(tr.wheel_rates), np.asarray(res.params.wheel_axes),
                             np.asarray(res.params.wheel_inertias))
    h = np.asarray(inertial_momentum(tr.q, tr.omega, s.truth.inertia, hw))
    return np.max(np.linalg.norm(h - h[0], axis=1)) / np.linalg.norm(h[0])


@pytest.mark.parametrize("name", REQUIRED)
def test_required_scenarios_load(name):
    s = load_scenario(name)
    assert s.name == name
    assert s.n_samples >= 2 and s.truth_model_path and s.prior_model_path


def test_slew_scenarios_design():
    """Slew rates of a few mrad/s; post-PRM has a very small Z rotation (Fig. B2)."""
    for name in ("slew_2000_03_15", "slews_pre_soi", "slews_post_prm", "slews_post_probe"):
        s = load_scenario(name)
        assert s.control == "rwa" and not s.uses_thrusters
        assert all(0.2e-3 <= sl.rate_rad_s <= 5e-3 for sl in s.slews)
    z = [abs(sl.angle_rad) for sl in load_scenario("slews_post_prm").slews if sl.axis[2] == 1]
    assert max(z) < np.deg2rad(2)
    assert load_scenario("slew_2000_03_15").sample_period_s == 4.0          # 0.25 Hz
    assert load_scenario("slew_2000_03_15").duration_s == 4 * 3600


def _bad(mutate):
    d = _dict("slews_post_probe")
    mutate(d)
    with pytest.raises(InputError) as e:
        scenario_from_dict(d, "bad.toml")
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith("bad.toml")
    return msg


def test_unknown_key_named():
    assert "run.durration_s" in _bad(lambda d: d["run"].update(durration_s=1.0))
    assert "'bogus'" in _bad(lambda d: d.update(bogus=1))


def test_missing_required_named():
    assert "run.dt_s" in _bad(lambda d: d["run"].pop("dt_s"))
    assert "truth.model" in _bad(lambda d: d["truth"].pop("model"))


def test_impossible_values_named():
    assert "Ixx" in _bad(lambda d: d["truth"]["inertia"].update(Ixx=-7362.0))
    assert "slew[0].axis" in _bad(lambda d: d["slew"][0].update(axis=[1.0, 1.0, 0.0]))
    msg = _bad(lambda d: d.update(window=[{"name": "A", "t0_s": 100.0, "t1_s": 9000.0}]))
    assert "window[0].t1_s" in msg
    assert "slew[5].t_start_s" in _bad(lambda d: d["slew"][5].update(t_start_s=5900.0))
    assert "rwa4_axis" in _bad(lambda d: d["truth"].update(rwa4_axis=[0.0, 0.9, 0.5]))
    assert "truth.inertia" in _bad(lambda d: d["truth"]["inertia"].update(Izz=20000.0))


def test_cli_rejects_bad_scenario(tmp_path, run_cli):
    d = scenario_path("slews_post_probe").read_text().replace("dt_s = 0.25",
                                                              "dt_s = 0.25\ndt = 1")
    p = tmp_path / "bad.toml"
    p.write_text(d)
    code, out, err = run_cli("simulate", p, "--out", tmp_path / "o")
    assert code == 2 and "run.dt" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


def test_cli_simulate_writes_run_atomically(tmp_path, run_cli):
    text = scenario_path("fsds_biasing").read_text().replace("duration_s = 640.0",
                                                             "duration_s = 120.0")
    p = tmp_path / "short_fsds.toml"
    p.write_text(text)
    out = tmp_path / "run"
    code, _, err = run_cli("simulate", p, "--out", out, "--seed", 7)
    assert code == 0, err
    assert sorted(x.name for x in out.iterdir()) == [".cassini-bayes-files", "pulses.csv",
                                                     "telemetry.csv", "truth.json"]
    truth = json.loads((out / "truth.json").read_text())
    assert truth["seed"] == 7 and truth["thrust_n"]["Y2"] == 0.75
    assert truth["inertia_kgm2"]["Ixx"] == 7375.02 and truth["noise"]["gyro_rad_s"] == 1e-6
    assert truth["momentum_balance_rel_error"] < 1e-9
    code, _, err = run_cli("check", out / "telemetry.csv", "--pulses", out / "pulses.csv")
    assert code == 0, err
    code, _, err = run_cli("simulate", p, "--out", out)                  # exists: refused
    assert code == 2 and "--force" in err
    code, _, err = run_cli("simulate", p, "--out", out, "--force", "--seed", 8)
    assert code == 0 and json.loads((out / "truth.json").read_text())["seed"] == 8
    assert [x.name for x in tmp_path.iterdir() if x.name.startswith(".")] == []


@pytest.fixture(scope="module")
def short_runs():
    """The four inertia slew scenarios and rwa4_rwa, cut to a common length (2 compilations)."""
    names = ("slew_2000_03_15", "slews_pre_soi", "slews_post_prm", "slews_post_probe", "rwa4_rwa")
    return {n: simulate(jax.random.key(i), _truncated(n)) for i, n in enumerate(names)}


def test_momentum_conserved_in_rwa_scenarios(short_runs):
    """No thrusters, no external torque: true inertial momentum conserved to ≤ 1e-9."""
    for name, res in short_runs.items():
        assert _h_rel_drift(res) <= 1e-9, name
        assert res.pulses is None


def test_inertia_recovered_noise_free(short_runs):
    """Feldman & Lee Eq 11 / free-momentum least squares on the noise-free truth: ≤ 1e-4."""
    res = short_runs["slews_post_probe"]
    fit = fit_inertia_baseline([res.truth], res.scenario.truth, method="free")
    pi_true = np.asarray(res.params.inertia)
    assert np.max(np.abs(fit.pi - pi_true) / pi_true[:3].min()) <= 1e-4
    fit_eq11 = fit_inertia_baseline([res.truth], res.scenario.truth, method="all_axes")
    assert np.max(np.abs(fit_eq11.pi - pi_true) / pi_true[:3].min()) <= 1e-4


def test_post_prm_worse_conditioned_than_post_probe(short_runs):
    """The small Z rotation of post-PRM (Fig. B2) leaves S of Eq 11 far worse conditioned, and
    its weakest direction is Izz (the paper's +5.08 % Izz error)."""
    info = {}
    for n in ("slews_post_prm", "slews_post_probe"):
        res = short_runs[n]
        sc = res.scenario
        hw = wheel_momentum_body(np.nan_to_num(res.truth.wheel_rates), sc.truth.wheel_axes,
                                 sc.truth.wheel_inertias)
        s_mat = np.asarray(stacked_system(res.truth.q, res.truth.omega, hw)[0])   # Eq 11
        i = sc.prior.inertia
        prior_sd = np.array([0.1 * i[0, 0], 0.1 * i[1, 1], 0.1 * i[2, 2], 75.0, 75.0, 75.0])
        scaled = s_mat * prior_sd
        _, _, vt = np.linalg.svd(scaled, full_matrices=False)
        sd = np.sqrt(np.diag(np.linalg.inv(scaled.T @ scaled)))
        info[n] = (np.linalg.cond(s_mat), vt[-1], sd)
    c_prm, c_probe = info["slews_post_prm"][0], info["slews_post_probe"][0]
    print(f"\ncond(S), Eq 11: post-PRM {c_prm:.3g}, post-Probe {c_probe:.3g}")
    assert c_prm > 5 * c_probe
    assert abs(info["slews_post_prm"][1][2]) > 0.99                     # weakest: Izz
    assert info["slews_post_prm"][2][2] > 10 * info["slews_post_probe"][2][2]


def test_rwa4_rwa_holds_attitude_and_recovers_axis(short_runs):
    """Brown §III.C: controller believes RWA4 at RWA1 (5° off here) and still holds attitude
    within a few mrad; Eq 3 on the first slew pair recovers the axis to 0.01° (noise-free)."""
    res = short_runs["rwa4_rwa"]
    assert np.max(np.linalg.norm(res.arrays.pointing_error, axis=1)) < 3e-3
    s, t = res.scenario, res.truth.t
    first, second = s.slews[0], s.slews[1]
    a = (t >= 30.0) & (t <= first.t_start_s - 10)
    b = (t >= first.t_end_s + 120) & (t <= second.t_start_s - 10)
    fit = fit_axis_rwa(res.truth.q, res.truth.omega, res.truth.wheel_rates, s.truth.wheel_axes,
                       s.truth.wheel_inertias, [(a, b)], unknown=3)
    u = s.truth.wheel("RWA4").axis
    assert np.degrees(np.arccos(np.clip(fit.axis @ u, -1, 1))) < 0.01


def test_rwa4_rwa_ten_degrees_off(short_runs):
    """Same compiled program (truth is a traced input): RWA4 10° from RWA1 still controlled."""
    res = short_runs["rwa4_rwa"]
    axes = np.asarray(res.params.wheel_axes).copy()
    axes[3] = [-0.173315571789, 0.797889954344, 0.57735026919]       # 10.0° from RWA1
    off = simulate(jax.random.key(9), res.scenario, res.params._replace(wheel_axes=axes))
    err = np.max(np.linalg.norm(off.arrays.pointing_error, axis=1))
    assert err < 3e-3
    assert _h_rel_drift(off) <= 1e-9


@pytest.mark.slow
@pytest.mark.parametrize("name", REQUIRED)
def test_full_scenarios_momentum_balance(name):
    """Every shipped scenario over its whole run: ΔH_N = accumulated thruster impulse (≤ 1e-6 of
    it), or conserved to ≤ 1e-9 without thrusters."""
    res = simulate(jax.random.key(0), load_scenario(name))
    if res.pulses is None:
        assert _h_rel_drift(res) <= 1e-9
    else:
        s, tr = res.scenario, res.truth
        hw = wheel_momentum_body(np.nan_to_num(tr.wheel_rates), np.asarray(res.params.wheel_axes),
                                 np.asarray(res.params.wheel_inertias))
        h = np.asarray(inertial_momentum(tr.q, tr.omega, s.truth.inertia, hw))
        imp = np.asarray(res.arrays.impulse_inertial)
        assert np.max(np.linalg.norm(h - h[0] - imp, axis=1)) <= 1e-6 * np.linalg.norm(imp[-1])


def test_overrides_per_thruster_and_believed_vector():
    d = _dict("rwa4_rwa")
    d["truth"]["thrust_n"] = [0.7, 0.71, 0.72, 0.73, 0.74, 0.75, 0.76, 0.77]
    d["rwa_controller"]["believed_axis"] = {"RWA4": [0.0, 0.816496580928, 0.577350269190]}
    s = scenario_from_dict(d)
    assert s.thrust_n[7] == 0.77
    np.testing.assert_allclose(s.rwa.believed_axes[3], s.prior.wheel("RWA1").axis, atol=1e-9)
    assert abs(np.degrees(np.arccos(s.truth.wheel("RWA4").axis @ s.rwa.believed_axes[3]))
               - 5.0) < 1e-6
    d["truth"]["thrust_n"] = [0.7] * 7
    with pytest.raises(InputError, match="truth.thrust_n"):
        scenario_from_dict(d)


# ---- `_real` variants: the same events with realistic error sources (docs/robust/README.md) ---

REAL = ["slew_2000_03_15_real", "slews_pre_soi_real", "slews_post_prm_real",
        "slews_post_probe_real", "biasing_day028_real", "rwa4_rcs_real", "rwa4_rwa_real"]
_EVENTS = ("run", "initial", "slew", "wheel_ramp", "deadband", "pulse", "window", "prior")


def _balance(res):
    """max |ΔH_N − body-fixed impulse − ∫ T_N dt| relative to the largest of |H_N|, |ΔH_N|."""
    a, p = res.arrays, res.params
    t = np.asarray(a.t)[:, None]
    h = np.asarray(a.h_inertial)
    inertial = np.asarray(p.torque_inertial_nm) * t + 0.5 * np.asarray(
        p.torque_inertial_rate_nm_s) * t * t
    miss = h - h[0] - np.asarray(a.impulse_inertial) - inertial
    scale = max(np.max(np.linalg.norm(h, axis=1)), np.max(np.linalg.norm(h - h[0], axis=1)))
    return np.max(np.linalg.norm(miss, axis=1)) / scale


@pytest.mark.parametrize("name", REAL)
def test_real_variants_same_events_with_every_error_on(name):
    base = name.removesuffix("_real")
    real, nominal = _dict(name), _dict(base)
    for key in _EVENTS:                      # only the errors differ from the nominal scenario
        if key == "window":
            assert [w | {"name": 0} for w in real.get(key, [])] == \
                [w | {"name": 0} for w in nominal.get(key, [])]
        else:
            assert real.get(key) == nominal.get(key), key
    assert real["truth"]["inertia"] == nominal["truth"]["inertia"]
    s = load_scenario(name)
    assert s.name == name
    n = s.noise
    assert np.all(np.abs(n.gyro_bias_rad_s) > 0) and np.all(np.abs(n.gyro_scale_factor) > 0)
    assert np.any(s.external_torque_body_nm) and s.truth.wheel_inertias[0] != \
        s.prior.wheel_inertias[0]
    if name != "slew_2000_03_15_real":       # the March 2000 variant predates these two effects
        assert s.flex is not None and n.time_tag_jitter_s > 0


@pytest.fixture(scope="module")
def short_real_runs():
    """The `_real` variants cut to 480 s (one compiled program per controller set-up; the RWA4 RCS
    ramp starts at 420 s)."""
    return {n: simulate(jax.random.key(i), _truncated(n, 480.0)) for i, n in enumerate(REAL)}


def test_real_variants_simulate(short_real_runs):
    for name, res in short_real_runs.items():
        a, tel = res.arrays, res.telemetry
        assert np.all(np.isfinite(tel.omega)) and np.all(np.isfinite(tel.q)), name
        assert np.all(np.diff(tel.t) > 0), name
        jitter = res.scenario.noise.time_tag_jitter_s
        assert (np.std(tel.t - res.truth.t) > 0) == (jitter > 0), name
        assert (np.max(np.abs(a.flex_eta)) > 0) == (res.scenario.flex is not None), name
        # momentum changes only by the external torques and the thrusters
        assert _balance(res) < 1e-9, (name, _balance(res))


@pytest.mark.slow
@pytest.mark.parametrize("name", REAL)
def test_full_real_variants_momentum_balance(name):
    res = simulate(jax.random.key(0), load_scenario(name))
    assert _balance(res) < 1e-9
    assert np.max(np.abs(res.arrays.pointing_error[:, :2])) < (0.16 if "rcs" in name else 2e-3)


def test_cli_simulate_takes_a_shipped_scenario_by_name(tmp_path, run_cli, monkeypatch):
    """``simulate slew_2000_03_15`` (no path, no suffix) finds the shipped scenario from any
    folder; a name that is neither a file nor shipped is one line naming it."""
    monkeypatch.chdir(tmp_path)
    code, _, err = run_cli("simulate", "slew_2000_03_15", "--out", tmp_path / "o")
    assert code == 0, err
    assert json.loads((tmp_path / "o" / "truth.json").read_text())["scenario"]
    code, _, err = run_cli("simulate", "no_such_scenario", "--out", tmp_path / "p")
    assert code == 2 and "no_such_scenario" in err and len(err.strip().splitlines()) == 1
