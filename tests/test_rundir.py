"""Atomic run directories (cassini_bayes.rundir)."""

from __future__ import annotations

import errno
import hashlib
import json
import os
import tomllib

import arviz as az
import numpy as np
import pytest

from cassini_bayes import files, rundir
from cassini_bayes.errors import InputError
from cassini_bayes.report import minimal_report_html
from cassini_bayes.rundir import (RunDir, check_out, file_record, is_package_output,
                                  write_config, write_posterior, write_summary)


def _siblings(path):
    return sorted(p.name for p in path.parent.iterdir())


def _old_run(out):
    """A run directory as a cassini-bayes fit leaves it (recognised by its config.toml)."""
    out.mkdir()
    (out / "old.txt").write_text("old")
    (out / "config.toml").write_text('command = "fit inertia"\nversion = "0.1.0"\n')


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
    with pytest.raises(InputError, match="force=True"):
        RunDir(out)
    # an empty directory is fine
    empty = tmp_path / "empty"
    empty.mkdir()
    with RunDir(empty) as rd:
        (rd.path / "new.txt").write_text("new")
    assert (empty / "new.txt").exists()


@pytest.mark.parametrize("swap", [True, False], ids=["renameat2", "two-renames"])
def test_force_replaces_atomically(tmp_path, monkeypatch, swap):
    if not swap:  # a file system without RENAME_EXCHANGE
        monkeypatch.setattr(files, "exchange_dirs", lambda a, b: False)
    out = tmp_path / "run"
    _old_run(out)
    with RunDir(out, force=True) as rd:
        (rd.path / "new.txt").write_text("new")
        assert (out / "old.txt").exists()  # the old run stays intact until the new one is done
    assert sorted(p.name for p in out.iterdir()) == [".cassini-bayes-files", "new.txt"]
    assert _siblings(out) == ["run"]


def test_force_failure_keeps_old_run(tmp_path):
    out = tmp_path / "run"
    _old_run(out)
    with pytest.raises(RuntimeError):
        with RunDir(out, force=True) as rd:
            (rd.path / "new.txt").write_text("new")
            raise RuntimeError("crash")
    assert sorted(p.name for p in out.iterdir()) == ["config.toml", "old.txt"]
    assert _siblings(out) == ["run"]


def test_full_disk_while_writing_keeps_old_run(tmp_path):
    out = tmp_path / "run"
    _old_run(out)
    with pytest.raises(OSError):
        with RunDir(out, force=True) as rd:
            (rd.path / "summary.json").write_text("{}")
            raise OSError(errno.ENOSPC, "No space left on device", str(rd.path / "posterior.nc"))
    assert sorted(p.name for p in out.iterdir()) == ["config.toml", "old.txt"]
    assert _siblings(out) == ["run"]


def test_exchange_swaps_in_one_step(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir()
    b.mkdir()
    (a / "new").write_text("")
    (b / "old").write_text("")
    if not files.exchange_dirs(a, b):
        pytest.skip("no renameat2(RENAME_EXCHANGE) here")
    assert [p.name for p in b.iterdir()] == ["new"] and [p.name for p in a.iterdir()] == ["old"]


def test_force_never_deletes_a_file_a_user_added(tmp_path):
    """A run directory lists the files it was written with; ``force`` refuses to replace one
    that holds anything else (a user's notes), at any depth, and replaces it once they are
    moved out."""
    out = tmp_path / "run"
    with RunDir(out) as rd:
        (rd.path / "config.toml").write_text('command = "fit inertia"\nversion = "0.1.0"\n')
        (rd.path / "sub").mkdir()
        (rd.path / "sub" / "a.csv").write_text("1")
    assert (out / rundir.WRITTEN).read_text() == "config.toml\nsub/a.csv\n"
    (out / "sub" / "my_notes.txt").write_text("mine")
    with pytest.raises(InputError, match=r"did not write \(sub/my_notes.txt\)"):
        check_out(out, force=True)
    with pytest.raises(InputError, match="did not write"):
        with RunDir(out, force=True) as rd:
            pass
    assert (out / "sub" / "my_notes.txt").read_text() == "mine"
    (out / "sub" / "my_notes.txt").unlink()
    with RunDir(out, force=True) as rd:
        (rd.path / "config.toml").write_text('command = "fit inertia"\nversion = "0.1.0"\n')
    assert sorted(p.name for p in out.iterdir()) == [rundir.WRITTEN, "config.toml"]


def test_force_refuses_a_users_folder(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("precious")
    with pytest.raises(InputError, match="not a cassini-bayes output"):
        RunDir(out, force=True)
    (out / "config.toml").write_text('version = "1"\n')  # a config.toml of something else
    with pytest.raises(InputError, match="not a cassini-bayes output"):
        check_out(out, force=True)
    assert (out / "notes.txt").read_text() == "precious"


@pytest.mark.parametrize("name, text", [
    ("config.toml", 'command = "sbc"\nversion = "0.1.0"\n'),                 # fit, sbc
    ("config.toml", 'kind = "impulse_ratio"\n[run]\nversion = "0.1.0"\n'),  # experiment
    ("truth.json", '{"scenario": "s", "version": "0.1.0"}'),                  # simulate
    ("results.json", '{"seed": 0, "version": "0.1.0"}'),                      # reproduce
])
def test_package_outputs_are_recognised(tmp_path, name, text):
    (tmp_path / name).write_text(text)
    assert is_package_output(tmp_path)
    (tmp_path / name).write_bytes(b"\xff\xfe binary")
    assert not is_package_output(tmp_path)


def test_out_may_not_hold_the_inputs(tmp_path):
    run = tmp_path / "sim"
    run.mkdir()
    (run / "truth.json").write_text('{"scenario": "s", "version": "0.1.0"}')
    csv = run / "telemetry.csv"
    csv.write_text("t\n0\n")
    for out in (run, tmp_path, csv):
        with pytest.raises(InputError, match="input"):
            check_out(out, force=True, inputs=[csv])
    assert check_out(tmp_path / "new", inputs=[csv]) == (tmp_path / "new").resolve()


def test_parent_must_be_a_writable_directory(tmp_path):
    f = tmp_path / "file"
    f.write_text("x")
    with pytest.raises(InputError, match="not a directory"):
        check_out(f / "run")
    assert check_out(tmp_path / "a" / "b" / "run")  # missing parents are fine...
    assert not (tmp_path / "a").exists()           # ...and not created by the check
    if os.geteuid() != 0:  # root writes anywhere
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o555)
        with pytest.raises(InputError, match="cannot write"):
            check_out(ro / "run")
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []


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


def test_posterior_too_large_for_the_disk_is_refused_before_writing(tmp_path, monkeypatch):
    """Less free space than the arrays take: ENOSPC before the netCDF writer starts (which,
    out of space mid-file, printed HDF5 tracebacks), naming the folder, not RunDir's temp."""
    import shutil
    from collections import namedtuple

    idata = az.from_dict(posterior={"x": np.zeros((2, 100))})
    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda p: usage(1 << 30, 1 << 30, 1 << 20))
    out = tmp_path / "run"
    with pytest.raises(OSError) as e:
        with RunDir(out) as rd:
            write_posterior(rd.path, idata)
    assert e.value.errno == errno.ENOSPC and e.value.filename == str(tmp_path)
    assert "needs about 16 MiB, 1 MiB free" in e.value.strerror
    assert not out.exists() and _siblings(out) == []


def _temporary(parent, name, mark):
    """A temporary run directory as a killed writer leaves it (``mark``: its writer note, or
    None for none)."""
    d = parent / f".{name}.tmp-x1y2z3"
    (d / "figures").mkdir(parents=True)
    (d / "posterior.nc").write_bytes(b"\0" * 1000)
    (d / "figures" / "trace.png").write_bytes(b"png")
    if mark is not None:
        (d / rundir.TEMP_MARK).write_text(json.dumps(mark))
    return d


def test_stale_temporary_directories_of_ended_writers_are_removed(tmp_path):
    """SIGKILL leaves ``.NAME.tmp-…`` behind (no handler can run). The next run directory
    written beside it removes those whose writer on this host has ended — and never one
    without the package's note, one of another host, or one whose writer still runs."""
    import socket
    import subprocess
    import sys

    ended = subprocess.Popen([sys.executable, "-c", "pass"])
    ended.wait()
    alive = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    host = socket.gethostname()
    try:
        stale = _temporary(tmp_path, "a", {"host": host, "pid": ended.pid, "started": None})
        running = _temporary(tmp_path, "b", {"host": host, "pid": alive.pid,
                                             "started": rundir._process_start(alive.pid)})
        reused = _temporary(tmp_path, "c", {"host": host, "pid": alive.pid,
                                            "started": "another-boot:1"})  # its id, reused
        elsewhere = _temporary(tmp_path, "d", {"host": host + "-other", "pid": ended.pid,
                                               "started": None})
        unmarked = _temporary(tmp_path, "e", None)
        with RunDir(tmp_path / "run") as rd:
            (rd.path / "config.toml").write_text('command = "fit inertia"\nversion = "0"\n')
            assert json.loads((rd.path / rundir.TEMP_MARK).read_text())["pid"] == os.getpid()
        assert not stale.exists()
        assert running.exists() and elsewhere.exists() and unmarked.exists()
        assert (not reused.exists()) == (rundir._process_start(alive.pid) is not None)
    finally:
        alive.kill()
        alive.wait()
    # the finished run holds no writer note, and does not list one
    assert sorted(p.name for p in (tmp_path / "run").iterdir()) == [".cassini-bayes-files",
                                                                   "config.toml"]
    assert (tmp_path / "run" / ".cassini-bayes-files").read_text() == "config.toml\n"
    # nor does a run that replaced another with force
    with RunDir(tmp_path / "run", force=True) as rd:
        (rd.path / "config.toml").write_text('command = "fit inertia"\nversion = "1"\n')
    assert sorted(p.name for p in (tmp_path / "run").iterdir()) == [".cassini-bayes-files",
                                                                   "config.toml"]
    assert "version = \"1\"" in (tmp_path / "run" / "config.toml").read_text()
    assert not list(tmp_path.glob(".run.*"))
