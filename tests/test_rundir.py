"""Atomic run directories (cassini_bayes.rundir)."""

from __future__ import annotations

import hashlib
import json
import tomllib

import arviz as az
import numpy as np
import pytest

from cassini_bayes.errors import InputError
from cassini_bayes.rundir import (RunDir, file_record, minimal_report_html, write_config,
                                  write_posterior, write_summary)


def _siblings(path):
    return sorted(p.name for p in path.parent.iterdir())


def test_written_only_on_success(tmp_path):
    out = tmp_path / "run"
    with RunDir(out) as rd:
        assert rd.path != out and rd.path.parent == tmp_path
        (rd.path / "a.txt").write_text("x")
        assert not out.exists()  # nothing under the final name while writing
    assert (out / "a.txt").read_text() == "x"
    assert _siblings(out) == ["run"]  # no temporary left behind


def test_failure_leaves_nothing(tmp_path):
    out = tmp_path / "run"
    with pytest.raises(RuntimeError):
        with RunDir(out) as rd:
            (rd.path / "half.txt").write_text("half")
            raise RuntimeError("crash while writing")
    assert not out.exists()
    assert _siblings(out) == []


def test_refuses_non_empty_without_force(tmp_path):
    out = tmp_path / "run"
    out.mkdir()
    (out / "old.txt").write_text("old")
    with pytest.raises(InputError, match="--force"):
        RunDir(out)
    # an empty directory is fine
    empty = tmp_path / "empty"
    empty.mkdir()
    with RunDir(empty) as rd:
        (rd.path / "new.txt").write_text("new")
    assert (empty / "new.txt").exists()


def test_force_replaces_atomically(tmp_path):
    out = tmp_path / "run"
    out.mkdir()
    (out / "old.txt").write_text("old")
    with RunDir(out, force=True) as rd:
        (rd.path / "new.txt").write_text("new")
        assert (out / "old.txt").exists()  # the old run stays intact until the new one is done
    assert sorted(p.name for p in out.iterdir()) == ["new.txt"]
    assert _siblings(out) == ["run"]


def test_force_failure_keeps_old_run(tmp_path):
    out = tmp_path / "run"
    out.mkdir()
    (out / "old.txt").write_text("old")
    with pytest.raises(RuntimeError):
        with RunDir(out, force=True) as rd:
            (rd.path / "new.txt").write_text("new")
            raise RuntimeError("crash")
    assert sorted(p.name for p in out.iterdir()) == ["old.txt"]


def test_refuses_a_file(tmp_path):
    f = tmp_path / "file"
    f.write_text("x")
    with pytest.raises(InputError, match="not a directory"):
        RunDir(f, force=True)


def test_writers(tmp_path):
    data = tmp_path / "in.csv"
    data.write_text("t\n0\n")
    rec = file_record(data)
    assert rec["sha256"] == hashlib.sha256(b"t\n0\n").hexdigest()
    idata = az.from_dict(posterior={"x": np.zeros((2, 5))})
    with RunDir(tmp_path / "run") as rd:
        write_posterior(rd.path, idata)
        write_summary(rd.path, {"kind": "inertia", "x": float("nan"), "a": np.arange(2)})
        write_config(rd.path, {"seed": 1, "inputs": {"telemetry": [rec]}, "none": None})
    run = tmp_path / "run"
    assert json.loads((run / "summary.json").read_text()) == {"kind": "inertia", "x": None,
                                                             "a": [0, 1]}
    cfg = tomllib.loads((run / "config.toml").read_text())
    assert cfg["inputs"]["telemetry"][0]["path"] == str(data.resolve()) and "none" not in cfg
    assert az.from_netcdf(run / "posterior.nc").posterior["x"].shape == (2, 5)


def test_minimal_report_has_diagnostics():
    html = minimal_report_html({"kind": "inertia", "diagnostics": {"max_r_hat": 1.001},
                                "parameters": {"Ixx": {"mean": 1.0}}})
    assert html.startswith("<!DOCTYPE html>") and "max_r_hat" in html and "Ixx" in html
