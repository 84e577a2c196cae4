"""Gaussian knowledge of the inertia entries, as the thrust and RWA4 models take it: an inertia
run's posterior (read from its run directory) or the spacecraft model's knowledge.
"""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

import numpy as np

from cassini_bayes.errors import InputError, arg
from cassini_bayes.inference.inertia.prior import inertia_prior
from cassini_bayes.names import INERTIA_NAMES
from cassini_bayes.physics.momentum import inertia_vector
from cassini_bayes.spacecraft import Spacecraft

__all__ = ["InertiaGaussian", "inertia_from_run", "inertia_from_idata", "inertia_prior_gaussian",
           "inertia_mean_tril"]


class InertiaGaussian(NamedTuple):
    """Gaussian knowledge of the inertia entries ``(Ixx … Iyz)``: ``mean`` (6,) kg m², ``cov``
    (6, 6) (kg m²)²; e.g. an inertia run's posterior mean and covariance."""

    mean: np.ndarray
    cov: np.ndarray


def inertia_from_run(run_dir: str | Path) -> InertiaGaussian:
    """Posterior mean and covariance of ``Ixx … Iyz`` from an inertia run directory.

    Reads ``RUN_DIR/posterior.nc`` (an earlier ``cassini-bayes fit inertia``). Raises
    :class:`InputError` when the file is missing or holds no inertia draws.
    """
    from cassini_bayes.rundir import read_posterior

    idata = read_posterior(run_dir, "inertia", arg("inertia_posterior", run_dir))
    return inertia_from_idata(idata, str(Path(run_dir) / "posterior.nc"))


def inertia_from_idata(idata, source: str) -> InertiaGaussian:
    """Posterior mean and covariance of ``Ixx … Iyz`` from an inertia fit's InferenceData
    (``source`` names it in errors)."""
    try:
        post = idata.posterior
        draws = np.stack([np.asarray(post[n].values, float).ravel() for n in INERTIA_NAMES], -1)
    except (KeyError, AttributeError) as e:
        raise InputError(f"{source}: no inertia draws ({e.args[0]} missing); give the run "
                         "directory of an inertia fit") from None
    if draws.shape[0] < 10 or not np.all(np.isfinite(draws)):
        raise InputError(f"{source}: too few or non-finite inertia draws; re-run the inertia fit")
    cov = np.cov(draws, rowvar=False)
    return InertiaGaussian(draws.mean(0), 0.5 * (cov + cov.T))


def inertia_prior_gaussian(spacecraft: Spacecraft) -> InertiaGaussian:
    """The model file's inertia knowledge as a Gaussian: mean the predicted tensor, independent
    sd ``moi_uncertainty × moment`` and ``poi_uncertainty`` (the inertia model's prior,
    :func:`~cassini_bayes.inference.inertia.prior.inertia_prior`, without its truncation to physical
    tensors, which ±10 % about a physical prediction does not reach)."""
    prior = inertia_prior(spacecraft)
    return InertiaGaussian(prior.mean, np.diag(prior.sd ** 2))


def inertia_mean_tril(inertia: InertiaGaussian | None, i_fixed: np.ndarray):
    """The inertia prior's mean (6,) kg m² and Cholesky factor (jittered by 1e-9 kg² m⁴), or
    the fixed prediction ``i_fixed`` (3, 3) with a zero factor."""
    if inertia is not None:
        tril = np.linalg.cholesky(np.asarray(inertia.cov) + 1e-9 * np.eye(6))
        return np.asarray(inertia.mean, float), tril
    return np.asarray(inertia_vector(i_fixed)), np.zeros((6, 6))
