"""JAX set up as cassini_bayes computes: 64-bit, the compilation cache, CPU devices for chains.

:func:`setup_jax` is the one call: every entry point makes it before it computes (the command
line, the API functions that compute through :func:`jax_entry`, the experiments, SBC), and a
script that uses the package's modules directly makes it once after its imports. Importing the
package sets nothing (docs/api.md, "JAX settings").

Kept apart from :mod:`cassini_bayes.inference.runner` (which imports NumPyro) because it must
run before anything initialises the JAX backend: XLA fixes the number of CPU devices when the
backend starts. When a caller has already run JAX code the request comes too late, and
:func:`warn_if_vectorised` says so at the fit that suffers from it.
"""

from __future__ import annotations

import contextlib
import functools
import os
import warnings
from collections.abc import Callable, Iterator
from typing import Any, TypeVar, cast

DEFAULT_CHAINS = 4

_FLAG = "xla_force_host_platform_device_count"
# "late": asked after the backend had started (the request had no effect); "warned": said so
_state = {"late": False, "warned": False}


def request_host_devices(n: int | None = None) -> None:
    """Ask JAX for ``n`` CPU devices; by default one per core and at least one per default chain
    (4), so the default chains run ``"parallel"`` (pmap) even on a 2-core machine: vectorised
    chains run in lock-step, every iteration waiting for the deepest tree (about half the speed,
    docs/performance.md).

    Only effective before JAX initialises its backend; harmless afterwards. Leaves an explicit
    ``--xla_force_host_platform_device_count`` in ``XLA_FLAGS`` alone.
    """
    import jax

    if n is not None and (isinstance(n, bool) or not isinstance(n, int) or n < 1):
        from cassini_bayes.errors import InputError

        raise InputError(f"n={n!r}: give a positive number of devices, or None for the default")
    if _FLAG in os.environ.get("XLA_FLAGS", ""):
        return
    n = max(1, n or max(DEFAULT_CHAINS, os.cpu_count() or 1))
    try:
        jax.config.update("jax_num_cpu_devices", n)
    except RuntimeError:  # backend already initialised
        _state["late"] = True


def host_devices_for_fits() -> None:
    """:func:`request_host_devices` with its default, unless the process already chose its CPU
    devices (``XLA_FLAGS``, ``jax_num_cpu_devices``, an earlier request): what a fit function
    calls first, so that a library user's chains run in parallel as the command line's do."""
    import jax

    if _FLAG in os.environ.get("XLA_FLAGS", "") or jax.config.jax_num_cpu_devices != -1:
        return
    request_host_devices()


def setup_jax() -> None:
    """Set JAX up as the package computes, once per process (later calls change nothing):

    * 64-bit (``jax_enable_x64``): the conservation checks and least-squares recoveries the
      package promises (1e-9, 1e-8 relative) are beyond float32;
    * the persistent compilation cache (:func:`cassini_bayes._jax_cache.enable_once`);
    * when JAX's backend has not started and the process has not chosen its CPU devices, one
      per core and at least 4 (:func:`request_host_devices`), so that chains run in parallel.
    """
    import jax

    from cassini_bayes import _jax_cache

    if not jax.config.jax_enable_x64:
        jax.config.update("jax_enable_x64", True)
    _jax_cache.enable_once()
    host_devices_for_fits()


def require_x64(what: str) -> None:
    """Refuse to compute ``what`` in 32-bit: a script that skipped :func:`setup_jax` would get
    float32 numbers without a word."""
    import jax

    if not jax.config.jax_enable_x64:
        raise RuntimeError(f"{what} needs JAX in 64-bit: call cassini_bayes.setup_jax() once "
                           "after the imports (the command line and the API functions do)")


_F = TypeVar("_F", bound=Callable[..., Any])


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """NumPy's BLAS (OpenBLAS, MKL) on one thread while the package computes, as before after.

    The package's NumPy linear algebra is many small products (thousands of rows, tens of
    columns) between JAX programs: BLAS threads cost more to start and spin than they save, and
    take the cores that XLA's sampling threads need."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        yield


def jax_entry(fn: _F) -> _F:
    """Decorate a public function that computes with JAX: :func:`setup_jax` first, so that
    whichever the caller runs first (a simulation, a check, a fit) computes in 64-bit and the
    fits that follow get their devices. The function keeps its signature (and its types)."""
    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        setup_jax()
        with one_blas_thread():
            return fn(*args, **kwargs)

    return cast(_F, wrapper)


def warn_if_vectorised(chains: int) -> None:
    """One warning per process when ``chains`` chains must run vectorised (lock-step, about half
    the speed) because JAX's backend had started with fewer CPU devices before a fit could ask
    for more; silent when the devices were chosen (``XLA_FLAGS``, :func:`request_host_devices`)."""
    if chains < 2 or not _state["late"] or _state["warned"]:
        return
    import jax

    have = jax.local_device_count()
    if have >= chains:
        return
    _state["warned"] = True
    warnings.warn(  # stacklevel: the fit function's caller, through its two decorators
        f"JAX had started before cassini_bayes could ask for CPU devices: the {chains} chains run "
        f"vectorised on {have} device(s), about half as fast as in parallel; call "
        "cassini_bayes.request_host_devices() before any JAX computation (right after the "
        "imports) to run them in parallel", stacklevel=6)


MAPPING_SHARE = 0.5
"""Share of the kernel's memory-mapping limit past which :func:`release_compiled_programs`
drops JAX's in-memory programs."""


def release_compiled_programs(share: float = MAPPING_SHARE) -> bool:
    """Drop JAX's compiled programs held in memory (``jax.clear_caches``) when this process holds
    more than ``share`` of the kernel's memory-mapping limit (Linux ``vm.max_map_count``); True
    when it did.

    Every XLA CPU program loaded keeps about three mappings and a fit loads hundreds, so a long
    campaign whose every replicate compiles its own programs reaches the limit and dies in
    LLVM ("Cannot allocate memory"). Called between replicates; the next fit reloads what it
    needs from the compilation cache. Where ``/proc`` is absent it does nothing."""
    try:
        with open("/proc/sys/vm/max_map_count", "rb") as f:
            limit = int(f.read())
        with open("/proc/self/maps", "rb") as f:
            held = sum(1 for _ in f)
    except (OSError, ValueError):
        return False
    if held <= share * limit:
        return False
    import gc

    import jax

    jax.clear_caches()
    gc.collect()
    return True
