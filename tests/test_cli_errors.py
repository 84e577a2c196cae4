"""The CLI's one error path (cassini_bayes.cli.main, docs/cli.md): usage errors, bad input, OS and
internal errors, Ctrl-C, and what ``--out``/``--force`` may touch.

Every case asserts the exit status, at most three lines on stderr, no traceback, and (where the
run has input files) that they are unchanged. Most cases stop before any sampling; one tiny fit
(1 chain x 20 + 20 draws, idealised model) provides a real run directory.
"""

from __future__ import annotations

import errno
import hashlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import jax
import pytest

from cassini_bayes._paths import EXPERIMENTS_DIR, MODELS_DIR, SCENARIOS_DIR, input_path, \
    model_path
from cassini_bayes.errors import InputError
from cassini_bayes.spacecraft import load_spacecraft
from cassini_bayes.telemetry import write_telemetry
from run_dirs import make_run
from slews import make_slews

SC = "cassini_2000_03_15"
TINY = ["--chains", "1", "--warmup", "20", "--draws", "20", "--idealised"]
ROOT = Path(__file__).resolve().parents[1]


def _sha(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _tree(d: Path) -> dict[str, str]:
    return {str(p.relative_to(d)): _sha(p) for p in sorted(d.rglob("*")) if p.is_file()}


def _one_error(code: int, err: str, expect: int, *words: str) -> None:
    lines = err.strip().splitlines()
    assert code == expect, err
    assert 1 <= len(lines) <= 3 and "Traceback" not in err, err
    for w in words:
        assert w in err, err


def _leftovers(d: Path) -> list[str]:
    return sorted(p.name for p in Path(d).iterdir() if p.name.startswith("."))


# ``python -m cassini_bayes.cli`` with Python's own Ctrl-C handling even when the test runner was
# started with SIGINT ignored (a background job), which a child would inherit
_MAIN = ("import runpy, signal; signal.signal(signal.SIGINT, signal.default_int_handler); "
         "runpy.run_module('cassini_bayes.cli', run_name='__main__', alter_sys=True)")


def _cli(*args, cwd=None) -> subprocess.Popen:
    """``cassini-bayes ARGS`` (the console entry, :func:`cassini_bayes.cli.entry`) in a fresh
    process."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH",
                                                                                 "")])}
    return subprocess.Popen([sys.executable, "-c", _MAIN, *map(str, args)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            cwd=cwd)


@pytest.fixture(scope="module")
def csv(tmp_path_factory):
    path = tmp_path_factory.mktemp("tel") / "slew.csv"
    write_telemetry(path, make_slews(jax.random.key(11), load_spacecraft(SC), dur=120.0))
    return path


@pytest.fixture(scope="module")
def run(tmp_path_factory, csv):
    """A finished (tiny) inertia run directory."""
    from cassini_bayes.cli import main

    out = tmp_path_factory.mktemp("runs") / "inertia"
    code = main(["fit", "inertia", "--telemetry", str(csv), "--spacecraft", SC, "--out",
                 str(out), *TINY])
    assert code == 0
    return out


# ------------------------------------------------------------------------------ usage errors


@pytest.mark.parametrize("args, words", [
    (["bogus"], ["No such command"]),
    (["fit", "inertia"], ["--telemetry"]),
    (["fit", "inertia", "--telemetry", "x.csv", "--spacecraft", SC, "--out", "o",
      "--chains", "0"], ["--chains"]),
    (["fit", "inertia", "--seed", "abc"], ["--seed"]),
    (["fit", "inertia", "--telemetry", "x.csv", "--spacecraft", SC, "--out", "o",
      "--seed", "-1"], ["--seed"]),
    (["fit", "thrust", "--telemetry", "x.csv", "--spacecraft", SC, "--out", "o",
      "--seed", str(2**64)], ["--seed"]),
    (["sbc", "toy", "-n", "4", "--out", "o", "--seed", str(2**63)], ["--seed"]),
    (["sbc", "toy", "-n", "0", "--out", "o"], ["--replicates"]),
    (["simulate", "s.toml", "--out", "o", "--seed", "-5"], ["--seed"]),
    (["experiment", "e.toml", "--out", "o", "--seed", str(2**70)], ["--seed"]),
    (["reproduce", "--out", "o", "--seed", "-1"], ["--seed"]),
    (["fit", "inertia", "--nope"], ["--nope"]),
])
def test_usage_errors_exit_2_in_a_few_lines(run_cli, args, words):
    code, _, err = run_cli(*args)
    _one_error(code, err, 2, *words)


def test_no_arguments_and_usage_errors_in_a_real_process(tmp_path):
    p = _cli(cwd=tmp_path)
    out, err = p.communicate(timeout=120)
    assert p.returncode == 2 and "Usage" in out + err and "Traceback" not in err
    p = _cli("fit", "inertia", "--telemetry", "x.csv", "--spacecraft", SC, "--out", "o",
             "--chains", "0", cwd=tmp_path)
    out, err = p.communicate(timeout=120)
    _one_error(p.returncode, err, 2, "--chains")


# --------------------------------------------------------------- internal and OS errors


def test_internal_error_is_one_line_with_a_hint(run, run_cli, monkeypatch):
    import cassini_bayes.report

    def broken(*a, **k):
        raise ZeroDivisionError("boom")

    monkeypatch.setattr(cassini_bayes.report, "build_report", broken)
    monkeypatch.delenv("CASSINI_BAYES_DEBUG", raising=False)
    code, _, err = run_cli("report", run)
    _one_error(code, err, 1, "internal error (ZeroDivisionError): boom", "CASSINI_BAYES_DEBUG=1")
    monkeypatch.setenv("CASSINI_BAYES_DEBUG", "1")
    code, _, err = run_cli("report", run)
    assert code == 1 and "Traceback" in err  # asked for


@pytest.mark.parametrize("exc, words", [
    (OSError(errno.ENOSPC, "No space left on device", "/data/report.html"),
     ["/data/report.html", "No space left"]),
    (PermissionError(errno.EACCES, "Permission denied", "/data/x"), ["/data/x", "Permission"]),
])
def test_os_errors_are_one_line_naming_the_path(run, run_cli, monkeypatch, exc, words):
    import cassini_bayes.report

    def failing(*a, **k):
        raise exc

    monkeypatch.setattr(cassini_bayes.report, "build_report", failing)
    code, _, err = run_cli("report", run)
    _one_error(code, err, 1, *words)


def test_full_disk_while_writing_a_fit_keeps_the_old_run(run, csv, run_cli, monkeypatch):
    import cassini_bayes.rundir

    before, sha_in = _tree(run), _sha(csv)

    def full(run_dir, idata):
        (Path(run_dir) / "posterior.nc").write_bytes(b"half")
        raise OSError(errno.ENOSPC, "No space left on device", str(run_dir / "posterior.nc"))

    monkeypatch.setattr(cassini_bayes.rundir, "write_posterior", full)
    code, _, err = run_cli("fit", "inertia", "--telemetry", csv, "--spacecraft", SC, "--out",
                           run, "--force", *TINY)
    _one_error(code, err, 1, "posterior.nc", "No space left")
    assert _tree(run) == before and _sha(csv) == sha_in
    assert _leftovers(run.parent) == []


# --------------------------------------------------------------------------------- Ctrl-C


def _cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")
def test_ctrl_c_during_a_fit_exits_130_and_leaves_nothing(tmp_path, csv):
    out = tmp_path / "run"
    sha_in = _sha(csv)
    p = _cli("fit", "inertia", "--telemetry", csv, "--spacecraft", SC, "--out", out,
             "--chains", "1", "--warmup", "20000", "--draws", "20000", "--idealised")
    deadline = time.monotonic() + 120
    while p.poll() is None and _cpu_seconds(p.pid) < 6 and time.monotonic() < deadline:
        time.sleep(0.2)  # past start-up (about 1 s of CPU): reading, compiling or sampling
    assert p.poll() is None, p.communicate()[1]
    p.send_signal(signal.SIGINT)
    try:
        _, err = p.communicate(timeout=120)
    finally:
        p.kill()
    _one_error(p.returncode, err, 130, "interrupted")
    assert not out.exists() and _leftovers(tmp_path) == [] and _sha(csv) == sha_in


# ``python -m cassini_bayes.cli`` whose run directories wait, once their config.toml is written,
# for a signal: the window in which a kill used to leave a half-written .NAME.tmp-… behind
_MAIN_SLOW_WRITE = (
    "import runpy, time, cassini_bayes.rundir as rd\n"
    "write = rd.write_config\n"
    "def slow(*a, **k):\n"
    "    p = write(*a, **k)\n"
    "    time.sleep(120)\n"
    "    return p\n"
    "rd.write_config = slow\n"
    "runpy.run_module('cassini_bayes.cli', run_name='__main__', alter_sys=True)\n")


def test_sigterm_exits_143_and_leaves_no_temporary_directory(tmp_path):
    """``kill -TERM`` (a batch system's stop) while a run directory is written: the temporary
    directory is removed as on Ctrl-C, nothing appears under --out, and the process exits 143
    (128 + SIGTERM), where Python's default would leave ``.NAME.tmp-…`` behind."""
    inertia = make_run(tmp_path / "runs", "inertia")
    out = tmp_path / "budget"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH",
                                                                                 "")])}
    p = subprocess.Popen([sys.executable, "-c", _MAIN_SLOW_WRITE, "budget", "--inertia",
                          str(inertia), "--out", str(out), "--draws", "20"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    deadline = time.monotonic() + 120
    while p.poll() is None and time.monotonic() < deadline and not any(
            (d / "config.toml").exists() for d in tmp_path.glob(".budget.tmp-*")):
        time.sleep(0.1)
    assert p.poll() is None, p.communicate()[1]
    p.send_signal(signal.SIGTERM)
    try:
        _, err = p.communicate(timeout=60)
    finally:
        p.kill()
    _one_error(p.returncode, err, 143, "terminated")
    assert not out.exists() and _leftovers(tmp_path) == []


def test_sigterm_in_a_command_cleans_up_like_ctrl_c(tmp_path, run_cli, monkeypatch):
    """In process: SIGTERM raised inside a run directory being written ends the command with
    143 and one line; the temporary directory is gone and the previous SIGTERM handler is back."""
    import cassini_bayes.rundir as rd

    write = rd.write_config

    def killed(*a, **k):
        write(*a, **k)
        os.kill(os.getpid(), signal.SIGTERM)
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:   # the handler raises here
            time.sleep(0.01)
        raise AssertionError("SIGTERM was not handled")

    def ignored(signum, frame):   # (were main's handler missing, the test fails, not pytest)
        pass

    monkeypatch.setattr(rd, "write_config", killed)
    inertia = make_run(tmp_path / "runs", "inertia")
    previous = signal.signal(signal.SIGTERM, ignored)
    try:
        code, _, err = run_cli("budget", "--inertia", inertia, "--out", tmp_path / "b",
                               "--draws", 20)
        assert signal.getsignal(signal.SIGTERM) is ignored
    finally:
        signal.signal(signal.SIGTERM, previous)
    _one_error(code, err, 143, "terminated")
    assert _leftovers(tmp_path) == [] and not (tmp_path / "b").exists()


def test_ctrl_c_in_a_command_is_130_in_process(run, run_cli, monkeypatch):
    import cassini_bayes.report

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(cassini_bayes.report, "build_report", interrupted)
    code, _, err = run_cli("report", run)
    _one_error(code, err, 130, "interrupted")


def test_ctrl_c_in_sbc_keeps_checkpoints_and_says_resume(tmp_path, run_cli, monkeypatch):
    import cassini_bayes.analysis.campaign as campaign

    def interrupted(spec, n, work, **kw):
        Path(work).mkdir()
        (Path(work) / "batch_000000.npz").write_bytes(b"")
        raise KeyboardInterrupt

    monkeypatch.setattr(campaign, "run_campaign", interrupted)
    out = tmp_path / "sbc"
    code, _, err = run_cli("sbc", "toy", "-n", 4, "--out", out)
    _one_error(code, err, 130, "1 finished batch", "--resume")
    assert not out.exists() and _leftovers(tmp_path) == [".sbc.sbc-work"]


# ------------------------------------------------------------------------ --out and --force


def test_force_never_replaces_a_users_folder(tmp_path, csv, run_cli):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("precious")
    for args in (["fit", "inertia", "--telemetry", csv, "--spacecraft", SC, *TINY],
                 ["simulate", ROOT / "experiments/scenarios/slew_2000_03_15.toml"],
                 ["experiment", ROOT / "experiments/impulse_ratio.toml", "--quick"],
                 ["reproduce", "--quick"],
                 ["sbc", "toy", "-n", "4"]):
        code, _, err = run_cli(*args, "--out", mine, "--force")
        _one_error(code, err, 2, "not a cassini-bayes output")
    assert _tree(mine) == {"notes.txt": _sha(mine / "notes.txt")}


def test_out_holding_the_inputs_is_refused_even_with_force(tmp_path, csv, run_cli):
    sim = tmp_path / "sim"
    sim.mkdir()
    tel = sim / "telemetry.csv"
    tel.write_bytes(csv.read_bytes())
    (sim / "truth.json").write_text('{"scenario": "s", "version": "0.1.0"}')  # simulate's own
    before = _tree(sim)
    for out in (sim, tmp_path):
        code, _, err = run_cli("fit", "inertia", "--telemetry", tel, "--spacecraft", SC,
                               "--out", out, "--force", *TINY)
        _one_error(code, err, 2, "input")
    exp = tmp_path / "e.toml"
    exp.write_text((ROOT / "experiments/impulse_ratio.toml").read_text())
    code, _, err = run_cli("experiment", exp, "--out", tmp_path, "--force")
    _one_error(code, err, 2, "input")
    assert _tree(sim) == before


def test_out_under_a_file_is_refused(tmp_path, csv, run_cli):
    f = tmp_path / "file"
    f.write_text("x")
    code, _, err = run_cli("fit", "inertia", "--telemetry", csv, "--spacecraft", SC,
                           "--out", f / "run", *TINY)
    _one_error(code, err, 2, "not a directory")
    code, _, err = run_cli("sbc", "toy", "-n", 4, "--out", f / "run")
    _one_error(code, err, 2, "not a directory")


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write in read-only folders")
def test_out_in_a_read_only_folder_is_refused(tmp_path, csv, run_cli):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    code, _, err = run_cli("fit", "inertia", "--telemetry", csv, "--spacecraft", SC,
                           "--out", ro / "run", *TINY)
    _one_error(code, err, 2, "cannot write")


def test_force_replaces_a_previous_run(run, csv, run_cli):
    code, _, err = run_cli("fit", "inertia", "--telemetry", csv, "--spacecraft", SC, "--out",
                           run, "--force", "--seed", "3", *TINY)
    assert code == 0, err
    assert "seed = 3" in (run / "config.toml").read_text() and _leftovers(run.parent) == []


def test_report_out_creates_its_folder_and_spares_the_run_files(run, run_cli, tmp_path):
    page = tmp_path / "new" / "deeper" / "page.html"
    code, out, err = run_cli("report", run, "--out", page)
    assert code == 0, err
    assert page.read_text().lstrip().lower().startswith("<!doctype html")
    before = _tree(run)
    for target in (run / "summary.json", tmp_path / "new"):
        code, _, err = run_cli("report", run, "--out", target)
        _one_error(code, err, 2)
    assert _tree(run) == before
    code, _, err = run_cli("report", tmp_path / "nope", "--out", tmp_path / "a" / "p.html")
    _one_error(code, err, 2)
    assert not (tmp_path / "a").exists()  # no empty folder left behind


def test_report_out_never_overwrites_a_users_file(run, run_cli, tmp_path):
    """An existing --out file: a user's file is never replaced (not even with --force); a page
    cassini-bayes wrote is replaced only with --force."""
    mine = tmp_path / "notes.csv"
    mine.write_text("t,x\n0,1\n")
    for extra in ((), ("--force",)):
        code, _, err = run_cli("report", run, "--out", mine, *extra)
        _one_error(code, err, 2, "not a page cassini-bayes wrote")
    assert mine.read_text() == "t,x\n0,1\n"
    page = tmp_path / "page.html"
    assert run_cli("report", run, "--out", page)[0] == 0
    code, _, err = run_cli("report", run, "--out", page)
    _one_error(code, err, 2, "add --force")
    assert run_cli("report", run, "--out", page, "--force")[0] == 0


# ------------------------------------------------------------------------------ input files


@pytest.mark.parametrize("command", ["simulate", "experiment"])
def test_directory_or_binary_input_is_one_line(tmp_path, run_cli, command):
    binary = tmp_path / "blob.toml"
    binary.write_bytes(bytes(range(256)))
    for bad, word in ((tmp_path, "directory"), (binary, "UTF-8")):
        code, _, err = run_cli(command, bad, "--out", tmp_path / "o")
        _one_error(code, err, 2, word)
    code, _, err = run_cli("sbc", "toy", "-n", 4, "--out", tmp_path / "o", "--scenario", binary)
    _one_error(code, err, 2, "UTF-8")


def test_every_file_argument_follows_one_path_rule(tmp_path, monkeypatch):
    """:func:`cassini_bayes._paths.input_path`: a file that exists (``.toml`` may be left off)
    wins; only a bare name falls back to the shipped files; a path with a folder part that does
    not exist is refused, naming the missing folder (the issue-28 hole: ``simulate
    typo/slews_post_probe.toml`` ran the shipped scenario)."""
    from cassini_bayes.experiments import load_experiment
    from cassini_bayes.simulate import load_scenario
    from cassini_bayes.simulate.health_campaign import load_campaign
    from cassini_bayes.simulate.scenario import scenario_path

    monkeypatch.chdir(tmp_path)
    assert scenario_path("slews_post_probe") == SCENARIOS_DIR / "slews_post_probe.toml"
    assert input_path("inertia_table1", "experiment", EXPERIMENTS_DIR) == \
        EXPERIMENTS_DIR / "inertia_table1.toml"
    for load, name in ((load_scenario, "slews_post_probe.toml"),
                       (load_campaign, "health_control.toml"),
                       (load_experiment, "inertia_table1.toml"),
                       (load_spacecraft, "cassini_post_probe.toml")):
        with pytest.raises(InputError, match=r"typo/.*the folder typo does not exist"):
            load(f"typo/{name}")
    with pytest.raises(InputError, match="no shipped scenario of that name.*slews_post_probe,"):
        scenario_path("slews_post_probee")
    (tmp_path / "mine.toml").write_text("")
    assert scenario_path("mine") == Path("mine.toml")   # a file here, .toml left off
    with pytest.raises(InputError, match="telemetry file not found; check the path$"):
        input_path("nope.csv", "telemetry", suffix=None)   # no shipped telemetry to fall to


def test_spacecraft_path_with_a_missing_folder_is_an_error(tmp_path, csv, run_cli,
                                                           monkeypatch):
    code, _, err = run_cli("fit", "inertia", "--telemetry", csv, "--spacecraft",
                           "typo/cassini_post_probe.toml", "--out", tmp_path / "o", *TINY)
    _one_error(code, err, 2, "typo/cassini_post_probe.toml")
    monkeypatch.chdir(tmp_path)
    assert model_path("cassini_post_probe") == MODELS_DIR / "cassini_post_probe.toml"
    assert model_path("cassini_post_probe.toml") == MODELS_DIR / "cassini_post_probe.toml"
    (tmp_path / "cassini_post_probe.toml").write_text("")  # a file in cwd wins over the shipped
    assert model_path("cassini_post_probe") == Path("cassini_post_probe.toml")
    with pytest.raises(InputError, match="directory"):
        model_path(str(tmp_path))


@pytest.mark.parametrize("setting, word", [
    ("thin=0", "thin"), ("num_chains=0", "num_chains"), ("num_draws=2.5", "num_draws"),
    ("num_warmup=-1", "num_warmup"), ("thin=50", "thin"),
])
def test_sbc_sampler_settings_are_checked(tmp_path, run_cli, setting, word):
    code, _, err = run_cli("sbc", "toy", "-n", 4, "--out", tmp_path / "o", "--set", setting,
                           "--set", "num_draws=20" if "num_draws" not in setting else "thin=1")
    _one_error(code, err, 2, word)
    assert _leftovers(tmp_path) == []


def test_sbc_bad_scheduler_address_is_one_line(tmp_path, run_cli):
    code, _, err = run_cli("sbc", "toy", "-n", 4, "--out", tmp_path / "o", "--executor", "dask",
                           "--scheduler", "no-port-here")
    _one_error(code, err, 2, "no-port-here")
    assert _leftovers(tmp_path) == []  # no checkpoint directory left to block the next run


def test_damaged_sbc_checkpoints_are_recomputed(tmp_path):
    from cassini_bayes.analysis.campaign import load_checkpoints

    (tmp_path / "batch_000000.npz").write_bytes(b"PK\x03\x04 truncated")
    (tmp_path / "batch_000001.npz").write_bytes(b"")
    with pytest.warns(RuntimeWarning, match="unreadable checkpoint"):
        assert load_checkpoints(tmp_path, 2) == {}


def test_unreadable_sbc_manifest_is_one_line(tmp_path, run_cli):
    out = tmp_path / "o"
    work = tmp_path / ".o.sbc-work"
    work.mkdir()
    (work / "manifest.json").write_text("{ truncated")
    (work / "batch_000000.npz").write_bytes(b"a finished batch")   # something to keep
    code, _, err = run_cli("sbc", "toy", "-n", 4, "--out", out, "--resume")
    _one_error(code, err, 2, "manifest", "--force")


def test_a_work_folder_without_a_finished_batch_is_started_over(tmp_path, run_cli):
    """A campaign killed before its first batch leaves only its manifest: nothing to keep, so
    the next run starts over without asking for --resume or --force."""
    out = tmp_path / "o"
    work = tmp_path / ".o.sbc-work"
    work.mkdir()
    (work / "manifest.json").write_text("{}")
    code, _, err = run_cli("sbc", "toy", "-n", 4, "--out", out, "--batch", 4,
                           "--set", "num_warmup=50", "--set", "num_draws=50")
    assert code == 0, err
    assert not work.exists() and (out / "summary.json").exists()


def test_ctrl_c_swallowed_by_python_is_delivered_again(run, run_cli, monkeypatch):
    """A KeyboardInterrupt raised inside a ``__del__`` (or a gc callback, as JAX's) is only
    reported as "Exception ignored"; main sends SIGINT again so the run still stops."""
    import cassini_bayes.report

    class Swallowed:
        def __del__(self):
            raise KeyboardInterrupt

    def slow(*a, **k):
        Swallowed()  # the interrupt lands in __del__ and is swallowed
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:  # the work goes on ... until SIGINT comes again
            time.sleep(0.01)
        return run / "report.html"

    monkeypatch.setattr(cassini_bayes.report, "build_report", slow)
    # a user's Ctrl-C reaches Python's handler; a test runner started in the background (CI) may
    # have SIGINT ignored, and then the repeated SIGINT would be ignored too
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        code, _, err = run_cli("report", run)
    finally:
        signal.signal(signal.SIGINT, previous)
    _one_error(code, err, 130, "interrupted")
