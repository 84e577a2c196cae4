"""Experiment files and the ``cassini-bayes experiment`` command."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest

from cassini_bayes._paths import EXPERIMENTS_DIR
from cassini_bayes.errors import InputError
from cassini_bayes.experiments import (
    ExperimentOutput,
    check_fact,
    experiment_from_dict,
    load_experiment,
    register,
    registered_kinds,
    run_experiment,
)

SHIPPED = sorted(EXPERIMENTS_DIR.glob("*.toml"))
RUNNABLE = [p for p in SHIPPED
            if tomllib.loads(p.read_text()).get("kind") in registered_kinds()]


def test_the_physics_experiments_are_shipped():
    names = {p.stem for p in RUNNABLE}
    assert {"impulse_ratio", "mass_property_mc"} <= names


@pytest.mark.parametrize("path", RUNNABLE, ids=[p.stem for p in RUNNABLE])
def test_each_experiment_file_runs_with_tiny_settings(path, tmp_path, run_cli):
    out = tmp_path / path.stem
    code, stdout, err = run_cli("experiment", path, "--out", out, "--quick", "--seed", 3)
    assert code == 0, err
    assert stdout.strip() == str(out / "report.html")
    results = json.loads((out / "results.json").read_text())
    assert results["kind"] == tomllib.loads(path.read_text())["kind"]
    assert results["quick"] is True and results["seed"] == 3
    for fig in results["figures"]:
        assert (out / fig["path"]).stat().st_size > 1000
    page = (out / "report.html").read_text()
    assert page.count("data:image/png;base64,") == len(results["figures"])
    assert "http://" not in page and "https://" not in page
    # config.toml is the resolved experiment: loading it gives the same kind and settings
    again = load_experiment(out / "config.toml")
    assert again.kind.name == results["kind"] and dict(again.settings) == results["settings"]
    assert again.seed == 3 and again.name == path.stem
    assert not list(tmp_path.glob(".*.tmp"))  # no temporary directory left behind


def test_paper_checks_of_the_physics_experiments_pass(tmp_path):
    rec = run_experiment(EXPERIMENTS_DIR / "impulse_ratio.toml", tmp_path / "ir", quick=True)
    by_id = {c.fact_id: c for c in rec.output.checks if c.fact_id}
    for fid in ("R_125ms_tf65", "R_250ms_tf65", "R_125ms_tf40", "R_fsds_mix", "F_fsds_corrected",
                "table2_day028_tf65", "table2_day094_tf40"):
        assert by_id[fid].passed, by_id[fid]


def test_same_seed_same_results_and_config_rerun(tmp_path):
    src = EXPERIMENTS_DIR / "mass_property_mc.toml"
    a = run_experiment(src, tmp_path / "a", seed=7, quick=True)
    b = run_experiment(tmp_path / "a" / "config.toml", tmp_path / "b")  # seed from [run]
    ra = json.loads((tmp_path / "a" / "results.json").read_text())["results"]
    rb = json.loads((tmp_path / "b" / "results.json").read_text())["results"]
    assert ra == rb and b.seed == 7
    c = run_experiment(src, tmp_path / "c", seed=8, quick=True)
    assert c.output.summary != a.output.summary


def test_existing_out_refused_without_force(tmp_path, run_cli):
    src = EXPERIMENTS_DIR / "impulse_ratio.toml"
    out = tmp_path / "run"
    out.mkdir()
    (out / "keep.txt").write_text("x")
    code, _, err = run_cli("experiment", src, "--out", out, "--quick")
    assert code == 2 and "--force" in err and len(err.strip().splitlines()) == 1
    assert (out / "keep.txt").exists()
    code, _, err = run_cli("experiment", src, "--out", out, "--quick", "--force")
    assert code == 2 and "not a cassini-bayes output" in err  # --force spares a user's folder
    assert (out / "keep.txt").exists()
    run = tmp_path / "run2"
    assert run_cli("experiment", src, "--out", run, "--quick")[0] == 0
    code, _, err = run_cli("experiment", src, "--out", run, "--quick", "--force", "--seed", 3)
    assert code == 0, err
    assert json.loads((run / "results.json").read_text())["seed"] == 3


def _write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "exp.toml"
    p.write_text(text)
    return p


@pytest.mark.parametrize("text, words", [
    ('kind = "no_such_kind"\n', ["unknown experiment kind", "no_such_kind", "impulse_ratio"]),
    ('kind = "impulse_ratio"\ntitel = "x"\n', ["unknown key 'titel'"]),
    ('kind = "impulse_ratio"\n[settings]\ngrid_pionts = 5\n', ["'settings.grid_pionts'"]),
    ('kind = "impulse_ratio"\n[settings]\ngrid_points = "many"\n',
     ["'settings.grid_points'", "integer"]),
    ('kind = "mass_property_mc"\n[settings]\ndistribution = "cauchy"\n',
     ["'settings.distribution'", "uniform"]),
    ('kind = "mass_property_mc"\n[settings]\nphi_range_deg = [0, "x"]\n',
     ["'settings.phi_range_deg[1]'"]),
    ('title = "no kind"\n', ["missing required key 'kind'"]),
    ('kind = "impulse_ratio"\n[run]\nsede = 1\n', ["unknown key 'run.sede'"]),
    ('kind = "impulse_ratio"\n[settings\n', ["not valid TOML"]),
])
def test_bad_experiment_files_give_one_line_and_exit_2(tmp_path, run_cli, text, words):
    path = _write(tmp_path, text)
    code, out, err = run_cli("experiment", path, "--out", tmp_path / "out")
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and str(path) in lines[0]
    for w in words:
        assert w in lines[0]
    assert "Traceback" not in err and not (tmp_path / "out").exists()


def test_settings_checked_by_the_kind_give_one_line(tmp_path, run_cli):
    path = _write(tmp_path, 'kind = "mass_property_mc"\n[settings]\nflight_epochs = ["launch"]\n')
    code, _, err = run_cli("experiment", path, "--out", tmp_path / "out", "--quick")
    assert code == 2 and "flight_epochs" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists() and not list(tmp_path.glob(".out.*"))


def test_missing_file_is_an_input_error(tmp_path):
    with pytest.raises(InputError, match="not found"):
        load_experiment(tmp_path / "nope.toml")


@pytest.fixture
def own_registry(monkeypatch):
    """The kinds a test registers are forgotten after it (the registry has no public way to
    drop a kind: this is the one place a test reaches into it)."""
    from cassini_bayes.experiments import _registry

    monkeypatch.setattr(_registry, "_KINDS", dict(registered_kinds()))


def test_a_kind_that_fails_leaves_no_directory(tmp_path, own_registry):
    @register("test_boom", defaults={"n": 1})
    def boom(key, settings, ctx):
        raise RuntimeError("kaboom")

    path = _write(tmp_path, 'kind = "test_boom"\n')
    with pytest.raises(RuntimeError, match="kaboom"):
        run_experiment(path, tmp_path / "out")
    assert not (tmp_path / "out").exists()
    assert [p.name for p in tmp_path.iterdir()] == ["exp.toml"]


def test_a_new_kind_is_one_function(tmp_path, own_registry):
    """The framework contract: register a function, write a two-line file, run it."""

    @register("test_square", defaults={"x": 3.0}, quick={"x": 2.0})
    def square(key, settings, ctx):
        return ExperimentOutput(summary={"x2": settings["x"] ** 2},
                                checks=(check_fact("R_fsds_mix", 1.34058),))

    path = _write(tmp_path, 'kind = "test_square"\n[settings]\nx = 4\n')
    rec = run_experiment(path, tmp_path / "full")
    assert rec.output.summary == {"x2": 16.0}
    assert rec.output.checks[0].passed and rec.output.checks[0].paper == "1.3406"
    rec = run_experiment(path, tmp_path / "quick", quick=True)
    assert rec.output.summary == {"x2": 4.0}


def test_bad_model_name_names_the_experiment_file(tmp_path, run_cli):
    path = _write(tmp_path, 'kind = "impulse_ratio"\n[settings]\nspacecraft = "no_such_model"\n')
    code, _, err = run_cli("experiment", path, "--out", tmp_path / "out", "--quick")
    assert code == 2 and str(path) in err and "no_such_model" in err
    assert len(err.strip().splitlines()) == 1


def test_paper_fact_verdicts():
    from cassini_bayes.analysis.paper_facts import PAPER_FACTS, fact

    ids = [f.id for f in PAPER_FACTS]
    assert len(ids) == len(set(ids))
    r = fact("R_125ms_tf65")          # value row: printed precision, half a unit of the last digit
    assert r.passes(1.39462) and r.passes(1.3954999) and not r.passes(1.3956)
    assert r.printed == "1.395"
    b = fact("rwa4_mass_property_deg")  # budget row: within the bound
    assert b.passes(1.5) and not b.passes(1.5001) and b.printed == "≤ 1.5 deg"
    t = fact("rwa4_rcs_total_deg")
    assert t.passes(2.99) and not t.passes(3.0) and t.printed == "< 3 deg"
    assert fact("rwa4_rcs_mean_deg").passes(0.9) is None  # reference row: no verdict of its own
    assert not r.passes(float("nan"))
    with pytest.raises(InputError, match="unknown paper fact"):
        fact("R_999ms")


def test_table_settings_are_checked_key_by_key(tmp_path, own_registry):

    @register("test_tables", defaults={"events": [{"day": 28, "width_s": 0.125}]})
    def tables(key, settings, ctx):
        return ExperimentOutput(summary={"events": settings["events"]})

    path = _write(tmp_path, 'kind = "test_tables"\n[[settings.events]]\nday = 49\n')
    rec = run_experiment(path, tmp_path / "ok")
    assert rec.output.summary == {"events": [{"day": 49, "width_s": 0.125}]}
    path = _write(tmp_path, 'kind = "test_tables"\n[[settings.events]]\ndya = 49\n')
    with pytest.raises(InputError, match=r"settings.events\[0\].dya"):
        load_experiment(path)


def test_a_fits_config_toml_is_named_as_such():
    with pytest.raises(InputError, match="config.toml of a 'fit inertia' run, not an experiment"):
        experiment_from_dict({"command": "fit inertia", "version": "0.1.0", "seed": 0},
                             "c.toml")
