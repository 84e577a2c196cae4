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
"""

from cassini_bayes.inference.inertia import (InertiaPosterior, InertiaPrior, fit_inertia,
                                             inertia_prior, prepare_inertia, sample_prior)
from cassini_bayes.inference.runner import (Diagnostics, SamplerSettings, diagnostics,
                                            run_nuts)
from cassini_bayes.inference.rwa4 import Rwa4Posterior, fit_rwa4, prepare_rwa4
from cassini_bayes.inference.thrust import (InertiaGaussian, ThrustPosterior, fit_thrust,
                                            inertia_from_run, prepare_thrust)

__all__ = ["Diagnostics", "SamplerSettings", "diagnostics", "run_nuts", "InertiaPosterior",
           "InertiaPrior", "fit_inertia", "inertia_prior", "prepare_inertia", "sample_prior",
           "InertiaGaussian", "ThrustPosterior", "fit_thrust", "inertia_from_run",
           "prepare_thrust", "Rwa4Posterior", "fit_rwa4", "prepare_rwa4"]
