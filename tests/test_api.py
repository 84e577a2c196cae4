"""The public Python API (:mod:`cassini_bayes`, docs/api.md): one small fit per model gives the
numbers the CLI writes (and wrote before the fit logic left the CLI, ``tests/data/fit_pins.json``),
``save`` writes the CLI's run directory, and importing the package is cheap and leaves JAX alone.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tomllib

import arviz as az
import numpy as np
import pytest

import cassini_bayes as cb
from cassini_bayes.errors import InputError, command_line
from fit_pins import (PINS, RECIPES, SMALL, assert_same, assert_within_tolerance, cli_args,
                      numbers, write_inputs)

RUN_FILES = [".cassini-bayes-files", "config.toml", "posterior.nc", "report.html",
             "summary.json"]
PINNED = json.loads(PINS.read_text())


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """The pinned fits' input files, per model."""
    return {m: write_inputs(m, tmp_path_factory.mktemp(m)) for m in RECIPES}


def _api_fit(model: str, files: dict, *, as_objects: bool):
    _, _, spacecraft, _, seed = RECIPES[model]
    tel = cb.read_telemetry(files["telemetry"]) if as_objects else files["telemetry"]
    sc = cb.load_spacecraft(spacecraft) if as_objects else spacecraft
    if model == "inertia":
        return cb.fit_inertia(tel, sc, seed=seed, **SMALL)
    if model == "thrust":
        pulses = cb.read_pulses(files["pulses"]) if as_objects else files["pulses"]
        return cb.fit_thrust(tel, pulses, sc, seed=seed, **SMALL)
    return cb.fit_rwa4(tel, sc, method="rcs", prior="cone", seed=seed, **SMALL)


# the pins are what the CLI wrote for these fits; the CLI itself is run again for the inertia fit
# here and for the others in the slow tier (each thrust/RWA4 fit costs about a minute)
CLI_AGAIN = [pytest.param("inertia"),
             *(pytest.param(m, marks=pytest.mark.slow) for m in RECIPES if m != "inertia")]


@pytest.mark.parametrize("model", CLI_AGAIN)
def test_fit_matches_the_cli_and_the_pinned_numbers(model, inputs, tmp_path, run_cli):
    """Objects in, the same summary.json numbers as ``cassini-bayes fit`` with the same seed and
    options (1e-9 relative: one machine, one process); both match the pins by their stated
    tolerances (exact where no sampler touches a number, Monte Carlo error where one does);
    ``save`` writes the same four files."""
    code, _, err = run_cli(*cli_args(model, inputs[model], tmp_path / "cli"))
    assert code == 0, err
    cli_summary = json.loads((tmp_path / "cli" / "summary.json").read_text())
    cli_idata = az.from_netcdf(tmp_path / "cli" / "posterior.nc")
    assert_within_tolerance(PINNED[model], numbers(cli_summary), f"{model} (CLI vs pin)",
                            idata=cli_idata)

    fit = _api_fit(model, inputs[model], as_objects=True)
    assert isinstance(fit, cb.FitResult) and fit.kind == model
    summary = fit.summary()
    assert_same(numbers(cli_summary), numbers(summary), f"{model} (API vs CLI)")
    assert summary["warnings"] == cli_summary["warnings"]
    assert fit.baseline == summary["baseline"]
    assert fit.sensitivity == summary.get("sensitivity")
    assert fit.converged == summary["diagnostics"]["converged"]
    assert set(fit.idata.groups()) >= {"posterior", "sample_stats", "prior"}

    out = fit.save(tmp_path / "api")
    assert sorted(p.name for p in out.iterdir()) == RUN_FILES
    assert json.loads((out / "summary.json").read_text()) == cli_summary
    cfg = tomllib.loads((out / "config.toml").read_text())
    cli_cfg = tomllib.loads((tmp_path / "cli" / "config.toml").read_text())
    assert cfg["inputs"].pop("spacecraft") == {"model": fit.config["spacecraft"]["name"]}
    cli_cfg["inputs"].pop("spacecraft")
    for c in (cfg, cli_cfg):    # the compilation cache's hits and misses are the process's own
        assert set(c.pop("jax_cache")) == {"dir", "hits", "misses", "rejected"}
    assert cfg == cli_cfg   # telemetry/pulses read from files record those files


@pytest.mark.parametrize("model", [m for m in RECIPES if m != "inertia"])
def test_fit_gives_the_pinned_numbers(model, inputs, tmp_path):
    """Paths in: the pinned summary.json numbers, by their stated tolerances;
    ``save`` writes the four files of a run directory."""
    fit = _api_fit(model, inputs[model], as_objects=False)
    assert_within_tolerance(PINNED[model], numbers(fit.summary()), f"{model} (API vs pin)",
                            idata=fit.idata)
    assert sorted(p.name for p in fit.save(tmp_path / "run").iterdir()) == RUN_FILES
    if model == "rwa4":   # RCS, no inertia posterior: a warning exactly when the cone passes 3°
        cone = fit.summary()["direction"]["cone_deg"]["95"]     # 2.18° here
        assert (cone > 3.0) == any("flight-calibrated" in w for w in fit.warnings)


def test_rcs_fit_beyond_browns_budget_without_an_inertia_posterior_warns():
    """Brown's 3° for the RCS method assumes a flight-calibrated inertia; with the model file's
    ±10 % knowledge the cone is ~6° (docs/robust/README.md), and the fit says so, naming the
    argument that fixes it. Not for the RWA method, nor with an inertia posterior."""
    from cassini_bayes.api._rwa4 import rcs_budget_warning

    msg = rcs_budget_warning("rcs", False, 5.87)
    assert "5.87°" in msg and "3° budget" in msg and "inertia_posterior" in msg
    assert rcs_budget_warning("rcs", False, 2.9) == ""
    assert rcs_budget_warning("rcs", True, 5.87) == ""
    assert rcs_budget_warning("rwa", False, 5.87) == ""


def test_paths_in_and_save_refuses_to_overwrite(inputs, tmp_path):
    """Paths in (a shipped model by name) give the same fit as objects in; ``save`` refuses a
    non-empty directory without ``force=True``, naming the argument, and replaces its own."""
    fit = _api_fit("inertia", inputs["inertia"], as_objects=False)
    assert_within_tolerance(PINNED["inertia"], numbers(fit.summary()), idata=fit.idata)
    out = fit.save(tmp_path / "run")
    with pytest.raises(InputError, match="force=True"):
        fit.save(out)
    assert fit.save(out, force=True) == out
    with pytest.raises(InputError, match="input"):
        fit.save(inputs["inertia"]["telemetry"].parent, force=True)


def test_experiment_and_fit_runs_have_the_same_summary_keys(inputs, tmp_path):
    """One run writer: an experiment's per-fit run directory carries the summary.json keys (and
    files) of ``cassini-bayes fit``."""
    from cassini_bayes._paths import EXPERIMENTS_DIR
    from cassini_bayes.experiments import load_experiment, run_experiment

    out = tmp_path / "exp"
    run_experiment(load_experiment(EXPERIMENTS_DIR / "inertia_table1.toml"), out, quick=True)
    sub = out / "fits" / "post_probe"
    # (the experiment's own .cassini-bayes-files lists the files of its sub-runs)
    assert sorted(p.name for p in sub.iterdir()) == sorted(RUN_FILES[1:] + ["telemetry.csv"])
    exp_summary = json.loads((sub / "summary.json").read_text())
    assert set(exp_summary) == set(PINNED["inertia"]["summary"]) | {"warnings"}
    assert exp_summary["model"] == "idealised" and exp_summary["wheel_errors"] is None


def test_library_errors_name_arguments_the_cli_options(inputs):
    with pytest.raises(InputError, match=r"wheel_errors='x': choose 'per_wheel' or 'common'"):
        cb.fit_inertia(inputs["inertia"]["telemetry"], "cassini_2000_03_15", wheel_errors="x")
    with pytest.raises(InputError, match=r"mode='each'"):
        cb.fit_thrust(inputs["thrust"]["telemetry"], inputs["thrust"]["pulses"], "fsds",
                      mode="each")
    with pytest.raises(InputError, match=r"method='rwa' needs RWA slew pairs"):
        cb.fit_rwa4(inputs["rwa4"]["telemetry"], "cassini_pre_soi", method="rwa")
    with pytest.raises(InputError, match=r"chains=0"):
        cb.fit_inertia(inputs["inertia"]["telemetry"], "cassini_2000_03_15", chains=0)
    with command_line(), pytest.raises(InputError, match=r"--method rwa needs RWA slew pairs"):
        cb.fit_rwa4(inputs["rwa4"]["telemetry"], "cassini_pre_soi", method="rwa")


def test_wrong_inputs_are_input_errors_naming_the_argument(inputs):
    """Mistakes of type, shape or range in the public functions' arguments are one-line
    ``InputError`` s, as from files: never a NumPy, JAX or pathlib error from inside."""
    import numpy as np

    tel_path = inputs["inertia"]["telemetry"]
    empty = cb.Telemetry(np.empty(0), np.empty((0, 4)), np.empty((0, 3)), np.empty((0, 4)))
    tel = cb.read_telemetry(tel_path)
    short = cb.Telemetry(tel.t[:10], tel.q, tel.omega, tel.wheel_rates)
    cases = [
        (lambda: cb.fit_inertia(empty, "cassini_2000_03_15"), r"<telemetry>: only 0 sample"),
        (lambda: cb.fit_inertia(short, "cassini_2000_03_15"), r"mismatched lengths: 'q'"),
        (lambda: cb.fit_inertia({"t": [0.0]}, "cassini_2000_03_15"),
         r"telemetry: give a path, a loaded object or a list of them, not dict"),
        (lambda: cb.fit_inertia(tel_path, "cassini_2000_03_15", target_accept="x"),
         r"target_accept: use a number in 0.5 .. 0.999, got 'x'"),
        (lambda: cb.fit_inertia(tel_path, "cassini_2000_03_15", chains=100_000),
         r"chains=100000: use an integer in 1 .. 64"),
        (lambda: cb.fit_inertia([tel_path, tel_path], "cassini_2000_03_15"),
         r"holds the same samples as"),
        (lambda: cb.read_telemetry(42), r"expected the path of a telemetry file, got int"),
        (lambda: cb.read_telemetry("telemetry"), r"^telemetry: telemetry file not found"),
        (lambda: cb.load_spacecraft(None), r"expected the path of a spacecraft model"),
        (lambda: cb.check_telemetry(tel_path, wheel_tol_rpm=-2),
         r"wheel_tol_rpm: must be a positive finite number"),
        (lambda: cb.budget(inertia=42), r"inertia: give a FitResult or a run directory, not "
                                        r"int"),
        (lambda: cb.budget(inertia=str(tel_path.parent), seed=-1), r"seed=-1"),
        (lambda: cb.fit_health(42, "cassini_post_probe"), r"events: give events.csv files"),
        (lambda: cb.fit_health([("x", tel_path, tel_path)] * 2, "cassini_post_probe"),
         r"events date_days: use a number, got 'x'"),
    ]
    for call, message in cases:
        with pytest.raises(InputError, match=message):
            call()


def test_check_and_leak_monitor_take_loaded_objects(inputs):
    """``check_telemetry`` and ``monitor_leak`` take what the readers return, as the fits do."""
    files = inputs["thrust"]
    tel, log = cb.read_telemetry(files["telemetry"]), cb.read_pulses(files["pulses"])
    sc = cb.load_spacecraft("fsds")
    by_path = cb.check_telemetry(files["telemetry"], pulses=files["pulses"], spacecraft="fsds")
    by_object = cb.check_telemetry(tel, pulses=log, spacecraft=sc)
    assert by_object.quiet == by_path.quiet and by_object.thrusters == by_path.thrusters
    leak = cb.monitor_leak(tel, sc, pulses=log)
    assert leak.config["inputs"]["spacecraft"] == {"model": sc.name}
    assert leak.summary()["t_end_s"] == float(tel.t[-1])
    leak.summary()["t_end_s"] = -1.0                  # a copy: the result keeps its own
    assert leak.summary()["t_end_s"] == float(tel.t[-1])


def test_simulate_wraps_the_command(tmp_path, run_cli):
    """``cb.simulate_scenario`` writes what ``cassini-bayes simulate`` writes, byte for byte."""
    from cassini_bayes.simulate.scenario import scenario_path

    code, _, err = run_cli("simulate", scenario_path("fsds_biasing"), "--out",
                           tmp_path / "cli", "--seed", "3")
    assert code == 0, err
    sim = cb.simulate_scenario("fsds_biasing", seed=3)
    assert sim.pulses is not None and sim.truth()["seed"] == 3
    out = sim.save(tmp_path / "api")
    for name in ("telemetry.csv", "pulses.csv", "truth.json"):
        assert (out / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()


def _python(code: str, xla_flags: str | None = None) -> str:
    """stdout of ``python -c code`` in a fresh process, ``XLA_FLAGS`` as given (default unset)."""
    import os

    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}
    if xla_flags is not None:
        env["XLA_FLAGS"] = xla_flags
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, check=True).stdout


def test_import_is_cheap_and_leaves_jax_alone():
    """``import cassini_bayes`` imports no JAX, and with the public names touched no NumPyro or
    ArviZ; neither changes a JAX setting (64-bit, the compilation cache, host devices): the
    functions that compute do (:func:`cassini_bayes.setup_jax`). The names are the documented
    ones."""
    code = ("import sys, cassini_bayes as cb\n"
            "assert 'jax' not in sys.modules and 'numpy' not in sys.modules\n"
            "cb.fit_inertia, cb.fit_thrust, cb.fit_rwa4, cb.simulate_scenario, cb.FitResult\n"
            "cb.propagate_conic, cb.VectorTree, cb.setup_jax\n"
            "assert 'numpyro' not in sys.modules and 'arviz' not in sys.modules\n"
            "import jax\n"
            "print(jax.config.jax_enable_x64, jax.config.jax_compilation_cache_dir,\n"
            "      jax.local_device_count(), sorted(cb.__all__))")
    out = _python(code).split(maxsplit=3)
    assert out[:3] == ["False", "None", "1"]
    assert set(cb.__all__) >= {"read_telemetry", "read_pulses", "load_spacecraft",
                               "simulate_scenario",
                               "fit_inertia", "fit_thrust", "fit_rwa4", "FitResult"}
    assert callable(cb.simulate_scenario)


HEAVY = ("jax", "numpy", "numpyro", "arviz", "xarray", "matplotlib", "scipy")


def test_the_command_line_and_a_fit_up_to_its_sampler_import_nothing_heavy():
    """``import cassini_bayes.cli`` (every command registered: what ``--help`` costs) imports none
    of JAX, NumPy, NumPyro, ArviZ, xarray, matplotlib, SciPy; a fit's modules up to the sampler
    (the API function, the model, the runner, the progress display) import no ArviZ or
    matplotlib: they come when the posterior exists."""
    code = ("import sys\n"
            "import cassini_bayes.cli\n"
            f"print(sorted(m for m in {HEAVY!r} if m in sys.modules))\n"
            "from cassini_bayes.api import fit_inertia, fit_thrust, fit_rwa4\n"
            "import cassini_bayes.inference.progress, cassini_bayes.inference.runner\n"
            "import cassini_bayes.inference.inertia, cassini_bayes.inference.thrust\n"
            "import cassini_bayes.inference.rwa4\n"
            "print(sorted(m for m in ('arviz', 'xarray', 'matplotlib') if m in sys.modules))")
    cli, fit = _python(code).splitlines()
    assert cli == "[]"
    assert fit == "[]"


def test_arviz_is_imported_without_compiling_numba(tmp_path):
    """The package's ArviZ import keeps an installed numba away from ArviZ (which would compile a
    numba ufunc at import), and numba stays importable afterwards. A stand-in ``numba`` on the
    path records whether it was imported."""
    fake = tmp_path / "numba"
    fake.mkdir()
    (fake / "__init__.py").write_text("import os\nopen(os.environ['MARK'], 'a').write('x')\n")
    mark = tmp_path / "imported"
    code = ("import sys\n"
            "from cassini_bayes._arviz import load_arviz\n"
            "az = load_arviz()\n"
            "print(az.utils.Numba.numba_flag, 'numba' in sys.modules)\n"
            "import numba\n")
    import os

    env = {**os.environ, "PYTHONPATH": f"{tmp_path}{os.pathsep}{os.environ.get('PYTHONPATH', '')}",
           "MARK": str(mark)}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         check=True).stdout
    assert out.split() == ["False", "False"]
    assert mark.read_text() == "x"       # imported once, by the script, after ArviZ


def test_the_fits_run_numpys_blas_on_one_thread():
    """Inside a computing API function NumPy's BLAS runs one thread; the caller's setting is back
    afterwards."""
    from threadpoolctl import threadpool_info

    from cassini_bayes._devices import jax_entry

    before = [d["num_threads"] for d in threadpool_info() if d["user_api"] == "blas"]
    if not before:
        pytest.skip("no BLAS thread pool loaded")
    inside = jax_entry(lambda: [d["num_threads"] for d in threadpool_info()
                                if d["user_api"] == "blas"])()
    assert inside == [1] * len(before)
    assert [d["num_threads"] for d in threadpool_info() if d["user_api"] == "blas"] == before


_FIT_MISSING_FILE = ("import warnings, cassini_bayes as cb\n"
                     "with warnings.catch_warnings(record=True) as w:\n"
                     "    warnings.simplefilter('always')\n"
                     "    try:\n"
                     "        cb.fit_inertia('no_such_file.csv', 'cassini_post_probe', chains=4)\n"
                     "    except cb.InputError:\n"
                     "        pass\n"
                     "said = [x for x in w if 'request_host_devices' in str(x.message)]\n"
                     "print(len(said), said[0].filename if said else '-')\n")


def test_a_fit_asks_for_one_cpu_device_per_chain_before_jax_starts():
    """A fit function called before any JAX computation asks for the command line's devices (one
    per core, at least 4), so its chains run in parallel; a later fit needs no new request."""
    out = _python(_FIT_MISSING_FILE + _FIT_MISSING_FILE.replace("import warnings, cassini_bayes "
                                                                "as cb\n", "")
                  + "import jax; print(jax.local_device_count())").split()
    assert out[:4] == ["0", "-", "0", "-"]
    assert int(out[4]) >= 4


def test_setup_jax_is_what_every_entry_point_calls_and_sampling_refuses_32_bit():
    """The sampler refuses to run in 32-bit (a script that skipped :func:`cassini_bayes.setup_jax`),
    naming the call; a public function that computes (here the conic propagator) makes it."""
    code = ("import os, jax, cassini_bayes as cb\n"
            "os.environ['CASSINI_BAYES_JAX_CACHE'] = 'off'\n"
            "from cassini_bayes.inference.runner import SamplerSettings, run_nuts\n"
            "import numpyro, numpyro.distributions as dist\n"
            "model = lambda: numpyro.sample('x', dist.Normal(0.0, 1.0))\n"
            "try:\n"
            "    run_nuts(jax.random.key(0), model, model_kwargs={}, prior_draws=0,\n"
            "             settings=SamplerSettings(chains=1, warmup=10, draws=10))\n"
            "except RuntimeError as e:\n"
            "    print('refused' if 'cassini_bayes.setup_jax()' in str(e) else e)\n"
            "r, v = cb.propagate_conic([7e6, 0.0, 0.0], [0.0, 7.5e3, 0.0], 3.986e14, 60.0)\n"
            "print(jax.config.jax_enable_x64, r.dtype)\n")
    assert _python(code).split() == ["refused", "True", "float64"]


def test_a_fit_after_jax_started_warns_once_what_to_call():
    """When the caller ran JAX code first (one CPU device), the fit cannot ask for more: one
    warning, at the caller's line, names ``request_host_devices``; the next fit is silent. Chosen
    devices (``XLA_FLAGS``) are the caller's choice: no warning."""
    start = "import jax.numpy as jnp; float(jnp.ones(2).sum())\n"
    twice = _FIT_MISSING_FILE + _FIT_MISSING_FILE.replace("import warnings, cassini_bayes as cb\n",
                                                          "")
    assert _python(start + twice).split() == ["1", "<string>", "0", "-"]
    assert _python(start + twice, "--xla_force_host_platform_device_count=2").split() == \
        ["0", "-", "0", "-"]


def test_an_inertia_posterior_run_is_recorded_with_its_hash_and_moves_the_baseline(tmp_path):
    """``inertia_posterior=RUN``: config.toml keeps the run and its posterior.nc's sha256 (a
    re-run can tell the run was replaced), and the thrust baseline uses the posterior's mean
    inertia as the RWA4 baseline does (it used the model's prediction)."""
    import arviz as az
    import jax
    import numpy as np

    from cassini_bayes.api._thrust import _inertia_knowledge, thrust_baseline
    from cassini_bayes.physics.momentum import INERTIA_NAMES, inertia_vector
    from cassini_bayes.rundir import file_record
    from cassini_bayes.simulate import load_scenario, simulate

    sc = cb.load_spacecraft("cassini_post_probe")
    mean = 1.02 * np.asarray(inertia_vector(sc.inertia), float)       # 2 % above the model
    draws = mean + np.random.default_rng(0).normal(0.0, 1.0, (2, 50, 6))
    run = tmp_path / "inertia_run"
    run.mkdir()
    az.from_dict(posterior={n: draws[..., i] for i, n in enumerate(INERTIA_NAMES)}).to_netcdf(
        str(run / "posterior.nc"))
    (run / "summary.json").write_text(json.dumps({"kind": "inertia"}))
    knowledge, entry, paths = _inertia_knowledge(run, False)
    assert entry["inertia_posterior"] == {"run": str(run.resolve()),
                                          "posterior": file_record(run / "posterior.nc")}
    sim = simulate(jax.random.key(0), load_scenario("biasing_day028"))
    events = [(sim.telemetry, sim.pulses)]
    f_model = thrust_baseline(events, sc, "mean")[0]["F"]
    f_post = thrust_baseline(events, sc, "mean", knowledge)[0]["F"]
    assert f_post != f_model and abs(f_post / f_model - 1) < 0.05


class _Sampled(Exception):
    """Raised in place of the sampler: what the API gave it is all a test needs."""


@pytest.mark.parametrize("model", ["inertia", "rwa4"])
def test_stale_samples_are_left_out_of_inertia_and_wheel_axis_fits(model, inputs, tmp_path,
                                                                   monkeypatch):
    """A packet that repeats its neighbour (rows 41 and 42 equal but for the time) reaches
    neither the checks nor the sampler, as in the thrust fit (the warning that names them:
    ``test_flex_mode.py``)."""
    from dataclasses import replace

    import cassini_bayes.inference.inertia as inertia_pkg
    import cassini_bayes.inference.rwa4 as rwa4_pkg
    from cassini_bayes.telemetry import read_telemetry, write_telemetry

    tel = read_telemetry(inputs[model]["telemetry"])
    i = 40
    rows = [np.array(x, copy=True) for x in (tel.q, tel.omega, tel.wheel_rates)]
    for x in rows:
        x[i + 1] = x[i]
    stale = tmp_path / "stale.csv"
    write_telemetry(stale, replace(tel, q=rows[0], omega=rows[1], wheel_rates=rows[2]))
    seen = []

    def sampler(key, data, *args, **kw):
        seen.append(data)
        raise _Sampled

    pkg, name = (inertia_pkg, "fit_inertia") if model == "inertia" else (rwa4_pkg, "fit_rwa4")
    monkeypatch.setattr(pkg, name, sampler)
    with pytest.raises(_Sampled):
        _api_fit(model, {"telemetry": stale}, as_objects=False)
    got = seen[0][0] if model == "inertia" else seen[0]
    assert got.n == tel.n - 2 and tel.t[i] not in got.t and tel.t[i + 1] not in got.t
