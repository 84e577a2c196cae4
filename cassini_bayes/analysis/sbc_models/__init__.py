"""Models that simulation-based calibration can run: the adapter contract and the registry.

An SBC campaign (:mod:`cassini_bayes.analysis.campaign`) needs from a model an
:class:`SbcModel`: ``prior_sample(key) -> {name: scalar}`` (one draw from the *same* prior the
posterior uses, one scalar per ranked name), ``simulate`` or ``simulate_batch`` (synthetic data
from the package's simulator), ``fit(key, data) -> SbcFit`` (every post-warm-up draw, shape
``(chains, draws)``, and the divergence count; the campaign thins them by ``settings["thin"]``,
Talts et al. 2018, Sec. 5.1) and ``parameter_names``.

A ``vectorized`` model's ``fit`` is pure JAX: a batch of replicates is fitted with one
``jax.vmap`` of the package's NUTS program (:func:`nuts_fit`), after an optional per-replicate
``prepare`` in NumPy. A model whose fit runs NumPy/SciPy between compiled programs (thrust,
RWA4) sets ``vectorized=False`` and is fitted replicate by replicate.

Adapters are built by name from a :class:`ModelSpec` (plain data: the model name, an optional
scenario file's *text* and options), so that a Dask worker rebuilds the same adapter from what
the client sends it. Register one with :func:`register`. Registered: ``toy`` (a linear-Gaussian
regression that tests the machinery), ``inertia``, ``thrust`` and ``rwa4`` (one module each; their
factories' docstrings state truth, data, fit and options; each has ``--set robust=true`` for the
robust model the CLI fits by default). Their default scenarios are shipped files under
``experiments/scenarios/sbc/``.
"""

from __future__ import annotations

# the adapter modules register their models on import (``toy``, ``inertia``, ``thrust``, ``rwa4``)
from cassini_bayes.analysis.sbc_models import _toy  # noqa: F401
from cassini_bayes.analysis.sbc_models._contract import ModelSpec as ModelSpec
from cassini_bayes.analysis.sbc_models._contract import SbcFit as SbcFit
from cassini_bayes.analysis.sbc_models._contract import SbcModel as SbcModel
from cassini_bayes.analysis.sbc_models._contract import build_model as build_model
from cassini_bayes.analysis.sbc_models._contract import register as register
from cassini_bayes.analysis.sbc_models._contract import registered_models as registered_models
from cassini_bayes.analysis.sbc_models._inertia import INERTIA_SCENARIO as INERTIA_SCENARIO
from cassini_bayes.analysis.sbc_models._inertia import (
    robust_inertia_truth as robust_inertia_truth,
)
from cassini_bayes.analysis.sbc_models._nuts import nuts_fit as nuts_fit
from cassini_bayes.analysis.sbc_models._rwa4 import RWA4_SCENARIO as RWA4_SCENARIO
from cassini_bayes.analysis.sbc_models._rwa4 import robust_rwa4_truth as robust_rwa4_truth
from cassini_bayes.analysis.sbc_models._thrust import THRUST_SBC_NAMES as THRUST_SBC_NAMES
from cassini_bayes.analysis.sbc_models._thrust import THRUST_SCENARIO as THRUST_SCENARIO

__all__ = [
    "SbcFit",
    "SbcModel",
    "ModelSpec",
    "register",
    "registered_models",
    "build_model",
    "nuts_fit",
    "robust_inertia_truth",
    "robust_rwa4_truth",
    "INERTIA_SCENARIO",
    "THRUST_SCENARIO",
    "THRUST_SBC_NAMES",
    "RWA4_SCENARIO",
]
