"""NumPyro models and the MCMC runner; results as ArviZ InferenceData.

* :mod:`~cassini_bayes.inference.runner` — NUTS on the CPU, sampler cache, ArviZ diagnostics;
* :mod:`~cassini_bayes.inference.inertia` — inertia tensor from RWA slews (physical by
  construction; idealised or robust);
* :mod:`~cassini_bayes.inference.thrust` — thrust and pulse time constants from biasing events;
* :mod:`~cassini_bayes.inference.rwa4` — a wheel's spin axis on the sphere (Brown's RCS and RWA
  methods);
* :mod:`~cassini_bayes.inference.nuisance`, :mod:`~cassini_bayes.inference.sensitivity` — the
  robust models' sensor and actuator errors and what neglecting them would cost;
* :mod:`~cassini_bayes.inference.laplace` — the Laplace step that whitens the samplers' coordinates;
* :mod:`~cassini_bayes.inference.summary` — the ``summary.json`` of a run (docs/design.md §4.5).

The names below are imported on first use, so that a command imports only the model it fits.
"""

import importlib

_HOMES = {
    "inertia": ["InertiaPosterior", "InertiaPrior", "fit_inertia", "inertia_prior",
                "prepare_inertia", "sample_prior"],
    "runner": ["Diagnostics", "SamplerSettings", "diagnostics", "run_nuts"],
    "rwa4": ["Rwa4Posterior", "fit_rwa4", "prepare_rwa4"],
    "thrust": ["InertiaGaussian", "ThrustPosterior", "fit_thrust", "inertia_from_run",
               "prepare_thrust"],
}
_HOME = {name: module for module, names in _HOMES.items() for name in names}

__all__ = ["Diagnostics", "SamplerSettings", "diagnostics", "run_nuts", "InertiaPosterior",
           "InertiaPrior", "fit_inertia", "inertia_prior", "prepare_inertia", "sample_prior",
           "InertiaGaussian", "ThrustPosterior", "fit_thrust", "inertia_from_run",
           "prepare_thrust", "Rwa4Posterior", "fit_rwa4", "prepare_rwa4"]


def __getattr__(name: str):
    """Import a name from its module on first use: importing one submodule (``progress``,
    ``runner``) does not import every model, nor ArviZ."""
    if name in _HOME:
        value = getattr(importlib.import_module(f"{__name__}.{_HOME[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
