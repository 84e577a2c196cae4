"""``cassini-bayes fit inertia`` end to end: run directory, summary.json contract, errors."""

from __future__ import annotations

import json
import tomllib

import arviz as az
import jax
import numpy as np
import pytest

from cassini_bayes.spacecraft import load_spacecraft
from cassini_bayes.telemetry import Telemetry, write_telemetry
from margins import assert_mixed, assert_verdict_consistent
from slews import make_slews

SMALL = ["--chains", "4", "--warmup", "400", "--draws", "400"]
PARAM_KEYS = {"mean", "sd", "q05", "q50", "q95", "r_hat", "ess_bulk", "ess_tail"}
INERTIA = ["Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz"]


@pytest.fixture(scope="module")
def csv(tmp_path_factory):
    sc = load_spacecraft("cassini_2000_03_15")
    path = tmp_path_factory.mktemp("tel") / "slew.csv"
    write_telemetry(path, make_slews(jax.random.key(11), sc))
    return path


@pytest.fixture(scope="module")
def run(tmp_path_factory, csv):
    from cassini_bayes.cli import main

    out = tmp_path_factory.mktemp("runs") / "inertia"
    code = main(["fit", "inertia", "--telemetry", str(csv), "--spacecraft",
                 "cassini_2000_03_15", "--out", str(out), "--seed", "7", *SMALL,
                 "--target-accept", "0.95"])
    return code, out


def test_writes_the_run_directory(run, csv):
    code, out = run
    assert code == 0
    assert sorted(p.name for p in out.iterdir()) == [".cassini-bayes-files", "config.toml",
                                                     "posterior.nc", "report.html",
                                                     "summary.json"]
    summary = json.loads((out / "summary.json").read_text())
    assert {"kind", "parameters", "baseline", "diagnostics", "seed", "version"} <= set(summary)
    assert summary["kind"] == "inertia" and summary["seed"] == 7
    assert summary["version"] == "0.1.0"
    assert list(summary["parameters"]) == INERTIA
    for v in summary["parameters"].values():
        assert PARAM_KEYS <= set(v)
        assert 0.0 <= v["contraction"] <= 1.0
    assert set(summary["baseline"]) == set(INERTIA)
    assert {"divergences", "max_r_hat", "min_ess_bulk", "converged"} <= set(
        summary["diagnostics"])
    assert_mixed(summary["diagnostics"])
    assert_verdict_consistent(summary["diagnostics"])
    # the least-squares baseline and the posterior agree on rich data (within 1 %)
    for name in INERTIA[:3]:
        assert abs(summary["baseline"][name] / summary["parameters"][name]["mean"] - 1) < 0.01

    cfg = tomllib.loads((out / "config.toml").read_text())
    assert cfg["seed"] == 7 and cfg["version"] == "0.1.0"
    assert cfg["inputs"]["telemetry"][0]["path"] == str(csv.resolve())
    assert len(cfg["inputs"]["telemetry"][0]["sha256"]) == 64
    assert cfg["sampler"]["target_accept"] == 0.95
    assert cfg["sampler"]["draws"] == 400 and cfg["spacecraft"]["inertia"]["Ixx"] == 8810.8
    assert cfg["sampler"]["chain_method"] == "auto"     # asked for; and what it became here:
    assert cfg["sampler"]["chain_method_used"] in ("parallel", "vectorized")
    assert cfg["sampler"]["cpu_devices"] >= 1

    idata = az.from_netcdf(out / "posterior.nc")
    assert {"posterior", "sample_stats", "prior", "observed_data", "residuals"} <= set(
        idata.groups())
    assert idata.residuals["residual"].dims == ("t", "axis")
    assert (out / "report.html").read_text().lstrip().lower().startswith("<!doctype html")


def test_existing_out_needs_force(run, csv, run_cli):
    _, out = run
    code, _, err = run_cli("fit", "inertia", "--telemetry", csv, "--spacecraft",
                           "cassini_2000_03_15", "--out", out, *SMALL)
    assert code == 2 and "--force" in err and len(err.strip().splitlines()) == 1


def test_missing_file_is_one_line(tmp_path, run_cli):
    code, _, err = run_cli("fit", "inertia", "--telemetry", tmp_path / "nope.csv",
                           "--spacecraft", "cassini_2000_03_15", "--out", tmp_path / "o")
    assert code == 2 and "nope.csv" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


def test_no_excitation_is_one_line(tmp_path, run_cli):
    sc = load_spacecraft("cassini_2000_03_15")
    tel = make_slews(jax.random.key(5), sc, dur=40.0)
    n = tel.n
    still = Telemetry(tel.t, np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)),
                      1e-7 * np.asarray(jax.random.normal(jax.random.key(6), (n, 3))),
                      np.tile(tel.wheel_rates[:1], (n, 1)), tel.wheel_names, None, "x")
    path = tmp_path / "still.csv"
    write_telemetry(path, still)
    code, _, err = run_cli("fit", "inertia", "--telemetry", path, "--spacecraft",
                           "cassini_2000_03_15", "--out", tmp_path / "o")
    assert code == 2 and "do not excite" in err and len(err.strip().splitlines()) == 1


def test_strict_exits_3_but_writes_everything(tmp_path, csv, run_cli):
    out = tmp_path / "short"
    code, _, err = run_cli("fit", "inertia", "--telemetry", csv, "--spacecraft",
                           "cassini_2000_03_15", "--out", out, "--chains", "2", "--warmup",
                           "20", "--draws", "20", "--strict")
    assert code == 3 and "did not converge" in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["diagnostics"]["converged"] is False
    with pytest.raises(AssertionError):  # the tests' margins fail on an unmixed run too
        assert_mixed(summary["diagnostics"])
    assert (out / "posterior.nc").exists() and (out / "report.html").exists()
