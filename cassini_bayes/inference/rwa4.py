"""RWA4 spin-axis posterior on the sphere (Brown 2012 §III.B, §III.C, made Bayesian).

Model
-----
Both of Brown's methods rest on the conservation of the total inertial angular momentum between
quiet windows (no thruster firing). Per sample ``i`` of window group ``g`` (an "A"/"B" window
pair)

    A(q_i)ᵀ c_i = H_g,    c_i = I ω_i + Σ_known J_k ρ_k,i g_k + J_4 ρ_4,i u4      (Brown Eqs 1, 3)

(``A(q)`` inertial→body, Brown Eq 2; ``I`` kg m²; ``ρ`` rad/s; ``J`` kg m²). Brown averages each
window and solves the difference for ``u4``; so does the likelihood here (:func:`_loglik`): the
change of the window-mean inertial momentum is zero up to the noise of the means. A per-sample
likelihood (each sample's momentum equal to the pair's, ``H_g`` integrated out) was tried first:
on ``rwa4_rcs`` it preferred an inertia 55 % off the truth by 1460 log-units — the drift samples
carry inertia information that the simulator's dynamics do not match to the gyro-noise level — so
the window means, Brown's own information, are used.

* RCS method (Eq 1): one pair, "Time A" before and "Time B" after the RWA4 spin-up while the
  spacecraft drifts; RWA4 is the only wheel and ``I ω`` carries the balance, so the inertia matters.
* RWA method (Eq 3): one pair per slew pair (quiescent windows at two attitudes), RWA2 and RWA3
  known; ``I ω`` is small but kept.

Noise: linearising the gyro (``σ_ω``) and wheel-rate (``σ_ρ``) errors gives the body covariance
``B = σ_ω² I I + σ_ρ² Σ_k J_k² g_k g_kᵀ`` (``g_4 = u4``) per sample, rotated to inertial axes and
averaged over each window; the levels are fixed at the data's own white-noise estimates σ̂ (three
numbers per pair cannot estimate them; the sampler's three noise coordinates are prior-only).
A constant external torque (Brown: ≈ 3e-6 N m, i.e. < 0.1° over 30 minutes) is neglected.

Priors
------
* ``u4``: uniform on the sphere, or concentrated on the articulation cone (angle from +Z within
  ``Normal(54.7356°, 1°)``, any articulation angle): a factor
  ``−½ ((θ_z(u4) − 54.7356°)/1°)²``. 1° is the mechanical cant tolerance we assume; the 1/8 s
  articulation-command resolution (≈ 1.5°, Brown §I) moves the azimuth, not the cant.
* Inertia: the spacecraft model's predicted tensor with its knowledge requirements as 1σ (the
  prior of :mod:`cassini_bayes.inference.inertia`), or a Gaussian (an inertia run's posterior);
  sampled jointly, so the mass-property error is part of the posterior (Brown's Monte Carlo
  analysis, ≤ 1.5°, comes out of the posterior instead of being added afterwards). The inertia is
  parameterised through the Cholesky factor of its second-moment matrix (every draw physical).

Sphere parameterisation
-----------------------
Stan's ``unit_vector``: ``x ∈ R³`` with a rotation-invariant density, ``u4 = x/|x|``; any radial
density leaves ``u4`` uniform. We use ``p(x) ∝ exp(−½(|x| − R)²)`` with ``R = 1/σ̂_u``, ``σ̂_u``
(rad) the smallest angular sd of the likelihood at the least-squares axis (with the prior-mean
inertia), and sample ``y = x − R û_LS``. Then the radial and tangential sds of ``x`` are both of
order one (DESIGN.md §7 scaling pitfall) and the "funnel" of the plain construction (tangential
scale ∝ |x|) varies by only ±3/R. An antipodal mode would be separated from ``R û`` by the low
density near ``x = 0``; it can only matter when the data are uninformative, in which case
``R = 1``, the sampler moves freely over the sphere, and the wide cone radii say so.

Finally the sampler sees ``w`` with ``θ = centre + tril w`` (``θ`` = ``y``, the prior-whitened
log-Cholesky inertia coordinates and the log noise scales), ``centre``/``tril`` a Laplace
approximation (:func:`cassini_bayes.inference.laplace.laplace`): on the RCS method the data fix
``|I Δω| = J_4 |Δρ_4|`` far more tightly than the inertia prior, a direction NUTS would otherwise
have to find. The density is exact in ``θ``; the affine map only conditions the geometry.
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

from cassini_bayes.errors import InputError
from cassini_bayes.estimators.rwa4 import fit_axis_rcs, fit_axis_rwa
from cassini_bayes.frames import dcm, quat_conjugate, quat_continuous, quat_multiply, quat_to_rotvec
from cassini_bayes.inference.inertia import (cholesky_params_from_pi, inertia_prior,
                                             is_physical, pi_from_cholesky_params)
from cassini_bayes.inference.sphere import direction_summary
from cassini_bayes.inference.laplace import laplace
from cassini_bayes.inference.thrust import InertiaGaussian, rate_noise_levels
from cassini_bayes.physics.momentum import INERTIA_NAMES, inertia_matrix, regressor
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import RPM_TO_RAD_S, Telemetry

__all__ = [
    "U4_NAMES",
    "METHODS",
    "PRIORS",
    "CONE_ANGLE_DEG",
    "CONE_SD_DEG",
    "MIN_SPIN_CHANGE_RPM",
    "detect_windows",
    "Rwa4Problem",
    "prepare_rwa4",
    "rwa4_model",
    "sample_rwa4_prior",
    "Rwa4Posterior",
    "fit_rwa4",
]

U4_NAMES = ("u4_x", "u4_y", "u4_z")
METHODS = ("rcs", "rwa")
PRIORS = ("uniform", "cone")
CONE_ANGLE_DEG = float(np.degrees(np.arccos(1.0 / np.sqrt(3.0))))   # 54.7356°, Brown §I
CONE_SD_DEG = 1.0
MIN_SPIN_CHANGE_RPM = 10.0   # smaller RWA4 changes between A and B cannot calibrate the axis
NOISE_NAMES = ("sigma_omega", "sigma_rho", "sigma_theta")
NOISE_PRIOR_LOG_SD = 1.0
_NOISE_STEP = 0.1
_NOISE_FLOORS = np.array([1e-9, 1e-7, 1e-9])
_WHEEL = "RWA4"

Window = tuple[float, float]


# --------------------------------------------------------------------------------------------
# Windows
# --------------------------------------------------------------------------------------------

def _median_rpm(tel: Telemetry, w: Window) -> float:
    m = (tel.t >= w[0]) & (tel.t <= w[1])
    return float(np.nanmedian(np.asarray(tel.wheel_rate(_WHEEL), float)[m]) / RPM_TO_RAD_S)


def detect_windows(tel: Telemetry, method: str) -> list[tuple[Window, Window]]:
    """Time A / Time B window pairs from the quiet periods (:func:`cassini_bayes.windows.
    quiet_periods`).

    * RCS: the two consecutive quiet periods across the largest change of RWA4's median rate.
    * RWA: consecutive quiet periods paired in order, ``(Q0, Q1), (Q2, Q3), …`` — Brown's "Time A"
      before and "Time B" after the first slew of each slew pair.

    Raises
    ------
    InputError
        Fewer than two quiet periods; for RCS, no RWA4 spin change of ``MIN_SPIN_CHANGE_RPM``.
    """
    from cassini_bayes.windows import quiet_periods

    quiet = quiet_periods(tel)
    if len(quiet) < 2:
        raise InputError(f"found {len(quiet)} quiet period(s) (≥ 60 s, |ω| ≤ 1 mrad/s, wheels "
                         "steady, no thruster firing); the RWA4 calibration needs a Time A and a "
                         "Time B: give them with --window-a T0:T1 --window-b T0:T1",
                         path=tel.source)
    if method == "rcs":
        rpm = np.array([_median_rpm(tel, w) for w in quiet])
        jumps = np.abs(np.diff(rpm))
        k = int(np.nanargmax(jumps))
        if not jumps[k] >= MIN_SPIN_CHANGE_RPM:
            raise InputError(f"no RWA4 spin change between quiet periods (largest {jumps[k]:.3g} "
                             f"rpm < {MIN_SPIN_CHANGE_RPM:g} rpm); the RCS method needs RWA4 "
                             "spun up or down between Time A and Time B", path=tel.source)
        return [(quiet[k], quiet[k + 1])]
    return [(quiet[i], quiet[i + 1]) for i in range(0, len(quiet) - 1, 2)]


# --------------------------------------------------------------------------------------------
# Data preparation
# --------------------------------------------------------------------------------------------

class Rwa4Problem(NamedTuple):
    """Everything the RWA4 model needs, prepared once (SI units).

    Attributes
    ----------
    model_kwargs : arrays for :func:`rwa4_model`.
    method : ``"rcs"`` or ``"rwa"``; prior : ``"uniform"`` or ``"cone"``.
    pairs : the ``(Time A, Time B)`` windows (s) used, one pair per group.
    inertia : the Gaussian inertia prior (mean (6,), cov (6, 6), kg m²).
    inertia_source : ``"spacecraft"`` or ``"posterior"``.
    baseline : the least-squares axis (Brown Eq 1 or Eq 3 at the prior-mean inertia), (3,).
    radius : ``R`` of the sphere parameterisation (module docstring).
    sd_direction_deg : the likelihood's smallest angular sd at the baseline, deg.
    spin_change_rpm : change of RWA4's mean rate from A to B, per pair.
    noise_hat : (3,) σ̂ (rad/s, rad/s, rad).
    source : the telemetry file.
    """

    model_kwargs: dict
    method: str
    prior: str
    pairs: tuple[tuple[Window, Window], ...]
    inertia: InertiaGaussian
    inertia_source: str
    baseline: np.ndarray
    radius: float
    sd_direction_deg: float
    spin_change_rpm: np.ndarray
    noise_hat: np.ndarray
    source: str


def _attitude_noise(q: np.ndarray) -> float:
    if q.shape[0] < 4:
        return 0.0
    qc = np.asarray(quat_continuous(q))
    inc = np.asarray(quat_to_rotvec(quat_multiply(qc[1:], quat_conjugate(qc[:-1]))))
    d = np.diff(inc, axis=0).ravel()
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / np.sqrt(6.0))


def _inv3(b):
    """Inverse and log-determinant of batches (..., 3, 3) of symmetric positive-definite
    matrices, in closed form (LAPACK calls on 3×3 matrices cost far more than the arithmetic)."""
    c00 = b[..., 1, 1] * b[..., 2, 2] - b[..., 1, 2] * b[..., 1, 2]
    c11 = b[..., 0, 0] * b[..., 2, 2] - b[..., 0, 2] * b[..., 0, 2]
    c22 = b[..., 0, 0] * b[..., 1, 1] - b[..., 0, 1] * b[..., 0, 1]
    c01 = b[..., 0, 2] * b[..., 1, 2] - b[..., 0, 1] * b[..., 2, 2]
    c02 = b[..., 0, 1] * b[..., 1, 2] - b[..., 0, 2] * b[..., 1, 1]
    c12 = b[..., 0, 1] * b[..., 0, 2] - b[..., 0, 0] * b[..., 1, 2]
    det = b[..., 0, 0] * c00 + b[..., 0, 1] * c01 + b[..., 0, 2] * c02
    adj = jnp.stack([jnp.stack([c00, c01, c02], -1), jnp.stack([c01, c11, c12], -1),
                     jnp.stack([c02, c12, c22], -1)], -2)
    return adj / det[..., None, None], jnp.log(det)


def _loglik(u, pi, log_sigma, *, m_pi, r_u, k_h, n_w, t_aa, j4, known_cov):
    """Log-likelihood of the window-mean momentum balance of each A/B pair (Brown Eqs 1, 3):

    ``d_g = ⟨Aᵀ(I ω + h_known + J_4 ρ_4 u4)⟩_B − ⟨…⟩_A ~ N(0, C_A/n_A + C_B/n_B)``,
    ``C_w = ⟨A_iᵀ B A_i⟩_w``, ``B = σ_ω² I I + σ_ρ² (Σ_known J_k² g_k g_kᵀ + J_4² u4 u4ᵀ)``.
    Window arrays (index ``w = 2g`` for A, ``2g + 1`` for B): ``m_pi`` (W, 3, 6) with
    ``⟨Aᵀ I ω⟩ = m_pi π``; ``r_u`` (W, 3, 3) = ``⟨ρ_4 Aᵀ⟩``; ``k_h`` (W, 3) = ``⟨Aᵀ h_known⟩``;
    ``n_w`` (W,) sample counts; ``t_aa`` (W, 3, 3, 3, 3) = ``⟨A_jk A_lm⟩``.
    """
    i_m = inertia_matrix(pi)
    h = m_pi @ pi + j4 * r_u @ u + k_h                                  # (W, 3) inertial means
    d = h[1::2] - h[0::2]                                               # B − A per pair
    s2 = jnp.exp(2.0 * log_sigma)
    b = s2[0] * (i_m @ i_m) + s2[1] * (known_cov + j4**2 * jnp.outer(u, u))
    c_w = jnp.einsum("wjakb,jk->wab", t_aa, b) / n_w[:, None, None]
    cov = c_w[1::2] + c_w[0::2]
    cov_inv, logdet = _inv3(cov)
    quad = jnp.einsum("gi,gij,gj->g", d, cov_inv, d)
    return -0.5 * jnp.sum(quad + logdet + 3.0 * jnp.log(2.0 * jnp.pi))


def _tangent_basis(u: np.ndarray) -> np.ndarray:
    e = np.eye(3)[int(np.argmin(np.abs(u)))]
    e1 = np.cross(u, e)
    e1 /= np.linalg.norm(e1)
    return np.stack([e1, np.cross(u, e1)])


def prepare_rwa4(tel: Telemetry, spacecraft: Spacecraft, *, method: str = "rcs",
                 pairs: Sequence[tuple[Window, Window]] | None = None, prior: str = "uniform",
                 inertia: InertiaGaussian | None = None) -> Rwa4Problem:
    """Prepare the RWA4 problem from one telemetry file and its window pairs.

    Parameters
    ----------
    tel : telemetry with RWA4 running (and, for the RWA method, RWA2/RWA3).
    spacecraft : wheel axes/inertias (the RWA4 axis in the model is ignored) and inertia prior.
    method : ``"rcs"`` (Brown Eq 1) or ``"rwa"`` (Brown Eq 3).
    pairs : ``[(A, B), …]`` windows in s; detected (:func:`detect_windows`) when ``None``.
    prior : ``"uniform"`` or ``"cone"``.
    inertia : Gaussian inertia prior; default the spacecraft model's knowledge requirements.

    Raises
    ------
    InputError
        Unknown method/prior, no RWA4 rates, windows outside the data or overlapping, thrusters
        firing inside a window, no RWA4 spin change (RCS), data that cannot determine the axis.
    """
    if method not in METHODS:
        raise InputError(f"--method {method!r}: choose one of {', '.join(METHODS)}")
    if prior not in PRIORS:
        raise InputError(f"--prior {prior!r}: choose one of {', '.join(PRIORS)}")
    if _WHEEL not in tel.wheel_names or _WHEEL not in tel.active_wheels():
        raise InputError("no RWA4 rates (column rwa4, rpm); the RWA4 calibration needs RWA4 "
                         "running", path=tel.source)
    pairs = detect_windows(tel, method) if pairs is None else [tuple(p) for p in pairs]
    if not pairs:
        raise InputError("no window pair; give --window-a T0:T1 --window-b T0:T1",
                         path=tel.source)
    if method == "rcs" and len(pairs) != 1:
        raise InputError(f"the RCS method takes one Time A / Time B pair, got {len(pairs)}",
                         path=tel.source)
    t = np.asarray(tel.t, float)
    windows = [w for p in pairs for w in p]
    for w in windows:
        if w[0] < t[0] or w[1] > t[-1]:
            raise InputError(f"window {w[0]:.10g}:{w[1]:.10g} s lies outside the data "
                             f"({t[0]:.10g} to {t[-1]:.10g} s); choose windows inside it",
                             path=tel.source)
        if np.count_nonzero((t >= w[0]) & (t <= w[1])) < 2:
            raise InputError(f"window {w[0]:.10g}:{w[1]:.10g} s holds fewer than two samples; "
                             "widen it", path=tel.source)
    ws = sorted(windows)
    for a, b in zip(ws[:-1], ws[1:]):
        if b[0] <= a[1]:
            raise InputError(f"windows {a[0]:.10g}:{a[1]:.10g} and {b[0]:.10g}:{b[1]:.10g} s "
                             "overlap; each sample may belong to one window only",
                             path=tel.source)
    if tel.on_times is not None:
        for w in windows:
            m = (t >= w[0]) & (t <= w[1])
            if np.any(np.diff(tel.on_times[m], axis=0) > 0):
                raise InputError(f"thrusters fire inside window {w[0]:.10g}:{w[1]:.10g} s; "
                                 "momentum is not conserved there: choose a quiet window",
                                 path=tel.source)

    names = tel.wheel_names
    k4 = names.index(_WHEEL)
    rates = np.asarray(tel.wheel_rates, float)
    axes = np.stack([spacecraft.wheel(n).axis for n in names])
    js = np.array([spacecraft.wheel(n).inertia for n in names])
    active = np.any(np.isfinite(rates), axis=0)
    known = [k for k in range(len(names)) if k != k4 and active[k]]
    masks = [((t >= a[0]) & (t <= a[1]), (t >= b[0]) & (t <= b[1])) for a, b in pairs]
    rho4 = np.nan_to_num(rates[:, k4])
    spin = np.array([(rho4[mb].mean() - rho4[ma].mean()) / RPM_TO_RAD_S for ma, mb in masks])
    if method == "rcs" and abs(spin[0]) < MIN_SPIN_CHANGE_RPM:
        raise InputError(f"RWA4 changes by {spin[0]:.3g} rpm between Time A and Time B "
                         f"(< {MIN_SPIN_CHANGE_RPM:g} rpm): no spin change to calibrate from",
                         path=tel.source)

    if inertia is None:
        ip = inertia_prior(spacecraft)
        inertia, i_src = InertiaGaussian(ip.mean, np.diag(ip.sd**2)), "spacecraft"
    else:
        i_src = "posterior"
    i_mean = np.asarray(inertia.mean, float)
    if not is_physical(i_mean):
        raise InputError("the inertia prior mean is not a physical inertia tensor")
    i_pred = np.asarray(inertia_matrix(i_mean))

    # Least-squares baseline (Brown Eq 1 / Eq 3), also the sampler's centre.
    q = np.asarray(quat_continuous(np.asarray(tel.q, float)))
    omega = np.asarray(tel.omega, float)
    if method == "rcs":
        fit = fit_axis_rcs(q, omega, rates, axes, js, i_pred, masks[0][0], masks[0][1],
                           unknown=k4)
    else:
        fit = fit_axis_rwa(q, omega, rates, axes, js, masks, unknown=k4, inertia=i_pred)
    u_ls = np.asarray(fit.axis, float)

    known_cov = sum((js[k]**2 * np.outer(axes[k], axes[k]) for k in known), np.zeros((3, 3)))
    # noise levels from the window samples only (quiet: the robust estimate is cleanest there)
    s_w, s_r = [], []
    for w in windows:
        part = tel.slice(*w)
        s_w.append(rate_noise_levels(part)[0])
        s_r.append(rate_noise_levels(part)[1])
    s_q = max(np.median([_attitude_noise(q[(t >= w[0]) & (t <= w[1])]) for w in windows]), 0.0)
    noise = np.maximum(np.array([np.median(s_w), np.median(s_r), s_q]), _NOISE_FLOORS)

    a_all = np.asarray(dcm(jnp.asarray(q)))
    h_known_all = ((np.nan_to_num(rates[:, known]) * js[known]) @ axes[known] if known
                   else np.zeros((t.shape[0], 3)))
    reg = np.asarray(regressor(jnp.asarray(omega)))
    m_pi, r_u, k_h, n_w, t_aa = [], [], [], [], []
    for ma, mb in masks:
        for m in (ma, mb):
            at = np.swapaxes(a_all[m], -1, -2)                          # body → inertial
            m_pi.append(np.einsum("nij,njk->ik", at, reg[m]) / m.sum())
            r_u.append(np.einsum("n,nij->ij", rho4[m], at) / m.sum())
            k_h.append(np.einsum("nij,nj->i", at, h_known_all[m]) / m.sum())
            n_w.append(float(m.sum()))
            t_aa.append(np.einsum("nja,nkb->jakb", a_all[m], a_all[m]) / m.sum())
    data = dict(m_pi=jnp.asarray(np.stack(m_pi)), r_u=jnp.asarray(np.stack(r_u)),
                k_h=jnp.asarray(np.stack(k_h)), n_w=jnp.asarray(np.array(n_w)),
                t_aa=jnp.asarray(np.stack(t_aa)), j4=jnp.asarray(js[k4]),
                known_cov=jnp.asarray(known_cov))

    # Angular resolution of the likelihood at the baseline (prior-mean inertia, σ̂).
    basis = _tangent_basis(u_ls)

    def ll_tangent(v):
        u = jnp.asarray(u_ls) + v @ jnp.asarray(basis)
        return _loglik(u / jnp.linalg.norm(u), jnp.asarray(i_mean), jnp.log(jnp.asarray(noise)),
                       **data)

    info = -np.asarray(jax.jit(jax.hessian(ll_tangent))(jnp.zeros(2)))
    eig = np.linalg.eigvalsh(0.5 * (info + info.T))
    sd_min = 1.0 / np.sqrt(eig.max()) if eig.max() > 0 else np.inf
    radius = float(np.clip(1.0 / sd_min, 1.0, 1e5)) if np.isfinite(sd_min) else 1.0

    # Inertia coordinates: log-Cholesky around the prior mean, whitened by the prior covariance.
    lp_c = cholesky_params_from_pi(i_mean)
    jac = np.asarray(jax.jacfwd(pi_from_cholesky_params)(jnp.asarray(lp_c)))
    jinv = np.linalg.inv(jac)
    cov_lp = jinv @ np.asarray(inertia.cov) @ jinv.T
    tril = np.linalg.cholesky(0.5 * (cov_lp + cov_lp.T))
    prec_chol = np.linalg.cholesky(np.linalg.inv(np.asarray(inertia.cov)))

    kw = dict(data, x0=jnp.asarray(radius * u_ls), radius=jnp.asarray(radius),
              lp_centre=jnp.asarray(lp_c), lp_tril=jnp.asarray(tril),
              pi_mean=jnp.asarray(i_mean), pi_prec_chol=jnp.asarray(prec_chol),
              log_noise_hat=jnp.asarray(np.log(noise)),
              cone_angle=jnp.asarray(np.radians(CONE_ANGLE_DEG)),
              cone_sd=jnp.asarray(np.radians(CONE_SD_DEG)))
    centre, tril_w = laplace(lambda th: _log_density(th, kw, prior == "cone"), np.zeros(12))
    kw["centre"], kw["tril"] = jnp.asarray(centre), jnp.asarray(tril_w)
    return Rwa4Problem(
        model_kwargs=kw, method=method, prior=prior, pairs=tuple(pairs), inertia=inertia,
        inertia_source=i_src, baseline=u_ls, radius=radius,
        sd_direction_deg=float(np.degrees(sd_min)), spin_change_rpm=spin, noise_hat=noise,
        source=tel.source)


# --------------------------------------------------------------------------------------------
# Model
# --------------------------------------------------------------------------------------------

def _physical(theta, kw):
    """``u4`` (3,), ``π`` (6,) kg m², ``log σ`` (3,), ``|x|`` and ``log|∂π/∂lp|`` of the vector
    ``θ = (y (3), inertia_z (6), noise_z (3))``."""
    x = kw["x0"] + theta[:3]
    r = jnp.linalg.norm(x)
    lp = kw["lp_centre"] + kw["lp_tril"] @ theta[3:9]
    pi = pi_from_cholesky_params(lp)
    # log|det ∂π/∂lp| up to a constant: exp of the diagonal gives Σ lp_ii, L → L Lᵀ gives
    # 2³ L00³ L11² L22, Σ → I = tr(Σ) 1 − Σ is linear
    logdet = 4.0 * lp[0] + 3.0 * lp[1] + 2.0 * lp[2]
    # noise scales fixed at the data's σ̂: three numbers per window pair cannot estimate them
    return x / r, pi, kw["log_noise_hat"], r, logdet


def _log_density(theta, kw, cone: bool):
    """Log prior + log likelihood at ``θ`` (module docstring)."""
    u, pi, log_sigma, r, logdet = _physical(theta, kw)
    # u4 = x/|x| with a rotation-invariant density of x: uniform u4 (module docstring)
    log_prior = -0.5 * (r - kw["radius"]) ** 2
    if cone:
        angle = jnp.arccos(jnp.clip(u[2], -1.0, 1.0))
        log_prior += -0.5 * ((angle - kw["cone_angle"]) / kw["cone_sd"]) ** 2
    # Gaussian prior of π (physical by construction), Jacobian of the Cholesky map
    w = kw["pi_prec_chol"].T @ (pi - kw["pi_mean"])
    log_prior += -0.5 * jnp.sum(w**2) + logdet
    log_prior += jnp.sum(dist.Normal(0.0, NOISE_PRIOR_LOG_SD / _NOISE_STEP)
                         .log_prob(theta[9:12]))
    data = {k: kw[k] for k in _DATA_KEYS}
    return log_prior + _loglik(u, pi, log_sigma, **data)


_DATA_KEYS = ("m_pi", "r_u", "k_h", "n_w", "t_aa", "j4", "known_cov")


def _model(*, centre, tril, cone: bool, **kw):
    w = numpyro.sample("w", dist.ImproperUniform(constraints.real_vector, (), centre.shape))
    theta = centre + tril @ w
    numpyro.factor("log_density", _log_density(theta, kw, cone))
    u, pi, log_sigma, _, _ = _physical(theta, kw)
    for i, name in enumerate(U4_NAMES):
        numpyro.deterministic(name, u[i])
    for i, name in enumerate(INERTIA_NAMES):
        numpyro.deterministic(name, pi[i])


@lru_cache(maxsize=None)
def rwa4_model(prior: str = "uniform"):
    """The NumPyro model (one function object per prior, so compiled samplers are reused).

    Call it with ``**Rwa4Problem.model_kwargs``. Posterior sites: ``u4_x``, ``u4_y``, ``u4_z``,
    ``Ixx … Iyz`` (kg m²), ``sigma_omega``, ``sigma_rho`` (rad/s), ``sigma_theta`` (rad) and the
    sampler's whitened ``w`` (``θ = centre + tril w``, ``θ = (y, inertia_z, noise_z)``).
    """
    cone = prior == "cone"

    def model(**kwargs):
        return _model(cone=cone, **kwargs)

    model.__name__ = f"rwa4_model_{prior}"
    return model


def _sample_u4(key, n: int, cone: bool) -> np.ndarray:
    out, have, r = [], 0, 0
    while have < n:
        x = np.asarray(jax.random.normal(jax.random.fold_in(key, r), (max(4 * n, 1000), 3)))
        u = x / np.linalg.norm(x, axis=1, keepdims=True)
        if cone:
            keep = np.asarray(jax.random.uniform(jax.random.fold_in(key, 10_000 + r),
                                                 (u.shape[0],)))
            th = np.degrees(np.arccos(np.clip(u[:, 2], -1, 1)))
            u = u[keep < np.exp(-0.5 * ((th - CONE_ANGLE_DEG) / CONE_SD_DEG) ** 2)]
        out.append(u)
        have += u.shape[0]
        r += 1
    return np.concatenate(out)[:n]


def sample_rwa4_prior(key, problem: Rwa4Problem, n: int) -> dict[str, np.ndarray]:
    """``n`` draws of ``u4``, the inertia entries and the noise scales from the stated prior."""
    k_u, k_i, k_s = jax.random.split(key, 3)
    u = _sample_u4(k_u, n, problem.prior == "cone")
    out = {name: u[:, i] for i, name in enumerate(U4_NAMES)}
    chol = np.linalg.cholesky(np.asarray(problem.inertia.cov))
    kept, r = [], 0
    while sum(k.shape[0] for k in kept) < n and r < 100:
        z = np.asarray(jax.random.normal(jax.random.fold_in(k_i, r), (2 * n + 16, 6)))
        pi = np.asarray(problem.inertia.mean) + z @ chol.T
        kept.append(pi[is_physical(pi)])
        r += 1
    pi = np.concatenate(kept)[:n]
    out.update({name: pi[:, i] for i, name in enumerate(INERTIA_NAMES)})
    ls = np.log(problem.noise_hat) + NOISE_PRIOR_LOG_SD * np.asarray(
        jax.random.normal(k_s, (n, 3)))
    out.update({name: np.exp(ls[:, i]) for i, name in enumerate(NOISE_NAMES)})
    return out


# --------------------------------------------------------------------------------------------
# The fit
# --------------------------------------------------------------------------------------------

class Rwa4Posterior(NamedTuple):
    """Result of :func:`fit_rwa4`: InferenceData, diagnostics, problem and the direction summary
    (``{"mean": [x, y, z], "cone_deg": {"50": …, "90": …, "95": …}}``)."""

    idata: object
    diagnostics: object
    problem: Rwa4Problem
    direction: dict


def fit_rwa4(key, tel: Telemetry, spacecraft: Spacecraft, *, method: str = "rcs",
             pairs: Sequence[tuple[Window, Window]] | None = None, prior: str = "uniform",
             inertia: InertiaGaussian | None = None, settings=None,
             prior_draws: int = 500) -> Rwa4Posterior:
    """Posterior of the RWA4 spin axis (unit vector, body axes) with the inertia sampled jointly.

    Parameters
    ----------
    key : jax.random key.
    tel : the calibration telemetry.
    spacecraft : wheels and the inertia prior (its RWA4 axis is not used).
    method : ``"rcs"`` (Brown Eq 1) or ``"rwa"`` (Brown Eq 3).
    pairs : ``[(A, B), …]`` windows (s); detected from quiet periods when ``None``.
    prior : ``"uniform"`` on the sphere or ``"cone"`` (articulation cone).
    inertia : Gaussian inertia prior (e.g. :func:`~cassini_bayes.inference.thrust.
        inertia_from_run`); default the spacecraft model's knowledge requirements.
    settings : :class:`~cassini_bayes.inference.runner.SamplerSettings`.

    Returns
    -------
    Rwa4Posterior
        ``idata`` groups ``posterior`` (``u4_*``, ``Ixx … Iyz``, noise scales, sampler
        coordinates), ``sample_stats``, ``prior``, ``observed_data`` (window samples: ``omega``
        rad/s, ``rho4`` rad/s, ``group``), ``constant_data`` (baseline axis, windows, R).
    """
    import xarray as xr

    from cassini_bayes.inference.runner import SamplerSettings, diagnostics, run_nuts

    settings = settings or SamplerSettings()
    problem = prepare_rwa4(tel, spacecraft, method=method, pairs=pairs, prior=prior,
                           inertia=inertia)
    kw = problem.model_kwargs
    coords = {"w_dim": np.arange(12)}
    dims = {"w": ["w_dim"]}
    idata = run_nuts(key, rwa4_model(prior), model_kwargs=kw, settings=settings, coords=coords,
                     dims=dims, prior=lambda k, n: sample_rwa4_prior(k, problem, n),
                     prior_draws=prior_draws)
    post = idata.posterior
    draws = np.stack([post[n].values.ravel() for n in U4_NAMES], -1)
    direction = direction_summary(draws)

    observed = xr.Dataset(
        {"h_known_mean": (("window", "axis"), np.asarray(kw["k_h"]), {"units": "N m s",
                          "description": "window mean of A(q)ᵀ h_known (inertial)"}),
         "rho4_attitude_mean": (("window", "axis", "axis2"), np.asarray(kw["r_u"]),
                                {"units": "rad/s", "description": "window mean of ρ4 A(q)ᵀ"}),
         "n_samples": ("window", np.asarray(kw["n_w"]))},
        coords={"window": np.arange(np.asarray(kw["n_w"]).shape[0]), "axis": ["x", "y", "z"],
                "axis2": ["x", "y", "z"]}, attrs={"source": problem.source})
    win = np.array([[a[0], a[1], b[0], b[1]] for a, b in problem.pairs], float)
    constant = xr.Dataset(
        {"baseline": ("axis", problem.baseline),
         "windows": (("pair", "edge"), win, {"units": "s"}),
         "spin_change_rpm": ("pair", problem.spin_change_rpm),
         "radius": ((), problem.radius),
         "prior_inertia_mean": ("param", np.asarray(problem.inertia.mean)),
         "prior_inertia_sd": ("param", np.sqrt(np.diag(np.asarray(problem.inertia.cov))))},
        coords={"axis": ["x", "y", "z"], "pair": np.arange(win.shape[0]),
                "edge": ["a0", "a1", "b0", "b1"], "param": list(INERTIA_NAMES)})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        for name in ("observed_data", "constant_data"):
            if name in idata.groups():
                del idata[name]
        idata.add_groups({"observed_data": observed, "constant_data": constant})
    names = list(U4_NAMES) + list(INERTIA_NAMES)
    return Rwa4Posterior(idata, diagnostics(idata, names), problem, direction)
