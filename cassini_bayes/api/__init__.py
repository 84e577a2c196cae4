"""The public Python API, re-exported by :mod:`cassini_bayes` (docs/api.md).

Read inputs (:func:`read_telemetry`, :func:`read_pulses`, :func:`load_spacecraft`), make
synthetic ones (:func:`simulate`), and fit what ``cassini-bayes fit inertia|thrust|rwa4`` fits
(:func:`fit_inertia`, :func:`fit_thrust`, :func:`fit_rwa4`): each returns a :class:`FitResult`
whose ``summary()`` is the run's ``summary.json`` and whose ``save(dir)`` writes the run
directory the command writes. The command line is a thin layer over these functions.

Also here, for the experiments and the CLI: the per-model summary builders
(:func:`inertia_summary`, :func:`thrust_summary`, :func:`rwa4_summary`), the run writer
(:func:`write_run`, :func:`write_run_files`), :func:`fit_config` and :func:`collect_warnings`.
"""

from cassini_bayes._devices import request_host_devices
from cassini_bayes.api._budget import BudgetResult, budget
from cassini_bayes.api._check import TelemetryCheck, check_telemetry
from cassini_bayes.api._health import HealthResult, fit_health, simulate_health_campaign
from cassini_bayes.api._ivp import TrajectoryFit, fit_trajectory
from cassini_bayes.api._inertia import fit_inertia, inertia_baseline, inertia_summary
from cassini_bayes.api._leak import LeakResult, monitor_leak
from cassini_bayes.api._result import (FitResult, collect_warnings, fit_config, write_run,
                                       write_run_files)
from cassini_bayes.api._rwa4 import fit_rwa4, rwa4_sensitivity, rwa4_summary
from cassini_bayes.api._simulation import Simulation, simulate, truth_document
from cassini_bayes.api._thrust import (fit_thrust, thrust_baseline, thrust_sensitivity,
                                       thrust_summary)
from cassini_bayes.ivp import VectorTree, fit_chebyshev_segments, propagate_conic
from cassini_bayes.spacecraft import Spacecraft, load_spacecraft
from cassini_bayes.telemetry import PulseLog, Telemetry, read_pulses, read_telemetry

__all__ = [
    "read_telemetry", "read_pulses", "load_spacecraft", "simulate", "fit_inertia", "fit_thrust",
    "fit_rwa4", "FitResult", "Simulation", "Telemetry", "PulseLog", "Spacecraft",
    "request_host_devices", "inertia_baseline", "inertia_summary", "thrust_baseline",
    "thrust_sensitivity", "thrust_summary", "rwa4_sensitivity", "rwa4_summary", "write_run",
    "write_run_files", "fit_config", "collect_warnings", "truth_document",
    "fit_health", "HealthResult", "simulate_health_campaign", "monitor_leak", "LeakResult",
    "check_telemetry", "TelemetryCheck", "budget", "BudgetResult",
    "propagate_conic", "fit_chebyshev_segments", "VectorTree", "fit_trajectory", "TrajectoryFit",
]
