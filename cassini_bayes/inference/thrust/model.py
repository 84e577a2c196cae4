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
from cassini_bayes.inference.thrust.coords import _physical, _tau_from_z, _unpack
from cassini_bayes.inference.thrust.likelihood import _event_loglik
from cassini_bayes.inference.thrust.prior import _NOISE_STEP, NOISE_PRIOR_LOG_SD, thrust_names
from cassini_bayes.names import INERTIA_NAMES, TAU_NAMES

__all__ = ["thrust_model"]

def _event_stats(theta, kw, n_f: int, sample_inertia: bool) -> OffsetMarginal:
    """:class:`OffsetMarginal` of every event (leading axis E) at the sampler vector ``theta``."""
    _, f8, tau, log_sigma, pi = _physical(theta, kw, n_f, sample_inertia)
    return jax.vmap(_event_loglik, in_axes=(None, None, None, 0, 0, None))(
        pi, f8, (tau[0], tau[1], tau[2]), log_sigma, kw.events, kw.q_matrix)


def _log_density(theta, kw, n_f: int, sample_inertia: bool):
    """Log prior + log likelihood at the non-dimensional vector ``theta`` (module docstring);
    the offsets and the robust model's nuisance ``ν`` are integrated out exactly."""
    n_ev = kw.log_noise_hat.shape[0]
    f_z, tau_z, noise_z, inertia_z = _unpack(theta, n_f, n_ev, sample_inertia)
    _, log_prior_tau = _tau_from_z(tau_z, kw)
    log_prior = (jnp.sum(dist.Normal(0.0, 1.0).log_prob(f_z)) + log_prior_tau
                 + jnp.sum(dist.Normal(0.0, NOISE_PRIOR_LOG_SD / _NOISE_STEP).log_prob(noise_z)))
    if sample_inertia:
        log_prior += jnp.sum(dist.Normal(0.0, 1.0).log_prob(inertia_z))
    st = _event_stats(theta, kw, n_f, sample_inertia)
    out = log_prior + jnp.sum(st.loglik)
    if kw.nu_sd.shape[0]:
        out += nuisance_log_marginal(jnp.sum(st.info, 0), jnp.sum(st.score, 0), kw.nu_sd)
    return jnp.where(jnp.isfinite(out), out, -jnp.inf)


@lru_cache(maxsize=None)
def _nuisance_sampler(n_f: int, sample_inertia: bool):
    """Jitted ``(w (S, P), eps (S, R), kw) -> ν (S, R)``: a draw of ``ν`` from its exact Gaussian
    conditional given each draw of the sampled parameters (:func:`nuisance_marginal`), so that
    ``(θ, ν)`` are draws of the joint posterior. Batched to bound the memory (``n × 3 × R`` per
    draw)."""
    def one(args, kw):
        w, eps = args
        st = _event_stats(kw.centre + kw.tril @ w, kw, n_f, sample_inertia)
        _, mean, chol = nuisance_marginal(jnp.sum(st.info, 0), jnp.sum(st.score, 0), kw.nu_sd)
        z = mean + jax.scipy.linalg.solve_triangular(chol.T, eps, lower=False)
        return kw.nu_sd * z

    @jax.jit
    def draws(w, eps, kw):
        return jax.lax.map(lambda a: one(a, kw), (w, eps), batch_size=32)

    return draws


@lru_cache(maxsize=None)
def _laplace_density(n_f: int, sample_inertia: bool):
    """``f(θ, kw)`` for :func:`~cassini_bayes.inference.laplace.laplace`, one function object
    per layout so that its compiled derivatives are reused."""
    def f(theta, kw):
        return _log_density(theta, kw, n_f, sample_inertia)

    return f


def _model(kw, *, names: tuple[str, ...], sample_inertia: bool):
    w = numpyro.sample("w", dist.ImproperUniform(constraints.real_vector, (), kw.centre.shape))
    theta = kw.centre + kw.tril @ w
    numpyro.factor("log_density", _log_density(theta, kw, len(names), sample_inertia))
    thrust, _, tau, log_sigma, pi = _physical(theta, kw, len(names), sample_inertia)
    for i, name in enumerate(names):
        numpyro.deterministic(name, thrust[i])
    for i, name in enumerate(TAU_NAMES):
        numpyro.deterministic(name, tau[i])
    sig = jnp.exp(log_sigma)
    numpyro.deterministic("sigma_omega", sig[:, 0])
    numpyro.deterministic("sigma_rho", sig[:, 1])
    if sample_inertia:
        for i, name in enumerate(INERTIA_NAMES):
            numpyro.deterministic(name, pi[i])


@lru_cache(maxsize=None)
def thrust_model(mode: str, sample_inertia: bool = False):
    """The NumPyro model (one function object per mode, so compiled samplers are reused).

    Call it with ``data=ThrustProblem.data``. Posterior sites: the thrust names of the mode
    (N), ``tau_delay``, ``tau_rise``, ``tau_fall`` (s), ``sigma_omega``, ``sigma_rho`` (event)
    rad/s, ``Ixx … Iyz`` (kg m²) when ``sample_inertia``, and the sampler's whitened ``w``
    (the robust model's nuisance ``ν`` is integrated out; :func:`fit_thrust` adds its draws).
    """
    names = thrust_names(mode)

    def model(data):
        return _model(data, names=names, sample_inertia=sample_inertia)

    model.__name__ = f"thrust_model_{mode}_{'inertia' if sample_inertia else 'fixed'}"
    return model
