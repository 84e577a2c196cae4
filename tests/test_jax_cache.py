"""The persistent compilation cache (cassini_bayes._jax_cache): where it lives, what it counts,
that it never changes a draw, and that a cache refusing its own entries is one warning.

Everything that moves the cache runs in a fresh process: the cache is process-wide JAX state, and
this test process keeps the one conftest.py chose (never the user's own cache folder).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import jax
import numpy as np
import pytest
import xarray as xr

from cassini_bayes import _jax_cache
from cassini_bayes.spacecraft import load_spacecraft
from cassini_bayes.telemetry import write_telemetry
from slews import make_slews

ROOT = Path(__file__).resolve().parents[1]
SC = "cassini_2000_03_15"
SMALL = ["--chains", "2", "--warmup", "40", "--draws", "40", "--idealised", "--no-torque"]


def _python(code: str, *args, cache: str | None, **env) -> subprocess.CompletedProcess:
    """``python -c CODE ARGS`` in a fresh process with ``CASSINI_BAYES_JAX_CACHE=cache``."""
    full = {**os.environ, **env,
            "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    full.pop(_jax_cache.ENV, None)
    if cache is not None:
        full[_jax_cache.ENV] = cache
    return subprocess.run([sys.executable, "-c", code, *map(str, args)], capture_output=True,
                          text=True, env=full, timeout=600)


def _cli(*args, cache: str | None) -> subprocess.CompletedProcess:
    return _python("from cassini_bayes.cli import entry; entry()", *args, cache=cache)


# a few small programs, their results and the cache's counts, as JSON on stdout
_SMALL_PROGRAMS = """
import json
import cassini_bayes, jax, jax.numpy as jnp
from cassini_bayes import _jax_cache
cassini_bayes.setup_jax()
x = jnp.linspace(0.0, 1.0, 12).reshape(3, 4)
out = [float(jax.jit(lambda a: jnp.sin(a) @ a.T)(x).sum()), float(jax.jit(jnp.cumsum)(x).sum())]
print(json.dumps({"out": out, "stats": _jax_cache.stats().to_dict()}))
"""


# a small NUTS fit through the package's runner; its draws saved to ARGV[1] (.npz)
_SMALL_FIT = """
import sys
import cassini_bayes, jax, numpy as np, numpyro, numpyro.distributions as dist
from cassini_bayes import _jax_cache
cassini_bayes.setup_jax()
from cassini_bayes.inference.runner import SamplerSettings, run_nuts

def model(*, y):
    mu = numpyro.sample("mu", dist.Normal(0.0, 10.0))
    sigma = numpyro.sample("sigma", dist.HalfNormal(2.0))
    numpyro.sample("y", dist.Normal(mu, sigma), obs=y)

y = jax.random.normal(jax.random.key(0), (40,)) * 1.5 + 3.0
progress = len(sys.argv) > 2 and sys.argv[2] == "progress"
idata = run_nuts(jax.random.key(7), model, model_kwargs={"y": y}, prior_draws=0,
                 settings=SamplerSettings(chains=2, warmup=100, draws=100, progress=progress))
print(_jax_cache.stats().misses)
np.savez(sys.argv[1], **{k: idata.posterior[k].values for k in ("mu", "sigma")},
         **{k: idata.sample_stats[k].values for k in ("energy", "step_size", "tree_depth")})
"""


def test_resolve_order(monkeypatch, tmp_path):
    monkeypatch.setitem(_jax_cache._state, "jax_own", None)
    monkeypatch.delenv(_jax_cache.ENV, raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert _jax_cache.resolve() == tmp_path / "xdg" / "cassini-bayes" / "jax"
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/ignored")  # the XDG spec: absolute only
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert _jax_cache.resolve() == tmp_path / "home" / ".cache" / "cassini-bayes" / "jax"
    monkeypatch.setitem(_jax_cache._state, "jax_own", str(tmp_path / "jax-own"))
    assert _jax_cache.resolve() == tmp_path / "jax-own"  # a folder given to JAX itself
    monkeypatch.setenv(_jax_cache.ENV, str(tmp_path / "env"))
    assert _jax_cache.resolve() == tmp_path / "env"
    for off in ("off", "OFF", "0", "false", "none"):
        monkeypatch.setenv(_jax_cache.ENV, off)
        assert _jax_cache.resolve() is None
    assert _jax_cache.resolve(tmp_path / "arg") == tmp_path / "arg"  # the CLI option wins
    assert _jax_cache.resolve("off") is None


def test_tests_never_use_the_users_cache():
    assert _jax_cache.stats().dir == ROOT / ".pytest_cache" / "jax"


def test_counts_misses_then_hits_and_off(tmp_path):
    cache = tmp_path / "jax"
    cold = _python(_SMALL_PROGRAMS, cache=str(cache))
    warm = _python(_SMALL_PROGRAMS, cache=str(cache))
    off = _python(_SMALL_PROGRAMS, cache="off")
    runs = [json.loads(r.stdout) for r in (cold, warm, off)]
    assert runs[0]["out"] == runs[1]["out"] == runs[2]["out"]
    c, w, o = (r["stats"] for r in runs)
    assert c["dir"] == w["dir"] == str(cache) and c["misses"] >= 2 and c["rejected"] == 0
    assert w["hits"] >= 2 and w["misses"] == 0
    assert o == {"dir": "off", "hits": 0, "misses": 0, "rejected": 0}
    assert "warning" not in (cold.stderr + warm.stderr).lower()


def test_refused_entries_give_one_warning_and_no_cache(tmp_path):
    """Entries that are on disk but cannot be used (here: overwritten with junk; some jaxlib CPU
    builds refuse every entry over a CPU-feature mismatch) are one warning, not a silent
    recompile of every program on every run."""
    cache = tmp_path / "jax"
    first = json.loads(_python(_SMALL_PROGRAMS, cache=str(cache)).stdout)
    for entry in cache.glob("*-cache"):
        entry.write_bytes(b"not a compiled program")
    again = _python(_SMALL_PROGRAMS, cache=str(cache), PYTHONWARNINGS="default")
    result = json.loads(again.stdout)
    assert result["out"] == first["out"]
    assert result["stats"]["rejected"] >= 2 and result["stats"]["hits"] == 0
    ours = [ln for ln in again.stderr.splitlines() if "refuses the programs it stored" in ln]
    assert len(ours) == 1 and _jax_cache.ENV in ours[0], again.stderr


def test_unusable_folder_is_one_warning(tmp_path):
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    r = _python(_SMALL_PROGRAMS, cache=str(blocker / "jax"), PYTHONWARNINGS="default")
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["stats"]["dir"] == "off"
    assert r.stderr.count("cannot use") == 1 and _jax_cache.ENV in r.stderr


def test_same_draws_with_fresh_warm_and_no_cache(tmp_path):
    """The same key gives bit-identical draws whether the sampler was compiled (fresh cache),
    loaded (warm cache) or compiled without a cache."""
    cache = str(tmp_path / "jax")
    draws = {}
    for name, setting in [("fresh", cache), ("warm", cache), ("off", "off")]:
        r = _python(_SMALL_FIT, tmp_path / f"{name}.npz", cache=setting)
        assert r.returncode == 0, r.stderr
        with np.load(tmp_path / f"{name}.npz") as saved:
            draws[name] = dict(saved)
    for name in ("warm", "off"):
        assert draws[name].keys() == draws["fresh"].keys()
        for k in draws["fresh"]:
            np.testing.assert_array_equal(draws[name][k], draws["fresh"][k], err_msg=f"{name} {k}")


def test_progress_bar_changes_no_draw_and_keeps_the_cache(tmp_path):
    """With the progress bar (a terminal) the sampler runs the same programs, which the cache
    keeps (JAX never caches a program that calls back into Python: the bar is driven from
    Python between pieces of the loop), and gives the same draws as without it."""
    cache = str(tmp_path / "jax")
    draws, misses = {}, {}
    for name, progress in [("plain", ""), ("bar", "progress"), ("bar again", "progress")]:
        r = _python(_SMALL_FIT, tmp_path / f"{name}.npz", progress, cache=cache)
        assert r.returncode == 0, r.stderr
        misses[name] = int(r.stdout.split()[-1])
        with np.load(tmp_path / f"{name}.npz") as saved:
            draws[name] = dict(saved)
    assert misses["plain"] > 0 and misses["bar"] == 0 and misses["bar again"] == 0
    for k in draws["plain"]:
        np.testing.assert_array_equal(draws["bar"][k], draws["plain"][k], err_msg=k)


@pytest.fixture(scope="module")
def slews(tmp_path_factory):
    path = tmp_path_factory.mktemp("tel") / "slews.csv"
    write_telemetry(path, make_slews(jax.random.key(31), load_spacecraft(SC), dur=120.0))
    return path


def _posterior(run: Path) -> dict[str, np.ndarray]:
    with xr.open_dataset(run / "posterior.nc", group="posterior") as ds:
        return {k: ds[k].values for k in ds.data_vars}


@pytest.mark.slow
def test_fit_inertia_same_run_with_fresh_warm_and_no_cache(tmp_path, slews):
    """``cassini-bayes fit inertia``: the same seed gives bit-identical draws and summary.json
    whether the programs were compiled (fresh cache), loaded (warm cache) or compiled without a
    cache; config.toml says which; --jax-cache overrides the environment (2 min on the loaded
    2-core machine: three processes, two of them compiling everything)."""
    cache = tmp_path / "jax"
    runs, stats = {}, {}
    for name, option in [("fresh", str(cache)), ("warm", str(cache)), ("off", "off")]:
        out = tmp_path / name
        r = _cli("--jax-cache", option, "--verbose", "fit", "inertia", "--telemetry", slews,
                 "--spacecraft", SC, "--out", out, "--seed", 3, *SMALL,
                 cache=str(tmp_path / "ignored"))
        assert r.returncode == 0, r.stderr
        assert r.stderr.strip().splitlines()[-1].startswith("jax cache: ")
        runs[name] = out
        stats[name] = tomllib.loads((out / "config.toml").read_text())["jax_cache"]
    assert not (tmp_path / "ignored").exists()
    assert stats["fresh"]["dir"] == str(cache) and stats["fresh"]["misses"] > 0
    assert stats["warm"]["misses"] == 0 and stats["warm"]["hits"] > 0
    assert stats["off"] == {"dir": "off", "hits": 0, "misses": 0, "rejected": 0}
    fresh = _posterior(runs["fresh"])
    for name in ("warm", "off"):
        other = _posterior(runs[name])
        assert other.keys() == fresh.keys()
        for k, v in fresh.items():
            np.testing.assert_array_equal(other[k], v, err_msg=f"{name}: {k}")
        assert ((runs[name] / "summary.json").read_text()
                == (runs["fresh"] / "summary.json").read_text())
