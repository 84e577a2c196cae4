"""The predicted posterior of a manoeuvre: a scenario flown without noise, then the Laplace
approximation of the robust fit on that truth (:mod:`cassini_bayes.plan.inertia`).

:func:`evaluate_inertia` takes any scenario with slews (a shipped one, a user's, a plan's):
it runs the simulator at the scenario's own step with the sensor noise off, linearises the
robust inertia fit at the truth (the fit's mode on noise-free data) with the noise levels of the
scenario's sensors, and gives per parameter the predicted posterior sd, its budget, the prior sd,
and the largest use of each limit when limits are given.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import numpy as np

from cassini_bayes.physics.momentum import inertia_vector
from cassini_bayes.plan import checks
from cassini_bayes.plan.budgets import inertia_budgets
from cassini_bayes.plan.flight import no_noise
from cassini_bayes.plan.inertia import inertia_model, noise_sigmas, predict_sites
from cassini_bayes.plan.limits import Limits
from cassini_bayes.simulate import run as _run
from cassini_bayes.simulate.scenario import Scenario

__all__ = ["InertiaPrediction", "evaluate_inertia", "wheels_on"]


class InertiaPrediction(NamedTuple):
    """Predicted posterior of one manoeuvre (kg m², per ``Ixx … Iyz``).

    sd : predicted posterior sd, as a fit reports it; sd_data : the part the manoeuvre controls
    (the wheels' common spin-inertia scale held fixed); c_sd : sd of that common scale (a
    fraction, from its prior: no manoeuvre changes it). budget : the papers' budget;
    prior_sd : the model file's knowledge. usage : largest fraction of each limit on the
    simulated telemetry (empty without limits). duration_s : the scenario's length.
    pi : (6,) the true inertia the prediction is linearised at, kg m².
    sites, site_sd, site_prior_sd : every site of the robust fit (inertia, ``H_0``, ``T_N`` and
    each nuisance parameter, :func:`cassini_bayes.plan.inertia.site_labels`), its predicted
    posterior sd and its prior sd (SI).
    t, omega, wheel_rpm : the noise-free flight at the telemetry samples (s, rad/s, rpm; idle
    wheels NaN), for the report's figure; wheel_names their names.
    """

    sd: np.ndarray
    sd_data: np.ndarray
    c_sd: float
    budget: np.ndarray
    prior_sd: np.ndarray
    usage: dict
    duration_s: float
    pi: np.ndarray
    t: np.ndarray
    omega: np.ndarray
    wheel_rpm: np.ndarray
    wheel_names: tuple[str, ...] = ()
    sites: tuple[str, ...] = ()
    site_sd: np.ndarray = np.zeros(0)
    site_prior_sd: np.ndarray = np.zeros(0)

    @property
    def ratio(self) -> np.ndarray:
        """``sd / budget`` per parameter."""
        return self.sd / self.budget

    @property
    def floor_ratio(self) -> np.ndarray:
        """``|π_i| c_sd / budget_i``: the ratio the wheels' common spin-inertia scale alone
        gives (π = (1 + c) π̃): no manoeuvre goes below it."""
        return np.abs(self.pi) * self.c_sd / self.budget

    @property
    def ratio_data(self) -> np.ndarray:
        """``sd_data / budget`` per parameter."""
        return self.sd_data / self.budget


def wheels_on(s: Scenario) -> list[str]:
    """Names of the scenario's wheels that run."""
    return [n for n, on in zip(s.wheel_names, s.wheels_on) if on]


def evaluate_inertia(s: Scenario, limits: Limits | None = None) -> InertiaPrediction:
    """Predicted posterior of the robust inertia fit of scenario ``s`` (module docstring)."""
    tp = _run.truth_params(s)
    arr = jax.tree_util.tree_map(np.asarray,
                                 _run.simulate_arrays(jax.random.key(0), s, tp, no_noise()))
    model = inertia_model(s.prior, wheels_on(s))
    n = s.noise
    sigma = noise_sigmas(n.gyro_rad_s, n.tach_noise_rpm, n.tach_quantum_rpm, n.star_tracker_rad)
    pi = np.asarray(inertia_vector(s.truth.inertia), float)
    tn = np.asarray(s.external_torque_inertial_nm, float)
    pred, labels, site_sd, site_prior = predict_sites(model, arr, pi, arr.h_inertial[0], tn,
                                                      sigma)
    pred = jax.tree_util.tree_map(np.asarray, pred)
    usage = {}
    if limits is not None:
        on = np.asarray(s.wheels_on, float)
        usage = checks.largest_usage(arr.t, arr.omega, arr.wheel_rates, s.prior.wheel_axes,
                                     s.prior.wheel_inertias, on, limits)
    prior = inertia_model_prior_sd(s)
    rpm = np.where(np.asarray(s.wheels_on)[None, :], arr.wheel_rates * 30.0 / np.pi, np.nan)
    return InertiaPrediction(pred.sd, pred.sd_data, float(pred.c_sd), inertia_budgets(s.prior),
                             prior, usage, s.duration_s, pi, arr.t, arr.omega, rpm,
                             tuple(s.wheel_names), labels, np.asarray(site_sd),
                             np.asarray(site_prior))


def inertia_model_prior_sd(s: Scenario) -> np.ndarray:
    """(6,) the model file's knowledge of ``Ixx … Iyz`` (the fit's prior sd), kg m²."""
    from cassini_bayes.inference.inertia.prior import inertia_prior

    return np.asarray(inertia_prior(s.prior).sd, float)

