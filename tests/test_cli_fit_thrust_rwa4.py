"""``cassini-bayes fit thrust`` and ``fit rwa4``: bad inputs (fast) and end to end (slow)."""

from __future__ import annotations

import json

import jax
import numpy as np
import pytest

from cassini_bayes.telemetry import RPM_TO_RAD_S, Telemetry, write_telemetry

SC_FSDS = "models/fsds.toml"
SC_PRE_SOI = "models/cassini_pre_soi.toml"


@pytest.fixture
def steady_csv(tmp_path):
    n = 300
    rates = np.full((n, 4), np.nan)
    rates[:, 3] = 100.0 * RPM_TO_RAD_S
    tel = Telemetry(np.arange(float(n)), np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)),
                    np.zeros((n, 3)), rates)
    path = tmp_path / "steady.csv"
    write_telemetry(path, tel)
    return path


def test_thrust_without_pulses_is_one_line_error(run_cli, steady_csv, tmp_path):
    code, _, err = run_cli("fit", "thrust", "--telemetry", steady_csv, "--spacecraft", SC_FSDS,
                           "--out", tmp_path / "run")
    assert code == 2 and "--pulses" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "run").exists()


def test_rwa4_bad_windows_are_one_line_errors(run_cli, steady_csv, tmp_path):
    base = ("fit", "rwa4", "--method", "rcs", "--telemetry", steady_csv, "--spacecraft",
            SC_PRE_SOI, "--out", tmp_path / "run")
    code, _, err = run_cli(*base, "--window-a", "0:100", "--window-b", "200:900")
    assert code == 2 and "outside the data" in err and len(err.strip().splitlines()) == 1
    code, _, err = run_cli(*base, "--window-a", "0:100")
    assert code == 2 and "--window-b" in err
    code, _, err = run_cli(*base, "--window-a", "0:100", "--window-b", "150:250")
    assert code == 2 and "spin change" in err
    code, _, err = run_cli(*base)        # no excitation: no second quiet period to compare
    assert code == 2 and len(err.strip().splitlines()) == 1
    code, _, err = run_cli(*base[:3], "wheel", *base[4:])
    assert code == 2 and "--method" in err
    assert not (tmp_path / "run").exists()


_SMALL = ("--chains", "2", "--warmup", "150", "--draws", "150", "--seed", "3")
_KEYS = {"kind", "parameters", "baseline", "diagnostics", "seed", "version"}
_PARAM_KEYS = {"mean", "sd", "q05", "q50", "q95", "r_hat", "ess_bulk", "ess_tail"}


def _check_run(run):
    for f in ("posterior.nc", "summary.json", "config.toml", "report.html"):
        assert (run / f).is_file(), f
    s = json.loads((run / "summary.json").read_text())
    assert _KEYS <= set(s)
    assert set(s["diagnostics"]) >= {"divergences", "max_r_hat", "min_ess_bulk", "converged"}
    for v in s["parameters"].values():
        assert _PARAM_KEYS <= set(v)
    return s


@pytest.mark.slow
def test_fit_thrust_end_to_end(run_cli, tmp_path):
    from cassini_bayes.simulate import load_scenario, simulate
    from cassini_bayes.telemetry import write_pulses

    r = simulate(jax.random.key(31), load_scenario("fsds_biasing"))
    write_telemetry(tmp_path / "tel.csv", r.telemetry)
    write_pulses(tmp_path / "pulses.csv", r.pulses)
    code, out, err = run_cli("fit", "thrust", "--telemetry", tmp_path / "tel.csv", "--pulses",
                             tmp_path / "pulses.csv", "--spacecraft", SC_FSDS, "--out",
                             tmp_path / "run", *_SMALL)
    assert code == 0, err
    s = _check_run(tmp_path / "run")
    assert s["kind"] == "thrust"
    assert set(s["parameters"]) == {"F", "tau_delay", "tau_rise", "tau_fall"}
    assert abs(s["parameters"]["F"]["mean"] - 0.75) < 0.075
    assert "F" in s["baseline"]


@pytest.mark.slow
def test_fit_rwa4_end_to_end(run_cli, tmp_path):
    from cassini_bayes.inference.sphere import angles_deg
    from cassini_bayes.simulate import load_scenario, simulate

    sc = load_scenario("rwa4_rcs")
    r = simulate(jax.random.key(32), sc)
    write_telemetry(tmp_path / "tel.csv", r.telemetry)
    code, out, err = run_cli("fit", "rwa4", "--method", "rcs", "--telemetry",
                             tmp_path / "tel.csv", "--spacecraft", SC_PRE_SOI, "--out",
                             tmp_path / "run", "--prior", "cone", *_SMALL)
    assert code == 0, err
    s = _check_run(tmp_path / "run")
    assert s["kind"] == "rwa4"
    assert set(s["parameters"]) == {"u4_x", "u4_y", "u4_z"}
    d = s["direction"]
    assert set(d) == {"mean", "cone_deg"} and set(d["cone_deg"]) == {"50", "90", "95"}
    assert angles_deg(np.array(d["mean"])[None], sc.truth.wheel("RWA4").axis)[0] < 3.0
    assert s["model"] == "robust"
    sens = s["sensitivity"]
    assert set(sens) == {"gyro_bias", "gyro_scale", "wheel_inertia", "wheel_inertia_common",
                         "body_torque", "inertial_torque", "torque_rate"}
    assert all(e["modelled"] and e["parameters"]["axis"]["units"] == "deg" for e in sens.values())
