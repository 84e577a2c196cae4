"""Synthetic telemetry for every calibration scenario of the papers (pure JAX, vmappable, keyed).

Public API (re-exported from the private modules):

* :func:`load_scenario`, :class:`Scenario` — TOML scenarios under ``experiments/scenarios/``;
* :func:`simulate` ``(key, scenario) -> SimResult`` — truth, noisy telemetry, pulse log;
* :func:`simulate_batch` ``(keys, scenario, truth=None) -> SimArrays`` — replicates in one
  compiled, vmapped call (truth parameters may be batched too, for SBC);
* :class:`TruthParams`, :func:`truth_params`, :func:`quiet_windows`, :func:`with_errors` (sensor
  and wheel errors of the robust models' nuisance, for closed-world campaigns);
* :class:`FlexMode` — the optional flexible/slosh mode (hybrid coordinates).
"""

from cassini_bayes.simulate.run import (
    PULSE_RING,
    SimArrays,
    SimResult,
    TruthParams,
    noise_params,
    pulse_log,
    quiet_windows,
    simulate,
    simulate_arrays,
    simulate_batch,
    trace_count,
    truth_params,
    with_errors,
)
from cassini_bayes.simulate.scenario import (FlexMode, Noise, Scenario, load_scenario,
                                            scenario_from_dict)
from cassini_bayes.simulate.sensors import NoiseParams

__all__ = [
    "PULSE_RING",
    "FlexMode",
    "Noise",
    "NoiseParams",
    "Scenario",
    "SimArrays",
    "SimResult",
    "TruthParams",
    "load_scenario",
    "noise_params",
    "pulse_log",
    "quiet_windows",
    "scenario_from_dict",
    "simulate",
    "simulate_arrays",
    "simulate_batch",
    "trace_count",
    "truth_params",
    "with_errors",
]
