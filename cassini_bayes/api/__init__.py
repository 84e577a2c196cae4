"""The public Python API, re-exported by :mod:`cassini_bayes` (docs/api.md).

Read inputs (:func:`read_telemetry`, :func:`read_pulses`, :func:`load_spacecraft`), make
synthetic ones (:func:`simulate_scenario`), and fit what
``cassini-bayes fit inertia|thrust|wheel-axis|rwa4`` fits (:func:`fit_inertia`, :func:`fit_thrust`,
:func:`fit_wheel_axis`, :func:`fit_rwa4`): each returns a :class:`FitResult` whose ``summary()``
is the run's ``summary.json`` and whose ``save(dir)`` writes the run directory the command
writes. The command line is a thin layer over these functions.

Also here, for the experiments and the CLI: the per-model summary builders
(:func:`inertia_summary`, :func:`thrust_summary`, :func:`rwa4_summary`), the run writer
(:func:`write_run`, :func:`write_run_files`), :func:`fit_config` and :func:`collect_warnings`.

Each name is imported from its module on first use.
"""

import importlib as _importlib
import typing as _typing

if _typing.TYPE_CHECKING:   # the types for checkers; at run time each name loads on first use
    from cassini_bayes._devices import request_host_devices, setup_jax
    from cassini_bayes.api._budget import BudgetResult, budget
    from cassini_bayes.api._check import TelemetryCheck, check_telemetry
    from cassini_bayes.api._health import HealthResult, fit_health, simulate_health_campaign
    from cassini_bayes.api._inertia import fit_inertia, inertia_baseline, inertia_summary
    from cassini_bayes.api._ivp import (
        TrajectoryFit,
        VectorTree,
        fit_chebyshev_segments,
        fit_trajectory,
        propagate_conic,
    )
    from cassini_bayes.api._leak import LeakResult, monitor_leak
    from cassini_bayes.api._plan import PlanEvaluation, evaluate_plan
    from cassini_bayes.api._plan_axis import WheelAxisPlanResult, plan_wheel_axis
    from cassini_bayes.api._plan_inertia import PlanResult, plan_inertia
    from cassini_bayes.api._plan_thrust import ThrustPlanResult, plan_thrust
    from cassini_bayes.api._result import (
        FitResult,
        collect_warnings,
        fit_config,
        write_run,
        write_run_files,
    )
    from cassini_bayes.api._rwa4 import fit_rwa4, rwa4_sensitivity, rwa4_summary
    from cassini_bayes.api._simulation import Simulation, simulate_scenario, truth_document
    from cassini_bayes.api._thrust import (
        fit_thrust,
        thrust_baseline,
        thrust_sensitivity,
        thrust_summary,
    )
    from cassini_bayes.spacecraft import Spacecraft, load_spacecraft
    from cassini_bayes.telemetry import PulseLog, Telemetry, read_pulses, read_telemetry

_HOMES = {
    "cassini_bayes._devices": ["request_host_devices", "setup_jax"],
    "cassini_bayes.api._budget": ["BudgetResult", "budget"],
    "cassini_bayes.api._check": ["TelemetryCheck", "check_telemetry"],
    "cassini_bayes.api._health": ["HealthResult", "fit_health", "simulate_health_campaign"],
    "cassini_bayes.api._ivp": ["TrajectoryFit", "fit_trajectory", "VectorTree",
                               "fit_chebyshev_segments", "propagate_conic"],
    "cassini_bayes.api._inertia": ["fit_inertia", "inertia_baseline", "inertia_summary"],
    "cassini_bayes.api._leak": ["LeakResult", "monitor_leak"],
    "cassini_bayes.api._plan": ["PlanEvaluation", "evaluate_plan"],
    "cassini_bayes.api._plan_axis": ["WheelAxisPlanResult", "plan_wheel_axis"],
    "cassini_bayes.api._plan_inertia": ["PlanResult", "plan_inertia"],
    "cassini_bayes.api._plan_thrust": ["ThrustPlanResult", "plan_thrust"],
    "cassini_bayes.api._result": ["FitResult", "collect_warnings", "fit_config", "write_run",
                                  "write_run_files"],
    "cassini_bayes.api._rwa4": ["fit_wheel_axis", "fit_rwa4", "rwa4_sensitivity",
                                "rwa4_summary"],
    "cassini_bayes.api._simulation": ["Simulation", "simulate_scenario", "truth_document"],
    "cassini_bayes.api._thrust": ["fit_thrust", "thrust_baseline", "thrust_sensitivity",
                                  "thrust_summary"],
    "cassini_bayes.spacecraft": ["Spacecraft", "load_spacecraft"],
    "cassini_bayes.telemetry": ["PulseLog", "Telemetry", "read_pulses", "read_telemetry"],
}
_HOME = {name: module for module, names in _HOMES.items() for name in names}

__all__ = [
    "read_telemetry", "read_pulses", "load_spacecraft", "simulate_scenario", "fit_inertia",
    "fit_thrust", "fit_rwa4", "fit_wheel_axis", "FitResult", "Simulation", "Telemetry",
    "PulseLog", "Spacecraft",
    "request_host_devices", "setup_jax", "inertia_baseline", "inertia_summary", "thrust_baseline",
    "thrust_sensitivity", "thrust_summary", "rwa4_sensitivity", "rwa4_summary", "write_run",
    "write_run_files", "fit_config", "collect_warnings", "truth_document",
    "fit_health", "HealthResult", "simulate_health_campaign", "monitor_leak", "LeakResult",
    "check_telemetry", "TelemetryCheck", "budget", "BudgetResult",
    "propagate_conic", "fit_chebyshev_segments", "VectorTree", "fit_trajectory", "TrajectoryFit",
    "evaluate_plan", "plan_inertia", "plan_thrust", "plan_wheel_axis", "PlanEvaluation",
    "PlanResult", "ThrustPlanResult", "WheelAxisPlanResult",
]


def __getattr__(name: str) -> object:
    """Import a public name from its module on first use: a command imports only what it runs
    (``cassini-bayes check`` no fitting code, ``fit inertia`` no simulator)."""
    if name in _HOME:
        value = getattr(_importlib.import_module(_HOME[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
