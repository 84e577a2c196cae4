"""Open-world truths (cassini_bayes/simulate/open_world.py) and the campaign script
(benchmarks/coverage_open_world.py).

The statistical checks use fixed seeds; each states its tolerance, chosen at ≥ 4 standard errors
so that a false failure on a fresh seed would have probability < 1e-4 (the seeds are fixed, so
the tests are deterministic on one CPU).
"""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path

import numpy as np
import pytest

from cassini_bayes.errors import InputError
from cassini_bayes.simulate import scenario_from_dict
from cassini_bayes.simulate.open_world import (EFFECT_LAWS, LAWS, apply_time_tags, draw_law,
                                               draw_open_world)
from cassini_bayes.telemetry import Telemetry

ROOT = Path(__file__).resolve().parents[1]


def _flat(rec: dict) -> dict:
    return {k: np.asarray(v["values"], float) for k, v in rec.items()
            if isinstance(v, dict) and v.get("values") is not None}


def test_reproducible_from_the_seed():
    a = draw_open_world("slews_post_prm", 7)
    b = draw_open_world("slews_post_prm", np.random.default_rng(7))
    c = draw_open_world("slews_post_prm", 8)
    assert json.dumps(a.record) == json.dumps(b.record)
    assert a.scenario == b.scenario
    np.testing.assert_array_equal(a.time_tag_error_s, b.time_tag_error_s)
    np.testing.assert_array_equal(a.slip, b.slip)
    assert not np.array_equal(_flat(a.record)["gyro_bias_rad_s"],
                              _flat(c.record)["gyro_bias_rad_s"])


@pytest.mark.parametrize("law", LAWS)
def test_laws_have_the_stated_sd_and_family(law):
    x = draw_law(np.random.default_rng(1), law, 2.0, 200_000)
    # sd within 4 standard errors (t3's sample sd converges slowly: a looser 5 %)
    assert abs(x.std() / 2.0 - 1.0) < (0.05 if law == "student_t3" else 0.01)
    kurt = np.mean((x - x.mean()) ** 4) / x.var() ** 2
    if law == "uniform":
        assert np.max(np.abs(x)) <= math.sqrt(3.0) * 2.0
        assert abs(kurt - 1.8) < 0.05
    elif law == "laplace":
        assert abs(kurt - 6.0) < 0.5
    else:   # t3: infinite kurtosis; twice the Normal's mass beyond 3 sd at least
        assert np.mean(np.abs(x) > 6.0) > 2 * 0.0027
    with pytest.raises(InputError, match="unknown law"):
        draw_law(np.random.default_rng(1), "normal", 1.0, 3)


def test_every_effect_is_non_normal_wider_than_the_prior_and_recorded():
    ow = draw_open_world("biasing_day028", 3, widen=2.0, draw_inertia=True)
    kn = scenario_from_dict(ow.scenario).prior.knowledge
    rec = ow.record
    assert {rec[k]["law"] for k in EFFECT_LAWS} <= set(LAWS)
    assert rec["gyro_bias_rad_s"]["sd"] == pytest.approx(2.0 * kn.gyro_bias_sd_rad_s)
    assert rec["gyro_scale_factor"]["sd"] == pytest.approx(2.0 * kn.gyro_scale_factor_sd)
    assert rec["wheel_axis_tilt_deg"]["sd"] == pytest.approx(2.0 * kn.wheel_axis_sd_deg)
    assert rec["time_tag_error_s"]["sd"] == pytest.approx(2.0 * kn.time_tag_sd_s)
    e = np.asarray(rec["wheel_inertia_errors"]["values"])
    assert np.all(np.abs(e) <= math.sqrt(3.0) * 2.0 * kn.wheel_inertia_sd_frac)
    # what is recorded is what the simulator gets
    sc = scenario_from_dict(ow.scenario)
    np.testing.assert_allclose(sc.wheel_inertia_errors, e)
    np.testing.assert_allclose(sc.noise.gyro_bias_rad_s, rec["gyro_bias_rad_s"]["values"])
    np.testing.assert_allclose(sc.external_torque_body_nm,
                               rec["external_torque_body_nm"]["values"])
    assert sc.flex.freq_hz == rec["flex_mode"]["freq_hz"]
    assert sc.noise.time_tag_jitter_s == 0.0         # replaced by the uniform time tags
    # the true inertia: off the prediction, inside the model file's knowledge box
    v, c = np.asarray(rec["inertia"]["values"]), np.asarray(rec["inertia"]["prediction"])
    assert np.all(np.abs(v - c) <= np.asarray(rec["inertia"]["half_width"]))
    assert not np.allclose(v, c)
    assert sc.truth.inertia[0, 0] == pytest.approx(v[0])
    json.dumps(rec)


def test_draws_are_independent_per_wheel_and_axis():
    n = 300
    rows = [_flat(draw_open_world("slews_post_probe", s).record) for s in range(n)]
    tol = 4.0 / math.sqrt(n)      # 4 standard errors of a zero correlation
    for name in ("gyro_bias_rad_s", "gyro_scale_factor", "wheel_inertia_errors",
                 "external_torque_body_nm"):
        x = np.array([r[name] for r in rows])
        r = np.corrcoef(x, rowvar=False)
        assert np.max(np.abs(r - np.eye(r.shape[0]))) < tol, name
    tilt = np.array([r["wheel_axis_tilt_deg"].ravel() for r in rows])
    r = np.corrcoef(tilt, rowvar=False)
    assert np.max(np.abs(r - np.eye(r.shape[0]))) < tol
    # and across effects: wheel 1's error against the gyro bias about X
    a = np.array([r["wheel_inertia_errors"][0] for r in rows])
    b = np.array([r["gyro_bias_rad_s"][0] for r in rows])
    assert abs(np.corrcoef(a, b)[0, 1]) < tol


def test_solved_wheel_is_not_tilted():
    ow = draw_open_world("rwa4_rcs", 0, solved_wheel="RWA4")
    assert "RWA4" not in ow.scenario["truth"]["wheel_axis_tilt_deg"]
    on = ow.scenario["initial"]["wheels_on"]
    assert "RWA4" in on
    assert ow.record["wheel_axis_tilt_deg"]["wheels"] == [w for w in on if w != "RWA4"]


def test_solved_wheel_keeps_the_scenarios_own_axis():
    """A scenario that tilts the wheel it calibrates (ESPA RW2, 1°) keeps that tilt in the open
    world, also with the drawn tilts switched off: the offset is what the fit must find."""
    from cassini_bayes.simulate.open_world import base_scenario, without

    own = base_scenario("wheel_axis_espa_bus")["truth"]["wheel_axis_tilt_deg"]["RW2"]
    ow = draw_open_world("wheel_axis_espa_bus", 3, solved_wheel="RW2")
    tilts = ow.scenario["truth"]["wheel_axis_tilt_deg"]
    assert tilts["RW2"] == own and set(tilts) == {"RW1", "RW2", "RW3", "RW4"}
    assert "RW2" not in ow.record["wheel_axis_tilt_deg"]["wheels"]
    assert without(ow, ["tilts"]).scenario["truth"]["wheel_axis_tilt_deg"] == {"RW2": own}


def test_time_tags_and_stale_samples():
    ow = draw_open_world("biasing_day028", 5, slip_prob=0.05)
    n = ow.time_tag_error_s.shape[0]
    assert np.count_nonzero(ow.slip) > 0
    assert ow.record["slips"]["index"] == np.flatnonzero(ow.slip).tolist()
    t = np.arange(n, dtype=float)
    tel = Telemetry(t=t, q=np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)),
                    omega=np.arange(3 * n, dtype=float).reshape(n, 3),
                    wheel_rates=np.arange(4 * n, dtype=float).reshape(n, 4), on_times=None)
    out = apply_time_tags(tel, ow)
    np.testing.assert_allclose(out.t, t + ow.time_tag_error_s)
    assert np.all(np.diff(out.t) > 0)
    i = np.flatnonzero(ow.slip)
    np.testing.assert_array_equal(out.omega[i], tel.omega[i + ow.slip[i]])
    keep = ow.slip == 0
    np.testing.assert_array_equal(out.wheel_rates[keep], tel.wheel_rates[keep])
    with pytest.raises(InputError, match="samples"):
        apply_time_tags(Telemetry(t=t[:10], q=tel.q[:10], omega=tel.omega[:10],
                                  wheel_rates=tel.wheel_rates[:10]), ow)


@pytest.mark.slow
def test_campaign_script_end_to_end(tmp_path, capsys):
    """One seed, tiny sampler: the record is written, and a rerun resumes (fits nothing)."""
    spec = importlib.util.spec_from_file_location(
        "coverage_open_world", ROOT / "benchmarks" / "coverage_open_world.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    out = tmp_path / "ow.jsonl"
    args = ["--families", "post_prm", "--seeds", "1", "--models", "per_wheel", "idealised",
            "--chains", "1", "--warmup", "30", "--draws", "30", "--out", str(out)]
    mod.main(args)
    rows = [json.loads(x) for x in out.read_text().splitlines()]
    assert len(rows) == 1 and set(rows[0]["fits"]) == {"per_wheel", "idealised"}
    f = rows[0]["fits"]["per_wheel"]
    assert len(f["hit"]) == 6 and isinstance(f["adequacy_ok"], bool)
    assert rows[0]["drawn"]["wheel_inertia_errors"]["law"] == "uniform"
    mod.main(args)
    assert len(out.read_text().splitlines()) == 1
    assert len(json.loads((tmp_path / "ow.jsonl.manifest.json").read_text())["runs"]) == 2
    assert "post_prm" in capsys.readouterr().out


def test_without_switches_off_only_the_named_effects():
    from cassini_bayes.simulate.open_world import without

    ow = draw_open_world("slews_post_prm", 4)
    off = without(ow, ["drift", "flex", "slips"])
    assert "flex_mode" not in off.scenario and "flex_mode" in ow.scenario
    assert off.scenario["truth"]["external_torque_inertial_rate_nm_s"] == [0.0, 0.0, 0.0]
    assert not np.any(off.slip)
    np.testing.assert_array_equal(off.time_tag_error_s, ow.time_tag_error_s)
    assert off.scenario["truth"]["wheel_inertia_errors"] == ow.scenario["truth"][
        "wheel_inertia_errors"]
    assert off.record["off"] == ["drift", "flex", "slips"]
    with pytest.raises(InputError, match="unknown effect"):
        without(ow, ["sloshing"])


def test_thrusters_drawn_after_every_other_effect():
    """``draw_thrusters``: thrusts within ±5 % of nominal, time constants in the model file's
    ranges, the centre of mass moved; every other draw as without it; a model without
    thrusters is refused."""
    a = draw_open_world("biasing_espa_bus", 3)
    b = draw_open_world("biasing_espa_bus", 3, draw_thrusters=True)
    for k, v in _flat(a.record).items():
        np.testing.assert_array_equal(_flat(b.record)[k], v, err_msg=k)
    sc = scenario_from_dict(b.scenario, src="espa")
    f0 = sc.prior.thrust_per_thruster
    f = np.asarray(b.scenario["truth"]["thrust_n"])
    assert f.shape == f0.shape and np.all(np.abs(f / f0 - 1.0) <= 0.05)
    assert not np.allclose(f, f0)
    for k in ("tau_delay", "tau_rise", "tau_fall"):
        lo, hi = getattr(sc.prior.pulse, f"{k}_range")
        assert lo <= b.scenario["truth"][f"{k}_s"] <= hi
    offset = np.asarray(sc.truth.com_m) - np.asarray(sc.prior.com_m)
    np.testing.assert_allclose(offset, b.record["thrusters"]["center_of_mass_offset_m"]["values"])
    with pytest.raises(InputError, match="no thrusters"):
        draw_open_world("slews_cubesat_12u", 3, draw_thrusters=True)
