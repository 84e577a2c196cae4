"""NumPyro models and the MCMC runner; results as ArviZ InferenceData.

* :mod:`~cassini_bayes.inference.runner` — NUTS on the CPU, sampler cache, ArviZ diagnostics;
* :mod:`~cassini_bayes.inference.inertia` — inertia tensor from RWA slews (physical by
  construction);
* :mod:`~cassini_bayes.inference.summary` — the ``summary.json`` of a run (DESIGN.md §4).
"""

from cassini_bayes.inference.inertia import (InertiaPosterior, InertiaPrior, fit_inertia,
                                             inertia_prior, prepare_inertia, sample_prior)
from cassini_bayes.inference.runner import (Diagnostics, SamplerSettings, diagnostics,
                                            run_nuts)

__all__ = ["Diagnostics", "SamplerSettings", "diagnostics", "run_nuts", "InertiaPosterior",
           "InertiaPrior", "fit_inertia", "inertia_prior", "prepare_inertia", "sample_prior"]
