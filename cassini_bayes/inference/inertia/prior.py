"""The inertia model's prior, stated in the physical parameters: the log-Cholesky
parameterisation that keeps every tensor physical, the prior of ``π`` (the spacecraft model's
knowledge as one sd), the priors of ``H_0``, ``T_N`` and the noise scale, and draws from them
(:mod:`cassini_bayes.inference.inertia`, "Prior").
"""

from __future__ import annotations

from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.errors import InputError
from cassini_bayes.inference.nuisance import split_nuisance
from cassini_bayes.names import INERTIA_NAMES, INERTIA_NOISE_NAMES
from cassini_bayes.physics.momentum import inertia_matrix, inertia_vector
from cassini_bayes.spacecraft import Spacecraft

__all__ = ["NOISE_PRIOR_LOG_SD", "NOISE_NAMES",
           "pi_from_cholesky_params", "cholesky_params_from_pi", "is_physical", "InertiaPrior",
           "inertia_prior", "sample_prior"]

NOISE_PRIOR_LOG_SD = 1.0      # sd of log σ around the data's own noise level σ̂
NOISE_NAMES = INERTIA_NOISE_NAMES


def pi_from_cholesky_params(lp):
    """``π = (Ixx, Iyy, Izz, Ixy, Ixz, Iyz)`` (kg m²) of log-Cholesky parameters of ``Σ``.

    ``lp = (log L00, log L11, log L22, L10, L20, L21)`` (L in √(kg m²)); ``Σ = L Lᵀ`` and
    ``I = tr(Σ) 1 − Σ``. Any real ``lp`` gives a positive-definite ``I`` obeying the triangle
    inequalities.
    """
    lp = jnp.asarray(lp)
    d = jnp.exp(lp[..., :3])
    o = jnp.zeros_like(lp[..., 0])
    l_mat = jnp.stack([jnp.stack([d[..., 0], o, o], -1),
                       jnp.stack([lp[..., 3], d[..., 1], o], -1),
                       jnp.stack([lp[..., 4], lp[..., 5], d[..., 2]], -1)], -2)
    sigma = l_mat @ jnp.swapaxes(l_mat, -1, -2)
    tr = jnp.trace(sigma, axis1=-2, axis2=-1)
    return inertia_vector(tr[..., None, None] * jnp.broadcast_to(jnp.eye(3), sigma.shape) - sigma)


# jitted once: called eagerly, each would compile a handful of one-operation XLA programs
# (a slice and a stack each) per shape, every process (docs/performance.md)
inertia_matrix_jit = jax.jit(inertia_matrix)
_inertia_vector = jax.jit(inertia_vector)


def cholesky_params_from_pi(pi) -> np.ndarray:
    """Inverse of :func:`pi_from_cholesky_params`; raises ``ValueError`` for a non-physical π."""
    i_m = np.asarray(inertia_matrix_jit(np.asarray(pi, float)))
    sigma = 0.5 * np.trace(i_m) * np.eye(3) - i_m
    l_mat = np.linalg.cholesky(sigma)  # LinAlgError (a ValueError) when not physical
    return np.array([np.log(l_mat[0, 0]), np.log(l_mat[1, 1]), np.log(l_mat[2, 2]),
                     l_mat[1, 0], l_mat[2, 0], l_mat[2, 1]])


def is_physical(pi) -> np.ndarray:
    """Whether each ``π`` (..., 6) is positive definite and obeys the triangle inequalities."""
    i_m = np.asarray(inertia_matrix_jit(np.asarray(pi, float)))
    sigma = 0.5 * np.trace(i_m, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) - i_m
    return np.linalg.eigvalsh(sigma)[..., 0] > 0


def log_jacobian(lp):
    """``log|det ∂π/∂lp|`` of :func:`pi_from_cholesky_params`, up to a constant.

    ``lp → L`` (exp of the diagonal) contributes ``Σ lp_ii``; ``L → Σ = L Lᵀ`` contributes
    ``2³ L00³ L11² L22``; ``Σ → I = tr(Σ) 1 − Σ`` is linear (constant). Total
    ``4 lp0 + 3 lp1 + 2 lp2`` (checked against ``jax.jacfwd`` in the tests).
    """
    return 4.0 * lp[0] + 3.0 * lp[1] + 2.0 * lp[2]


class InertiaPrior(NamedTuple):
    """The stated prior of the inertia model, from the spacecraft model.

    ``mean`` (6,) the predicted tensor (kg m²); ``sd`` (6,) its knowledge requirement as one
    standard deviation: ``moi_uncertainty × moment`` for Ixx, Iyy, Izz and ``poi_uncertainty``
    for Ixy, Ixz, Iyz (``π`` is truncated to physical tensors). ``h0_sd``: each file's inertial
    momentum ``H_0`` per axis, N m s, the wheels' momentum capacity
    (:attr:`~cassini_bayes.spacecraft.Spacecraft.momentum_capacity_nms`): the momentum a
    spacecraft under wheel control carries. ``torque_sd``: the external torque ``T_N`` per axis,
    N m, the model file's ``[torque_knowledge] sd_nm``.
    """

    mean: np.ndarray
    sd: np.ndarray
    h0_sd: float
    torque_sd: float

    @property
    def file_sd(self) -> np.ndarray:
        """(6,) prior sd of one file's ``(H_0, T_N)``: N m s, N m."""
        return np.r_[np.full(3, self.h0_sd), np.full(3, self.torque_sd)]


def inertia_prior(spacecraft: Spacecraft) -> InertiaPrior:
    """Prior of the inertia model from a spacecraft model (see :class:`InertiaPrior`)."""
    mean = np.asarray(_inertia_vector(np.asarray(spacecraft.inertia, float)), float)
    sd = np.concatenate([spacecraft.moi_uncertainty * mean[:3],
                         np.full(3, spacecraft.poi_uncertainty)])
    return InertiaPrior(mean, sd, spacecraft.momentum_capacity_nms,
                        spacecraft.knowledge.torque_sd_nm)


def _pi_normals(key_pi, r, n: int):
    """Standard normal draws (2n + 16, 6) of rejection round ``r`` of :func:`sample_prior`."""
    return jax.random.normal(jax.random.fold_in(key_pi, r), (2 * n + 16, 6))


@partial(jax.jit, static_argnums=(1, 2, 3, 4))
def _prior_normals(key, n: int, n_files: int, n_noise: int, n_nu: int) -> dict:
    """Every standard normal draw of :func:`sample_prior` in one XLA program (each drawn
    eagerly would be a program of its own): the first rejection round's, ``H0``'s, ``T_N``'s,
    the noise scales' (``n_noise`` files) and the nuisance's (``n_nu``), from the same keys as
    always, so the draws are the same."""
    key_pi, key_h, key_t, key_s = jax.random.split(key, 4)
    return {"key_pi": key_pi, "pi": _pi_normals(key_pi, 0, n),
            "H0": jax.random.normal(key_h, (n, n_files, 3)),
            "T_N": jax.random.normal(key_t, (n, n_files, 3)),
            "noise": jax.random.normal(key_s, (n, n_noise)),
            "nu": jax.random.normal(jax.random.fold_in(key_s, 1), (n, n_nu))}


_pi_normals_jit = jax.jit(_pi_normals, static_argnums=2)


def sample_prior(key, prior: InertiaPrior, n: int, *, n_files: int = 1, torque: bool = True,
                 log_noise=None, layout=None, max_rounds: int = 100) -> dict[str, np.ndarray]:
    """``n`` draws from the stated prior (module docstring), ``π`` by rejection of non-physical.

    Returns a dict: ``Ixx … Iyz`` (n,), ``H0`` (n, F, 3), ``T_N`` (n, F, 3) when ``torque``, and
    ``noise_scale`` and the noise levels (n, F) when ``log_noise`` (F, 3), the log of the
    empirical-Bayes levels ``σ*``, is given; with a robust ``layout``
    (:class:`~cassini_bayes.inference.nuisance.NuisanceLayout`) also ``gyro_bias`` (n, F, 3),
    ``gyro_scale`` (n, 3), ``wheel_scale`` (n, K) per wheel or (n,) common, ``wheel_tilt``
    (n, K, 2), ``T_body`` (n, F, 3) and, where the layout has them, ``wheel_scale_common`` (n,)
    and ``T_N_rate`` (n, F, 3) (:func:`~cassini_bayes.inference.nuisance.split_nuisance`).
    The same function gives the simulator and SBC their truth, so the model's prior and the
    truth's prior agree exactly.
    """
    n_files_noise = 0 if log_noise is None else np.shape(log_noise)[0]
    draws = _prior_normals(key, n, n_files, n_files_noise, 0 if layout is None else layout.size)
    kept = []
    total = 0
    for r in range(max_rounds):
        z = np.asarray(draws["pi"] if r == 0 else _pi_normals_jit(draws["key_pi"], r, n))
        pi = prior.mean + prior.sd * z
        pi = pi[is_physical(pi)]
        kept.append(pi)
        total += pi.shape[0]
        if total >= n:
            break
    else:
        raise InputError("the inertia prior puts almost no mass on physical tensors; check the "
                         "spacecraft model's inertia and its uncertainties")
    pi = np.concatenate(kept)[:n]
    out = {name: pi[:, i] for i, name in enumerate(INERTIA_NAMES)}
    out["H0"] = prior.h0_sd * np.asarray(draws["H0"])
    if torque:
        out["T_N"] = prior.torque_sd * np.asarray(draws["T_N"])
    if log_noise is not None:
        log_scale = NOISE_PRIOR_LOG_SD * np.asarray(draws["noise"])
        out["noise_scale"] = np.exp(log_scale)
        ls = np.asarray(log_noise) + log_scale[..., None]
        for i, name in enumerate(NOISE_NAMES):
            out[name] = np.exp(ls[..., i])
    if layout is not None:
        nu = layout.sd * np.asarray(draws["nu"])
        out.update(split_nuisance(nu, layout))
    return out
