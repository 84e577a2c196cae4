"""The inertia fit: NUTS on the prepared problem, the robust nuisance sites, and the
InferenceData with the residuals (:func:`fit_inertia`).
"""

from __future__ import annotations

import warnings
from typing import Any, NamedTuple, Sequence

import numpy as np

from cassini_bayes.diagnostics import Diagnostics
from cassini_bayes.inference.idata import replace_groups
from cassini_bayes.inference.inertia.data import InertiaProblem, prepare_inertia
from cassini_bayes.inference.inertia.likelihood import momentum_residuals
from cassini_bayes.inference.inertia.model import problem_model
from cassini_bayes.inference.inertia.prior import NOISE_NAMES, sample_prior
from cassini_bayes.names import EFFECTS, INERTIA_NAMES
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import Telemetry

__all__ = ["InertiaPosterior", "AXES", "ROBUST_SITES", "robust_sites", "fit_inertia"]


def _warn_weak(problem: InertiaProblem) -> None:
    for w in problem.weak_directions:
        warnings.warn(f"weakly identified (prior-dominated): {w}", stacklevel=3)


class InertiaPosterior(NamedTuple):
    """Result of :func:`fit_inertia`: the InferenceData, its diagnostics, the prepared problem."""

    idata: Any
    """ArviZ InferenceData (its groups are attributes ArviZ sets at run time)."""
    diagnostics: Diagnostics
    problem: InertiaProblem


AXES = ("x", "y", "z")
# Posterior sites of the robust nuisance vector ν (nuisance.py); a problem's own are
# :func:`robust_sites`.
ROBUST_SITES = tuple(site for effect, site in EFFECTS.items()
                     if effect not in ("inertial_torque", "flex_mode"))


def robust_sites(layout) -> list[str]:
    """The posterior sites of ``layout``'s robust nuisance parameters, in its order."""
    return [EFFECTS[e] for e in layout.slices]


def _seen_nuisance(layout, post) -> tuple[np.ndarray, float]:
    """The nuisance vector the likelihood sees (R,), from the posterior means of the physical
    sites: the wheel scales relative to the common ``c``, ``δ_k = (c_k − c)/(1 + c)`` (the shared
    ``c_s`` is seen as zero), the torques divided by ``1 + c``; and ``1 + c``."""
    nu = np.zeros(layout.size)
    mean = {name: post[name].mean(("chain", "draw")).values.reshape(-1)
            for name in robust_sites(layout)}
    for effect, sl in layout.slices.items():
        if effect != "wheel_inertia_common":
            nu[sl] = mean[EFFECTS[effect]]
    sl = layout.slices["wheel_inertia"]
    c = float(np.mean(nu[sl]))
    nu[sl] = (nu[sl] - c) / (1.0 + c)
    for effect in layout.torque_effects:
        nu[layout.slices[effect]] /= 1.0 + c
    return nu, 1.0 + c


def _data_groups(problem: InertiaProblem, r: np.ndarray, std: np.ndarray) -> dict:
    """The ``residuals``, ``observed_data`` and ``constant_data`` groups of :func:`fit_inertia`."""
    import xarray as xr

    n_files = len(problem.sources)
    t_coord = {"t": ("t", problem.t, {"units": "s"}), "axis": list(AXES),
               "file": ("t", problem.file_idx)}
    residuals = xr.Dataset(
        {"residual": (("t", "axis"), r, {"units": "N m s", "frame": "inertial",
                                         "description": "posterior-mean momentum residual"}),
         "residual_std": (("t", "axis"), std, {"units": "1", "frame": "body",
                                               "description": "whitened body residual"})},
        coords=t_coord, attrs={"sources": list(problem.sources)})
    observed = xr.Dataset(
        {"omega": (("t", "axis"), problem.omega, {"units": "rad/s"}),
         "h_wheels": (("t", "axis"), problem.h_wheels, {"units": "N m s"}),
         "q": (("t", "quat"), problem.q)},
        coords={**t_coord, "quat": ["q1", "q2", "q3", "q4"]},
        attrs={"sources": list(problem.sources)})
    constant = xr.Dataset(
        {"prior_mean": ("param", problem.prior.mean, {"units": "kg m^2"}),
         "prior_sd": ("param", problem.prior.sd, {"units": "kg m^2"}),
         "laplace_mean": ("param", problem.laplace_mean, {"units": "kg m^2"}),
         "laplace_sd": ("param", problem.laplace_sd, {"units": "kg m^2"}),
         "information_ratio": ("direction", problem.information_ratio),
         "noise_hat": (("file", "noise"), problem.noise_hat),
         "noise_eb": (("file", "noise"), problem.noise_eb)},
        coords={"param": list(INERTIA_NAMES), "direction": np.arange(6),
                "file": np.arange(n_files), "noise": list(NOISE_NAMES)})
    return {"observed_data": observed, "constant_data": constant, "residuals": residuals}


def fit_inertia(key, telemetries: Sequence[Telemetry], spacecraft: Spacecraft, *,
                torque: bool = True, robust: bool = True, wheel_errors: str = "per_wheel",
                settings=None, prior_draws: int = 500) -> InertiaPosterior:
    """Posterior of the inertia tensor from one or more RWA-slew telemetry files.

    Parameters
    ----------
    key : jax.random key (the CLI makes it from ``--seed``).
    telemetries : slews sharing one inertia; each has its own conserved momentum (and torque).
    spacecraft : the model giving the prior (predicted tensor, knowledge requirements) and the
        wheel axes and spin inertias.
    torque : include the constant inertial external torque ``T_N`` per file.
    robust : include the sensor and actuator nuisance parameters (gyro bias per file, gyro scale
        factor, wheel spin-inertia scales, wheel spin-axis tilts; priors from
        ``spacecraft.knowledge``; :mod:`cassini_bayes.inference.nuisance`). The default, as on
        the CLI: flight data always carry these errors. ``False`` is the papers' idealised model
        (for clean simulations and comparisons with the papers).
    wheel_errors : robust model's wheel spin-inertia errors: ``"per_wheel"`` (default, one scale
        per active wheel) or ``"common"`` (one scale for all wheels, the earlier model).
    settings : :class:`~cassini_bayes.inference.runner.SamplerSettings`.
    prior_draws : number of prior draws stored in the ``prior`` group.

    Returns
    -------
    InertiaPosterior
        ``idata`` with groups

        * ``posterior``: ``Ixx … Iyz`` (kg m²), ``H0`` (file, axis) N m s, ``T_N`` (file, axis)
          N m, ``sigma_omega``/``sigma_rho`` (file) rad/s, ``sigma_theta`` (file) rad, and the
          sampler's non-dimensional ``z``, ``noise_z``; when ``robust`` also ``gyro_bias``
          (file, axis) rad/s, ``gyro_scale`` (axis), ``wheel_scale`` (wheel; a scalar for the
          common model), ``wheel_tilt`` (wheel, tilt) rad;
        * ``sample_stats`` (NUTS), ``prior`` (same names, drawn from the stated prior);
        * ``observed_data``: ``omega`` (t, axis) rad/s, ``q`` (t, quat), ``h_wheels`` (t, axis)
          N m s (wheel momentum in body axes), ``file`` (t);
        * ``constant_data``: ``prior_mean``/``prior_sd`` (param) kg m², ``noise_hat`` (file,
          noise), ``laplace_mean``/``laplace_sd`` (param), ``information_ratio`` (direction);
        * ``residuals`` (custom group, for the report's residuals-vs-time plot): coordinate ``t``
          (s, the file's own clock; several files are concatenated in order and told apart by the
          coordinate ``file`` along ``t``), ``residual`` (t, axis) the posterior-mean momentum
          residual ``A(q_t)ᵀ(I ω_t + H_w,t) − H_0 − T_N (t − t_0)`` in inertial axes, N m s, and
          ``residual_std`` (t, axis) the body residual whitened by the noise covariance at the
          posterior mean (dimensionless, ~N(0, 1) when the noise model fits).

    Raises
    ------
    UnidentifiableError
        The slews do not excite the inertia at all.
    """
    from cassini_bayes.inference.progress import step
    from cassini_bayes.inference.runner import SamplerSettings, diagnostics, run_nuts

    settings = settings or SamplerSettings()
    with step("preparing: noise levels, least squares, whitening"):
        problem = prepare_inertia(telemetries, spacecraft, torque=torque, robust=robust,
                                  wheel_errors=wheel_errors)
    _warn_weak(problem)
    n_files = len(telemetries)
    data = problem.data
    coords, dims = _coords_dims(problem, n_files, wheel_errors)
    log_nh = np.asarray(data.log_noise)

    def prior(key_prior, n):
        return sample_prior(key_prior, problem.prior, n, n_files=n_files, torque=torque,
                            log_noise=log_nh, layout=problem.layout if robust else None)

    idata = run_nuts(key, problem_model(problem), model_kwargs={"data": data},
                     settings=settings, coords=coords, dims=dims, prior=prior,
                     prior_draws=prior_draws)

    r, std = _posterior_mean_residuals(problem, idata.posterior, torque, robust)
    replace_groups(idata, _data_groups(problem, r, std))
    names = (list(INERTIA_NAMES) + ["H0"] + (["T_N"] if torque else []) + ["noise_scale"]
             + (robust_sites(problem.layout) if robust else []))
    return InertiaPosterior(idata, diagnostics(idata, names), problem)


def _coords_dims(problem, n_files: int, wheel_errors: str):
    """The ArviZ coordinates and dimensions of the inertia posterior's sites: per file, axis,
    noise component, wheel and tilt."""
    coords = {"file": np.arange(n_files), "axis": list(AXES), "noise": list(NOISE_NAMES),
              "z_dim": np.arange(problem.data.centre.shape[0]), "noise_z_dim": np.arange(n_files),
              "wheel": list(problem.layout.wheels), "tilt": ["u1", "u2"]}
    dims = {"H0": ["file", "axis"], "T_N": ["file", "axis"], "z": ["z_dim"],
            "noise_z": ["noise_z_dim"], "noise_scale": ["file"],
            "gyro_bias": ["file", "axis"], "gyro_scale": ["axis"], "wheel_tilt": ["wheel", "tilt"],
            "T_body": ["file", "axis"], "T_N_rate": ["file", "axis"],
            **({"wheel_scale": ["wheel"]} if wheel_errors == "per_wheel" else {}),
            **{name: ["file"] for name in NOISE_NAMES}}
    return coords, dims


def _posterior_mean_residuals(problem, post, torque: bool, robust: bool):
    """The momentum residuals at the posterior mean (inertia, momenta, torques, noise levels and,
    for the robust model, the nuisance effects the data see)."""
    pi_mean = np.array([float(post[n].mean()) for n in INERTIA_NAMES])
    h0_mean = post["H0"].mean(("chain", "draw")).values
    tq_mean = post["T_N"].mean(("chain", "draw")).values if torque else np.zeros_like(h0_mean)
    sig_mean = np.stack([np.exp(np.log(post[n]).mean(("chain", "draw")).values)
                         for n in NOISE_NAMES], -1)
    nu_mean = None
    if robust:  # the residual is that of π̃ = π/(1 + c) and δ_k = (c_k − c)/(1 + c) (nuisance.py)
        nu_mean, scale = _seen_nuisance(problem.layout, post)
        pi_mean, h0_mean, tq_mean = pi_mean / scale, h0_mean / scale, tq_mean / scale
    return momentum_residuals(problem, pi_mean, h0_mean, tq_mean, sig_mean, nu_mean)
