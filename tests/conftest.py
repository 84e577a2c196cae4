"""Test configuration: JAX set up as the package does (64-bit, the cache), strict rank promotion,
fixed keys, CLI runner."""

from __future__ import annotations

import os

os.environ.setdefault("XLA_FLAGS", "--xla_force_host_platform_device_count=4")
os.environ.setdefault("MPLBACKEND", "Agg")
# Persistent compilation cache: test workers (pytest -n), the CLI subprocesses they start and
# reruns share compiled programs, which dominate the suite's run time on a 2-core machine. Set
# before cassini_bayes.setup_jax() (it enables the cache), and never the user's own cache folder.
os.environ["CASSINI_BAYES_JAX_CACHE"] = os.path.abspath(
    os.path.join(os.path.dirname(__file__), os.pardir, ".pytest_cache", "jax"))

import jax  # noqa: E402
import pytest  # noqa: E402

import cassini_bayes  # noqa: E402
import cassini_bayes._arviz  # noqa: E402

cassini_bayes.setup_jax()  # 64-bit and the cache above, as every entry point of the package
# ArviZ as the package imports it (numba hidden: ArviZ 0.23's numba path of mcse(method="sd")
# fails under NumPy 2), before any test module imports it
cassini_bayes._arviz.load_arviz()

jax.config.update("jax_numpy_rank_promotion", "raise")


@pytest.fixture(autouse=True, scope="module")
def _release_compiled_programs():
    """After each test module, drop JAX's in-memory compiled programs (``jax.clear_caches``):
    each executable holds memory maps, and a worker that keeps those of every test it ran passes
    the kernel's ``vm.max_map_count``, where XLA aborts or segfaults compiling. Later
    modules reload what they share from the persistent cache."""
    yield
    jax.clear_caches()


@pytest.fixture
def key():
    return jax.random.key(20260315)


@pytest.fixture
def run_cli(capsys):
    """Run ``cassini-bayes ARGS`` in-process; returns (exit_code, stdout, stderr)."""
    from cassini_bayes.cli import main

    def _run(*args):
        code = main([str(a) for a in args])
        out = capsys.readouterr()
        return code, out.out, out.err

    return _run
