"""The inertia model as a NumPyro model: the sampler's coordinates, the prior in the physical
parameters and the likelihood from per-file sufficient statistics
(:mod:`cassini_bayes.inference.inertia`, "Sampler coordinates").
"""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING

import jax.numpy as jnp
import numpyro
import numpyro.distributions as dist
from numpyro.distributions import constraints

from cassini_bayes.inference.inertia.prior import (NOISE_NAMES, log_jacobian,
                                                   pi_from_cholesky_params)
from cassini_bayes.names import INERTIA_NAMES

if TYPE_CHECKING:
    from cassini_bayes.inference.inertia.data import InertiaData, InertiaProblem

__all__ = ["inertia_model", "problem_model"]


def _unpack(theta, n_files: int, torque: bool):
    lp = theta[:6]
    n_nuis = 6 if torque else 3
    nuis = theta[6:6 + n_nuis * n_files].reshape(n_files, n_nuis)
    h0 = nuis[:, :3]
    tq = nuis[:, 3:6] if torque else jnp.zeros_like(h0)
    return lp, h0, tq


def _model(data: InertiaData, *, torque: bool, per_wheel: bool = True, common: bool = False,
           n_torque_sets: int = 1):
    (fmat, gvec, q_star, n_obs, theta_star, centre, tril, pi_mean, pi_sd, file_sd, log_noise,
     nu_sd, nu_weights) = data
    n_files = log_noise.shape[0]
    p_tot = centre.shape[0]
    z = numpyro.sample("z", dist.ImproperUniform(constraints.real_vector, (), (p_tot,)))
    # Noise scale per file, log s ~ N(0, 1); sampled in units of its posterior sd ≈ 1/√(3N/2).
    u = numpyro.sample("noise_z", dist.Normal(0.0, jnp.sqrt(0.5 * n_obs)).to_event(1))
    log_scale = u / jnp.sqrt(0.5 * n_obs)
    theta = centre + tril @ z
    lp, h0_t, tq_t = _unpack(theta, n_files, torque)
    pi_t = pi_from_cholesky_params(lp)
    nu = theta[6 + (6 if torque else 3) * n_files:]
    # Robust model: the likelihood sees π̃ = π/(1 + c), H̃_0, T̃_N and the wheel scales relative
    # to the common c = ωᵀ w (module docstring; nuisance.py). The wheel block w holds the S
    # per-wheel d̃_k and, with ``common``, the shared c̃_s; c = mean_k d̃_k + c̃_s. Physically
    # d_k = m + (1 + c)(d̃_k − m), m = mean_k d̃_k, c_s = c̃_s, so c_k = d_k + c_s = c + (1 + c)
    # (d̃_k − m): the seen differences are (c_k − c)/(1 + c). Idealised: c = 0.
    n_block = 0 if nu_weights is None else nu_weights.shape[0]
    n_d = n_block - int(common)
    b0 = 3 * n_files + 3
    w_sc = nu[b0:b0 + n_block]
    c = nu_weights @ w_sc if nu_sd is not None else 0.0
    pi, h0, tq = (1.0 + c) * pi_t, (1.0 + c) * h0_t, (1.0 + c) * tq_t

    # Prior, in physical coordinates (module docstring); the affine part of z → θ has a constant
    # Jacobian, the log-Cholesky map's is added here, and (π̃, H̃_0, T̃_N) → (π, H_0, T_N) at
    # fixed c contributes (6 + 3F [+ 3F]) log(1 + c).
    log_prior = (jnp.sum(dist.Normal(pi_mean, pi_sd).log_prob(pi)) + log_jacobian(lp)
                 + jnp.sum(dist.Normal(0.0, file_sd[None, :3]).log_prob(h0)))
    if torque:
        log_prior += jnp.sum(dist.Normal(0.0, file_sd[None, 3:]).log_prob(tq))
    if nu_sd is not None:
        log_prior += (6 + (6 if torque else 3) * n_files) * jnp.log1p(c)
        # Robust nuisance ν ~ N(0, sd from the spacecraft model's knowledge); see nuisance.py.
        # The torques (body-fixed, and the inertial rate), like T_N, are (1 + c) times what the
        # likelihood sees; d̃ → d at fixed c and c̃_s has |∂d/∂d̃| = (1 + c)^(S−1).
        n_rest = 3 * n_files * n_torque_sets
        body = nu_sd.shape[0] - n_rest
        m = jnp.mean(w_sc[:n_d])
        d_phys = m + (1.0 + c) * (w_sc[:n_d] - m)
        nu_phys = jnp.concatenate([nu[:b0], d_phys, w_sc[n_d:], nu[b0 + n_block:body],
                                   (1.0 + c) * nu[body:]])
        log_prior += (jnp.sum(-0.5 * (nu_phys / nu_sd)**2)
                      + (n_rest + n_d - 1) * jnp.log1p(c))
        scales = d_phys + (w_sc[n_d] if common else 0.0)
        numpyro.deterministic("gyro_bias", nu[:3 * n_files].reshape(n_files, 3))
        numpyro.deterministic("gyro_scale", nu[3 * n_files:3 * n_files + 3])
        numpyro.deterministic("wheel_scale", scales if per_wheel else scales[0])
        if common:
            numpyro.deterministic("wheel_scale_common", w_sc[n_d])
        numpyro.deterministic("wheel_tilt", nu[b0 + n_block:body].reshape(-1, 2))
        torques = nu_phys[body:].reshape(n_torque_sets, n_files, 3)
        numpyro.deterministic("T_body", torques[0])
        if n_torque_sets > 1:
            numpyro.deterministic("T_N_rate", torques[1])
    numpyro.factor("prior", log_prior)

    for i, name in enumerate(INERTIA_NAMES):
        numpyro.deterministic(name, pi[i])
    numpyro.deterministic("H0", h0)
    if torque:
        numpyro.deterministic("T_N", tq)
    numpyro.deterministic("noise_scale", jnp.exp(log_scale))
    sig = jnp.exp(log_noise + log_scale[:, None])
    for i, name in enumerate(NOISE_NAMES):
        numpyro.deterministic(name, sig[:, i])

    # Likelihood from sufficient statistics: Σ_t e_tᵀ B̂_t⁻¹ e_t = δᵀFδ + 2gᵀδ + Q*, δ = θ − θ*.
    phys = jnp.concatenate([pi_t, _pack(h0_t, tq_t, torque), nu])
    delta = phys - theta_star
    quad = (jnp.einsum("p,fpq,q->f", delta, fmat, delta) + 2.0 * gvec @ delta + q_star)
    numpyro.factor("loglik", jnp.sum(-0.5 * quad * jnp.exp(-2.0 * log_scale)
                                     - n_obs * log_scale))


def _pack(h0, tq, torque: bool):
    return (jnp.concatenate([h0, tq], -1) if torque else h0).reshape(-1)


@lru_cache(maxsize=None)
def inertia_model(torque: bool, robust: bool = False, wheel_errors: str = "per_wheel",
                  common: bool = False, torque_rate: bool = False):
    """The NumPyro model function (one object per flag set, so compiled code is reused); the
    flags must match the problem's (:func:`problem_model` reads them from it).

    Call it with ``data=InertiaProblem.data`` (per-file sufficient statistics, so its shapes
    depend on the number of files, wheels and the flags only, not on the number of samples).
    Posterior sites: ``Ixx … Iyz`` (kg m²), ``H0`` (file, axis) N m s, ``T_N`` (file, axis) N m
    when ``torque``, ``noise_scale`` (file), ``sigma_omega``, ``sigma_rho`` (rad/s) and
    ``sigma_theta`` (rad) per file, and the sampler's ``z``, ``noise_z``; when ``robust`` also
    ``gyro_bias`` (file, axis) rad/s, ``gyro_scale`` (axis), ``wheel_scale`` (wheel) fractions
    (one per wheel; a scalar with ``wheel_errors="common"``, which must match the problem's),
    ``wheel_tilt`` (wheel, tilt) rad and ``T_body`` (file, axis) N m, a body-fixed external
    torque, with ``common`` the shared wheel scale ``wheel_scale_common`` and with
    ``torque_rate`` the inertial torque rate ``T_N_rate`` (file, axis) N m/s
    (:mod:`cassini_bayes.inference.nuisance`).
    """
    def model(data: InertiaData):
        if not robust:
            data = data._replace(nu_sd=None, nu_weights=None)
        return _model(data, torque=torque, per_wheel=wheel_errors == "per_wheel",
                      common=robust and common, n_torque_sets=1 + int(robust and torque_rate))

    model.__name__ = (f"inertia_model_torque_{torque}_robust_{robust}_{wheel_errors}"
                      f"_common_{common}_rate_{torque_rate}")
    model.__doc__ = _model.__doc__
    return model


def problem_model(problem: InertiaProblem):
    """:func:`inertia_model` with the flags of a prepared ``problem``."""
    layout = problem.layout
    return inertia_model(problem.torque, problem.robust, layout.wheel_errors,
                         common=layout.has_common, torque_rate="torque_rate" in layout.slices)
