"""Predicted posterior of the wheel-axis fit (RWA method, Brown 2012 §III.C) for a manoeuvre.

The fit (:mod:`cassini_bayes.inference.rwa4`, ``fit wheel-axis --method rwa``) samples the wheel's
axis ``u`` (gnomonic chart ``v``) and the inertia ``π`` (log-Cholesky chart ``ζ``), ``θ = (v, ζ)``;
the robust model's nuisance effects (gyro bias and scale factor, spin-inertia scales, the known
wheels' tilts, body and inertial torques) enter the window-mean balances and each quiet
window's momentum slope (the RWA method's torque measurement) linearly and are integrated out
exactly in its likelihood. So its posterior is a density in eight coordinates, and the
prediction is its Laplace approximation on the telemetry flown without noise:

1. the scenario is simulated with every sensor error off (:func:`noise_free_telemetry`);
2. the fit's own data preparation (:func:`~cassini_bayes.inference.rwa4.prepare_rwa4`: windows
   detected as the fit detects them, window means and slopes, nuisance columns, charts) runs on
   it, and the white-noise levels it would estimate from noisy data are replaced by the
   scenario's sensors' (:func:`~cassini_bayes.plan.inertia.noise_sigmas`, floored as the fit
   floors them);
3. the mode is found by the fit's own :func:`~cassini_bayes.inference.laplace.laplace`, and the
   negative Hessian of the fit's own log density (``jax.hessian``: prior, chart Jacobians and the
   likelihood with the nuisances integrated out) there is the posterior precision: on noise-free
   data the balances and slopes vanish at the truth, so it is the expected Fisher information
   plus the prior (the noise covariance's own dependence on ``θ`` aside, which is second order);
4. every posterior site (``u4_x … u4_z``, ``Ixx … Iyz``) follows by the delta method through the
   chart (``jax.jacfwd``), and the direction's spread from the tangent-plane covariance of ``u``
   (:func:`cone_radii`).
"""

from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.analysis.paper_facts import fact
from cassini_bayes.names import INERTIA_NAMES, U4_NAMES
from cassini_bayes.plan import checks
from cassini_bayes.plan.inertia import noise_sigmas
from cassini_bayes.plan.limits import Limits
from cassini_bayes.simulate.scenario import Noise, Scenario

__all__ = [
    "AXIS_SITES",
    "AxisPrediction",
    "axis_budget_deg",
    "cone_radii",
    "effect_shares",
    "evaluate_wheel_axis",
    "noise_free_telemetry",
    "planned_pairs",
    "predict_axis",
    "scenario_noise",
    "solved_wheel",
]

AXIS_SITES = tuple(U4_NAMES) + tuple(INERTIA_NAMES)
CONE_LEVELS = ("50", "90", "95")
_CONE_DRAWS = 100_000     # draws of the tangent-plane Gaussian for the cone radii (fixed key)
_PRIOR_DRAWS = 4000       # prior draws for the sites' prior sd (fixed key)


def axis_budget_deg() -> float:
    """Brown's expected accuracy of the RWA method (deg, Brown 2012 §III.C): the yardstick of
    the predicted 90 % cone."""
    return float(fact("rwa4_rwa_expected_deg").value)


class AxisPrediction(NamedTuple):
    """Predicted posterior of the wheel-axis fit of one manoeuvre.

    wheel : the wheel solved for. sites : ``u4_x … u4_z``, ``Ixx … Iyz``; site_sd,
    site_prior_sd : their predicted posterior and prior sd (unit vector components; kg m²).
    axis : (3,) the mode on the noise-free flight; true_axis : (3,) the scenario's true axis.
    tangent_cov : (2, 2) covariance of the direction in the tangent plane at ``axis`` (rad²).
    sd_direction_deg : the direction's largest angular sd; cone_deg : the radii of the cones
    about the mean holding 50/90/95 % (deg), as :func:`~cassini_bayes.inference.sphere.
    direction_summary` reports a fit's. budget_deg : Brown's expected accuracy.
    pairs : the Time A / Time B windows (s) the fit uses. noise : (3,) the noise levels used
    (rad/s, rad/s, rad). shares : the share of the axis's predicted variance each robust effect
    carries (:func:`effect_shares`). usage : the largest fraction of each limit on the simulated
    telemetry (empty without limits). duration_s; t, omega, wheel_rpm, wheel_names : the
    noise-free flight (s, rad/s, rpm with idle wheels NaN) for the report's figure.
    """

    wheel: str
    sites: tuple[str, ...]
    site_sd: np.ndarray
    site_prior_sd: np.ndarray
    axis: np.ndarray
    true_axis: np.ndarray
    tangent_cov: np.ndarray
    sd_direction_deg: float
    cone_deg: dict
    budget_deg: float
    pairs: tuple
    noise: np.ndarray
    usage: dict
    duration_s: float
    t: np.ndarray
    omega: np.ndarray
    wheel_rpm: np.ndarray
    wheel_names: tuple[str, ...] = ()
    shares: dict = {}


def scenario_noise(s: Scenario) -> np.ndarray:
    """The fit's white-noise levels ``(σ_ω, σ_ρ, σ_θ)`` of the scenario's sensors."""
    n = s.noise
    return noise_sigmas(n.gyro_rad_s, n.tach_noise_rpm, n.tach_quantum_rpm, n.star_tracker_rad)


def solved_wheel(s: Scenario, wheel: str | None) -> str:
    """The wheel a scenario calibrates: ``wheel`` (the scenario's spelling), else the one running
    wheel whose true axis differs from the prior model's, else the fit's default (RWA4)."""
    from cassini_bayes.errors import InputError, arg
    from cassini_bayes.inference.rwa4 import WHEEL

    names = {n.upper(): n for n in s.wheel_names}
    on = {n for n, o in zip(s.wheel_names, s.wheels_on) if o}
    if wheel is not None:
        name = names.get(str(wheel).upper())
        if name is None or name not in on:
            raise InputError(f"{arg('wheel', wheel)}: not a running wheel of scenario "
                             f"{s.name!r} (running: {', '.join(sorted(on))})", path=s.source)
        return name
    moved = [n for n in s.wheel_names if n in on and float(
        s.truth.wheel(n).axis @ s.prior.wheel(n).axis) < 1.0 - 1e-12]
    if len(moved) == 1:
        return moved[0]
    if WHEEL in on:
        return WHEEL
    raise InputError(f"scenario {s.name!r}: say which wheel's axis is calibrated "
                     f"(--wheel, one of {', '.join(sorted(on))})", path=s.source)


def noise_free_telemetry(s: Scenario):
    """The scenario flown with every sensor error off: ``(SimResult, Telemetry)``."""
    from cassini_bayes.simulate import simulate

    sim = simulate(jax.random.key(0), replace(s, noise=Noise()))
    return sim, sim.telemetry


def cone_radii(tangent_cov: np.ndarray) -> dict:
    """Radii (deg) of the cones about the mean holding 50/90/95 % of directions whose gnomonic
    tangent coordinates are ``N(0, tangent_cov)`` (fixed draws: the same numbers every call)."""
    z = np.random.default_rng(0).standard_normal((_CONE_DRAWS, 2))
    v = z @ np.linalg.cholesky(tangent_cov + 1e-30 * np.eye(2)).T
    ang = np.degrees(np.arctan(np.linalg.norm(v, axis=1)))
    return {k: float(np.quantile(ang, float(k) / 100.0)) for k in CONE_LEVELS}


class _Laplace(NamedTuple):
    centre: np.ndarray
    cov: np.ndarray
    site_cov: np.ndarray
    axis: np.ndarray
    tangent_cov: np.ndarray


def predict_axis(problem, sigmas) -> _Laplace:
    """Laplace approximation of the fit's posterior for the prepared ``problem``
    (:func:`~cassini_bayes.inference.rwa4.prepare_rwa4`) with the white-noise levels ``sigmas``
    (3,): the mode by the fit's :func:`~cassini_bayes.inference.laplace.laplace`, the precision
    by ``jax.hessian`` of the fit's log density, the sites by the delta method (module
    docstring)."""
    from cassini_bayes.inference.laplace import laplace
    from cassini_bayes.inference.rwa4.model import LOG_DENSITY, PHYSICAL

    log_density, physical = LOG_DENSITY[problem.chart], PHYSICAL[problem.chart]
    kw = problem.data._replace(log_noise_hat=jnp.log(jnp.asarray(sigmas, float)))
    centre, _ = laplace(log_density, problem.data.centre, data=kw)
    centre = jnp.asarray(centre)
    hess = -np.asarray(jax.hessian(log_density)(centre, kw))
    cov = np.linalg.inv(0.5 * (hess + hess.T))
    cov = 0.5 * (cov + cov.T)

    def sites(th):
        u, pi, _, _ = physical(th, kw)
        return jnp.concatenate([u, pi])

    jac = np.asarray(jax.jacfwd(sites)(centre))
    u = np.asarray(sites(centre))[:3]
    basis = np.asarray(tangent_basis(u))
    jt = basis @ jac[:3]                    # tangent-plane coordinates of u, rad per θ
    return _Laplace(np.asarray(centre), cov, jac @ cov @ jac.T, u, jt @ cov @ jt.T)


def _tangent_var(problem, kw, centre, jt_of) -> float:
    from cassini_bayes.inference.rwa4.model import LOG_DENSITY

    hess = -np.asarray(jax.hessian(LOG_DENSITY[problem.chart])(jnp.asarray(centre), kw))
    jt = jt_of
    return float(np.trace(jt @ np.linalg.solve(0.5 * (hess + hess.T), jt.T)))


def effect_shares(problem, sigmas, lap: _Laplace) -> dict[str, float]:
    """Share of the axis's predicted tangent-plane variance (its trace) each robust effect of
    the fit's layout carries: ``1 − var(effect known)/var``, the effect known meaning its prior
    sd set to 0 at the same mode; ``"sensor noise"``: the variance left with every effect
    known, over the whole. Says which error a manoeuvre is limited by (the shares need not add
    to 1: the effects are correlated in the data)."""
    from cassini_bayes.inference.rwa4.model import PHYSICAL

    kw = problem.data._replace(log_noise_hat=jnp.log(jnp.asarray(sigmas, float)))
    physical = PHYSICAL[problem.chart]
    basis = np.asarray(tangent_basis(lap.axis))
    jt = basis @ np.asarray(jax.jacfwd(lambda th: physical(th, kw)[0])(jnp.asarray(lap.centre)))
    total = float(np.trace(lap.tangent_cov))
    sd = np.asarray(kw.nu_sd, float)
    out = {}
    for effect, sl in problem.layout.slices.items():
        if sd[sl].size == 0:
            continue
        known = sd.copy()
        known[sl] = 0.0
        out[effect] = 1.0 - _tangent_var(problem, kw._replace(nu_sd=jnp.asarray(known)),
                                         lap.centre, jt) / total
    out["sensor noise"] = _tangent_var(problem, kw._replace(nu_sd=jnp.zeros_like(kw.nu_sd)),
                                       lap.centre, jt) / total
    return out


def tangent_basis(u: np.ndarray) -> np.ndarray:
    """(2, 3) orthonormal basis of the plane perpendicular to the direction of ``u``."""
    from cassini_bayes.inference.rwa4.data import tangent_basis as basis

    return basis(np.asarray(u, float) / np.linalg.norm(u))


def prior_site_sd(problem) -> np.ndarray:
    """(9,) prior sd of ``u4_x … Iyz``: the inertia prior's Gaussian sd (its physical factor
    is 1 − 3e-4 at the mean), ``1/√3`` per component for the uniform axis prior, fixed-key
    draws for the cone prior."""
    inertia = np.sqrt(np.diag(np.asarray(problem.inertia.cov, float)))
    if problem.prior == "uniform":
        return np.concatenate([np.full(3, 1.0 / np.sqrt(3.0)), inertia])
    from cassini_bayes.inference.rwa4 import sample_rwa4_prior

    d = sample_rwa4_prior(jax.random.key(0), problem, _PRIOR_DRAWS)
    return np.concatenate([[np.std(d[n]) for n in U4_NAMES], inertia])


def planned_pairs(s: Scenario) -> list | None:
    """The Time A / Time B pairs a plan wrote into its scenario (``[[window]]`` named ``A1``,
    ``B1``, ``A2``, …), or ``None`` when it has none."""
    w = {x.name: (x.t0_s, x.t1_s) for x in s.windows}
    n = 0
    while f"A{n + 1}" in w and f"B{n + 1}" in w:
        n += 1
    return [(w[f"A{i + 1}"], w[f"B{i + 1}"]) for i in range(n)] or None


def evaluate_wheel_axis(s: Scenario, wheel: str | None = None, limits: Limits | None = None,
                        *, prior: str = "uniform", pairs=None) -> AxisPrediction:
    """Predicted posterior of the robust RWA-method wheel-axis fit of scenario ``s`` (module
    docstring): ``wheel`` the wheel solved for (default :func:`solved_wheel`), ``prior`` the
    fit's axis prior, ``pairs`` its windows (default: a plan's own, :func:`planned_pairs`, else
    detected as the fit detects them)."""
    from cassini_bayes.inference.rwa4 import prepare_rwa4

    wheel = solved_wheel(s, wheel)
    if pairs is None:
        pairs = planned_pairs(s)
    sim, tel = noise_free_telemetry(s)
    problem = prepare_rwa4(tel, s.prior, method="rwa", pairs=pairs, prior=prior, wheel=wheel)
    sig = scenario_noise(s)
    lap = predict_axis(problem, sig)
    arr = sim.arrays
    usage = {}
    if limits is not None:
        usage = checks.largest_usage(arr.t, arr.omega, arr.wheel_rates, s.prior.wheel_axes,
                                     s.prior.wheel_inertias, np.asarray(s.wheels_on, float),
                                     limits)
    ev = np.linalg.eigvalsh(lap.tangent_cov)
    rpm = np.where(np.asarray(s.wheels_on)[None, :], np.asarray(arr.wheel_rates) * 30.0 / np.pi,
                   np.nan)
    k = list(s.wheel_names).index(wheel)
    return AxisPrediction(
        wheel=wheel, sites=AXIS_SITES, site_sd=np.sqrt(np.diag(lap.site_cov)),
        site_prior_sd=prior_site_sd(problem), axis=lap.axis,
        true_axis=np.asarray(sim.params.wheel_axes, float)[k], tangent_cov=lap.tangent_cov,
        sd_direction_deg=float(np.degrees(np.sqrt(ev[-1]))), cone_deg=cone_radii(lap.tangent_cov),
        budget_deg=axis_budget_deg(), pairs=tuple(problem.pairs), noise=np.asarray(sig),
        usage=usage, duration_s=s.duration_s, t=np.asarray(arr.t), omega=np.asarray(arr.omega),
        wheel_rpm=rpm, wheel_names=tuple(s.wheel_names),
        shares=effect_shares(problem, sig, lap) if problem.robust else {})
