"""Inertia-tensor posterior from reaction-wheel slews (Feldman & Lee 2006 §IV, made Bayesian).

Model
-----
One or more slew telemetry files share the inertia tensor ``I``; file ``f`` has its own conserved
inertial momentum ``H_0,f`` (N m s) and, optionally, a constant inertial external torque
``T_N,f`` (N m, Feldman & Lee App. A). Per sample ``t`` of file ``f`` the momentum residual is

    r_t = A(q_t)ᵀ (I ω_t + H_w,t) − H_0,f − T_N,f (t − t_0,f)        (Feldman & Lee Eq 3)

and it is zero for noise-free data. The likelihood is written on the body-axis residual
``e_t = A(q_t) r_t = I ω_t + H_w,t − A(q_t) H_N,t`` (same Mahalanobis distance, ``A`` is a
rotation). Linearising the three measurement errors gives its covariance exactly:

    B_t = σ_ω² I I  +  σ_ρ² Σ_k J_k² g_k g_kᵀ  +  σ_θ² [h_t×][h_t×]ᵀ,    h_t = A(q_t) H_N,t

(``σ_ω`` rad/s white gyro noise per axis, ``σ_ρ`` rad/s white wheel-rate noise per wheel, ``σ_θ``
rad isotropic attitude error per axis: a body-frame error ``δθ`` turns ``A(q)ᵀ h`` into
``A(q)ᵀ (h + δθ × h)``). In inertial axes this is the ``Aᵀ(I Σ_ω I + …)A + [H_N×]σ_θ²[H_N×]ᵀ``.
Because the rate noise enters through ``I`` itself (errors in variables), the
likelihood stays calibrated when ω, ρ and q are all noisy, not only the paper's ``Γ``. The wheel
spin inertias ``J_k`` are known (Psiaki 2005: otherwise the scale of ``I`` is unidentified).

Robust model (``robust=True``; the CLI's default)
-------------------------------------------------
Flight telemetry carries errors the papers' model leaves out. The robust model adds, as nuisance
parameters with priors from the spacecraft model's ``[gyro]``/``[wheel_knowledge]`` sections
(:class:`~cassini_bayes.spacecraft.Knowledge`): a gyro bias per axis and file and a gyro
scale-factor error per axis (``ω_meas = (1 + s) ω + b + noise``), a spin-inertia scale
``c_k = c_s + d_k`` per active wheel, a part ``c_s`` shared by every wheel plus each wheel's own
``d_k`` (``wheel_errors="per_wheel"``, the default; ``"common"``: one scale ``c`` for all, the
earlier model), two small tilts of each active wheel's spin axis, a body-fixed torque and, with
``T_N``, the inertial torque's rate ``Ṫ_N`` (``−A(q_t) ½ (t − t_0)² Ṫ_N``: solar and RTG
torques change as the slews turn the sun line). All enter the residual linearly to first order
(:mod:`cassini_bayes.inference.nuisance`), so the sufficient-statistics likelihood below keeps
its O(P²) cost (P grows by 9F + 4 + 3K). The common scale ``c = c_s + mean_k d_k`` does not
enter the likelihood at all: scaling ``I``, ``H_0``, ``T_N`` and every wheel inertia together leaves every momentum balance unchanged (Psiaki 2005). Dividing the
balance by ``1 + c`` shows what the data see: ``π̃ = π/(1 + c)`` (likewise ``H_0``, ``T_N``) and
the wheel scales relative to the common one, ``δ_k = (c_k − c)/(1 + c)``, which enter linearly
(column ``J_k ρ_k g_k``) and are exact: ``(1 + c_k)/(1 + c) = 1 + δ_k``. The model sets
``π = (1 + c) π̃`` and ``c_k = c + (1 + c) δ_k``; ``c`` keeps its prior and the moments'
posterior sd carries it (prior sd ``√(σ_s² + σ_J²/K)``: 0.58 % for three wheels at the default
0.5 % shared and 0.5 % each; 0.5 % in the common model), while the ``δ_k`` are learned from
slews about several axes. The constant external torque ``T_N``
is in both models (``torque=True``), prior sd 15 µN m per axis (Feldman & Lee App. A bound;
Brown quotes solar/gas torques of the same few-µN m order).

Physical inertia by construction
--------------------------------
``Σ = ½ tr(I) 1 − I`` (the second-moment matrix of the mass distribution) is positive definite
exactly when ``I`` is a physically realisable inertia (positive definite *and* the triangle
inequalities ``I_1 + I_2 > I_3``: ``I_1 + I_2 − I_3 = 2 σ_3``). We parameterise ``Σ = L Lᵀ`` with a
Cholesky factor ``L`` (log-diagonal, so any real vector is valid) and set ``I = tr(Σ) 1 − Σ``.
Every draw is therefore physical.

Prior, stated in the physical parameters
----------------------------------------
* ``(Ixx … Iyz) ~ Normal(predicted, scale)`` truncated to physical tensors, with
  ``scale = moi_uncertainty × predicted moment`` for the moments and ``poi_uncertainty`` (kg m²)
  for the products: the spacecraft model's knowledge requirement (±10 %, ±75 kg m²) is taken as
  **one standard deviation**. Why one and not two or three: the requirement is a pre-launch
  design budget, not a measured error; Table 1 shows a flight product error (Post-PRM ``Ixz``,
  −102 kg m²) beyond ±75, which a 2σ or 3σ reading would call a 2.7σ/4σ event. A 1σ prior is
  still informative where the slews are not (Post-PRM ``Izz``) and negligible where they are.
* ``H_0 ~ Normal(0, 100 N m s)`` per axis: the four wheels hold at most 4 × 34 N m s (Brown §I).
* ``T_N ~ Normal(0, 15 µN m)`` per axis: Feldman & Lee App. A bound for March 2000.
* Noise: ``σ_j = s_f σ*_j`` (``j`` = ω, ρ, θ) with an unknown overall scale per file,
  ``log s_f ~ N(0, 1)``, and relative levels ``σ*`` fixed by empirical Bayes (below).

Noise levels and the fast likelihood
------------------------------------
``σ̂`` — the robust white-noise level of each signal (:func:`noise_levels`: MAD of second
differences ÷ √6) — starts an iterated generalised least squares (:func:`prepare_inertia`) that
alternates the posterior mode of ``θ = (π, H_0,f, T_N,f)`` with Fisher-scoring steps of
``log σ_f`` (prior ``N(log σ̂, 1)``) on the Gaussian likelihood above; the result ``σ*`` fixes
``B̂_t = B_t(σ*, I*, h*_t)`` at the mode. The likelihood sampled is then exactly Gaussian in the
residual with covariance ``s_f² B̂_t``, and since ``e_t`` is linear in ``θ`` its quadratic form
reduces to per-file sufficient statistics (a P×P matrix, a P-vector and a scalar, P = 6 + 6F):
each gradient costs O(P²) instead of O(N), which is what makes 4 × 1000 draws on 3600 samples
take about a second. What this gives up, and why that is acceptable: the dependence of ``B_t`` on
``I`` and ``H_N`` inside the sampler (relative changes of order the posterior sd of ``I``, ≤ 1e-3)
and the posterior uncertainty of the *relative* noise levels (the overall level ``s_f`` is
sampled; the tests check that the whitened residuals have unit variance and that the intervals
cover the truth).

Sampler coordinates
-------------------
The sampler does not see the physical parameters. It samples an unconstrained, non-dimensional
vector ``z`` (order one under the posterior, docs/design.md §7.4) mapped affinely to
``(log-Cholesky of Σ, H_0, T_N)`` around the Laplace approximation of the posterior (GLS mode and
covariance, pushed through the Jacobian of the Cholesky map), and ``noise_z`` = ``log s_f`` in
units of its posterior sd. The prior density is added in the physical space with
``numpyro.factor``, including ``log|det ∂π/∂lp|`` (closed form, checked against ``jax.jacfwd``), so
the posterior over ``π`` is exactly prior × likelihood whatever the centring: the centring only
conditions the geometry NUTS sees. ``z`` is given an improper flat density for that reason; prior
draws come from :func:`sample_prior` (rejection from the stated truncated Normal), which the
simulator and SBC can use to draw truth from the same prior.
"""

from __future__ import annotations

import warnings
from functools import lru_cache
from typing import NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np
import numpyro
import numpyro.distributions as dist
from numpyro.distributions import constraints

from cassini_bayes.errors import InputError, UnidentifiableError
from cassini_bayes.inference.nuisance import EFFECTS, split_nuisance
from cassini_bayes.frames import dcm, quat_conjugate, quat_continuous, quat_multiply, quat_to_rotvec
from cassini_bayes.physics.momentum import (INERTIA_NAMES, inertia_matrix, inertia_vector,
                                            regressor, wheel_momentum_body)
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import Telemetry

__all__ = [
    "H0_PRIOR_SD_NMS",
    "TORQUE_PRIOR_SD_NM",
    "NOISE_PRIOR_LOG_SD",
    "NOISE_NAMES",
    "InertiaPrior",
    "InertiaProblem",
    "inertia_prior",
    "pi_from_cholesky_params",
    "cholesky_params_from_pi",
    "is_physical",
    "noise_levels",
    "prepare_inertia",
    "problem_model",
    "robust_sites",
    "inertia_model",
    "sample_prior",
    "momentum_residuals",
    "InertiaPosterior",
    "fit_inertia",
    "ROBUST_SITES",
]

H0_PRIOR_SD_NMS = 100.0       # N m s per axis: 4 wheels × 34 N m s capacity (Brown §I)
TORQUE_PRIOR_SD_NM = 15e-6    # N m per axis: Feldman & Lee App. A, < 15 µN m (March 2000)
NOISE_PRIOR_LOG_SD = 1.0      # sd of log σ around the data's own noise level σ̂
NOISE_NAMES = ("sigma_omega", "sigma_rho", "sigma_theta")
MIN_RATE_SNR = 3.0            # rms body rate / its noise level below which a file is "still"
# Floors of σ̂ (rad/s, rad/s, rad): keep noise-free synthetic data finite.
_NOISE_FLOORS = np.array([1e-9, 1e-7, 1e-9])


# --------------------------------------------------------------------------------------------
# Cholesky parameterisation of a physical inertia
# --------------------------------------------------------------------------------------------

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


def cholesky_params_from_pi(pi) -> np.ndarray:
    """Inverse of :func:`pi_from_cholesky_params`; raises ``ValueError`` for a non-physical π."""
    i_m = np.asarray(inertia_matrix(np.asarray(pi, float)))
    sigma = 0.5 * np.trace(i_m) * np.eye(3) - i_m
    l_mat = np.linalg.cholesky(sigma)  # LinAlgError (a ValueError) when not physical
    return np.array([np.log(l_mat[0, 0]), np.log(l_mat[1, 1]), np.log(l_mat[2, 2]),
                     l_mat[1, 0], l_mat[2, 0], l_mat[2, 1]])


def is_physical(pi) -> np.ndarray:
    """Whether each ``π`` (..., 6) is positive definite and obeys the triangle inequalities."""
    i_m = np.asarray(inertia_matrix(np.asarray(pi, float)))
    sigma = 0.5 * np.trace(i_m, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) - i_m
    return np.linalg.eigvalsh(sigma)[..., 0] > 0


# --------------------------------------------------------------------------------------------
# Prior
# --------------------------------------------------------------------------------------------

class InertiaPrior(NamedTuple):
    """The stated prior on ``π`` (kg m²), before truncation to physical tensors.

    ``mean`` (6,) the spacecraft model's predicted tensor; ``sd`` (6,) its knowledge requirement
    as one standard deviation: ``moi_uncertainty × moment`` for Ixx, Iyy, Izz and
    ``poi_uncertainty`` for Ixy, Ixz, Iyz.
    """

    mean: np.ndarray
    sd: np.ndarray


def inertia_prior(spacecraft: Spacecraft) -> InertiaPrior:
    """Prior of the inertia entries from a spacecraft model (see the module docstring)."""
    mean = np.asarray(inertia_vector(spacecraft.inertia), float)
    sd = np.concatenate([spacecraft.moi_uncertainty * mean[:3],
                         np.full(3, spacecraft.poi_uncertainty)])
    return InertiaPrior(mean, sd)


# --------------------------------------------------------------------------------------------
# Data preparation
# --------------------------------------------------------------------------------------------

def _mad_sd(x: np.ndarray) -> float:
    x = x[np.isfinite(x)]
    if x.size == 0:
        return 0.0
    return float(1.4826 * np.median(np.abs(x - np.median(x))))


@jax.jit
def _file_arrays(q, omega, rates, axes, inertias):
    """One compiled pass over a file: DCMs, wheel momentum, regressor, attitude increments."""
    q = quat_continuous(q)
    a = dcm(q)
    h_w = wheel_momentum_body(rates, axes, inertias)
    inc = quat_to_rotvec(quat_multiply(q[1:], quat_conjugate(q[:-1])))
    return a, h_w, regressor(omega), inc


def _noise_from_arrays(omega, rates, inc) -> np.ndarray:
    def second_diff_sd(x):
        if x.shape[0] < 4 or x.size == 0:
            return 0.0
        return _mad_sd(np.diff(x, n=2, axis=0).ravel()) / np.sqrt(6.0)

    s_w = second_diff_sd(omega)
    s_r = second_diff_sd(rates)
    s_q = _mad_sd(np.diff(inc, axis=0).ravel()) / np.sqrt(6.0) if inc.shape[0] >= 3 else 0.0
    return np.maximum(np.array([s_w, s_r, s_q]), _NOISE_FLOORS)


def noise_levels(tel: Telemetry, spacecraft: Spacecraft) -> np.ndarray:
    """Robust white-noise levels ``(σ_ω rad/s, σ_ρ rad/s, σ_θ rad)`` of one telemetry file.

    For white noise of sd ``σ`` on a smooth signal, second differences have sd ``√6 σ``; the
    median absolute deviation ignores the few samples where the slew profile itself bends. The
    attitude uses second differences of the body-frame rotation increments
    ``rotvec(q_{t+1} q_t⁻¹)``. Each level is floored (1e-9 rad/s, 1e-7 rad/s, 1e-9 rad). On
    slews sampled slowly the wheel-rate level also picks up the wheels' own acceleration changes;
    it is only the centre of a wide prior.
    """
    rates, axes, js = _wheel_arrays(tel, spacecraft)
    _, _, _, inc = _file_arrays(jnp.asarray(tel.q, float), jnp.asarray(tel.omega, float),
                                jnp.asarray(rates), jnp.asarray(axes), jnp.asarray(js))
    return _noise_from_arrays(np.asarray(tel.omega, float), rates, np.asarray(inc))


class InertiaProblem(NamedTuple):
    """Everything the inertia model needs, prepared once from the data (SI units).

    ``model_kwargs`` are the arrays passed to :func:`inertia_model` (all samples of all files
    concatenated along one axis of length ``N``, sample index last; ``onehot`` (F, N) says which
    file a sample belongs to), so two problems with the same shapes reuse one compiled sampler.
    The other fields describe the data for the run directory and the report.

    Attributes
    ----------
    model_kwargs : dict of arrays for :func:`inertia_model`.
    torque : whether ``T_N`` is a parameter (selects the model function).
    prior : the stated prior of ``π``.
    t : (N,) sample times, s; ``file_idx`` (N,) int.
    omega : (N, 3) rad/s; ``h_wheels`` (N, 3) N m s body; ``q`` (N, 4) sign-continuous.
    sources : the telemetry file names, one per file.
    noise_hat : (F, 3) data noise levels σ̂ (rad/s, rad/s, rad), second-difference estimate.
    noise_eb : (F, 3) empirical-Bayes noise levels σ* (same units) fixing ``B̂_t``.
    residual_data : per-sample arrays (structure of arrays) for :func:`momentum_residuals`.
    laplace_mean, laplace_sd : Laplace approximation of the posterior of ``π`` (kg m²); robust:
        ``π = (1 + c) π̃`` with the wheel scale ``c`` at its prior (nuisance.py), to first order.
    information_ratio : (6,) eigenvalues of ``D F D`` (data information of π with H_0/T_N
        profiled, ``D`` the prior sd): < 1 means that direction is prior-dominated.
    weak_directions : human-readable list of prior-dominated parameter combinations.
    robust : whether the robust nuisance parameters ``ν`` are in the model.
    layout : :class:`~cassini_bayes.inference.nuisance.NuisanceLayout` of ``ν`` (always built).
    sensitivity : :class:`~cassini_bayes.inference.sensitivity.Sensitivity` of ``π`` to every
        effect, linearised at the mode.
    robust_cols : (N, 3, R) body columns of ``ν`` (robust only), to correct the residuals.
    """

    model_kwargs: dict
    torque: bool
    prior: InertiaPrior
    t: np.ndarray
    file_idx: np.ndarray
    omega: np.ndarray
    h_wheels: np.ndarray
    q: np.ndarray
    sources: tuple[str, ...]
    noise_hat: np.ndarray
    noise_eb: np.ndarray
    laplace_mean: np.ndarray
    laplace_sd: np.ndarray
    information_ratio: np.ndarray
    weak_directions: tuple[str, ...]
    residual_data: dict
    robust: bool = False
    layout: object = None
    sensitivity: object = None
    robust_cols: np.ndarray | None = None


def _wheel_arrays(tel: Telemetry, spacecraft: Spacecraft):
    """Rates (n, k) rad/s (NaN→0), axes (k, 3), inertias (k,) of the telemetry's active wheels."""
    names = tel.active_wheels()
    if not names:
        raise InputError("no wheel has any rate; an RWA slew needs the wheel rates rwa1..rwa4 "
                         "(rpm)",
                         path=tel.source)
    cols, axes, js = [], [], []
    for name in names:
        w = spacecraft.wheel(name)
        cols.append(np.nan_to_num(np.asarray(tel.wheel_rate(name), float)))
        axes.append(w.axis)
        js.append(w.inertia)
    return np.stack(cols, 1), np.stack(axes), np.asarray(js)


def _body_cov_terms(inertia: np.ndarray, wheel_cov: np.ndarray, h_body: np.ndarray):
    """The three (n, 3, 3) terms of ``B_t`` per unit variance.

    ``I I``, ``Σ_k J_k² g_k g_kᵀ`` and ``[h×][h×]ᵀ = |h|² 1 − h hᵀ``.
    """
    n = h_body.shape[0]
    k = (np.sum(h_body**2, -1)[:, None, None] * np.eye(3)
         - h_body[:, :, None] * h_body[:, None, :])
    return (np.broadcast_to(inertia @ inertia, (n, 3, 3)), np.broadcast_to(wheel_cov, (n, 3, 3)),
            k)


def prepare_inertia(telemetries: Sequence[Telemetry], spacecraft: Spacecraft, *,
                    torque: bool = True, robust: bool = False, wheel_errors: str = "per_wheel",
                    max_iter: int = 20) -> InertiaProblem:
    """Prepare the inertia problem: arrays, noise covariance, sufficient statistics, checks.

    Steps (all NumPy, O(N) once):

    1. per file: DCMs, wheel momentum, the regressor, the data noise levels ``σ̂``, and the
       columns of every effect the model may carry (``H_0``, ``T_N``, the robust nuisance
       parameters ``ν`` of :mod:`cassini_bayes.inference.nuisance`);
    2. iterated generalised least squares with empirical-Bayes noise levels: alternate the GLS
       posterior mode of ``θ = (π, H_0,f, T_N,f[, ν])`` (prior included) and a Fisher-scoring step
       of ``log σ_f`` (3 per file, prior ``N(log σ̂, 1)``) on the Gaussian likelihood with
       covariance ``B_t(σ, I, h_t)``, until the steps are < 1e-6 (the robust columns, linear in
       ``ν`` around the current mode ``I*``, are rebuilt each step);
    3. per file, the sufficient statistics of the quadratic form
       ``Q_f(θ) = Σ_t e_tᵀ B̂_t⁻¹ e_t`` around the mode ``θ*``: ``F_f``, ``g_f``, ``Q_f(θ*)``;
    4. the Laplace approximation (mode, covariance) that centres and whitens the sampler's
       coordinates, the identifiability check, and the linearised sensitivity of ``π`` to every
       effect (:func:`cassini_bayes.inference.sensitivity.linear_sensitivity`).

    ``robust`` adds the nuisance parameters ``ν`` (gyro bias per file, gyro scale factor, wheel
    spin-inertia scales per wheel and shared, wheel spin-axis tilts, body-fixed torque and, with
    ``torque``, the inertial torque's rate) with priors from ``spacecraft.knowledge``;
    ``wheel_errors`` (``"per_wheel"`` or ``"common"``) picks the wheel spin-inertia model
    (:func:`~cassini_bayes.inference.nuisance.nuisance_layout`).

    Raises
    ------
    UnidentifiableError
        The slews carry no information about any inertia entry (no rotation, or rotation too small
        against the noise): the data are less informative than the prior in every direction.
    InputError
        A telemetry file has too few samples or no wheel rates.
    """
    from cassini_bayes.inference.nuisance import nuisance_layout, robust_columns
    from cassini_bayes.inference.sensitivity import linear_sensitivity

    if not telemetries:
        raise InputError("no telemetry given; pass at least one slew file")
    prior = inertia_prior(spacecraft)
    n_files = len(telemetries)
    # Full parameter vector (every effect); the model uses the subset ``active``.
    #   [π (6), (H_0 (3), T_N (3)) per file, ν (R)]
    wheels_any = []
    for tel in telemetries:
        for name in tel.active_wheels():
            if spacecraft.wheel(name).name not in wheels_any:
                wheels_any.append(spacecraft.wheel(name).name)
    layout = nuisance_layout(spacecraft, n_files, wheels_any, wheel_errors=wheel_errors,
                             torque_rate=torque)
    p_base = 6 + 6 * n_files
    p_full = p_base + layout.size
    active = list(range(6))
    for f in range(n_files):
        active += list(range(6 + 6 * f, 6 + 6 * f + (6 if torque else 3)))
    if robust:
        active += list(range(p_base, p_full))
    active = np.asarray(active)
    p_tot = active.size

    files = []
    for f, tel in enumerate(telemetries):
        if tel.n < 10:
            raise InputError(f"only {tel.n} samples; an inertia fit needs a slew of many samples",
                             path=tel.source)
        rates, axes, js = _wheel_arrays(tel, spacecraft)
        q_in = np.asarray(tel.q, float)
        w = np.asarray(tel.omega, float)
        a, h_w, reg, inc = (np.asarray(x) for x in _file_arrays(
            jnp.asarray(q_in), jnp.asarray(w), jnp.asarray(rates), jnp.asarray(axes),
            jnp.asarray(js)))
        t = np.asarray(tel.t, float)
        dt = t - t[0]
        cols = np.zeros((tel.n, 3, p_full))  # e_t = cols_t θ − y_t (body axes)
        cols[:, :, :6] = reg
        j0 = 6 + 6 * f
        cols[:, :, j0:j0 + 3] = -a
        cols[:, :, j0 + 3:j0 + 6] = -a * dt[:, None, None]
        names = [spacecraft.wheel(n).name for n in tel.active_wheels()]
        files.append(dict(t=t, dt=dt, a=a, h_w=h_w, w=w, cols=cols, y=-h_w,
                          wheel_h={n: rates[:, k] * js[k] for k, n in enumerate(names)},
                          wcov=np.einsum("k,ki,kj->ij", js**2, axes, axes),
                          s_hat=_noise_from_arrays(w, rates, inc),
                          q=np.asarray(quat_continuous(jnp.asarray(q_in)))))

    def set_robust_columns(pi):
        i_star = np.asarray(inertia_matrix(pi if is_physical(pi) else prior.mean))
        for f, fd in enumerate(files):
            fd["cols"][:, :, p_base:] = robust_columns(layout, f, i_star, fd["w"], fd["h_w"],
                                                       fd["wheel_h"], fd["a"], fd["t"])

    set_robust_columns(prior.mean)
    # The common wheel spin-inertia scale c = ωᵀ w (w the wheel-scale block of θ) is not in the
    # likelihood: the data see only the momentum balance normalised by (1 + c), i.e. π/(1 + c),
    # H_0/(1 + c), T_N/(1 + c) and the relative scales δ = P w, P = 1 − 1 ωᵀ (module docstring),
    # so the fitted columns are cols @ fit_map with the wheel block projected by P (common model:
    # P = 0, the column dropped); the model maps π = (1 + c) π̃. (Keeping ``c H_w`` as a linear
    # column with a fixed noise covariance would let the fit shrink the noise term along the
    # unidentified scale and drag c many prior sd low.) The sensitivity keeps the full columns.
    w_index = p_base + np.arange(layout.size)[layout.wheel_block]
    scale_w = layout.scale_weights
    n_d = layout.n_scales                  # the per-wheel d_k; the shared c_s is seen as zero
    fit_map = np.eye(p_full)
    fit_map[np.ix_(w_index, w_index)] = 0.0
    d_index = w_index[:n_d]
    fit_map[np.ix_(d_index, d_index)] = np.eye(n_d) - np.full((n_d, n_d), 1.0 / n_d)

    def fitted(x):
        """The fitted columns ``x @ fit_map`` of (n, 3, p_full) columns ``x``."""
        return np.einsum("nip,pq->niq", x, fit_map, optimize=True)

    # Excitation: the body rates must rise above their own noise (errors in variables: a regressor
    # made of noise carries no information even though least squares would use it).
    snr = np.array([np.sqrt(np.mean(np.sum(fd["w"]**2, -1)) / (3 * fd["s_hat"][0]**2))
                    for fd in files])
    if snr.max() < MIN_RATE_SNR:
        src = ", ".join(t.source for t in telemetries)
        raise UnidentifiableError(
            f"{src}: the slews do not excite the inertia: the body rates are at their noise level "
            f"(rms/noise {snr.max():.2g} < {MIN_RATE_SNR:g}), so none of "
            f"{', '.join(INERTIA_NAMES)} is identified; give telemetry of RWA slews")
    for f in np.flatnonzero(snr < MIN_RATE_SNR):
        warnings.warn(f"{telemetries[f].source}: body rates at their noise level (rms/noise "
                      f"{snr[f]:.2g}); this file adds no information on the inertia", stacklevel=2)

    # Prior of the full vector (sd; a zero sd pins the effect at zero).
    full_sd = np.r_[prior.sd, np.tile(np.r_[np.full(3, H0_PRIOR_SD_NMS),
                                            np.full(3, TORQUE_PRIOR_SD_NM)], n_files), layout.sd]
    full_prec = 1.0 / np.maximum(full_sd, 1e-300)**2
    full_prec = np.minimum(full_prec, 1e30)
    full_mean = np.r_[prior.mean, np.zeros(p_full - 6)]
    prior_prec = full_prec[active]
    prior_mean = full_mean[active]
    log_s = np.log(np.stack([fd["s_hat"] for fd in files]))
    log_s_hat = log_s.copy()
    theta_full = full_mean.copy()

    def weights(f, th_full, ls):
        fd = files[f]
        i_m = np.asarray(inertia_matrix(th_full[:6] if is_physical(th_full[:6]) else prior.mean))
        j0 = 6 + 6 * f
        h_n = th_full[j0:j0 + 3] + np.outer(fd["dt"], th_full[j0 + 3:j0 + 6])
        h_body = np.einsum("nij,nj->ni", fd["a"], np.broadcast_to(h_n, fd["w"].shape))
        terms = _body_cov_terms(i_m, fd["wcov"], h_body)
        s2 = np.exp(2 * ls)
        b = sum(s2[j] * terms[j] for j in range(3))
        return np.linalg.inv(b), terms, b

    for it in range(max_iter):
        info = np.zeros((p_tot, p_tot))
        rhs = np.zeros(p_tot)
        for f, fd in enumerate(files):
            w_inv, _, _ = weights(f, theta_full, log_s[f])
            c = fitted(fd["cols"])[:, :, active]
            wc = np.einsum("nij,njq->niq", w_inv, c)
            info += np.einsum("nip,niq->pq", c, wc, optimize=True)
            rhs += np.einsum("niq,ni->q", wc, fd["y"], optimize=True)
        theta_full = full_mean.copy()
        theta_full[active] = np.linalg.solve(info + np.diag(prior_prec),
                                             rhs + prior_prec * prior_mean)
        if robust:
            set_robust_columns(theta_full[:6])
        max_step = 0.0
        for f, fd in enumerate(files):
            w_inv, terms, _ = weights(f, theta_full, log_s[f])
            e = np.einsum("nip,p->ni", fd["cols"], fit_map @ theta_full) - fd["y"]
            we = np.einsum("nij,nj->ni", w_inv, e)
            s2 = np.exp(2 * log_s[f])
            d = [2 * s2[j] * terms[j] for j in range(3)]
            wd = [np.einsum("nij,njk->nik", w_inv, dj) for dj in d]
            grad = np.array([0.5 * (np.einsum("ni,nij,nj->", we, d[j], we)
                                    - np.einsum("nii->", wd[j])) for j in range(3)])
            fisher = np.array([[0.5 * np.einsum("nij,nji->", wd[j], wd[k]) for k in range(3)]
                               for j in range(3)])
            grad -= (log_s[f] - log_s_hat[f]) / NOISE_PRIOR_LOG_SD**2
            fisher += np.eye(3) / NOISE_PRIOR_LOG_SD**2
            step = np.clip(np.linalg.solve(fisher, grad), -1.0, 1.0)
            log_s[f] += step
            max_step = max(max_step, float(np.abs(step).max()))
        if max_step < 1e-6:
            break
    theta = theta_full[active]
    set_robust_columns(theta[:6])  # the linearisation point I* at the mode (also for sensitivity)

    # Sufficient statistics at the mode, with the empirical-Bayes noise covariance B̂_t; the
    # information of the full vector (every effect) feeds the sensitivity analysis.
    info_full = np.zeros((p_full, p_full))
    fmat = np.zeros((n_files, p_tot, p_tot))
    gvec = np.zeros((n_files, p_tot))
    q_star = np.zeros(n_files)
    n_obs = np.zeros(n_files)
    for f, fd in enumerate(files):
        w_inv, _, _ = weights(f, theta_full, log_s[f])
        wc_full = np.einsum("nij,njq->niq", w_inv, fd["cols"])
        f_full = np.einsum("nip,niq->pq", fd["cols"], wc_full, optimize=True)
        info_full += f_full
        f_fit = fit_map.T @ f_full @ fit_map
        fmat[f] = f_fit[np.ix_(active, active)]
        e = np.einsum("nip,p->ni", fd["cols"], fit_map @ theta_full) - fd["y"]
        gvec[f] = np.einsum("niq,ni->q", fitted(wc_full)[:, :, active], e, optimize=True)
        q_star[f] = np.einsum("ni,nij,nj->", e, w_inv, e)
        n_obs[f] = 3 * e.shape[0]
    info = (fit_map.T @ info_full @ fit_map)[np.ix_(active, active)]
    nuis_prec = prior_prec[6:]

    # Data information of π with the nuisance (H_0, T_N, ν) profiled out under their priors.
    f_nn = info[6:, 6:] + np.diag(nuis_prec)
    f_pi = info[:6, :6] - info[:6, 6:] @ np.linalg.solve(f_nn, info[6:, :6])
    dmat = np.diag(prior.sd)
    ratio, vecs = np.linalg.eigh(dmat @ f_pi @ dmat)
    ratio = np.maximum(ratio, 0.0)
    weak = tuple(" + ".join(f"{v:+.2f} {INERTIA_NAMES[i]}" for i, v in enumerate(vec)
                            if abs(v) > 0.3)
                 for r, vec in zip(ratio, vecs.T) if r < 1.0)
    if ratio.max() < 1.0:
        src = ", ".join(t.source for t in telemetries)
        raise UnidentifiableError(
            f"{src}: the slews do not excite the inertia: the data inform none of "
            f"{', '.join(INERTIA_NAMES)} beyond the prior (largest information/prior ratio "
            f"{ratio.max():.2g}); give telemetry that rotates the spacecraft about its axes")

    # Laplace approximation (prior included) → affine whitening of the sampler's coordinates.
    cov = np.linalg.inv(info + np.diag(prior_prec))
    cov = 0.5 * (cov + cov.T)
    c_sd = 0.0  # Laplace sd of the common wheel scale c = ωᵀ w (robust; π = (1 + c) π̃)
    if robust:
        w_act = np.searchsorted(active, w_index)
        c_sd = float(np.sqrt(scale_w @ cov[np.ix_(w_act, w_act)] @ scale_w))
    pi_c = theta[:6] if is_physical(theta[:6]) else prior.mean
    lp_c = cholesky_params_from_pi(pi_c)
    jac = np.asarray(jax.jacfwd(pi_from_cholesky_params)(jnp.asarray(lp_c)))
    tmat = np.eye(p_tot)
    tmat[:6, :6] = np.linalg.inv(jac)
    cov_theta = tmat @ cov @ tmat.T
    tril = np.linalg.cholesky(0.5 * (cov_theta + cov_theta.T))
    centre = np.r_[lp_c, theta[6:]]

    groups = {"external_torque": np.concatenate([np.arange(9 + 6 * f, 12 + 6 * f)
                                                 for f in range(n_files)])}
    for name, sl in layout.slices.items():
        groups[name] = p_base + np.arange(p_full - p_base)[sl]
    sens = linear_sensitivity(info_full, full_prec, full_sd, active, groups)

    model_kwargs = dict(
        fmat=jnp.asarray(fmat), gvec=jnp.asarray(gvec), q_star=jnp.asarray(q_star),
        n_obs=jnp.asarray(n_obs), theta_star=jnp.asarray(theta),
        centre=jnp.asarray(centre), tril=jnp.asarray(tril),
        pi_mean=jnp.asarray(prior.mean), pi_sd=jnp.asarray(prior.sd),
        log_noise=jnp.asarray(log_s),
    )
    if robust:
        model_kwargs["nu_sd"] = jnp.asarray(layout.sd)
        model_kwargs["nu_weights"] = jnp.asarray(scale_w)
    onehot = np.concatenate([np.full(fd["t"].size, f) for f, fd in enumerate(files)])
    onehot = (onehot[None, :] == np.arange(n_files)[:, None]).astype(float)
    residual_data = dict(
        omega_t=jnp.asarray(np.concatenate([fd["w"] for fd in files]).T),
        h_wheels_t=jnp.asarray(np.concatenate([fd["h_w"] for fd in files]).T),
        a_t=jnp.asarray(np.ascontiguousarray(np.moveaxis(
            np.concatenate([fd["a"] for fd in files]), 0, -1))),
        dt=jnp.asarray(np.concatenate([fd["dt"] for fd in files])),
        onehot=jnp.asarray(onehot),
        wheel_cov_t=jnp.asarray(np.concatenate(
            [np.broadcast_to([fd["wcov"][i, j] for i, j in _SYM], (fd["t"].size, 6))
             for fd in files]).T.copy()))
    return InertiaProblem(
        model_kwargs=model_kwargs, torque=torque, prior=prior,
        t=np.concatenate([fd["t"] for fd in files]),
        file_idx=np.concatenate([np.full(fd["t"].size, f) for f, fd in enumerate(files)]),
        omega=np.concatenate([fd["w"] for fd in files]),
        h_wheels=np.concatenate([fd["h_w"] for fd in files]),
        q=np.concatenate([fd["q"] for fd in files]), sources=tuple(t.source for t in telemetries),
        noise_hat=np.exp(log_s_hat), noise_eb=np.exp(log_s), laplace_mean=theta[:6],
        laplace_sd=np.sqrt(np.diag(cov)[:6] + (theta[:6] * c_sd)**2),
        information_ratio=ratio, weak_directions=weak,
        residual_data=residual_data, robust=robust, layout=layout, sensitivity=sens,
        robust_cols=(np.concatenate([fd["cols"][:, :, p_base:] for fd in files])
                     if robust else None))


# --------------------------------------------------------------------------------------------
# Model
# --------------------------------------------------------------------------------------------

def _unpack(theta, n_files: int, torque: bool):
    lp = theta[:6]
    n_nuis = 6 if torque else 3
    nuis = theta[6:6 + n_nuis * n_files].reshape(n_files, n_nuis)
    h0 = nuis[:, :3]
    tq = nuis[:, 3:6] if torque else jnp.zeros_like(h0)
    return lp, h0, tq


_SYM = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))


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
         for k, (i, j) in enumerate(_SYM)]
    return e, b


def _log_jacobian(lp):
    """``log|det ∂π/∂lp|`` of :func:`pi_from_cholesky_params`, up to a constant.

    ``lp → L`` (exp of the diagonal) contributes ``Σ lp_ii``; ``L → Σ = L Lᵀ`` contributes
    ``2³ L00³ L11² L22``; ``Σ → I = tr(Σ) 1 − Σ`` is linear (constant). Total
    ``4 lp0 + 3 lp1 + 2 lp2`` (checked against ``jax.jacfwd`` in the tests).
    """
    return 4.0 * lp[0] + 3.0 * lp[1] + 2.0 * lp[2]


def _model(*, fmat, gvec, q_star, n_obs, theta_star, centre, tril, pi_mean, pi_sd, log_noise,
           torque: bool, per_wheel: bool = True, common: bool = False, n_torque_sets: int = 1,
           nu_sd=None, nu_weights=None):
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
    log_prior = (jnp.sum(dist.Normal(pi_mean, pi_sd).log_prob(pi)) + _log_jacobian(lp)
                 + jnp.sum(dist.Normal(0.0, H0_PRIOR_SD_NMS).log_prob(h0)))
    if torque:
        log_prior += jnp.sum(dist.Normal(0.0, TORQUE_PRIOR_SD_NM).log_prob(tq))
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

    Call it with ``**InertiaProblem.model_kwargs`` (per-file sufficient statistics, so its shapes
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
    def model(**kwargs):
        if not robust:
            kwargs.pop("nu_sd", None)
            kwargs.pop("nu_weights", None)
        return _model(torque=torque, per_wheel=wheel_errors == "per_wheel",
                      common=robust and common, n_torque_sets=1 + int(robust and torque_rate),
                      **kwargs)

    model.__name__ = (f"inertia_model_torque_{torque}_robust_{robust}_{wheel_errors}"
                      f"_common_{common}_rate_{torque_rate}")
    model.__doc__ = _model.__doc__
    return model


def problem_model(problem: "InertiaProblem"):
    """:func:`inertia_model` with the flags of a prepared ``problem``."""
    layout = problem.layout
    return inertia_model(problem.torque, problem.robust, layout.wheel_errors,
                         common=layout.has_common, torque_rate="torque_rate" in layout.slices)


# --------------------------------------------------------------------------------------------
# Prior draws and residuals
# --------------------------------------------------------------------------------------------

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
    key_pi, key_h, key_t, key_s = jax.random.split(key, 4)
    kept = []
    total = 0
    for r in range(max_rounds):
        z = np.asarray(jax.random.normal(jax.random.fold_in(key_pi, r), (2 * n + 16, 6)))
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
    out["H0"] = H0_PRIOR_SD_NMS * np.asarray(jax.random.normal(key_h, (n, n_files, 3)))
    if torque:
        out["T_N"] = TORQUE_PRIOR_SD_NM * np.asarray(jax.random.normal(key_t, (n, n_files, 3)))
    if log_noise is not None:
        log_scale = NOISE_PRIOR_LOG_SD * np.asarray(
            jax.random.normal(key_s, (n, np.shape(log_noise)[0])))
        out["noise_scale"] = np.exp(log_scale)
        ls = np.asarray(log_noise) + log_scale[..., None]
        for i, name in enumerate(NOISE_NAMES):
            out[name] = np.exp(ls[..., i])
    if layout is not None:
        nu = layout.sd * np.asarray(jax.random.normal(jax.random.fold_in(key_s, 1),
                                                      (n, layout.size)))
        out.update(split_nuisance(nu, layout))
    return out


@jax.jit
def _residuals_jit(pi, h0, tq, log_sigma, data):
    e, b = _body_residual(pi, h0, tq, log_sigma, **data)
    a_t = data["a_t"]
    r = jnp.einsum("jin,jn->ni", a_t, e)  # inertial residual r_t = A_tᵀ e_t, (N, 3)
    b_mat = jnp.stack([jnp.stack([b[0], b[3], b[4]], -1), jnp.stack([b[3], b[1], b[5]], -1),
                       jnp.stack([b[4], b[5], b[2]], -1)], -2)  # (N, 3, 3)
    std = jax.scipy.linalg.solve_triangular(jnp.linalg.cholesky(b_mat), e.T[..., None],
                                            lower=True)
    return r, std[..., 0]


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


def _warn_weak(problem: InertiaProblem) -> None:
    for w in problem.weak_directions:
        warnings.warn(f"weakly identified (prior-dominated): {w}", stacklevel=3)


# --------------------------------------------------------------------------------------------
# The fit
# --------------------------------------------------------------------------------------------

class InertiaPosterior(NamedTuple):
    """Result of :func:`fit_inertia`: the InferenceData, its diagnostics, the prepared problem."""

    idata: object
    diagnostics: object
    problem: InertiaProblem


AXES = ("x", "y", "z")
# Posterior sites of the robust nuisance vector ν (nuisance.py); a problem's own are
# :func:`robust_sites`.
ROBUST_SITES = tuple(site for effect, site in EFFECTS.items() if effect != "inertial_torque")


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
    import xarray as xr

    from cassini_bayes.inference.runner import SamplerSettings, diagnostics, run_nuts

    settings = settings or SamplerSettings()
    problem = prepare_inertia(telemetries, spacecraft, torque=torque, robust=robust,
                              wheel_errors=wheel_errors)
    _warn_weak(problem)
    n_files = len(telemetries)
    kw = problem.model_kwargs
    coords = {"file": np.arange(n_files), "axis": list(AXES), "noise": list(NOISE_NAMES),
              "z_dim": np.arange(kw["centre"].shape[0]), "noise_z_dim": np.arange(n_files),
              "wheel": list(problem.layout.wheels), "tilt": ["u1", "u2"]}
    dims = {"H0": ["file", "axis"], "T_N": ["file", "axis"], "z": ["z_dim"],
            "noise_z": ["noise_z_dim"], "noise_scale": ["file"],
            "gyro_bias": ["file", "axis"], "gyro_scale": ["axis"], "wheel_tilt": ["wheel", "tilt"],
            "T_body": ["file", "axis"], "T_N_rate": ["file", "axis"],
            **({"wheel_scale": ["wheel"]} if wheel_errors == "per_wheel" else {}),
            **{name: ["file"] for name in NOISE_NAMES}}
    log_nh = np.asarray(kw["log_noise"])

    def prior(key_prior, n):
        return sample_prior(key_prior, problem.prior, n, n_files=n_files, torque=torque,
                            log_noise=log_nh, layout=problem.layout if robust else None)

    idata = run_nuts(key, problem_model(problem), model_kwargs=kw,
                     settings=settings, coords=coords, dims=dims, prior=prior,
                     prior_draws=prior_draws)

    post = idata.posterior
    pi_mean = np.array([float(post[n].mean()) for n in INERTIA_NAMES])
    h0_mean = post["H0"].mean(("chain", "draw")).values
    tq_mean = post["T_N"].mean(("chain", "draw")).values if torque else np.zeros_like(h0_mean)
    sig_mean = np.stack([np.exp(np.log(post[n]).mean(("chain", "draw")).values)
                         for n in NOISE_NAMES], -1)
    nu_mean = None
    if robust:  # the residual is that of π̃ = π/(1 + c) and δ_k = (c_k − c)/(1 + c) (nuisance.py)
        nu_mean, scale = _seen_nuisance(problem.layout, post)
        pi_mean, h0_mean, tq_mean = pi_mean / scale, h0_mean / scale, tq_mean / scale
    r, std = momentum_residuals(problem, pi_mean, h0_mean, tq_mean, sig_mean, nu_mean)

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
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # "residuals" is not a standard group name
        for name in ("observed_data", "constant_data", "residuals"):
            if name in idata.groups():
                del idata[name]
        idata.add_groups({"observed_data": observed, "constant_data": constant,
                          "residuals": residuals})
    names = (list(INERTIA_NAMES) + ["H0"] + (["T_N"] if torque else []) + ["noise_scale"]
             + (robust_sites(problem.layout) if robust else []))
    return InertiaPosterior(idata, diagnostics(idata, names), problem)
