"""``check``'s quiet-period rule by default is the one ``fit wheel-axis`` detects its windows
with (issue 29). Cassini's slews flown by a spacecraft 10⁴ times lighter (inertia, wheel inertia,
torques × 1e-4: the same rates) give the same verdicts; flown also ten times slower (slew rates,
angles, accelerations, wheel speeds and every sensor noise × 0.1) the body-rate rule (a third of
the file's top rate) and the attitude check's turning stretches follow the file, and the wheel
tolerance, a wheel rate, comes from the slow spacecraft's model file (``[[wheel]]
quiet_tol_rpm``, docs/model_file.md); Cassini's former absolute rate default (1 mrad/s) and its
2-rpm wheel tolerance do not give the same quiet periods. Fits on the scaled spacecraft:
tests/test_scale_free.py."""

from __future__ import annotations

import copy

import pytest
import tomli_w

import cassini_bayes as cb
from cassini_bayes.errors import InputError
from cassini_bayes.inference.rwa4 import detect_windows
from cassini_bayes.simulate import scenario_from_dict
from cassini_bayes.spacecraft import QUIET_WHEEL_TOL_RPM
from cassini_bayes.windows import quiet_mask
from scaled import scaled_model, scaled_scenario

MASS_SCALE = 1e-4
RATE_SCALE = 0.1


def _slower(d: dict, r: float) -> dict:
    """The scenario dict flown ``r`` times slower: the same timeline, every rate, angle, wheel
    speed and sensor noise × ``r`` (accelerations × ``r``: the same durations)."""
    d = copy.deepcopy(d)
    for slew in d.get("slew", []):
        for k in ("angle_deg", "rate_mrad_s", "accel_mrad_s2"):
            slew[k] *= r
    d["initial"]["wheel_rpm"] = {k: v * r for k, v in d["initial"]["wheel_rpm"].items()}
    d["noise"] = {k: v * r for k, v in d["noise"].items()}
    return d


@pytest.fixture(scope="module")
def flights(tmp_path_factory):
    """Telemetry and model path of Cassini, the 1e-4 spacecraft, and the 1e-4 spacecraft
    flown 10× slower (same simulation key), whose model file states its wheels' quiet
    tolerance 10× Cassini's default."""
    tmp = tmp_path_factory.mktemp("slow")
    out = {}
    for name, s, r in (("cassini", 1.0, 1.0), ("light", MASS_SCALE, 1.0),
                       ("slow", MASS_SCALE, RATE_SCALE)):
        path = tmp / f"{name}.toml"
        model = scaled_model("cassini_post_probe", s)
        if r != 1.0:
            for w in model["wheel"]:
                w["quiet_tol_rpm"] = r * QUIET_WHEEL_TOL_RPM
        path.write_text(tomli_w.dumps(model))
        d = _slower(scaled_scenario("slews_post_probe", s, str(path)), r)
        tel = cb.simulate_scenario(scenario_from_dict(d, "slews_post_probe"), seed=11).telemetry
        out[name] = (tel, str(path))
    return out


def test_a_lighter_spacecraft_gets_the_same_verdicts(flights):
    (tel_a, sc_a), (tel_b, sc_b) = flights["cassini"], flights["light"]
    a = cb.check_telemetry(tel_a, spacecraft=sc_a)
    b = cb.check_telemetry(tel_b, spacecraft=sc_b)
    assert len(a.quiet) >= 5                     # the slews are told apart from the rests
    assert b.quiet == a.quiet and b.physics == a.physics
    assert [w.idle for w in b.wheels] == [w.idle for w in a.wheels]
    assert a.rate_rule == b.rate_rule == "a third of the file's top rate"


def test_a_slower_spacecraft_gets_the_same_quiet_periods(flights):
    """The body-rate bound follows the file's own rates; the wheel tolerance is the model
    file's (``quiet_tol_rpm``: at Cassini's 2 rpm the slow spacecraft's quiet periods end a
    sample earlier or later). ``check``, ``fit wheel-axis``'s window detection and
    ``windows.quiet_mask`` read it from the model alone."""
    (tel_a, sc_a), (tel_b, sc_b) = flights["cassini"], flights["slow"]
    a = cb.check_telemetry(tel_a, spacecraft=sc_a)
    b = cb.check_telemetry(tel_b, spacecraft=sc_b)
    assert b.quiet == a.quiet
    assert b.wheel_tol_rpm == pytest.approx(RATE_SCALE * a.wheel_tol_rpm)
    assert (a.wheel_tol_rule, b.wheel_tol_rule) == ("the default", "the model's quiet_tol_rpm")
    model_a, model_b = cb.load_spacecraft(sc_a), cb.load_spacecraft(sc_b)
    assert (quiet_mask(tel_b, spacecraft=model_b) == quiet_mask(tel_a, spacecraft=model_a)).all()
    assert (detect_windows(tel_b, "rwa", spacecraft=model_b)
            == detect_windows(tel_a, "rwa", spacecraft=model_a))
    # the test can fail: at Cassini's 2 rpm the slow spacecraft's quiet periods differ
    assert cb.check_telemetry(tel_b, spacecraft=sc_b, wheel_tol_rpm=2.0).quiet != a.quiet
    assert [w.idle for w in b.wheels] == [w.idle for w in a.wheels]
    # the same physics verdicts, and the attitude check cuts the same turning stretches (its
    # turn is relative to the file's attitude and gyro noise, consistency/_attitude.py)
    for line in (a.physics, b.physics):
        assert line.startswith("q vs ω consistent") and "wheel rpm confirmed" in line
    assert b.attitude.segments == a.attitude.segments
    assert b.attitude.turn_rad == pytest.approx(RATE_SCALE * a.attitude.turn_rad, rel=1e-3)
    assert b.attitude.alignment[0] == pytest.approx(a.attitude.alignment[0], abs=1e-5)
    assert b.attitude.scale == pytest.approx(a.attitude.scale, abs=1e-4)
    assert b.rate_max_rad_s == pytest.approx(RATE_SCALE * a.rate_max_rad_s, rel=0.05)
    # the test can fail: with Cassini's former absolute rate default the slow slews are quiet
    old = cb.check_telemetry(tel_b, spacecraft=sc_b, rate_max_rad_s=1e-3)
    assert old.quiet != a.quiet


def test_explicit_options_override_and_bad_ones_are_one_line(flights):
    tel, sc = flights["cassini"]
    c = cb.check_telemetry(tel, spacecraft=sc, rate_max_rad_s=1.0, wheel_tol_rpm=1e4)
    assert c.rate_rule == c.wheel_tol_rule == "given" and c.rate_max_rad_s == 1.0
    assert len(c.quiet) == 1
    for kw, where in (({"rate_max_rad_s": 0.0}, "rate_max_rad_s"),
                      ({"wheel_tol_rpm": float("nan")}, "wheel_tol_rpm")):
        with pytest.raises(InputError, match=f"{where}: must be a positive finite number"):
            cb.check_telemetry(tel, spacecraft=sc, **kw)

