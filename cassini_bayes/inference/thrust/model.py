"""The thrust model as a NumPyro model: the log density at the sampler's vector (events'
offsets and the robust nuisance integrated out), the nuisance's exact conditional draws, and the
model function per mode (:mod:`cassini_bayes.inference.thrust`).
"""

from __future__ import annotations

from functools import lru_cache

import jax
import jax.numpy as jnp
import numpyro
import numpyro.distributions as dist
from numpyro.distributions import constraints

from cassini_bayes.inference.gaussian import (OffsetMarginal, nuisance_log_marginal,
                                              nuisance_marginal)
from cassini_bayes.inference.thrust.coords import (Physical, n_tag, physical, tau_from_z,
                                                  unpack)
from cassini_bayes.inference.thrust.likelihood import event_loglik
from cassini_bayes.inference.thrust.prior import (NOISE_STEP, COM_NAMES, NOISE_PRIOR_LOG_SD,
                                                  thrust_names)
from cassini_bayes.names import INERTIA_NAMES, TAU_NAMES

__all__ = ["thrust_model", "thrust_sizes"]


def _event_stats(p: Physical, kw) -> OffsetMarginal:
    """:class:`OffsetMarginal` of every event (leading axis E) at the physical point ``p``."""
    return jax.vmap(event_loglik, in_axes=(None, None, None, 0, 0, None, None))(
        p.inertia, p.per_thruster, (p.tau[0], p.tau[1], p.tau[2]), p.log_sigma, kw.events,
        p.q_matrix, p.tag_scale)


def nuisance_sd(p: Physical, kw):
    """(R,) the robust nuisance's prior sds at the physical point ``p``: the time-tag walk's
    columns (``kw.tag_walk``) scaled with the time tags' sd."""
    if kw.tag_sd is None:
        return kw.nu_sd
    return kw.nu_sd * (1.0 + (p.tag_scale - 1.0) * kw.tag_walk)


def log_density(theta, kw, n_f: int, n_c: int, sample_inertia: bool):
    """Log prior + log likelihood at the non-dimensional vector ``theta`` (module docstring);
    the offsets and the robust model's nuisance ``ν`` are integrated out exactly. The thrust and
    centre-of-mass coordinates are ``N(0, 1)`` a priori (a rotation of the prior-whitened
    ``log F`` and offset keeps them so,
    :func:`~cassini_bayes.inference.thrust.coords.physical`); in impulse-bit coordinates
    (``kw.bit_width`` given) the prior is that of the physical point's whitened ``(log F, δ)``
    (the map has Jacobian 1)."""
    n_ev = kw.log_noise_hat.shape[0]
    f_z, com_z, tau_z, noise_z, inertia_z, tag_z = unpack(theta, n_f, n_c, n_ev,
                                                          sample_inertia, n_tag(kw))
    _, log_prior_tau = tau_from_z(tau_z, kw)
    p = physical(theta, kw, n_f, n_c, sample_inertia)
    prior_com = n_c > 0
    if kw.bit_width is not None:     # impulse-bit coordinates: the prior at the physical point
        f_z = p.whitened
        prior_com = False
    log_prior = (jnp.sum(dist.Normal(0.0, 1.0).log_prob(f_z)) + log_prior_tau
                 + jnp.sum(dist.Normal(0.0, NOISE_PRIOR_LOG_SD / NOISE_STEP).log_prob(noise_z)))
    if prior_com:
        log_prior += jnp.sum(dist.Normal(0.0, 1.0).log_prob(com_z))
    if sample_inertia:
        log_prior += jnp.sum(dist.Normal(0.0, 1.0).log_prob(inertia_z))
    log_prior += jnp.sum(dist.Normal(0.0, 1.0).log_prob(tag_z))
    st = _event_stats(p, kw)
    out = log_prior + jnp.sum(st.loglik)
    if kw.nu_sd.shape[0]:
        out += nuisance_log_marginal(jnp.sum(st.info, 0), jnp.sum(st.score, 0),
                                     nuisance_sd(p, kw))
    return jnp.where(jnp.isfinite(out), out, -jnp.inf)


@lru_cache(maxsize=None)
def nuisance_sampler(n_f: int, n_c: int, sample_inertia: bool):
    """Jitted ``(w (S, P), eps (S, R), kw) -> ν (S, R)``: a draw of ``ν`` from its exact Gaussian
    conditional given each draw of the sampled parameters (:func:`nuisance_marginal`), so that
    ``(θ, ν)`` are draws of the joint posterior. Batched to bound the memory (``n × 3 × R`` per
    draw)."""
    def one(args, kw):
        w, eps = args
        theta = kw.centre + kw.tril @ w
        p = physical(theta, kw, n_f, n_c, sample_inertia)
        st = _event_stats(p, kw)
        sd = nuisance_sd(p, kw)
        _, mean, chol = nuisance_marginal(jnp.sum(st.info, 0), jnp.sum(st.score, 0), sd)
        z = mean + jax.scipy.linalg.solve_triangular(chol.T, eps, lower=False)
        return sd * z

    @jax.jit
    def draws(w, eps, kw):
        return jax.lax.map(lambda a: one(a, kw), (w, eps), batch_size=32)

    return draws


@lru_cache(maxsize=None)
def laplace_density(n_f: int, n_c: int, sample_inertia: bool):
    """``f(θ, kw)`` for :func:`~cassini_bayes.inference.laplace.laplace`, one function object
    per layout so that its compiled derivatives are reused."""
    def f(theta, kw):
        return log_density(theta, kw, n_f, n_c, sample_inertia)

    return f


def thrust_sizes(mode: str, kw) -> tuple[int, int]:
    """``(n_f, n_c)``: the thrust parameters and centre-of-mass coordinates the sampler sees
    (static: from the mode and the number of thrusters, the columns of ``kw.q_matrix``)."""
    if mode == "thruster":
        return kw.q_matrix.shape[1], 3
    return len(thrust_names(mode)), 0


def _model(kw, *, mode: str, sample_inertia: bool):
    n_f, n_c = thrust_sizes(mode, kw)
    w = numpyro.sample("w", dist.ImproperUniform(constraints.real_vector, (), kw.centre.shape))
    theta = kw.centre + kw.tril @ w
    numpyro.factor("log_density", log_density(theta, kw, n_f, n_c, sample_inertia))
    p = physical(theta, kw, n_f, n_c, sample_inertia)
    if mode == "thruster":
        numpyro.deterministic("F", p.thrust)
        for i, name in enumerate(COM_NAMES):
            numpyro.deterministic(name, p.com[i])
    else:
        for i, name in enumerate(thrust_names(mode)):
            numpyro.deterministic(name, p.thrust[i])
    for i, name in enumerate(TAU_NAMES):
        numpyro.deterministic(name, p.tau[i])
    sig = jnp.exp(p.log_sigma)
    numpyro.deterministic("sigma_omega", sig[:, 0])
    numpyro.deterministic("sigma_rho", sig[:, 1])
    if kw.tag_sd is not None:
        numpyro.deterministic("time_tag_sd", kw.tag_sd[0] * p.tag_scale)
    if sample_inertia:
        for i, name in enumerate(INERTIA_NAMES):
            numpyro.deterministic(name, p.inertia[i])


@lru_cache(maxsize=None)
def thrust_model(mode: str, sample_inertia: bool = False):
    """The NumPyro model (one function object per mode, so compiled samplers are reused).

    Call it with ``data=ThrustProblem.data``. Posterior sites: the thrust names of the mode
    (N; mode ``"thruster"``: ``F`` along the spacecraft's thrusters and the centre-of-mass
    offset ``com_x``, ``com_y``, ``com_z``, m), ``tau_delay``, ``tau_rise``, ``tau_fall`` (s),
    ``sigma_omega``, ``sigma_rho`` (event) rad/s, ``time_tag_sd`` (s, the robust model with
    a stated time-tag sd), ``Ixx … Iyz`` (kg m²) when
    ``sample_inertia``, and the sampler's whitened ``w`` (the robust model's nuisance ``ν`` is
    integrated out; :func:`fit_thrust` adds its draws).
    """
    thrust_names(mode)    # an unknown mode is refused here

    def model(data):
        return _model(data, mode=mode, sample_inertia=sample_inertia)

    model.__name__ = f"thrust_model_{mode}_{'inertia' if sample_inertia else 'fixed'}"
    return model
