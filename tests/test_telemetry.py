"""Telemetry and pulse-log files: round trips, unit conversion, every bad input.

File formats: docs/design.md §4.1-4.2.

Each bad input is checked twice: the library raises ``InputError`` with one line that names the
file and the column/row, and ``cassini-bayes check`` turns it into ``error: …`` with exit code 2.
"""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

from cassini_bayes.errors import InputError
from cassini_bayes.frames import dcm, quat_continuous
from cassini_bayes.telemetry import (
    RPM_TO_RAD_S,
    THRUSTER_NAMES,
    PulseLog,
    PulseAtStartWarning,
    PulseSpanWarning,
    Telemetry,
    check_pulses_in_span,
    cumulative_on_times,
    read_pulses,
    read_telemetry,
    read_telemetry_many,
    validate_telemetry,
    with_on_times,
    write_pulses,
    write_telemetry,
)

HEADER = "t,q1,q2,q3,q4,wx,wy,wz,rwa1,rwa2,rwa3,rwa4"


def _slew(n: int = 200, seed: int = 0) -> Telemetry:
    """A small slew about z with irrational-looking floats (full 17-digit values)."""
    rng = np.random.default_rng(seed)
    t = 100.0 + np.cumsum(rng.uniform(0.2, 0.3, n))
    wz = 2e-3 * np.sin(np.pi * (t - t[0]) / (t[-1] - t[0]))
    ang = np.concatenate([[0.0], np.cumsum(0.5 * (wz[1:] + wz[:-1]) * np.diff(t))])
    axis = np.array([0.1, -0.2, 1.0]) / np.linalg.norm([0.1, -0.2, 1.0])
    q = np.concatenate([np.sin(ang / 2)[:, None] * axis, np.cos(ang / 2)[:, None]], 1)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w = wz[:, None] * axis + rng.normal(0, 1e-6, (n, 3))
    rpm = np.stack([600 + 300 * np.sin(t / 50), -800 + 10 * np.cos(t / 7),
                    1500 + rng.normal(0, 0.3, n), np.full(n, np.nan)], 1)
    return Telemetry(t, q, w, rpm * RPM_TO_RAD_S, source="mem")


def _csv(tmp_path, name: str, lines: list[str]) -> str:
    p = tmp_path / name
    p.write_text("\n".join(lines) + "\n")
    return str(p)


def _good_lines(n: int = 8) -> list[str]:
    rows = [HEADER]
    for i in range(n):
        rows.append(f"{i * 0.5},0,0,0,1,0,0,0,{600 + i},{-700 - i},900,")
    return rows


# --------------------------------------------------------------------------------------------
# round trips and units


def test_round_trip_full_precision(tmp_path):
    tel = _slew()
    path = tmp_path / "slew.csv"
    write_telemetry(path, tel)
    back = read_telemetry(path)
    np.testing.assert_array_equal(back.t, tel.t)
    np.testing.assert_array_equal(back.q, tel.q)
    np.testing.assert_array_equal(back.omega, tel.omega)
    # rad/s → rpm (file) → rad/s: within one rounding of each conversion
    np.testing.assert_allclose(back.wheel_rates[:, :3], tel.wheel_rates[:, :3], rtol=4e-16, atol=0)
    assert np.all(np.isnan(back.wheel_rates[:, 3]))
    assert back.active_wheels() == ("RWA1", "RWA2", "RWA3")
    assert back.on_times is None
    assert back.source == str(path)


def test_written_files_get_the_users_mode(tmp_path):
    """Atomic writes go through ``mkstemp`` (mode 0600); the file ends with the mode ``open``
    would give under the umask, as truth.json and the report do."""
    import os

    old = os.umask(0o022)
    try:
        write_telemetry(tmp_path / "a.csv", _slew(10))
        write_pulses(tmp_path / "p.csv", PulseLog(np.array([1.0]), np.array([0]),
                                                  np.array([0.1])))
    finally:
        os.umask(old)
    for name in ("a.csv", "p.csv"):
        assert (tmp_path / name).stat().st_mode & 0o777 == 0o644


def test_round_trip_with_on_times_and_pulses(tmp_path):
    tel = _slew(50)
    on = np.zeros((tel.n, 8))
    on[25:, 5] = 0.0625
    tel = Telemetry(tel.t, tel.q, tel.omega, tel.wheel_rates, on_times=on)
    write_telemetry(tmp_path / "a.csv", tel)
    back = read_telemetry(tmp_path / "a.csv")
    np.testing.assert_array_equal(back.on_times, on)
    log = PulseLog(np.array([1.25, 0.1, 3.0]), np.array([5, 7, 5]), np.array([0.05, 0.125, 0.2]))
    write_pulses(tmp_path / "p.csv", log)
    got = read_pulses(tmp_path / "p.csv")
    np.testing.assert_array_equal(got.t_on, [0.1, 1.25, 3.0])  # sorted by time
    assert got.names == ["Y4", "Y2", "Y2"]
    np.testing.assert_array_equal(got.width, [0.125, 0.05, 0.2])


def test_rpm_in_file_rad_s_inside(tmp_path):
    p = _csv(tmp_path, "w.csv", [HEADER, "0,0,0,0,1,0,0,0,60,-1800,0,",
                                 "1,0,0,0,1,0,0,0,60,-1800,0,"])
    tel = read_telemetry(p)
    np.testing.assert_allclose(tel.wheel_rate("RWA1"), 2 * np.pi)  # 60 rpm = 2π rad/s
    np.testing.assert_allclose(tel.wheel_rate("rwa2"), -60 * np.pi)  # −1800 rpm
    np.testing.assert_array_equal(tel.wheel_rate("RWA3"), 0.0)  # a wheel at rest is fine
    assert np.all(np.isnan(tel.wheel_rate("RWA4")))
    out = tmp_path / "w2.csv"
    write_telemetry(out, tel)
    assert out.read_text().splitlines()[1].split(",")[8:12] == ["60.0", "-1800.0", "0.0", ""]


def test_absent_wheel_columns_and_case_insensitive_header(tmp_path):
    p = _csv(tmp_path, "h.csv", ["T,Q1,Q2,Q3,Q4,WX,WY,WZ,RWA3", "0,0,0,0,1,0,0,0,850",
                                 "2,0,0,0,1,0,0,0,850"])
    tel = read_telemetry(p)
    assert tel.active_wheels() == ("RWA3",)
    assert tel.wheel_rates.shape == (2, 4)


def test_real_rpm_ranges_never_trip_the_rad_s_check(tmp_path):
    t = np.arange(400.0)
    for profile in (np.linspace(0, 1800, 400), np.linspace(0, 2000, 400), np.full(400, 0.0),
                    np.random.default_rng(1).normal(0, 0.5, 400), np.linspace(-20, 20, 400),
                    np.full(400, -850.0)):
        rates = np.stack([profile] * 3 + [np.full(400, np.nan)], 1) * RPM_TO_RAD_S
        tel = Telemetry(t, np.tile([0, 0, 0, 1.0], (400, 1)), np.zeros((400, 3)), rates)
        validate_telemetry(tel)


def test_sign_flips_are_accepted_and_removed(tmp_path):
    tel = _slew(60)
    q = tel.q.copy()
    q[10:20] *= -1
    q[40] *= -1
    p = tmp_path / "flip.csv"
    write_telemetry(p, Telemetry(tel.t, q, tel.omega, tel.wheel_rates))
    q_file = np.loadtxt(p, delimiter=",", skiprows=1, usecols=(1, 2, 3, 4))
    np.testing.assert_array_equal(q_file, q)  # the file holds the flips as given
    back = read_telemetry(p)
    np.testing.assert_array_equal(back.q, tel.q)  # continuous again, bit for bit
    np.testing.assert_array_equal(back.q, np.asarray(quat_continuous(q)))  # frames' rule
    for i in (9, 10, 19, 20, 40):  # the same attitudes
        np.testing.assert_allclose(np.asarray(dcm(back.q[i])), np.asarray(dcm(q[i])), atol=1e-15)


def test_genuine_attitude_jump_is_not_an_error(tmp_path):
    lines = [HEADER, "0,0,0,0,1,0,0,0,600,,,", "1,0,0,0,1,0,0,0,600,,,",
             "2,0,0,0.7071067811865476,0.7071067811865476,0,0,0,600,,,"]
    tel = read_telemetry(_csv(tmp_path, "jump.csv", lines))
    np.testing.assert_allclose(tel.q[2], [0, 0, 0.7071067811865476, 0.7071067811865476])


def test_near_unit_quaternion_renormalised(tmp_path):
    lines = [HEADER, "0,0,0,0,1.0009,0,0,0,600,,,", "1,0,0,0.6,0.8,0,0,0,600,,,"]
    tel = read_telemetry(_csv(tmp_path, "n.csv", lines))
    np.testing.assert_allclose(np.linalg.norm(tel.q, axis=1), 1.0, atol=1e-15)
    np.testing.assert_array_equal(tel.q[1], [0, 0, 0.6, 0.8])  # already unit: untouched


def test_atomic_write_refuses_to_overwrite(tmp_path):
    tel = _slew(20)
    p = tmp_path / "t.csv"
    write_telemetry(p, tel)
    before = p.read_bytes()
    with pytest.raises(InputError, match=r"t\.csv: already exists.*force=True"):
        write_telemetry(p, tel)
    assert p.read_bytes() == before
    tel2 = Telemetry(tel.t + 1.0, tel.q, tel.omega, tel.wheel_rates)
    write_telemetry(p, tel2, force=True)
    assert read_telemetry(p).t[0] == tel.t[0] + 1.0
    assert sorted(x.name for x in tmp_path.iterdir()) == ["t.csv"]  # no temp file left
    with pytest.raises(InputError, match="already exists"):
        write_pulses(p, PulseLog(np.array([0.0]), np.array([0]), np.array([0.1])))


def test_parquet_without_pyarrow_is_a_clear_error(tmp_path):
    pytest.importorskip("pandas")
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        p = tmp_path / "x.parquet"
        p.write_bytes(b"PAR1")
        with pytest.raises(InputError, match=r"x\.parquet: Parquet needs pyarrow"):
            read_telemetry(p)
        with pytest.raises(InputError, match="pyarrow"):
            write_telemetry(tmp_path / "y.parquet", _slew(10))
    else:
        tel = _slew(30)
        write_telemetry(tmp_path / "x.parquet", tel)
        np.testing.assert_array_equal(read_telemetry(tmp_path / "x.parquet").q, tel.q)


def test_read_many(tmp_path):
    write_telemetry(tmp_path / "a.csv", _slew(20, 1))
    write_telemetry(tmp_path / "b.csv", _slew(30, 2))
    tels = read_telemetry_many([tmp_path / "a.csv", tmp_path / "b.csv"])
    assert [x.n for x in tels] == [20, 30]
    with pytest.raises(InputError, match="no telemetry files"):
        read_telemetry_many([])
    with pytest.raises(InputError, match=r"c\.csv: telemetry file not found"):
        read_telemetry_many([tmp_path / "a.csv", tmp_path / "c.csv"])


# --------------------------------------------------------------------------------------------
# cumulative on-times


def test_cumulative_on_times_matches_the_clip_sum():
    log = PulseLog(np.array([1.0, 1.02, 2.0, 2.5, 7.0]), np.array([5, 7, 5, 0, 5]),
                   np.array([0.05, 0.1, 0.2, 1.0, 0.3]))
    t = np.linspace(0.0, 8.0, 801)
    got = cumulative_on_times(log, t)
    want = np.zeros((t.size, 8))
    for t_on, k, w in zip(log.t_on, log.thruster, log.width):
        want[:, k] += np.clip(t - t_on, 0.0, w)
    np.testing.assert_allclose(got, want - want[0], atol=1e-14)
    np.testing.assert_allclose(got[-1, [0, 5, 7]], [1.0, 0.55, 0.1], atol=1e-14)
    tel = Telemetry(t, np.tile([0, 0, 0, 1.0], (t.size, 1)), np.zeros((t.size, 3)),
                    np.zeros((t.size, 4)))
    np.testing.assert_allclose(with_on_times(tel, log).on_times, got)


def test_pulses_outside_span_warn_and_straddling_is_kept_with_a_warning():
    """A pulse on at the first sample is kept (one warning naming it); its on-time counts from
    that sample. With a thrust tail (``tail_s``) a pulse whose command ended just before the
    first sample still acts on the data and is kept too."""
    t = np.linspace(10.0, 20.0, 11)
    tel = Telemetry(t, np.tile([0, 0, 0, 1.0], (11, 1)), np.zeros((11, 3)), np.zeros((11, 4)),
                    source="tel.csv")
    log = PulseLog(np.array([1.0, 12.0, 25.0]), np.array([1, 1, 1]), np.array([0.1] * 3),
                   source="p.csv")
    with pytest.warns(PulseSpanWarning, match="2 of 3 pulses lie outside"):
        kept = check_pulses_in_span(log, tel)
    np.testing.assert_array_equal(kept.t_on, [12.0])
    on = PulseLog(np.array([9.95]), np.array([6]), np.array([0.1]), source="p.csv")
    with pytest.warns(PulseAtStartWarning,
                      match=r"p\.csv: pulse of Y3 at t_on = 9\.95 s .*first telemetry sample "
                            r"t = 10 s of tel\.csv; only what it does after"):
        assert check_pulses_in_span(on, tel).t_on.size == 1
    np.testing.assert_allclose(cumulative_on_times(on, t)[-1, 6], 0.05)
    ended = PulseLog(np.array([9.8]), np.array([6]), np.array([0.1]), source="p.csv")
    with pytest.warns(PulseSpanWarning, match="1 of 1 pulses lie outside"):
        assert check_pulses_in_span(ended, tel).t_on.size == 0
    with pytest.warns(PulseAtStartWarning, match="t_on = 9.8 s .* still decaying at the first"):
        assert check_pulses_in_span(ended, tel, tail_s=1.5).t_on.size == 1
    tail = PulseLog(np.array([19.95]), np.array([6]), np.array([0.1]), source="p.csv")
    with pytest.warns(PulseSpanWarning, match="still on at the last sample"):
        assert check_pulses_in_span(tail, tel).t_on.size == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_pulses_in_span(PulseLog(np.array([15.0]), np.array([0]), np.array([0.1])), tel)


# --------------------------------------------------------------------------------------------
# bad inputs: library message and CLI exit code


def _edit(lines, row, col, value):
    """Replace data row ``row`` (1-based), column ``col`` of a CSV given as lines."""
    header = lines[0].split(",")
    cells = lines[row].split(",")
    cells[header.index(col)] = value
    out = list(lines)
    out[row] = ",".join(cells)
    return out


def _with_column(lines, name, values):
    return [lines[0] + "," + name] + [ln + "," + v for ln, v in zip(lines[1:], values)]


def _without_column(lines, name):
    j = lines[0].split(",").index(name)
    return [",".join(c for k, c in enumerate(ln.split(",")) if k != j) for ln in lines]


def _rad_s_lines():
    lines = _good_lines()
    return [ln if i == 0 else ",".join(ln.split(",")[:9] + ["9.4", "-8.1", ""])
            for i, ln in enumerate(lines)]


def _deg_s_lines():
    # 0.1 rad turn about z at 1 mrad/s, rates written in deg/s (0.0573: below the 0.2 limit)
    lines = [HEADER]
    for i in range(101):
        a = 0.001 * i
        lines.append(f"{i},0,0,{float(np.sin(a / 2))!r},{float(np.cos(a / 2))!r},0,0,"
                     f"{float(np.degrees(0.001))!r},"
                     "600,-600,600,")
    return lines


def _time_in_ms_lines():
    # the same 0.1 rad turn in rad/s, the time column in milliseconds: ∫ω dt 1000x the turn
    lines = [HEADER]
    for i in range(101):
        a = 0.001 * i
        lines.append(f"{1000 * i},0,0,{float(np.sin(a / 2))!r},{float(np.cos(a / 2))!r},0,0,"
                     "0.001,600,-600,600,")
    return lines


BAD_TELEMETRY = {
    # id: (file lines, things the one-line message must contain)
    "missing-column": (lambda: _without_column(_good_lines(), "wy"), ["missing column 'wy'"]),
    "unknown-column": (lambda: _with_column(_good_lines(), "rwa5", ["1"] * 8),
                       ["unknown column 'rwa5'", "rename or remove"]),
    "duplicate-column": (lambda: _with_column(_good_lines(), "wx", ["0"] * 8),
                         ["duplicate column 'wx'"]),
    "non-numeric": (lambda: _edit(_good_lines(), 3, "wz", "abc"),
                    ["column 'wz', data row 3", "'abc' is not a number"]),
    "empty-required": (lambda: _edit(_good_lines(), 4, "q2", ""),
                       ["column 'q2', data row 4 (t = 1.5 s) is empty or NaN"]),
    "nan-required": (lambda: _edit(_good_lines(), 2, "wx", "nan"),
                     ["column 'wx', data row 2 (t = 0.5 s) is empty or NaN"]),
    "infinite": (lambda: _edit(_good_lines(), 2, "wx", "inf"), ["column 'wx'", "infinite"]),
    "partial-wheel": (lambda: _edit(_good_lines(), 5, "rwa2", ""),
                      ["column 'rwa2', data row 5", "off must be empty in every row"]),
    "duplicate-time": (lambda: _edit(_good_lines(), 4, "t", "1.0"),
                       ["'t' is not strictly increasing",
                        "data row 4 (t = 1 s) repeats data row 3"]),
    "time-goes-back": (lambda: _edit(_good_lines(), 6, "t", "0.7"),
                       ["not strictly increasing", "data row 6", "goes back"]),
    "non-unit-quaternion": (lambda: _edit(_good_lines(), 5, "q4", "1.01"),
                            ["q1..q4, data row 5 (t = 2 s)", "norm 1.01", "tolerance 0.001"]),
    "wheel-rad-s": (_rad_s_lines, ["column 'rwa2' looks like rad/s (max |value| 9.4)",
                                   "multiply by 60/(2*pi)"]),
    "omega-huge": (lambda: _edit(_good_lines(), 3, "wy", "0.5"),
                   ["wx wy wz, data row 3 (t = 1 s)", "|ω| = 0.5", "must be in rad/s"]),
    "omega-deg-s": (_deg_s_lines, ["wx wy wz", "look like deg/s", "57.2958"]),
    "time-in-ms": (_time_in_ms_lines, ["look like mrad/s (divide by 1000), or the time column t "
                                       "is in milliseconds (median step 1000 s"]),
    "ragged-row": (lambda: _good_lines()[:3] + [_good_lines()[3] + ",7"] + _good_lines()[4:],
                   ["data row 3 has 13 fields but the header has 12"]),
    "header-only": (lambda: [HEADER], ["header but no data rows"]),
    "single-row": (lambda: _good_lines(1), ["only 1 sample(s)", "at least two rows"]),
    "on-time-decreasing": (lambda: _with_column(_good_lines(), "on_Y2",
                                                ["0", "0", "0.05", "0.04", "0.04", "0.04", "0.04",
                                                 "0.04"]),
                           ["column 'on_Y2', data row 4", "decreases"]),
    "on-time-ms": (lambda: _with_column(_good_lines(), "on_Z1",
                                        ["0", "0", "50", "50", "50", "50", "50", "50"]),
                   ["column 'on_Z1', data row 3", "cumulative seconds"]),
}


@pytest.mark.parametrize("case", sorted(BAD_TELEMETRY))
def test_bad_telemetry(tmp_path, run_cli, case):
    make, needles = BAD_TELEMETRY[case]
    path = _csv(tmp_path, f"{case}.csv", make())
    with pytest.raises(InputError) as info:
        read_telemetry(path)
    msg = str(info.value)
    assert "\n" not in msg
    assert msg.startswith(path + ":")
    for needle in needles:
        assert needle in msg, msg
    code, out, err = run_cli("check", path)
    assert code == 2
    assert err.strip() == f"error: {msg}"
    assert "Traceback" not in err + out


def test_missing_and_empty_files(tmp_path, run_cli):
    code, _, err = run_cli("check", tmp_path / "nope.csv")
    assert code == 2 and "nope.csv: telemetry file not found" in err
    (tmp_path / "empty.csv").write_text("")
    code, _, err = run_cli("check", tmp_path / "empty.csv")
    assert code == 2 and "empty.csv: telemetry file is empty" in err
    (tmp_path / "blank.csv").write_text("\n\n")
    code, _, err = run_cli("check", tmp_path / "blank.csv")
    assert code == 2 and "blank.csv: telemetry file is empty" in err


def test_mismatched_lengths_in_memory(tmp_path):
    tel = _slew(20)
    bad = Telemetry(tel.t, tel.q[:-1], tel.omega, tel.wheel_rates, source="sim")
    with pytest.raises(InputError, match=r"sim: mismatched lengths: 'q' has shape \(19, 4\)"):
        write_telemetry(tmp_path / "m.csv", bad)
    assert not (tmp_path / "m.csv").exists()
    with pytest.raises(InputError, match="mismatched lengths"):
        cumulative_on_times(PulseLog(np.zeros(2), np.zeros(3, int), np.ones(2)), tel.t)


def test_check_units_can_be_turned_off(tmp_path):
    path = _csv(tmp_path, "slow.csv", _rad_s_lines())
    tel = read_telemetry(path, check_units=False)
    np.testing.assert_allclose(tel.wheel_rate("RWA2")[0], 9.4 * RPM_TO_RAD_S)


PULSE_HEADER = "t_on,thruster,width"
BAD_PULSES = {
    "unknown-thruster": (["1.0,Y2,0.05", "2.0,Z5,0.05"],
                         ["column 'thruster', data row 2 (t_on = 2 s)", "unknown thruster 'Z5'",
                          "Z1 Z2 Z3 Z4 Y1 Y2 Y3 Y4"]),
    "zero-width": (["1.0,Y2,0.05", "2.0,Y4,0"],
                   ["column 'width', data row 2 (t_on = 2 s)", "must be positive"]),
    "negative-width": (["1.0,Y2,-0.05"], ["column 'width', data row 1", "must be positive"]),
    "non-increasing": (["1.0,Y2,0.05", "3.0,Y4,0.05", "1.0,Y2,0.05"],
                       ["thruster Y2: t_on is not increasing", "data row 3 (t_on = 1 s)"]),
    "overlap": (["1.0,Z1,0.5", "1.2,Z1,0.1"],
                ["thruster Z1: overlapping pulses", "data row 1", "data row 2 (t_on = 1.2 s)",
                 "merge them into one pulse"]),
    "widths-in-ms": (["1.0,Z1,125", "1.5,Z1,125"],
                     ["thruster Z1: overlapping pulses", "the widths look like milliseconds "
                      "(median 125): the format wants seconds"]),
    "non-numeric": (["1.0,Z1,abc"], ["column 'width', data row 1: 'abc' is not a number"]),
    "missing-column": (None, ["missing column 'width'"]),
}


@pytest.mark.parametrize("case", sorted(BAD_PULSES))
def test_bad_pulses(tmp_path, run_cli, case):
    rows, needles = BAD_PULSES[case]
    lines = ["t_on,thruster", "1.0,Y2"] if rows is None else [PULSE_HEADER] + rows
    ppath = _csv(tmp_path, f"{case}-pulses.csv", lines)
    with pytest.raises(InputError) as info:
        read_pulses(ppath)
    msg = str(info.value)
    assert msg.startswith(ppath + ":") and "\n" not in msg
    for needle in needles:
        assert needle in msg, msg
    tpath = _csv(tmp_path, "tel.csv", _good_lines())
    code, _, err = run_cli("check", tpath, "--pulses", ppath)
    assert code == 2
    assert err.strip() == f"error: {msg}"


def test_pulse_thruster_names_case_insensitive(tmp_path):
    log = read_pulses(_csv(tmp_path, "p.csv", [PULSE_HEADER, "0.5, y2 ,0.05", "0.7,z4,0.1"]))
    assert log.names == ["Y2", "Z4"]
    assert list(THRUSTER_NAMES).index("Z4") == log.thruster[1]


def test_trailing_comma_in_header_and_directories(tmp_path, run_cli):
    path = _csv(tmp_path, "trail.csv", [HEADER + ","] + [ln + "," for ln in _good_lines()[1:]])
    with pytest.raises(InputError, match=r"trail\.csv: unknown column '\(blank, position 13\)'"):
        read_telemetry(path)
    code, _, err = run_cli("check", tmp_path)
    assert code == 2 and "is a directory" in err
    with pytest.raises(InputError, match="does not exist; create it first"):
        write_telemetry(tmp_path / "no" / "such.csv", _slew(10))


def test_on_times_rebased_and_missing_thrusters_zero(tmp_path):
    lines = _with_column(_good_lines(), "on_Y2", ["5", "5", "5.05", "5.05", "5.05", "5.05",
                                                  "5.05", "5.05"])
    tel = read_telemetry(_csv(tmp_path, "on.csv", lines))
    np.testing.assert_allclose(tel.on_times[:, 5], [0, 0, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05],
                               atol=1e-15)
    np.testing.assert_array_equal(np.delete(tel.on_times, 5, axis=1), 0.0)


def test_common_export_mistakes_are_named(tmp_path):
    """A semicolon- or tab-separated export and a gzip-compressed file get a message saying
    what to do, not "unknown column" or "not text"."""
    import gzip

    text = "\n".join(_good_lines())
    for sep, name in ((";", "semi.csv"), ("\t", "tabs.tsv")):
        (tmp_path / name).write_text(text.replace(",", sep))
        with pytest.raises(InputError, match=re.escape(f"split by {sep!r}: ") + ".* commas"):
            read_telemetry(tmp_path / name)
    (tmp_path / "t.csv.gz").write_bytes(gzip.compress(text.encode()))
    with pytest.raises(InputError, match="gzip-compressed; decompress it"):
        read_telemetry(tmp_path / "t.csv.gz")


def test_a_toml_file_with_a_byte_order_mark_loads(tmp_path):
    from cassini_bayes._paths import MODELS_DIR
    from cassini_bayes.spacecraft import load_spacecraft

    p = tmp_path / "m.toml"
    p.write_bytes(b"\xef\xbb\xbf" + (MODELS_DIR / "cassini_post_probe.toml").read_bytes())
    assert load_spacecraft(p).name == load_spacecraft("cassini_post_probe").name



def test_a_wheel_dropout_and_a_pulse_log_of_another_time_base_say_what_to_do(tmp_path):
    """A wheel empty in some rows: remove the rows or split the file (not "fill the gap", which
    invents data). A pulse log none of whose pulses touches the telemetry's span (an epoch
    offset between the files): `check` refuses, giving both spans (it had said "none fired")."""
    from cassini_bayes.api import check_telemetry

    lines = _good_lines()
    lines[3] = lines[3].rsplit(",", 3)[0] + ",,900,"          # rwa2 empty in one row
    with pytest.raises(InputError, match="remove those rows or split the file there"):
        read_telemetry(_csv(tmp_path, "dropout.csv", lines))
    tel = _csv(tmp_path, "tel.csv", _good_lines())
    far = _csv(tmp_path, "far.csv", [PULSE_HEADER, "700000001.0,Z1,0.1"])
    with pytest.raises(InputError, match=r"none of its 1 pulses \(t_on 700000001..700000001 s\) "
                                         r"falls inside the telemetry span 0..3.5 s"):
        check_telemetry(tel, pulses=far)
