"""The scripts under examples/ run as a user runs them (NumPyro's ``test/test_examples.py``).

Each script is run in this process with ``runpy`` as ``__main__`` and tiny sampler settings (so
it shares this process's JAX set-up and compiled programs), and must print and write what its
docstring says. The three fitting examples simulate a whole shipped scenario and fit it (minutes
on the 2-core machine), so they are ``slow``; the SBC example runs its toy model in the fast
suite, and every script's ``--help`` is checked there too.
"""

from __future__ import annotations

import json
import re
import runpy
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
SCRIPTS = ("inertia_from_slews.py", "inertia_espa_bus.py", "inertia_cubesat.py",
           "thrust_with_inertia_posterior.py", "rwa4_axis.py", "sbc_check.py", "leak_monitor.py",
           "ivp_flyby.py", "wheel_axis_espa_bus.py", "thrust_espa_bus.py")
SAMPLER_OPTIONS = ("--chains", "--warmup", "--draws")   # every script but the leak monitor's
TINY = ["--chains", "1", "--warmup", "60", "--draws", "60"]


def run_example(script: str, args, monkeypatch, capsys) -> str:
    """Run ``examples/SCRIPT ARGS`` as ``__main__``; returns its stdout (exit status 0 checked)."""
    monkeypatch.setattr(sys, "argv", [script, *map(str, args)])
    try:
        runpy.run_path(str(EXAMPLES / script), run_name="__main__")
    except SystemExit as e:  # argparse's --help / errors
        assert e.code in (0, None), capsys.readouterr().err
    return capsys.readouterr().out


def test_examples_are_listed_in_their_readme():
    readme = (EXAMPLES / "README.md").read_text()
    assert sorted(p.name for p in EXAMPLES.glob("*.py")) == sorted(SCRIPTS)
    for script in SCRIPTS:
        assert f"`{script}`" in readme


@pytest.mark.parametrize("script", SCRIPTS)
def test_example_help_names_the_sampler_settings(script, monkeypatch, capsys):
    out = run_example(script, ["--help"], monkeypatch, capsys)
    sampler = () if script in ("leak_monitor.py", "ivp_flyby.py") else SAMPLER_OPTIONS
    seed = () if script == "ivp_flyby.py" else ("--seed",)   # deterministic: nothing drawn
    for option in (*sampler, *seed, "--out"):
        assert option in out


def test_leak_monitor_finds_the_leak_and_lee_does_later(tmp_path, monkeypatch, capsys):
    """A 10 % Z1 leak from 600 s in half an hour of cruise: the Bayesian monitor names Z1 within
    two checks of the onset (measured: 60 s); Lee's threshold (50 N m s at ~0.1 N m) needs
    about eight minutes (measured: 501 s)."""
    out = run_example("leak_monitor.py", ["--fraction", "0.1", "--hours", "0.5",
                                          "--out", tmp_path / "run"], monkeypatch, capsys)
    bayes = re.search(r"Bayesian monitor: P\(leak\) >= 0.99 at (\d+) s .* thruster (\w+)", out)
    assert bayes and bayes[2] == "Z1" and 600 < int(bayes[1]) <= 720, out
    lee = re.search(r"Lee's monitor: trigger at (\d+) s, thruster (\w+)", out)
    assert lee and lee[2] == "Z1" and int(lee[1]) > int(bayes[1]), out
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["bayes"]["thruster"] == "Z1"


def test_sbc_check_prints_ranks_and_uniformity_p_values(tmp_path, monkeypatch, capsys):
    out = run_example("sbc_check.py", ["--model", "toy", "--replicates", "6", "--chains", "1",
                                       "--warmup", "60", "--draws", "60", "--thin", "2",
                                       "--batch", "3", "--out", tmp_path / "work"],
                      monkeypatch, capsys)
    assert "SBC of the 'toy' model: 6 replicates, ranks among 30 draws" in out
    for name in ("alpha", "beta", "sigma"):
        row = re.search(rf"^{name} +([0-9.]+) +([0-9.]+) +((?:\d+ ?){{6}})$", out, re.M)
        assert row, out
        assert 0 <= float(row[1]) <= 1 and 0 <= float(row[2]) <= 1
        assert all(0 <= int(r) <= 30 for r in row[3].split())
    assert "rank uniformity" in out
    assert sorted(p.name for p in (tmp_path / "work").glob("batch_*.npz")) == [
        "batch_000000.npz", "batch_000001.npz"]  # checkpoints a rerun reuses


def _saved_run(out: str, run: Path) -> dict:
    assert f"saved {run}" in out
    for name in ("posterior.nc", "summary.json", "config.toml", "report.html"):
        assert (run / name).is_file()
    return json.loads((run / "summary.json").read_text())


@pytest.mark.slow
def test_inertia_from_slews(tmp_path, monkeypatch, capsys):
    run = tmp_path / "run"
    out = run_example("inertia_from_slews.py", [*TINY, "--out", run], monkeypatch, capsys)
    summary = _saved_run(out, run)
    assert summary["kind"] == "inertia"
    for name in ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz"):
        mean = summary["parameters"][name]["mean"]
        assert re.search(rf"^{name} .* {mean:.1f} ", out, re.M), out


@pytest.mark.slow
@pytest.mark.parametrize("script, decimals, wheels, line", [
    ("inertia_espa_bus.py", 3, ["RW1", "RW2", "RW3", "RW4"],
     "espa-bus: wheels RW1, RW2, RW3, RW4 (telemetry columns rw1 rw2 rw3 rw4), 8 thrusters"),
    ("inertia_cubesat.py", 5, ["RWX", "RWY", "RWZ", "RWS"],
     "cubesat-12u: wheels RWX, RWY, RWZ, RWS, no thrusters")])
def test_inertia_of_other_spacecraft(script, decimals, wheels, line, tmp_path, monkeypatch,
                                     capsys):
    import arviz as az

    run = tmp_path / "run"
    out = run_example(script, [*TINY, "--out", run], monkeypatch, capsys)
    summary = _saved_run(out, run)
    assert summary["kind"] == "inertia" and line in out
    for name in ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz"):
        mean = summary["parameters"][name]["mean"]
        assert re.search(rf"^{name} .* {mean:.{decimals}f} ", out, re.M), out
    # the per-wheel nuisance parameters carry the model's wheel names
    post = az.from_netcdf(run / "posterior.nc").posterior
    assert post["wheel_scale"].coords["wheel"].values.tolist() == wheels


@pytest.mark.slow
def test_thrust_with_inertia_posterior(tmp_path, monkeypatch, capsys):
    run = tmp_path / "run"
    out = run_example("thrust_with_inertia_posterior.py", [*TINY, "--out", run], monkeypatch,
                      capsys)
    summary = _saved_run(out, run)
    assert summary["kind"] == "thrust"
    assert re.search(rf"^F +0\.699 .* {summary['parameters']['F']['mean']:.3f} ", out, re.M)
    for name in ("tau_delay", "tau_rise", "tau_fall"):
        assert re.search(rf"^{name} .* ms$", out, re.M), out


@pytest.mark.slow
def test_rwa4_axis(tmp_path, monkeypatch, capsys):
    run = tmp_path / "run"
    out = run_example("rwa4_axis.py", [*TINY, "--out", run], monkeypatch, capsys)
    summary = _saved_run(out, run)
    assert summary["kind"] == "rwa4"
    cones = summary["direction"]["cone_deg"]
    assert f"90 % {cones['90']:.3f} deg, 95 % {cones['95']:.3f} deg" in out
    assert re.search(r"posterior mean .* [0-9.]+ deg from the truth", out)


@pytest.mark.slow
def test_wheel_axis_espa_bus(tmp_path, monkeypatch, capsys):
    run = tmp_path / "run"
    out = run_example("wheel_axis_espa_bus.py", [*TINY, "--out", run], monkeypatch, capsys)
    summary = _saved_run(out, run)
    assert summary["kind"] == "rwa4" and summary["wheel"]["name"] == "RW2"
    assert re.search(r"model file .* 1\.000 deg from the truth", out), out
    assert re.search(r"posterior mean .* [0-9.]+ deg from the truth", out)


@pytest.mark.slow
def test_wheel_axis_of_the_cubesat(tmp_path, monkeypatch, capsys):
    """The same script calibrates the CubeSat's skew wheel (README's command)."""
    run = tmp_path / "run"
    out = run_example("wheel_axis_espa_bus.py", [*TINY, "--scenario", "wheel_axis_cubesat_12u",
                                                 "--wheel", "RWS", "--out", run],
                      monkeypatch, capsys)
    summary = _saved_run(out, run)
    assert summary["kind"] == "rwa4" and summary["wheel"]["name"] == "RWS"
    assert re.search(r"model file .* 1\.000 deg from the truth", out), out


@pytest.mark.slow
def test_thrust_espa_bus(tmp_path, monkeypatch, capsys):
    run = tmp_path / "run"
    out = run_example("thrust_espa_bus.py", [*TINY, "--out", run], monkeypatch, capsys)
    summary = _saved_run(out, run)
    assert summary["kind"] == "thrust"
    assert len(re.findall(r"F\[[AF][1-4]\] .* truth", out)) == 8, out
    assert re.search(r"com_x .* mm .* truth \+6\.00 mm", out), out
    assert re.search(r"\d of 8 thrusts inside their 90 % interval", out), out


def test_ivp_flyby_fits_segments_and_points_through_the_tree(tmp_path, monkeypatch, capsys):
    """Four days around the flyby: segments within 40 µrad at every sample, a conic about Titan
    far off, and the tree's Earth direction close to the truth (measured 0.3 µrad)."""
    out = run_example("ivp_flyby.py", ["--days", "4", "--out", tmp_path / "run"], monkeypatch,
                      capsys)
    m = re.search(r"largest angle ([\d.]+) µrad at the samples .* one conic about Titan: "
                  r"([\d.e+]+) µrad", out)
    assert m and float(m[1]) <= 40.0 and float(m[2]) > 40.0, out
    earth = re.search(r"target spacecraft → titan → saturn → sun → earth: largest angle to the "
                      r"truth ([\d.]+) µrad", out)
    assert earth and float(earth[1]) < 40.0, out
    assert (tmp_path / "run" / "segments.csv").exists()
