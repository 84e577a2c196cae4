"""The inertia model's momentum balance (Feldman & Lee 2006 Eq 3) and its noise covariance
``B_t`` per sample, and the residuals at given parameters
(:mod:`cassini_bayes.inference.inertia`, "Model").
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.physics.momentum import inertia_matrix

if TYPE_CHECKING:
    from cassini_bayes.inference.inertia.data import InertiaProblem

__all__ = ["momentum_residuals", "noise_covariance"]

SYM_INDEX = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))


def _body_residual(pi, h0, tq, log_sigma, *, omega_t, h_wheels_t, a_t, dt, onehot, wheel_cov_t):
    """Body residual ``e_t`` as (3, N) N m s and ``B_t`` as its six components (6, N).

    Data layout (structure of arrays, sample index last): ``omega_t`` (3, N) rad/s,
    ``h_wheels_t`` (3, N) N m s, ``a_t`` (3, 3, N) the DCMs ``A(q_t)``, ``dt`` (N,) s since the
    file's first sample, ``onehot`` (F, N) file membership, ``wheel_cov_t`` (6, N) the components
    of ``Σ_k J_k² g_k g_kᵀ`` (kg² m⁴) of the file's active wheels.
    """
    i_m = inertia_matrix(pi)
    h_n = h0.T @ onehot + (tq.T @ onehot) * dt[None, :]             # (3, N) inertial
    h_m = (a_t[:, 0] * h_n[0][None] + a_t[:, 1] * h_n[1][None]
           + a_t[:, 2] * h_n[2][None])                              # (3, N) body
    e = i_m @ omega_t + h_wheels_t - h_m
    s2 = jnp.exp(2.0 * log_sigma).T @ onehot                        # (3, N)
    i2 = i_m @ i_m
    hh = jnp.sum(h_m * h_m, 0)
    b = [s2[0] * i2[i, j] + s2[1] * wheel_cov_t[k]
         + s2[2] * ((hh if i == j else 0.0) - h_m[i] * h_m[j])
         for k, (i, j) in enumerate(SYM_INDEX)]
    return e, b


def _matrix(b):
    """(N, 3, 3) symmetric matrices from their six components (6, N) in ``SYM_INDEX`` order."""
    return jnp.stack([jnp.stack([b[0], b[3], b[4]], -1), jnp.stack([b[3], b[1], b[5]], -1),
                      jnp.stack([b[4], b[5], b[2]], -1)], -2)


@jax.jit
def _residuals_jit(pi, h0, tq, log_sigma, data):
    e, b = _body_residual(pi, h0, tq, log_sigma, **data)
    a_t = data["a_t"]
    r = jnp.einsum("jin,jn->ni", a_t, e)  # inertial residual r_t = A_tᵀ e_t, (N, 3)
    std = jax.scipy.linalg.solve_triangular(jnp.linalg.cholesky(_matrix(b)), e.T[..., None],
                                            lower=True)
    return r, std[..., 0]


@jax.jit
def _covariance_jit(pi, h0, tq, log_sigma, data):
    return _matrix(_body_residual(pi, h0, tq, log_sigma, **data)[1])


def momentum_residuals(problem: InertiaProblem, pi, h0, tq, sigma,
                       nu=None) -> tuple[np.ndarray, np.ndarray]:
    """Momentum residuals at given parameters (e.g. posterior means).

    Returns ``r`` (N, 3) N m s, ``A(q_t)ᵀ(I ω_t + H_w,t) − H_0 − T_N (t − t_0)`` in inertial axes,
    and ``std`` (N, 3), the body residual whitened by the Cholesky factor of ``B_t``: ~N(0, 1) when
    the noise model fits. ``h0``, ``tq`` (F, 3); ``sigma`` (F, 3) the noise scales; ``nu`` (R,)
    the robust nuisance vector (robust problems only): its linear correction of the body momentum
    is included.
    """
    data = problem.residual_data
    if nu is not None and problem.robust_cols is not None:
        corr = np.einsum("nir,r->in", problem.robust_cols, np.asarray(nu, float))
        data = dict(data, h_wheels_t=data["h_wheels_t"] + jnp.asarray(corr))
    r, std = _residuals_jit(jnp.asarray(pi), jnp.asarray(h0), jnp.asarray(tq),
                            jnp.log(jnp.asarray(sigma)), data)
    return np.asarray(r), np.asarray(std)


def noise_covariance(problem: InertiaProblem, pi, h0, tq, sigma) -> np.ndarray:
    """``B_t`` (N, 3, 3), (N m s)², the covariance of the body residual ``e_t`` per sample at given
    parameters (module docstring of :mod:`cassini_bayes.inference.inertia`). At the GLS mode
    (``problem.data.theta_star``) and the empirical-Bayes levels (``problem.noise_eb``) it is the
    ``B̂_t`` that the idealised model's likelihood scales by ``s_f²``. Arguments as
    :func:`momentum_residuals`."""
    return np.asarray(_covariance_jit(jnp.asarray(pi), jnp.asarray(h0), jnp.asarray(tq),
                                      jnp.log(jnp.asarray(sigma)), problem.residual_data))
