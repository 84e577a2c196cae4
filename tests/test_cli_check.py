"""``cassini-bayes check``: what it prints for valid files and how it fails for bad ones.

(Every bad-input rule of the readers is exercised through ``check`` in test_telemetry.py.)
"""

from __future__ import annotations

import numpy as np
import pytest

from cassini_bayes.telemetry import (
    RPM_TO_RAD_S,
    PulseLog,
    Telemetry,
    cumulative_on_times,
    write_pulses,
    write_telemetry,
)


def _tel(with_on: bool = False) -> Telemetry:
    """600 s at 2 Hz: quiet, a 100 s wheel slew (RWA1 500 → 1000 rpm), quiet."""
    t = np.arange(0.0, 600.0, 0.5)
    n = t.size
    ramp = np.clip((t - 200.0) / 100.0, 0, 1)
    wz = np.where((t > 200) & (t < 300), 1e-3 * np.sin(np.pi * (t - 200.0) / 100.0), 0.0)
    ang = np.concatenate([[0.0], np.cumsum(0.5 * (wz[1:] + wz[:-1]) * 0.5)])
    q = np.stack([np.zeros(n), np.zeros(n), np.sin(ang / 2), np.cos(ang / 2)], 1)
    rpm = np.stack([500 + 500 * ramp, -500 - 500 * ramp, np.full(n, 300.0), np.full(n, np.nan)], 1)
    on = None
    if with_on:
        on = cumulative_on_times(PulseLog(np.array([450.0, 460.0]), np.array([5, 7]),
                                          np.array([0.125, 0.25])), t)
    return Telemetry(t, q, np.stack([0 * t, 0 * t, wz], 1), rpm * RPM_TO_RAD_S, on_times=on)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("check")
    write_telemetry(d / "slew.csv", _tel())
    write_telemetry(d / "slew_on.csv", _tel(with_on=True))
    write_pulses(d / "pulses.csv", PulseLog(np.array([450.0, 460.0, 470.0]),
                                            np.array([5, 7, 5]), np.array([0.125, 0.25, 0.0625])))
    write_pulses(d / "late.csv", PulseLog(np.array([450.0, 700.0]), np.array([5, 5]),
                                          np.array([0.125, 0.1])))
    write_pulses(d / "straddle.csv", PulseLog(np.array([-0.2]), np.array([0]), np.array([0.5])))
    write_pulses(d / "tail.csv", PulseLog(np.array([599.4]), np.array([0]), np.array([0.5])))
    (d / "none.csv").write_text("t_on,thruster,width\n")
    return d


def test_check_summarises_a_valid_file(files, run_cli):
    code, out, err = run_cli("check", files / "slew.csv")
    assert code == 0, err
    assert err == ""
    text = " ".join(out.split())
    assert "valid telemetry" in text
    assert "rows 1200" in text
    assert "0 to 599.5 s (599.5 s)" in text
    assert "2 Hz (median step 0.5 s)" in text
    assert "RWA1 │ on │ 500.00 │ 1000.00" in text
    assert "RWA2 │ on │ -1000.00 │ -500.00" in text
    assert "RWA4 │ off (no data)" in text
    assert "no on_* columns and no pulse log" in text
    assert "2 quiet period(s), 1 slew(s)" in text


def test_library_check_says_what_the_command_prints(files):
    """``cassini_bayes.check_telemetry`` is what ``check`` prints, as data."""
    import cassini_bayes as cb

    c = cb.check_telemetry(files / "slew.csv", pulses=files / "pulses.csv")
    assert c.n == 1200 and c.sampling() == "2 Hz (median step 0.5 s)"
    assert [(w.name, w.on) for w in c.wheels] == [("RWA1", True), ("RWA2", True),
                                                   ("RWA3", True), ("RWA4", False)]
    assert (c.wheels[0].min_rpm, c.wheels[0].max_rpm) == pytest.approx((500.0, 1000.0))
    assert [(k.name, k.pulses) for k in c.thrusters] == [("Y2", 2), ("Y4", 1)]
    assert c.n_pulses == 3 and len(c.quiet) == 3
    assert "give spacecraft" in c.physics       # an argument, not a flag, from Python


def test_check_with_pulse_log(files, run_cli):
    code, out, err = run_cli("check", files / "slew.csv", "--pulses", files / "pulses.csv")
    assert code == 0, err
    text = " ".join(out.split())
    assert "Thrusters (from pulse log" in text
    assert "Y2 │ 2 │ 0.1875" in text
    assert "Y4 │ 1 │ 0.25" in text
    assert "valid pulse log, 3 pulses" in text
    assert "3 quiet period(s)" in text  # the pulses split the second quiet stretch


def test_check_with_on_time_columns(files, run_cli):
    code, out, err = run_cli("check", files / "slew_on.csv")
    assert code == 0, err
    text = " ".join(out.split())
    assert "Thrusters (from on_* columns)" in text
    assert "Y2 │ 1 │ 0.125" in text and "Y4 │ 1 │ 0.25" in text


def test_pulses_outside_span_and_straddling_warn(files, run_cli):
    code, out, err = run_cli("check", files / "slew.csv", "--pulses", files / "late.csv")
    assert code == 0, err
    assert "warning:" in out and "1 of 2 pulses lie outside" in " ".join(out.split())
    code, out, err = run_cli("check", files / "slew.csv", "--pulses", files / "straddle.csv")
    assert code == 0, err
    text = " ".join(out.split())
    assert "straddle.csv: pulse of Z1 at t_on = -0.2 s" in text
    assert "first telemetry sample t = 0 s" in text and "only what it does after" in text
    assert "Z1 │ 1 │ 0.3" in text  # on-time counted from the first sample: -0.2 + 0.5 → 0.3 s
    code, out, err = run_cli("check", files / "slew.csv", "--pulses", files / "tail.csv")
    assert code == 0, err
    text = " ".join(out.split())
    assert "still on at the last sample" in text
    assert "Z1 │ 1 │ 0.1" in text  # 599.4 → 599.5 s counted
    code, out, err = run_cli("check", files / "slew.csv", "--pulses", files / "none.csv")
    assert code == 0, err
    assert "none fired" in out and "valid pulse log, 0 pulses" in out


def test_check_is_listed_in_help(run_cli):
    code, out, _ = run_cli("--help")
    assert code == 0 and "check" in out
    code, out, _ = run_cli("check", "--help")
    assert code == 0 and "--pulses" in out


def test_no_unit_check_accepts_slow_wheels(tmp_path, run_cli):
    p = tmp_path / "idle.csv"
    p.write_text("t,q1,q2,q3,q4,wx,wy,wz,rwa1\n0,0,0,0,1,0,0,0,5\n1,0,0,0,1,0,0,0,5.5\n")
    code, _, err = run_cli("check", p)
    assert code == 2 and "--no-unit-check" in err
    code, out, err = run_cli("check", p, "--no-unit-check")
    assert code == 0, err
    assert "RWA1 │ on │ 5.00 │ 5.50" in " ".join(out.split())
