"""Choosing the slews of an inertia calibration: gradients through the simulator.

The objective of ``n`` slews (:mod:`cassini_bayes.plan.manoeuvre`'s parameters, which keep every
command within the rate and acceleration limits and every slew within its slot) is

    J = smax_i log(sd_i / b_i) + W Σ_t Σ_limits max(0, usage_t − margin)²

``sd_i`` the predicted posterior sd of parameter ``i`` (:mod:`cassini_bayes.plan.inertia`) on the
flight simulated without noise (:mod:`cassini_bayes.plan.flight`), ``b_i`` its budget
(:mod:`cassini_bayes.plan.budgets`), ``smax`` a smooth maximum (``logsumexp(κ x)/κ``,
:data:`SHARPNESS`) and the second term the penalty of :func:`cassini_bayes.plan.checks.penalty`
on the flight's wheel speeds, momenta and torques. ``J`` and its gradient (``jax.value_and_grad``
through the likelihood's information, the simulator's ``lax.scan`` and the command profile) go to
L-BFGS (SciPy). The number of slews is discrete: a short documented search tries each of
:data:`SLEW_COUNTS` that fits the duration and keeps the best.

``target``: ``"max_ratio"`` (default) the sd a fit reports; ``"max_ratio_data"`` the part the
manoeuvre controls (the wheels' common spin-inertia scale, which no manoeuvre informs, held
fixed; docs/planning.md).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.physics.momentum import inertia_vector
from cassini_bayes.plan import checks
from cassini_bayes.plan.budgets import inertia_budgets
from cassini_bayes.plan.flight import make_flight, planning_step
from cassini_bayes.plan.inertia import inertia_model, noise_sigmas, predict
from cassini_bayes.plan.limits import ACCEL_TORQUE_SHARE, Limits, torque_per_accel
from cassini_bayes.plan.manoeuvre import (
    SlewBounds,
    SlewParams,
    Slews,
    accel_limit,
    initial_params,
    rate_limit,
    slews_from_params,
)
from cassini_bayes.simulate.scenario import Scenario

__all__ = [
    "PENALTY_WEIGHT",
    "SHARPNESS",
    "SLEW_COUNTS",
    "TARGETS",
    "InertiaObjective",
    "OptimisedSlews",
    "inertia_objective",
    "optimise_slews",
    "slew_bounds",
    "slew_counts",
]

TARGETS = ("max_ratio", "max_ratio_data")
SLEW_COUNTS = (3, 4, 6, 8)
SHARPNESS = 20.0       # κ of the smooth maximum: within log(6)/κ = 0.09 of the largest log ratio
PENALTY_WEIGHT = 10.0


def slew_bounds(limits: Limits, base: Scenario, n: int) -> SlewBounds:
    """The bounds of ``n`` slews for the limits and the base scenario's spacecraft and wheels."""
    on = [w for w, o in zip(base.wheel_names, base.wheels_on) if o]
    return SlewBounds(n, limits.duration_s, limits.quiet_s, limits.rate_max_rad_s,
                      np.asarray(limits.axis_rate_max_rad_s, float), limits.accel_max_rad_s2,
                      torque_per_accel(base.prior, on),
                      ACCEL_TORQUE_SHARE * limits.wheel_torque_max_nm)


def slew_counts(limits: Limits, base: Scenario, counts=SLEW_COUNTS) -> list[int]:
    """The slew counts of ``counts`` whose slots each hold a slew that reaches the rate limit."""
    out = []
    for n in counts:
        b = slew_bounds(limits, base, n)
        e = np.eye(3)
        need = float(np.max(2.0 * np.asarray(rate_limit(b, e)) / np.asarray(accel_limit(b, e))))
        if b.slewing_s / n >= need:
            out.append(n)
    return out


class InertiaObjective(NamedTuple):
    """The objective of ``n`` slews: ``value_and_grad(flat)`` (jitted), the parameter shapes and
    the pieces needed to read a result."""

    value_and_grad: Callable
    terms: Callable
    bounds: SlewBounds
    unflatten: Callable


def inertia_objective(limits: Limits, base: Scenario, n: int, target: str = "max_ratio",
                      dt_s: float | None = None) -> InertiaObjective:
    """``J`` of the module docstring for ``n`` slews, flown at step ``dt_s`` (default
    :func:`~cassini_bayes.plan.flight.planning_step`)."""
    bounds = slew_bounds(limits, base, n)
    fly = make_flight(base, planning_step(base) if dt_s is None else dt_s)
    model = inertia_model(base.prior, [w for w, o in zip(base.wheel_names, base.wheels_on) if o])
    nz = base.noise
    sigma = jnp.asarray(noise_sigmas(nz.gyro_rad_s, nz.tach_noise_rpm, nz.tach_quantum_rpm,
                                     nz.star_tracker_rad))
    pi = jnp.asarray(np.asarray(inertia_vector(base.truth.inertia), float))
    tn = jnp.asarray(base.external_torque_inertial_nm, float)
    log_budget = jnp.log(jnp.asarray(inertia_budgets(base.prior)))
    on = np.asarray(base.wheels_on, float)
    axes, js = base.prior.wheel_axes, base.prior.wheel_inertias
    shapes = [(n, 3), (n,), (n,), (n,)]
    sizes = [int(np.prod(s)) for s in shapes]

    def unflatten(x):
        parts = jnp.split(x, np.cumsum(sizes)[:-1])
        return SlewParams(*(p.reshape(s) for p, s in zip(parts, shapes)))

    def terms(x):
        slews = slews_from_params(unflatten(x), bounds)
        arr = fly(slews)
        pred = predict(model, arr, pi, arr.h_inertial[0], tn, sigma)
        sd = pred.sd if target == "max_ratio" else pred.sd_data
        log_ratio = jnp.log(sd) - log_budget
        smooth = jax.scipy.special.logsumexp(SHARPNESS * log_ratio) / SHARPNESS
        pen = checks.penalty(arr.t, arr.omega, arr.wheel_rates, axes, js, on, limits)
        if np.isfinite(limits.slew_max_rad):
            pen = pen + jnp.sum(jnp.maximum(slews.angle_rad / limits.slew_max_rad - 1.0,
                                            0.0) ** 2)
        return smooth + PENALTY_WEIGHT * pen, (log_ratio, pen, slews)

    vg = jax.jit(jax.value_and_grad(lambda x: terms(x)[0]))
    return InertiaObjective(vg, jax.jit(terms), bounds, unflatten)


class OptimisedSlews(NamedTuple):
    """The best slews found for one count: ``slews`` (:class:`~cassini_bayes.plan.manoeuvre.
    Slews`, NumPy), ``objective`` ``J``, ``max_log_ratio`` (the target on the planning step's
    flight), ``penalty``, ``iterations``, ``evaluations``, ``seconds``."""

    n: int
    slews: Slews
    objective: float
    max_log_ratio: float
    penalty: float
    iterations: int
    evaluations: int
    seconds: float


def optimise_slews(limits: Limits, base: Scenario, n: int, *, target: str = "max_ratio",
                   max_iter: int = 60, start: SlewParams | None = None,
                   progress: Callable[[str], None] | None = None) -> OptimisedSlews:
    """L-BFGS on ``J`` for ``n`` slews from :func:`~cassini_bayes.plan.manoeuvre.
    initial_params` (or ``start``)."""
    import scipy.optimize

    t0 = time.perf_counter()
    obj = inertia_objective(limits, base, n, target)
    p0 = initial_params(obj.bounds) if start is None else start
    x0 = np.concatenate([np.asarray(a, float).ravel() for a in p0])
    count = [0]

    def fun(x):
        count[0] += 1
        v, g = obj.value_and_grad(jnp.asarray(x))
        v, g = float(v), np.asarray(g, float)
        if not (np.isfinite(v) and np.all(np.isfinite(g))):
            return np.inf, np.zeros_like(x)
        if progress is not None and count[0] % 5 == 1:
            progress(f"{n} slews: evaluation {count[0]}, J = {v:.4f}")
        return v, g

    res = scipy.optimize.minimize(fun, x0, jac=True, method="L-BFGS-B",
                                  options={"maxiter": max_iter, "ftol": 1e-10, "gtol": 1e-8})
    value, (log_ratio, pen, slews) = obj.terms(jnp.asarray(res.x))
    slews = jax.tree_util.tree_map(np.asarray, slews)
    return OptimisedSlews(n, slews, float(value), float(np.max(np.asarray(log_ratio))),
                          float(pen), int(res.nit), count[0], time.perf_counter() - t0)
