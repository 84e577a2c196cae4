"""Input that is well-formed but absurd, and resources that must stay bounded (docs/limits.md).

Every case is one :class:`InputError` line naming the file and the key, column or row; the fuzz
tests mutate good telemetry, pulse, spacecraft and scenario files at random (huge numbers, NaN,
text, deleted columns, truncation, non-UTF-8 bytes) and require that reading either succeeds or
raises ``InputError`` — never another exception, and no overflow warning (warnings are errors
inside them). Hypothesis runs derandomized, so the examples are the same on every run.
"""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import cassini_bayes.telemetry as telemetry
from cassini_bayes._paths import MODELS_DIR, SCENARIOS_DIR
from cassini_bayes.errors import InputError
from cassini_bayes.simulate.scenario import MAX_STEPS, load_scenario
from cassini_bayes.spacecraft import load_spacecraft
from cassini_bayes.telemetry import (PulseLog, Telemetry, read_pulses, read_telemetry,
                                     read_telemetry_many, validate_pulses)

HEADER = "t,q1,q2,q3,q4,wx,wy,wz,rwa1,rwa2,rwa3,rwa4,on_Z1,on_Y2"
GOOD_SC = (MODELS_DIR / "cassini_pre_soi.toml").read_text()
GOOD_SCENARIO = (SCENARIOS_DIR / "biasing_day049.toml").read_text()
FUZZ = settings(max_examples=150, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture])


def _tel_lines(n: int = 12) -> list[str]:
    rows = [HEADER]
    for i in range(n):
        a = 1e-4 * i
        qz, qw = float(np.sin(a / 2)), float(np.cos(a / 2))
        rows.append(f"{100 + i * 0.5},0,0,{qz!r},{qw!r},0,0,2e-4,"
                    f"{600 + i},{-700 - i},900,,{0.125 * (i // 4)},0")
    return rows


def _write(tmp_path, name: str, text: str | bytes):
    p = tmp_path / name
    p.write_bytes(text if isinstance(text, bytes) else text.encode())
    return p


def _edit_cell(lines: list[str], row: int, col: str, value: str) -> list[str]:
    out = list(lines)
    j = HEADER.split(",").index(col)
    cells = out[row].split(",")
    cells[j] = value
    out[row] = ",".join(cells)
    return out


def _one_line_error(call, *needles: str) -> str:
    with pytest.raises(InputError) as e:
        call()
    msg = str(e.value)
    assert "\n" not in msg
    for needle in needles:
        assert needle in msg, (needle, msg)
    return msg


def test_good_files_pass(tmp_path):
    tel = read_telemetry(_write(tmp_path, "tel.csv", "\n".join(_tel_lines())))
    assert tel.n == 12
    assert load_spacecraft(_write(tmp_path, "sc.toml", GOOD_SC)).name == "cassini-pre-soi"


# --------------------------------------------------------------------------------------------
# telemetry and pulse logs


@pytest.mark.parametrize("row, col, value, needles", [
    (4, "rwa1", "1e308", ["column 'rwa1'", "data row 4", "10000 rpm"]),
    (4, "rwa2", "-20000", ["column 'rwa2'", "data row 4"]),
    (3, "wx", "1e308", ["column 'wx'", "data row 3", "rad/s"]),
    (5, "t", "1e308", ["column 't'", "data row 5", "1e+10 s"]),
    (5, "t", "-inf", ["column 't'", "data row 5", "infinite"]),
    (2, "q2", "1e308", ["column 'q2'", "data row 2"]),
    (6, "on_Z1", "1e308", ["column 'on_Z1'", "data row 6"]),
    (6, "on_Y2", "-5", ["column 'on_Y2'", "decreases"]),
    (7, "t", "102.5000000001", ["column 't'", "data row 7", "apart"]),
])
def test_absurd_telemetry_values(tmp_path, row, col, value, needles):
    lines = _edit_cell(_tel_lines(), row, col, value)
    if col == "t" and value.startswith("102.5"):
        lines = _edit_cell(lines, row - 1, "t", "102.5")  # rows 6 and 7: 1e-10 s apart
    p = _write(tmp_path, "tel.csv", "\n".join(lines))
    for units in (True, False):  # the bounds hold without the unit heuristics too
        _one_line_error(lambda: read_telemetry(p, check_units=units), str(p), *needles)


def test_body_rate_bound_in_memory():
    t = np.arange(5.0)
    q = np.tile([0.0, 0.0, 0.0, 1.0], (5, 1))
    w = np.zeros((5, 3))
    w[2, 1] = 7.0
    tel = Telemetry(t, q, w, np.full((5, 4), np.nan), source="mem")
    _one_line_error(lambda: telemetry.validate_telemetry(tel, check_units=False),
                    "mem", "column 'wy'", "data row 3")


@pytest.mark.parametrize("line, needles", [
    ("1.0,Z1,1e308", ["column 'width'", "data row 1", "3600 s"]),
    ("1.0,Z1,0", ["column 'width'", "positive"]),
    ("1e308,Z1,0.125", ["column 't_on'", "data row 1"]),
    ("1.0,Z1,nan", ["column 'width'", "NaN"]),
])
def test_absurd_pulses(tmp_path, line, needles):
    p = _write(tmp_path, "p.csv", f"t_on,thruster,width\n{line}\n")
    _one_line_error(lambda: read_pulses(p), str(p), *needles)


def test_pulse_bounds_in_memory():
    log = PulseLog(np.array([1.0]), np.array([0]), np.array([1e308]), "mem")
    _one_line_error(lambda: validate_pulses(log), "mem", "width")


def test_row_limit_per_file_and_per_fit(tmp_path, monkeypatch):
    monkeypatch.setattr(telemetry.limits, "MAX_ROWS", 10)
    monkeypatch.setattr(telemetry.limits, "_CHUNK_ROWS", 4)  # the limit is checked reading
    p = _write(tmp_path, "long.csv", "\n".join(_tel_lines(12)))
    _one_line_error(lambda: read_telemetry(p), str(p), "more than 10 data rows", "decimate")
    a = _write(tmp_path, "a.csv", "\n".join(_tel_lines(6)))
    b = _write(tmp_path, "b.csv", "\n".join(_tel_lines(6)))
    assert read_telemetry(a).n == 6
    _one_line_error(lambda: read_telemetry_many([a, b]), str(b), "12 rows", "limit of 10")
    pulses = "\n".join(["t_on,thruster,width"] + [f"{i},Z1,0.125" for i in range(11)])
    lp = _write(tmp_path, "pulses.csv", pulses)
    _one_line_error(lambda: read_pulses(lp), str(lp), "more than 10 data rows", "pulse-log")


def test_row_limit_parquet(tmp_path, monkeypatch):
    pytest.importorskip("pyarrow")
    tel = read_telemetry(_write(tmp_path, "a.csv", "\n".join(_tel_lines(12))))
    pq = tmp_path / "a.parquet"
    telemetry.write_telemetry(pq, tel)
    assert read_telemetry(pq).n == 12
    monkeypatch.setattr(telemetry.limits, "MAX_ROWS", 10)
    _one_line_error(lambda: read_telemetry(pq), str(pq), "more than 10 data rows")


def test_chunked_reading_matches_and_names_the_global_row(tmp_path, monkeypatch):
    p = _write(tmp_path, "tel.csv", "\n".join(_tel_lines(12)))
    whole = read_telemetry(p)
    monkeypatch.setattr(telemetry.limits, "_CHUNK_ROWS", 5)
    chunked = read_telemetry(p)
    for a, b in ((whole.t, chunked.t), (whole.q, chunked.q), (whole.wheel_rates,
                                                              chunked.wheel_rates)):
        np.testing.assert_array_equal(a, b)
    bad = _write(tmp_path, "bad.csv", "\n".join(_edit_cell(_tel_lines(12), 11, "wz", "x")))
    _one_line_error(lambda: read_telemetry(bad), "column 'wz', data row 11")


# --------------------------------------------------------------------------------------------
# spacecraft model files


def _drop_inertia_table(s: str) -> str:
    return re.sub(r"\[inertia\].*?poi_uncertainty[^\n]*\n", "", s, flags=re.S)


@pytest.mark.parametrize("edit, needle", [
    (lambda s: s.replace("tau_delay_range = [0.003, 0.007]", "tau_delay_range = 0.003"),
     "pulse.tau_delay_range"),
    (lambda s: s.replace("tau_fall_range = [0.040, 0.090]", "tau_fall_range = [0.04, 0.09, 1]"),
     "pulse.tau_fall_range"),
    (lambda s: s.replace("tau_rise_range = [0.015, 0.025]", "tau_rise_range = ['a', 0.025]"),
     "pulse.tau_rise_range"),
    (lambda s: "inertia = 5\n" + _drop_inertia_table(s), "'inertia' must be a table"),
    (lambda s: s.replace("Ixx = 8802", "Ixx = 1e308"), "inertia.Ixx"),
    (lambda s: s.replace("Ixy = -137", "Ixy = -1e300"), "inertia.Ixy"),
    (lambda s: s.replace("Ixx = 8802", "Ixx = nan"), "inertia.Ixx"),
    (lambda s: s.replace("Ixx = 8802", "Ixx = \"8802\""), "inertia.Ixx"),
    (lambda s: s.replace("Ixx = 8802\n", ""), "inertia.Ixx"),
    (lambda s: s.replace("Ixx = 8802", "Ixx = 20000"), "triangle"),
    (lambda s: s.replace("Ixy = -137", "Ixy = -9000"), "positive definite"),
    (lambda s: s.replace("inertia = 0.161", "inertia = 1e-300", 1), "wheel[0].inertia"),
    (lambda s: s.replace("inertia = 0.161", "inertia = 1e6", 1), "wheel[0].inertia"),
    (lambda s: s.replace("[0.000000000000, 0.816496580928, 0.577350269190]", "[0, 0, 0]"),
     "wheel[0].axis"),
    (lambda s: s.replace("[0.000000000000, 0.816496580928, 0.577350269190]", "[0, 1e308, 0]"),
     "wheel[0].axis"),
    (lambda s: s.replace("[0.000000000000, 0.816496580928, 0.577350269190]", "\"z\""),
     "wheel[0].axis"),
    (lambda s: s.replace('name = "RWA1"', "name = 1"), "wheel[0].name"),
    (lambda s: s.replace("F = 0.75", "F = -0.75"), "thrust.F"),
    (lambda s: s.replace("F = 0.75", "F = inf"), "thrust.F"),
    (lambda s: s.replace("Lx = 1.234", "Lx = 1e9"), "thrusters.Lx"),
    (lambda s: s.replace("com = [0.0, 0.0, 0.0]", "com = [0.0, 0.0]"), "thrusters.com"),
    (lambda s: s.replace("kg = 4522.0", "kg = -1"), "mass.kg"),
    (lambda s: s.replace("tau_fall = 0.065", "tau_fall = 1e308"), "pulse.tau_fall"),
    (lambda s: s.replace("tau_fall = 0.065", "tau_fall = 0.065\ntau_log_sd_min = 3"),
     "pulse.tau_log_sd_min"),
    (lambda s: s.replace("tau_fall = 0.065", "tau_fall = 0.065\ntau_log_sd_min = 0"),
     "pulse.tau_log_sd_min"),
    (lambda s: "thrust = 3\n" + re.sub(r"\[thrust\]\nF = [^\n]*\n", "", s),
     "'thrust' must be a table"),
    (lambda s: s + "\n[gyro]\nbias_sd_rad_s = 1e300\n", "gyro.bias_sd_rad_s"),
    (lambda s: s.replace('name = "cassini-pre-soi"', "name = 3"), "'name'"),
])
def test_bad_spacecraft_values(tmp_path, edit, needle):
    text = edit(GOOD_SC)
    assert text != GOOD_SC
    p = _write(tmp_path, "sc.toml", text)
    _one_line_error(lambda: load_spacecraft(p), str(p), needle)


def test_spacecraft_file_not_utf8_or_a_directory(tmp_path):
    p = _write(tmp_path, "sc.toml", GOOD_SC.encode() + b"\n# \xff\xfe\n")
    _one_line_error(lambda: load_spacecraft(p), str(p), "not UTF-8")
    d = tmp_path / "models"
    d.mkdir()
    _one_line_error(lambda: load_spacecraft(d), str(d), "directory")
    (tmp_path / "dir.toml").mkdir()
    _one_line_error(lambda: load_spacecraft(tmp_path / "dir.toml"), "dir.toml", "directory")


# --------------------------------------------------------------------------------------------
# scenario files


@pytest.mark.parametrize("old, new, needle", [
    ("duration_s = 480.0", "duration_s = 3e6", "run.duration_s"),
    ("duration_s = 480.0", "duration_s = 1e300", "run.duration_s"),
    ("duration_s = 480.0", "duration_s = -480.0", "run.duration_s"),
    ("duration_s = 480.0", "duration_s = nan", "run.duration_s"),
    ("duration_s = 480.0", "duration_s = \"480\"", "run.duration_s"),
    ("dt_s = 0.125 ", "dt_s = 1e-300 ", "run.duration_s"),
    ("sample_period_s = 1.0", "sample_period_s = 1000.0", "run.sample_period_s"),
    ("duration_s = 480.0", "duration_s = 210000.0", "run.sample_period_s"),  # 210 001 samples
    ("target_rpm = 1026.0", "target_rpm = 1e308", "wheel_ramp[0].target_rpm"),
    ("torque_nm = 0.06", "torque_nm = 1e9", "wheel_ramp[0].torque_nm"),
    ("thrust_n = 0.699", "thrust_n = 1e308", "truth.thrust_n"),
    ("thrust_n = 0.699", "thrust_n = [1, 2]", "truth.thrust_n"),
    ("tau_fall_s = 0.065", "tau_fall_s = 1e5", "truth.tau_fall_s"),
    ("RWA1 = 0.0", "RWA1 = 1e6", "initial.wheel_rpm.RWA1"),
    ("seed = 2004049", "seed = 9223372036854775808", "seed"),
    ("gyro_rad_s = 1.0e-6", "gyro_rad_s = 1e300", "noise.gyro_rad_s"),
    ("seed = 2004049", "seed = -1", "seed"),
])
def test_bad_scenario_values(tmp_path, old, new, needle):
    assert old in GOOD_SCENARIO
    p = _write(tmp_path, "sc.toml", GOOD_SCENARIO.replace(old, new, 1))
    _one_line_error(lambda: load_scenario(p), str(p), needle)


def test_scenario_section_of_the_wrong_type(tmp_path):
    text = "run = 5\n" + re.sub(r"\[run\]\n(.*?=.*?\n)+", "", GOOD_SCENARIO, count=1)
    p = _write(tmp_path, "sc.toml", text)
    _one_line_error(lambda: load_scenario(p), str(p), "'run' must be a table")


def test_scenario_step_limit_names_the_limit(tmp_path):
    text = GOOD_SCENARIO.replace("duration_s = 480.0", f"duration_s = {MAX_STEPS * 0.125 + 1}")
    p = _write(tmp_path, "long.toml", text)
    _one_line_error(lambda: load_scenario(p), "run.duration_s", "2e+06", "split the run")


def test_scenario_file_not_utf8_or_a_directory(tmp_path):
    p = _write(tmp_path, "s.toml", b"\xff\xfe" + GOOD_SCENARIO.encode())
    _one_line_error(lambda: load_scenario(p), str(p), "not UTF-8")
    _one_line_error(lambda: load_scenario(tmp_path), str(tmp_path), "directory")


def test_cli_prints_one_line_and_exits_2(tmp_path, run_cli):
    p = _write(tmp_path, "tel.csv", "\n".join(_edit_cell(_tel_lines(), 4, "rwa1", "1e308")))
    code, out, err = run_cli("check", p)
    assert code == 2
    assert err.strip().count("\n") == 0 and "column 'rwa1'" in err


# --------------------------------------------------------------------------------------------
# fuzzing: success or InputError, nothing else

_JUNK = ["1e308", "-1e308", "1e300", "-1e200", "1e20", "-3e15", "inf", "-inf", "nan", "NaN", "",
         "abc", "1e-320", "0", "-0", "1e10", "--1", "0x10", "1_0", "true", " 5 ", "1e", "\x00"]
_TOML_JUNK = ["1e308", "-1e308", "1e300", "-1e200", "1e20", "-3e15", "inf", "nan", "-1", "0",
              "1e-300", "\"x\"", "[1, 2]", "[1e308, 0, 0]", "{ a = 1 }", "true", "[]",
              "9999999999999999999", "[[1]]", "'0.5'", "-0.0"]


def _mutate(text: bytes, data, junk: list[str], csv_like: bool) -> bytes:
    """Apply 1-3 random edits to ``text``."""
    for _ in range(data.draw(st.integers(1, 3))):
        lines = text.split(b"\n")
        op = data.draw(st.sampled_from(["cell", "cell", "drop_col", "truncate", "bytes",
                                        "drop_line", "dup_line"]))
        if op == "cell" and csv_like:  # mostly data rows; the header now and then
            i = data.draw(st.integers(-1, len(lines) - 1)) % len(lines)
            cells = lines[i].split(b",")
            j = data.draw(st.integers(0, len(cells) - 1))
            cells[j] = data.draw(st.sampled_from(junk)).encode()
            lines[i] = b",".join(cells)
        elif op == "cell":  # TOML: replace the value of a `key = value` line
            keyed = [i for i, ln in enumerate(lines) if b"=" in ln and not ln.startswith(b"#")]
            i = data.draw(st.sampled_from(keyed))
            key = lines[i].split(b"=", 1)[0]
            lines[i] = key + b"= " + data.draw(st.sampled_from(junk)).encode()
        elif op == "drop_col" and csv_like:
            j = data.draw(st.integers(0, 13))
            lines = [b",".join(c for k, c in enumerate(ln.split(b",")) if k != j)
                     for ln in lines]
        elif op == "truncate":
            cut = data.draw(st.integers(0, len(text)))
            return b"\n".join(lines)[:cut]
        elif op == "bytes":
            at = data.draw(st.integers(0, len(text)))
            bad = data.draw(st.sampled_from([b"\xff", b"\xc3\x28", b"\x80\x80", b"\x00"]))
            text = text[:at] + bad + text[at:]
            continue
        elif op == "drop_line" and len(lines) > 1:
            del lines[data.draw(st.integers(0, len(lines) - 1))]
        elif op == "dup_line":
            i = data.draw(st.integers(0, len(lines) - 1))
            lines.insert(i, lines[i])
        text = b"\n".join(lines)
    return text


def _succeeds_or_input_error(call, then=None) -> None:
    """``call()`` succeeds (then ``then(result)`` runs) or raises a one-line InputError."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # an overflow would be a bug
        with np.errstate(over="raise", invalid="raise", divide="raise"):
            try:
                out = call()
            except InputError as e:
                assert "\n" not in str(e)
                return
            if then is not None:
                then(out)


def _downstream(tel: Telemetry) -> None:
    """What the fits compute from validated telemetry must not overflow."""
    dt = np.diff(tel.t)
    span = tel.t - tel.t[0]
    np.sum(np.diff(tel.omega, axis=0) / dt[:, None])
    np.sum(tel.omega * span[:, None])
    rho = np.nan_to_num(tel.wheel_rates)
    np.sum(np.diff(rho, axis=0) / dt[:, None]) + np.sum(rho**2 * span[:, None])
    if tel.on_times is not None:
        np.sum(tel.on_times * span[:, None])


@FUZZ
@given(data=st.data())
def test_fuzz_telemetry(tmp_path, data):
    text = _mutate("\n".join(_tel_lines()).encode(), data, _JUNK, csv_like=True)
    p = _write(tmp_path, "fuzz.csv", text)
    units = data.draw(st.booleans())
    _succeeds_or_input_error(lambda: read_telemetry(p, check_units=units), _downstream)


@FUZZ
@given(data=st.data())
def test_fuzz_pulses(tmp_path, data):
    good = b"t_on,thruster,width\n1.0,Z1,0.125\n2.5,Y2,0.25\n3.0,Z1,0.5\n10,x4,1\n"
    p = _write(tmp_path, "fuzz.csv", _mutate(good, data, _JUNK + ["Z1", "q9"], csv_like=True))
    _succeeds_or_input_error(
        lambda: read_pulses(p),
        lambda log: np.sum((log.t_on + log.width) * log.width) + np.sum(np.diff(log.t_on)))


@FUZZ
@given(data=st.data())
def test_fuzz_spacecraft(tmp_path, data):
    p = _write(tmp_path, "fuzz.toml", _mutate(GOOD_SC.encode(), data, _TOML_JUNK, csv_like=False))
    _succeeds_or_input_error(lambda: load_spacecraft(p))


@FUZZ
@given(data=st.data())
def test_fuzz_scenario(tmp_path, data):
    text = _mutate(GOOD_SCENARIO.encode(), data, _TOML_JUNK, csv_like=False)
    p = _write(tmp_path, "fuzz.toml", text)
    _succeeds_or_input_error(lambda: load_scenario(p))


def test_simulate_refuses_an_oversized_scenario_built_in_code():
    from dataclasses import replace

    import jax

    from cassini_bayes.simulate import simulate

    s = load_scenario("biasing_day049")
    big = replace(s, duration_s=1e6)  # 8e6 steps: ~3 GB if it were allocated
    _one_line_error(lambda: simulate(jax.random.key(0), big), "run.duration_s", "split the run")
