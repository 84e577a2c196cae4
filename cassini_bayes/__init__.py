"""cassini_bayes: Bayesian uncertainty quantification of Cassini in-flight calibration.

Estimates the inertia tensor from reaction-wheel slews, the thrusters' force and pulse time
constants from wheel-biasing events, and the spin axis of the re-articulated wheel RWA4, as the
JPL papers did by least squares (kept here as baselines), but with calibrated posteriors.

The public API (docs/api.md)::

    import cassini_bayes as cb
    fit = cb.fit_inertia(cb.read_telemetry("slew.csv"), cb.load_spacecraft("cassini_post_probe"),
                         seed=0, chains=4, warmup=300, draws=500)
    fit.summary()["parameters"]["Izz"]      # the summary.json of `cassini-bayes fit inertia`
    fit.save("runs/inertia")                # its run directory

The names below are imported on first use, so ``import cassini_bayes`` stays cheap (no JAX, no
NumPyro, no ArviZ) and changes no JAX setting. The functions that compute set JAX up on entry
(:func:`setup_jax`): 64-bit, because the conservation checks and least-squares recoveries the
package promises (1e-9, 1e-8 relative) are beyond float32; JAX's persistent compilation cache
(``~/.cache/cassini-bayes/jax``, moved or switched off with ``CASSINI_BAYES_JAX_CACHE=DIR|off``,
:mod:`cassini_bayes._jax_cache`); and, before JAX's backend starts, one CPU device per core (at
least 4) so that the chains of a fit run in parallel, as the command line's do. A script that
uses the package's modules directly calls ``cassini_bayes.setup_jax()`` once after its imports
(docs/api.md, "JAX settings").
"""

import importlib as _importlib
import types as _types
import typing as _typing

__version__ = "0.1.0"

if _typing.TYPE_CHECKING:   # the types for checkers; at run time the names load on first use
    from cassini_bayes.api import (
        FitResult,
        PulseLog,
        Simulation,
        Spacecraft,
        Telemetry,
        VectorTree,
        budget,
        check_telemetry,
        evaluate_plan,
        fit_chebyshev_segments,
        fit_health,
        fit_inertia,
        fit_rwa4,
        fit_thrust,
        fit_trajectory,
        load_spacecraft,
        monitor_leak,
        plan_inertia,
        plan_thrust,
        plan_wheel_axis,
        propagate_conic,
        read_pulses,
        read_telemetry,
        request_host_devices,
        setup_jax,
        simulate_health_campaign,
        simulate_scenario,
    )
    from cassini_bayes.errors import InputError

__all__ = [  # noqa: RUF022  (grouped as docs/api.md lists them)
    "__version__",
    "read_telemetry", "read_pulses", "load_spacecraft", "simulate_scenario",
    "fit_inertia", "fit_thrust", "fit_rwa4", "fit_wheel_axis",
    "FitResult", "Simulation", "Telemetry", "PulseLog", "Spacecraft",
    "InputError", "setup_jax", "request_host_devices",
    "fit_health", "simulate_health_campaign", "monitor_leak", "check_telemetry", "budget",
    "propagate_conic", "fit_chebyshev_segments", "VectorTree", "fit_trajectory",
    "evaluate_plan", "plan_inertia", "plan_thrust", "plan_wheel_axis",
]

def _api() -> _types.ModuleType:
    """:mod:`cassini_bayes.api`, imported on first use. By name: the package's modules import
    ``__version__`` from here, and the layering contracts (``lint-imports``) must not read that
    as a dependency of every layer on the API, which this module never imports on its own."""
    return _importlib.import_module("cassini_bayes.api")


def __getattr__(name: str) -> object:
    """Import a public name from :mod:`cassini_bayes.api` on first use."""
    if name == "InputError":
        from cassini_bayes.errors import InputError

        return InputError
    if name in __all__:
        return getattr(_api(), name)
    raise AttributeError(f"module 'cassini_bayes' has no attribute {name!r}")


def __dir__() -> list[str]:
    """The public names (``__all__``) and the module's own dunders: no helpers, no imported
    modules, no subpackages."""
    return sorted(set(__all__) | {n for n in globals() if n.startswith("__") and n.endswith("__")})
