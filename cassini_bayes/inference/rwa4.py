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
numbers per pair cannot estimate them).

Robust model (the default)
--------------------------
Brown's balance also moves with effects his least squares leaves out, each small and entering
``d_g`` linearly (:mod:`cassini_bayes.inference.nuisance`, the inertia and thrust models' layout
and priors): gyro bias and scale factor (through ``I*``, the prior-mean tensor), a spin-inertia
scale per wheel (``J_k → (1 + c_k) J_k``, the solved wheel's own included; with
``wheel_errors="common"`` one ``c`` for every wheel, the earlier model), tilts of the *known*
wheels' axes (the solved wheel's axis is the unknown), a body-fixed external torque
(``∫ A(q_s)ᵀ ds T_B`` between the windows; Brown: ≈ 3e-6 N m, < 0.1° for the RCS method) and an
inertial one (``T_I Δt``: solar and RTG torques, Feldman & Lee App. A; over the RWA method's
long windows a few tens of µN m move the axis by more than the idealised cone). With
zero-mean Normal priors they are integrated out exactly: ``d ~ N(0, C + D Σ_ν Dᵀ)`` over all
pairs together (one effect is shared by every pair). The RWA method feels them most: 0.2° tilts
of RWA2 and RWA3, whose momenta match RWA4's, move Brown's axis by tenths of a degree, 20–50× the
idealised posterior's width on ``rwa4_rwa_real``; :func:`axis_sensitivity` reports each effect's
shift. ``robust=False`` is Brown's idealised model.

Priors
------
* ``u4``: uniform on the sphere, or concentrated on the articulation cone (angle from +Z within
  ``Normal(54.7356°, 1°)``, any articulation angle): a factor
  ``−½ ((θ_z(u4) − 54.7356°)/1°)²``. 1° is the mechanical cant tolerance we assume; the 1/8 s
  articulation-command resolution (≈ 1.5°, Brown §I) moves the azimuth, not the cant.
* Inertia: the spacecraft model's predicted tensor with its knowledge requirements as 1σ (the
  prior of :mod:`cassini_bayes.inference.inertia`), or a Gaussian (an inertia run's posterior);
  sampled jointly, so the mass-property error is part of the posterior (Brown's Monte Carlo
  analysis, ≤ 1.5°, comes out of the posterior instead of being added afterwards). The stated
  prior, the same in both charts and in :func:`sample_inertia_prior` (SBC truths included), is
  this Gaussian times the physical factor ``1 − exp(−(m/s)³)`` (:func:`_log_physical_factor`):
  ``m`` the smallest eigenvalue of the second moment ``½ tr(I) 1 − I`` (positive exactly for
  positive-definite tensors obeying the triangle inequalities), ``s`` half its value at the
  prior mean. The factor is 0 for unphysical tensors, 1 − 3e-4 at the mean, 0.63 half-way to
  the boundary: a stated softening of the truncation near the boundary, which NUTS needs (see
  "Sampler coordinates").

Sampler coordinates
-------------------
The axis is written in the gnomonic chart about the least-squares axis ``u0`` (tangent basis
``E``): ``u = (u0 + Eᵀ v)/√(1 + |v|²)``, ``v ∈ R²``; a uniform density on the sphere is
``(1 + |v|²)^(−3/2)`` in ``v``. The chart covers the hemisphere about ``u0``, which holds the
posterior whenever the data determine the axis at all (:func:`prepare_rwa4` refuses data whose
Laplace direction sd exceeds ``MAX_SD_DIRECTION_DEG``). The inertia is ``π = μ + L ξ`` with
``ξ ~ N(0, 1)`` (``L`` the prior's Cholesky factor) times the physical factor. The boundary is
near: on Cassini it is 3.16σ from the prior mean along the worst direction of ``ξ``, so a hard
cut (−∞) makes NUTS diverge (69 of 4000 transitions on ``rwa4_rwa``).

* RWA method: ``θ = (v, ζ)``; the data fix ``u`` and barely touch ``π``, which is sampled in
  the prior-whitened log-Cholesky coordinates ``ζ`` of the second-moment matrix (physical by
  construction, the boundary at infinity; the prior density through the map's Jacobian, times
  the physical factor, which is ``≈ (m/s)³`` there: linear in ``log m``, so smooth in ``ζ``).
* RCS method: the pair's balance is ``J₄ R (z + u)`` with ``z = R⁻¹(M π + Δk)/J₄`` (``R`` the
  change of ``⟨ρ₄ Aᵀ⟩``, ``M π`` that of ``⟨Aᵀ I ω⟩``): the data fix ``z = −u``, i.e. ``|z| = 1``
  (a curved ellipsoid in ``π``) and the direction of ``z`` (another sphere). In Cartesian ``π``
  and ``u`` this is a narrow curved ridge that NUTS cannot follow (checked: whitened axes of the
  earlier ``x = R u`` construction dropped by −1200 log-units at ±1 instead of −0.5). So the
  three combinations ``z`` of ``ξ`` are sampled in polar form, ``z = −e^ρ g(v_z)`` with the same
  chart ``g``, plus the three prior-only complements ``w``: ``θ = (v, ρ, v_z, w)``, Jacobian
  ``e^{3ρ} (1 + |v_z|²)^(−3/2)``; the constraint becomes ``ρ ≈ 0``, ``v_z ≈ v``, linear. Here
  ``π`` is linear in ``θ`` and the boundary is at a finite distance, where the physical factor
  turns trajectories back. It matters: the ridge ``v_z ≈ v`` moves ``u`` and ``ξ`` together (a
  3σ move of the axis along it is several prior σ of ``ξ``), so the axis posterior is limited by
  the inertia prior and the boundary, and NUTS reaches the factor's barrier in many fits. The
  first factor, ``1 − exp(−m/s)`` with ``s`` = ¼ of the mean's margin, is ``≈ m/s`` near the
  boundary: a log barrier whose curvature at a turning point of energy ``K`` grows as ``e^{2K}``
  (1004 divergences in a 208-replicate SBC; 37 on ten of its divergent replicates refitted).
  The cubic factor with ``s`` = ½ grows as ``e^{2K/3}``: 1 on the same ten (2 × 300 draws
  each; :func:`_log_physical_factor`), and 7 single divergences in the 208-replicate SBC
  (``docs/sbc/rwa4``). A map sending the boundary to infinity along rays from the prior mean
  (tried) bends the narrow ridge wherever it compresses (a whitened axis fell to −848 at −3):
  229 on the ten.

Finally the sampler sees ``w`` with ``θ = centre + tril w``, ``centre``/``tril`` a Laplace
approximation (:func:`cassini_bayes.inference.laplace.laplace`). The density is exact in ``θ``;
the affine map only conditions the geometry. Check (``rwa4_rcs``, seed 21): along every whitened
axis the log density at ±1, ±3 is within 0.5 of the Gaussian −0.5, −4.5. On SBC replicates the
physical factor's barrier shows at ±3 (up to 6.7 below −4.5 on six replicates, within 0.11 at
±1): a soft, finite wall, no cliff.
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

from cassini_bayes.errors import InputError, arg, spelled
from cassini_bayes.estimators.rwa4 import fit_axis_rcs, fit_axis_rwa
from cassini_bayes.frames import dcm, quat_conjugate, quat_continuous, quat_multiply, quat_to_rotvec
from cassini_bayes.inference.inertia import (cholesky_params_from_pi, inertia_prior,
                                             is_physical, pi_from_cholesky_params)
from cassini_bayes.inference.laplace import laplace
from cassini_bayes.inference.sphere import direction_summary
from cassini_bayes.inference.nuisance import NuisanceLayout, nuisance_layout, robust_columns
from cassini_bayes.inference.thrust import InertiaGaussian, rate_noise_levels
from cassini_bayes.physics.momentum import INERTIA_NAMES, inertia_matrix, regressor
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import RPM_TO_RAD_S, Telemetry
from cassini_bayes.windows import clamp_window

__all__ = [
    "U4_NAMES",
    "METHODS",
    "PRIORS",
    "CONE_ANGLE_DEG",
    "CONE_SD_DEG",
    "MIN_SPIN_CHANGE_RPM",
    "WHEEL",
    "detect_windows",
    "balance_misfit",
    "Rwa4Problem",
    "prepare_rwa4",
    "rwa4_model",
    "sample_rwa4_prior",
    "sample_inertia_prior",
    "Rwa4Posterior",
    "fit_rwa4",
    "axis_sensitivity",
]

U4_NAMES = ("u4_x", "u4_y", "u4_z")
METHODS = ("rcs", "rwa")
PRIORS = ("uniform", "cone")
CONE_ANGLE_DEG = float(np.degrees(np.arccos(1.0 / np.sqrt(3.0))))   # 54.7356°, Brown §I
CONE_SD_DEG = 1.0
MIN_SPIN_CHANGE_RPM = 10.0   # smaller spin changes between A and B cannot calibrate the axis
MAX_SD_DIRECTION_DEG = 20.0  # a wider Laplace direction sd: the data do not determine the axis
def _WINDOWS_HINT() -> str:  # noqa: N802 - a message constant, spelled for the caller
    return spelled("--window-a T0:T1 --window-b T0:T1", "windows=[((A0, A1), (B0, B1))] (s)")


WHEEL = "RWA4"               # the wheel solved for by default
_NOISE_FLOORS = np.array([1e-9, 1e-7, 1e-9])
_DIM = 8                     # sampler coordinates: 2 direction + 6 inertia (either chart)
_MARGIN_FRACTION = 2.0       # physical-factor scale s = (prior mean's margin) / this
_FACTOR_POWER = 3            # the physical factor is 1 − exp(−(m/s)^this)

Window = tuple[float, float]


# --------------------------------------------------------------------------------------------
# Windows
# --------------------------------------------------------------------------------------------

def _wheel_name(tel: Telemetry, wheel: str) -> str:
    """The telemetry's spelling of ``wheel``; InputError when it is absent or not running."""
    names = {n.upper(): n for n in tel.wheel_names}
    name = names.get(str(wheel).upper())
    if name is None or name not in tel.active_wheels():
        raise InputError(f"no {wheel} rates (column {str(wheel).lower()}, rpm); the spin-axis "
                         f"calibration needs {wheel} running", path=tel.source)
    return name


def _median_rpm(tel: Telemetry, w: Window, wheel: str) -> float:
    m = (tel.t >= w[0]) & (tel.t <= w[1])
    return float(np.nanmedian(np.asarray(tel.wheel_rate(wheel), float)[m]) / RPM_TO_RAD_S)


def detect_windows(tel: Telemetry, method: str,
                   wheel: str = WHEEL) -> list[tuple[Window, Window]]:
    """Time A / Time B window pairs from the quiet periods (:func:`cassini_bayes.windows.
    quiet_periods`).

    * RCS: the two consecutive quiet periods across the largest change of ``wheel``'s median
      rate.
    * RWA: consecutive quiet periods paired in order, ``(Q0, Q1), (Q2, Q3), …`` — Brown's "Time A"
      before and "Time B" after the first slew of each slew pair.

    Raises
    ------
    InputError
        Fewer than two quiet periods; for RCS, no spin change of ``MIN_SPIN_CHANGE_RPM``.
    """
    from cassini_bayes.windows import quiet_periods

    wheel = _wheel_name(tel, wheel) if method == "rcs" else wheel

    quiet = quiet_periods(tel)
    if len(quiet) < 2:
        raise InputError(f"found {len(quiet)} quiet period(s) (≥ 60 s, |ω| ≤ 1 mrad/s, wheels "
                         "steady, no thruster firing); the RWA4 calibration needs a Time A and a "
                         "Time B: give them with " + _WINDOWS_HINT(),
                         path=tel.source)
    if method == "rcs":
        rpm = np.array([_median_rpm(tel, w, wheel) for w in quiet])
        jumps = np.abs(np.diff(rpm))
        k = int(np.nanargmax(jumps))
        if not jumps[k] >= MIN_SPIN_CHANGE_RPM:
            raise InputError(f"no {wheel} spin change between quiet periods (largest "
                             f"{jumps[k]:.3g} rpm < {MIN_SPIN_CHANGE_RPM:g} rpm); the RCS method "
                             f"needs {wheel} spun up or down between Time A and Time B",
                             path=tel.source)
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
    sd_direction_deg : the Laplace approximation's largest angular sd of the axis, deg.
    spin_change_rpm : change of the wheel's mean rate from A to B, per pair.
    noise_hat : (3,) σ̂ (rad/s, rad/s, rad).
    source : the telemetry file.
    wheel : the wheel solved for.
    chart : ``"rcs"`` (balance coordinates) or ``"rwa"`` (direct), module docstring.
    layout : the nuisance layout of the robust model's effects (built for either model).
    nuisance : their columns (:func:`_nuisance_means`; in ``model_kwargs`` only when ``robust``).
    robust : whether the likelihood integrates the effects out.
    """

    model_kwargs: dict
    method: str
    prior: str
    pairs: tuple[tuple[Window, Window], ...]
    inertia: InertiaGaussian
    inertia_source: str
    baseline: np.ndarray
    sd_direction_deg: float
    spin_change_rpm: np.ndarray
    noise_hat: np.ndarray
    source: str
    wheel: str
    chart: str
    layout: NuisanceLayout
    nuisance: dict
    robust: bool


def _attitude_noise(q: np.ndarray) -> float:
    if q.shape[0] < 4:
        return 0.0
    qc = np.asarray(quat_continuous(q))
    inc = np.asarray(quat_to_rotvec(quat_multiply(qc[1:], quat_conjugate(qc[:-1]))))
    d = np.diff(inc, axis=0).ravel()
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / np.sqrt(6.0))


def _balance(u, pi, *, m_pi, r_u, k_h, j4):
    """Change of the window-mean inertial momentum per pair, ``d_g`` (G, 3) N m s (Brown Eqs 1,
    3): ``⟨Aᵀ(I ω + h_known + J_4 ρ_4 u4)⟩_B − ⟨…⟩_A``, zero for a perfect model."""
    h = m_pi @ pi + j4 * r_u @ u + k_h                                  # (W, 3) inertial means
    return h[1::2] - h[0::2]


def _noise_cov(u, pi, log_sigma, *, n_w, t_aa, j4, known_cov):
    """(G, 3, 3) covariance of ``d_g`` from white gyro and wheel-rate noise:
    ``C_A/n_A + C_B/n_B``, ``C_w = ⟨A_iᵀ B A_i⟩_w``,
    ``B = σ_ω² I I + σ_ρ² (Σ_known J_k² g_k g_kᵀ + J_4² u4 u4ᵀ)``."""
    i_m = inertia_matrix(pi)
    s2 = jnp.exp(2.0 * log_sigma)
    b = s2[0] * (i_m @ i_m) + s2[1] * (known_cov + j4**2 * jnp.outer(u, u))
    c_w = jnp.einsum("wjakb,jk->wab", t_aa, b) / n_w[:, None, None]
    return c_w[1::2] + c_w[0::2]


def _nuisance_cols(u, *, r_u, j4, nu_cols, nu_wheel):
    """(G, 3, R) columns of the robust nuisance vector ``ν`` in ``d_g``: the fixed inertial
    columns of :func:`_nuisance_means` plus the solved wheel's part of its spin-inertia scale
    (its own per-wheel scale, or the common one), ``J_4 Δ⟨ρ_4 Aᵀ⟩ u4`` (it depends on ``u4``)."""
    d_r = (r_u[1::2] - r_u[0::2]) @ u                                  # (G, 3)
    return nu_cols + j4 * d_r[:, :, None] * nu_wheel[None, None, :]


def _loglik(u, pi, log_sigma, *, m_pi, r_u, k_h, n_w, t_aa, j4, known_cov, nu_cols, nu_sd,
            nu_wheel):
    """Log-likelihood of the window-mean momentum balance of all A/B pairs (Brown Eqs 1, 3):
    ``d = (d_1 … d_G) ~ N(0, blockdiag(C_g) + D diag(ν_sd²) Dᵀ)``.

    ``d_g`` is :func:`_balance`, ``C_g`` :func:`_noise_cov`; ``D`` (:func:`_nuisance_cols`)
    holds the robust model's nuisance effects, which enter ``d`` linearly with zero-mean Normal
    priors and are integrated out exactly (``R = 0`` columns: the idealised model). One effect
    is shared by every pair, so the pairs are correlated. Window arrays (index ``w = 2g`` for A,
    ``2g + 1`` for B): ``m_pi`` (W, 3, 6) with ``⟨Aᵀ I ω⟩ = m_pi π``; ``r_u`` (W, 3, 3) =
    ``⟨ρ_4 Aᵀ⟩``; ``k_h`` (W, 3) = ``⟨Aᵀ h_known⟩``; ``n_w`` (W,) sample counts; ``t_aa``
    (W, 3, 3, 3, 3) = ``⟨A_jk A_lm⟩``.
    """
    d = _balance(u, pi, m_pi=m_pi, r_u=r_u, k_h=k_h, j4=j4).ravel()
    cov = jax.scipy.linalg.block_diag(*_noise_cov(u, pi, log_sigma, n_w=n_w, t_aa=t_aa, j4=j4,
                                                  known_cov=known_cov))
    cols = _nuisance_cols(u, r_u=r_u, j4=j4, nu_cols=nu_cols, nu_wheel=nu_wheel)
    cols = cols.reshape(d.shape[0], -1) * nu_sd[None, :]
    chol = jnp.linalg.cholesky(cov + cols @ cols.T)
    r = jax.scipy.linalg.solve_triangular(chol, d, lower=True)
    logdet = 2.0 * jnp.sum(jnp.log(jnp.diag(chol)))
    return -0.5 * (r @ r + logdet + d.shape[0] * jnp.log(2.0 * jnp.pi))


def _tangent_basis(u: np.ndarray) -> np.ndarray:
    """(2, 3) orthonormal basis of the plane perpendicular to the unit vector ``u``."""
    e = np.eye(3)[int(np.argmin(np.abs(u)))]
    e1 = np.cross(u, e)
    e1 /= np.linalg.norm(e1)
    return np.stack([e1, np.cross(u, e1)])


def _check_windows(tel: Telemetry, pairs, method: str) -> list:
    """The window pairs, ends up to half a sample past the data clamped onto it
    (:func:`~cassini_bayes.windows.clamp_window`, with a warning); one-line InputErrors for
    pairs the calibration cannot use."""
    if not pairs:
        raise InputError("no window pair; give " + _WINDOWS_HINT(),
                         path=tel.source)
    if method == "rcs" and len(pairs) != 1:
        raise InputError(f"the RCS method takes one Time A / Time B pair, got {len(pairs)}",
                         path=tel.source)
    t = np.asarray(tel.t, float)
    pairs = [tuple(clamp_window(w, t, f"{tel.source}: window {w[0]:.10g}:{w[1]:.10g} s")
                   for w in p) for p in pairs]
    windows = [w for p in pairs for w in p]
    for w in windows:
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
    return pairs


def _noise_levels(tel: Telemetry, q: np.ndarray, windows) -> np.ndarray:
    """σ̂ (3,): gyro (rad/s), wheel rate (rad/s), attitude (rad), medians over the windows
    (quiet: the robust white-noise estimate is cleanest there)."""
    t = np.asarray(tel.t, float)
    levels = np.array([rate_noise_levels(tel.slice(*w))[:2] for w in windows], float)
    s_q = np.median([_attitude_noise(q[(t >= w[0]) & (t <= w[1])]) for w in windows])
    return np.maximum(np.array([*np.median(levels, axis=0), s_q]), _NOISE_FLOORS)


def _window_means(q, omega, rates, axes, js, k_u, known, masks) -> dict:
    """The window averages of :func:`_loglik` (its docstring), as JAX arrays."""
    a_all = np.asarray(dcm(jnp.asarray(q)))
    h_known_all = ((np.nan_to_num(rates[:, known]) * js[known]) @ axes[known] if known
                   else np.zeros((q.shape[0], 3)))
    reg = np.asarray(regressor(jnp.asarray(omega)))
    rho = np.nan_to_num(rates[:, k_u])
    m_pi, r_u, k_h, n_w, t_aa = [], [], [], [], []
    for ma, mb in masks:
        for m in (ma, mb):
            at = np.swapaxes(a_all[m], -1, -2)                          # body → inertial
            m_pi.append(np.einsum("nij,njk->ik", at, reg[m]) / m.sum())
            r_u.append(np.einsum("n,nij->ij", rho[m], at) / m.sum())
            k_h.append(np.einsum("nij,nj->i", at, h_known_all[m]) / m.sum())
            n_w.append(float(m.sum()))
            t_aa.append(np.einsum("nja,nkb->jakb", a_all[m], a_all[m]) / m.sum())
    known_cov = sum((js[k]**2 * np.outer(axes[k], axes[k]) for k in known), np.zeros((3, 3)))
    return dict(m_pi=jnp.asarray(np.stack(m_pi)), r_u=jnp.asarray(np.stack(r_u)),
                k_h=jnp.asarray(np.stack(k_h)), n_w=jnp.asarray(np.array(n_w)),
                t_aa=jnp.asarray(np.stack(t_aa)), j4=jnp.asarray(js[k_u]),
                known_cov=jnp.asarray(known_cov))


def _nuisance_means(layout: NuisanceLayout, q, omega, rates, axes, js, known, names, masks,
                    t, inertia) -> dict:
    """The robust model's nuisance columns of ``d_g`` (:func:`_loglik`), as JAX arrays.

    The body-axis columns of :func:`~cassini_bayes.inference.nuisance.robust_columns` (gyro bias
    and scale factor through ``I*`` = ``inertia`` (3, 3), the prior-mean tensor; the known
    wheels' spin-inertia scales; the known wheels' axis tilts; a body-fixed torque through
    ``−A(q_t) ∫ A(q_s)ᵀ ds``) rotated to inertial axes and window-averaged like the momentum,
    B − A per pair: ``nu_cols`` (G, 3, R). ``nu_wheel`` (R,) marks the solved wheel's scale columns
    (per wheel: its own, the layout's last scale, and the shared one; common: the one scale),
    whose solved-wheel part
    :func:`_nuisance_cols` adds; ``nu_sd`` (R,) the prior sd.
    """
    a_all = np.asarray(dcm(jnp.asarray(q)))
    rho = np.nan_to_num(rates)
    wheel_h = {names[k]: js[k] * rho[:, k] for k in known}
    h_known = sum((wheel_h[names[k]][:, None] * axes[k] for k in known),
                  np.zeros((q.shape[0], 3)))
    cols = robust_columns(layout, 0, inertia, omega, h_known, wheel_h, a_all, t)
    inertial = np.einsum("nji,njr->nir", a_all, cols)                  # A(q)ᵀ · column
    diff = [inertial[mb].mean(0) - inertial[ma].mean(0) for ma, mb in masks]
    one_hot = np.zeros(layout.size)
    one_hot[layout.slices["wheel_inertia"].stop - 1] = 1.0
    if layout.has_common:                   # the shared scale reaches the solved wheel too
        one_hot[layout.slices["wheel_inertia_common"]] = 1.0
    return dict(nu_cols=jnp.asarray(np.stack(diff)), nu_sd=jnp.asarray(layout.sd),
                nu_wheel=jnp.asarray(one_hot))


def _no_nuisance(n_pairs: int) -> dict:
    """The idealised model: no nuisance columns (R = 0)."""
    return dict(nu_cols=jnp.zeros((n_pairs, 3, 0)), nu_sd=jnp.zeros(0), nu_wheel=jnp.zeros(0))


def _balance_map(data: dict, pi_mean: np.ndarray, pi_chol: np.ndarray):
    """The RCS method's linearising change of inertia coordinates (module docstring).

    With ``π = μ + L ξ`` the pair's balance is ``J₄ R (z + u4)`` with ``R = ΔR_u`` and
    ``z = a + K ξ``, ``a = R⁻¹(M μ + Δk)/J₄``, ``K = R⁻¹ M L/J₄`` (``M = Δm_π``). Returns ``a``
    (3,) and ``Q⁻¹`` (6, 6) with ``ξ = Q⁻¹ [z − a; w]``, the rows of ``Q`` being ``K`` and an
    orthonormal basis ``w`` of the prior-whitened inertia directions the balance does not see;
    ``None`` when ``R`` or ``K`` is singular (no spin change or no drift).
    """
    j4 = float(data["j4"])
    r = np.asarray(data["r_u"][1] - data["r_u"][0])
    m = np.asarray(data["m_pi"][1] - data["m_pi"][0])
    dk = np.asarray(data["k_h"][1] - data["k_h"][0])
    if np.linalg.cond(r) > 1e8:
        return None
    a = np.linalg.solve(r, m @ pi_mean + dk) / j4
    k = np.linalg.solve(r, m @ pi_chol) / j4
    _, s, vt = np.linalg.svd(k)
    if not s[-1] > 1e-8 * s[0]:
        return None
    return a, np.linalg.inv(np.concatenate([k, vt[3:]], 0))


def prepare_rwa4(tel: Telemetry, spacecraft: Spacecraft, *, method: str = "rcs",
                 pairs: Sequence[tuple[Window, Window]] | None = None, prior: str = "uniform",
                 inertia: InertiaGaussian | None = None, wheel: str = WHEEL,
                 robust: bool = True, wheel_errors: str = "per_wheel") -> Rwa4Problem:
    """Prepare the spin-axis problem of ``wheel`` from one telemetry file and its window pairs.

    Parameters
    ----------
    tel : telemetry with the wheel running (and, for the RWA method, the known wheels).
    spacecraft : wheel axes/inertias (the solved wheel's axis in the model is ignored) and the
        inertia prior.
    method : ``"rcs"`` (Brown Eq 1) or ``"rwa"`` (Brown Eq 3).
    pairs : ``[(A, B), …]`` windows in s; detected (:func:`detect_windows`) when ``None``.
    prior : ``"uniform"`` or ``"cone"``.
    inertia : Gaussian inertia prior; default the spacecraft model's knowledge requirements.
    wheel : the wheel whose axis is solved for (default RWA4; Brown's flight test: RWA1).
    robust : integrate out the nuisance effects of the module docstring ("Robust model"), with
        the priors of the spacecraft model's ``Knowledge``; ``False``: Brown's idealised model.
    wheel_errors : the robust model's wheel spin-inertia errors: ``"per_wheel"`` (default; the
        solved wheel has its own scale too) or ``"common"`` (one scale for every wheel).

    Raises
    ------
    InputError
        Unknown method/prior/wheel, no rates of the wheel, windows outside the data or
        overlapping, thrusters firing inside a window, no spin change (RCS), data that cannot
        determine the axis.
    """
    if method not in METHODS:
        raise InputError(f"{arg('method', method, cli_quote=True)}: choose one of "
                         f"{', '.join(METHODS)}")
    if prior not in PRIORS:
        raise InputError(f"{arg('prior', prior, cli_quote=True)}: choose one of "
                         f"{', '.join(PRIORS)}")
    wheel = _wheel_name(tel, wheel)
    pairs = detect_windows(tel, method, wheel=wheel) if pairs is None else \
        [tuple(p) for p in pairs]
    pairs = _check_windows(tel, pairs, method)

    t = np.asarray(tel.t, float)
    names = tel.wheel_names
    k_u = names.index(wheel)
    rates = np.asarray(tel.wheel_rates, float)
    axes = np.stack([spacecraft.wheel(n).axis for n in names])
    js = np.array([spacecraft.wheel(n).inertia for n in names])
    active = np.any(np.isfinite(rates), axis=0)
    known = [k for k in range(len(names)) if k != k_u and active[k]]
    masks = [((t >= a[0]) & (t <= a[1]), (t >= b[0]) & (t <= b[1])) for a, b in pairs]
    rho = np.nan_to_num(rates[:, k_u])
    spin = np.array([(rho[mb].mean() - rho[ma].mean()) / RPM_TO_RAD_S for ma, mb in masks])
    if method == "rcs" and abs(spin[0]) < MIN_SPIN_CHANGE_RPM:
        raise InputError(f"{wheel} changes by {spin[0]:.3g} rpm between Time A and Time B "
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
    i_chol = np.linalg.cholesky(np.asarray(inertia.cov, float))

    # Least-squares baseline (Brown Eq 1 / Eq 3), also the chart's centre.
    q = np.asarray(quat_continuous(np.asarray(tel.q, float)))
    omega = np.asarray(tel.omega, float)
    i_pred = np.asarray(inertia_matrix(i_mean))
    if method == "rcs":
        fit = fit_axis_rcs(q, omega, rates, axes, js, i_pred, masks[0][0], masks[0][1],
                           unknown=k_u)
    else:
        fit = fit_axis_rwa(q, omega, rates, axes, js, masks, unknown=k_u, inertia=i_pred)
    u_ls = np.asarray(fit.axis, float)

    noise = _noise_levels(tel, q, [w for p in pairs for w in p])
    data = _window_means(q, omega, rates, axes, js, k_u, known, masks)
    layout = nuisance_layout(spacecraft, 1, [names[k] for k in known],
                             wheel_errors=wheel_errors, scaled=[names[k] for k in known] + [wheel],
                             inertial_torque=True, torque_rate=True)
    nuisance = _nuisance_means(layout, q, omega, rates, axes, js, known, names, masks, t, i_pred)
    data.update(nuisance if robust else _no_nuisance(len(pairs)))
    kw = dict(data, u0=jnp.asarray(u_ls), basis=jnp.asarray(_tangent_basis(u_ls)),
              pi_mean=jnp.asarray(i_mean), pi_chol=jnp.asarray(i_chol),
              log_noise_hat=jnp.asarray(np.log(noise)),
              margin_scale=_margin_scale(i_mean),
              cone_weight=jnp.asarray(1.0 if prior == "cone" else 0.0),
              cone_angle=jnp.asarray(np.radians(CONE_ANGLE_DEG)),
              cone_sd=jnp.asarray(np.radians(CONE_SD_DEG)))
    theta0 = np.zeros(_DIM)
    chart = "rwa"
    lp_c = cholesky_params_from_pi(i_mean)
    jac = np.asarray(jax.jacfwd(pi_from_cholesky_params)(jnp.asarray(lp_c)))
    cov_lp = np.linalg.solve(jac, np.linalg.solve(jac, np.asarray(inertia.cov)).T)
    kw["lp_centre"] = jnp.asarray(lp_c)
    kw["lp_tril"] = jnp.asarray(np.linalg.cholesky(0.5 * (cov_lp + cov_lp.T)))
    if method == "rcs":
        bal = _balance_map(data, i_mean, i_chol)
        if bal is not None:
            chart = "rcs"
            kw["z_offset"], kw["q_inv"] = jnp.asarray(bal[0]), jnp.asarray(bal[1])
            theta0[2] = np.log(np.linalg.norm(bal[0]))
    centre, tril = laplace(_LOG_DENSITY[chart], theta0, data=kw)
    cov_v = (tril @ tril.T)[:2, :2]
    sd_dir = float(np.degrees(np.sqrt(np.linalg.eigvalsh(cov_v)[-1])))
    if not sd_dir < MAX_SD_DIRECTION_DEG:
        raise InputError(f"the data determine the {wheel} axis only to ±{sd_dir:.3g}° "
                         f"(Laplace sd > {MAX_SD_DIRECTION_DEG:g}°): no excitation between the "
                         "windows; choose windows across a spin change (RCS) or a slew (RWA)",
                         path=tel.source)
    kw["centre"], kw["tril"] = jnp.asarray(centre), jnp.asarray(tril)
    return Rwa4Problem(
        model_kwargs=kw, method=method, prior=prior, pairs=tuple(pairs), inertia=inertia,
        inertia_source=i_src, baseline=u_ls, sd_direction_deg=sd_dir, spin_change_rpm=spin,
        noise_hat=noise, source=tel.source, wheel=wheel, chart=chart, layout=layout,
        nuisance=nuisance, robust=robust)


# --------------------------------------------------------------------------------------------
# Model
# --------------------------------------------------------------------------------------------

def _gnomonic(v, kw):
    """Unit vector of the gnomonic chart ``v`` (2,) about ``u0`` and ``log dΩ/dv``."""
    s = 1.0 + jnp.sum(v**2)
    u = (kw["u0"] + v @ kw["basis"]) / jnp.sqrt(s)
    return u, -1.5 * jnp.log(s)


def _physical_rwa(theta, kw):
    """``u`` (3,), ``π`` (6,) kg m², ``ξ = L⁻¹(π − μ)`` and the log Jacobian of
    ``θ = (v (2), ζ (6))`` plus the log physical factor (:func:`_log_physical_factor`):
    log-Cholesky inertia coordinates ``lp = lp₀ + T ζ`` (physical by construction,
    :func:`~cassini_bayes.inference.inertia.pi_from_cholesky_params`)."""
    u, log_jac = _gnomonic(theta[:2], kw)
    lp = kw["lp_centre"] + kw["lp_tril"] @ theta[2:8]
    pi = pi_from_cholesky_params(lp)
    xi = jax.scipy.linalg.solve_triangular(kw["pi_chol"], pi - kw["pi_mean"], lower=True)
    # log|det ∂π/∂lp| up to a constant: exp of the diagonal gives Σ lp_ii, L → L Lᵀ gives
    # 2³ L00³ L11² L22, Σ → I = tr(Σ) 1 − Σ is linear
    return u, pi, xi, (log_jac + 4.0 * lp[0] + 3.0 * lp[1] + 2.0 * lp[2]
                       + _log_physical_factor(pi, kw["margin_scale"]))


def _physical_rcs(theta, kw):
    """As :func:`_physical_rwa` for ``θ = (v (2), log|z| (1), v_z (2), w (3))``: ``z = −|z|
    g(v_z)`` with the chart ``g`` of ``u``, ``ξ = Q⁻¹ [z − a; w]`` (:func:`_balance_map`)."""
    u, log_jac = _gnomonic(theta[:2], kw)
    z_dir, log_jac_z = _gnomonic(theta[3:5], kw)
    z = -jnp.exp(theta[2]) * z_dir
    xi = kw["q_inv"] @ jnp.concatenate([z - kw["z_offset"], theta[5:8]])
    pi = kw["pi_mean"] + kw["pi_chol"] @ xi
    # d³z = |z|³ d log|z| dΩ; π linear in ξ: the physical truncation is an explicit factor
    return u, pi, xi, (log_jac + log_jac_z + 3.0 * theta[2]
                       + _log_physical_factor(pi, kw["margin_scale"]))


def _physical_margin(pi):
    """Smallest eigenvalue (kg m²) of ``½ tr(I) 1 − I``: positive exactly when ``I`` is positive
    definite and obeys the triangle inequalities (the smallest second moment of the mass)."""
    i_m = inertia_matrix(pi)
    return jnp.linalg.eigvalsh(0.5 * jnp.trace(i_m) * jnp.eye(3) - i_m)[0]


def _margin_scale(mean) -> jax.Array:
    """The physical factor's scale ``s`` (kg m²): the prior mean's margin / ``_MARGIN_FRACTION``."""
    return jnp.asarray(float(_physical_margin(jnp.asarray(mean, float))) / _MARGIN_FRACTION)


def _log_physical_factor(pi, scale):
    """``log(1 − exp(−(m/s)³))`` for margin ``m > 0`` (:func:`_physical_margin`), ``−∞`` for
    ``m ≤ 0``: the physical truncation of the inertia prior, made smooth so that NUTS
    trajectories are turned back before the boundary instead of diverging on a cliff there.

    ``s`` (kg m²) = ½ the prior mean's margin (:data:`_MARGIN_FRACTION`), power 3
    (:data:`_FACTOR_POWER`): the factor is 1 − 3e-4 at the mean, 0.63 half-way to the boundary,
    and near it ``≈ (m/s)³``, a log barrier ``3 log m`` whose curvature at a NUTS turning point of
    energy ``K`` grows as ``e^{2K/3}``. The earlier ``1 − exp(−m/s)`` with ``s`` = ¼ of the
    margin (``e^{2K}``) gave 1004 divergences in a 208-replicate SBC and 37 when ten of its
    divergent replicates were refitted (2 × 300 draws each); this factor gave 1 on the same ten
    and 1 on replicates 0–23 (both times replicate 4, the smallest truth margin). A hard cut
    (``rwa4_rwa``: 69 divergences in 4000 draws) is worse still.
    """
    m = _physical_margin(pi)
    safe = jnp.where(m > 0, m, 1.0)
    return jnp.where(m > 0, jnp.log(-jnp.expm1(-(safe / scale) ** _FACTOR_POWER)), -jnp.inf)


def _log_density_with(physical, theta, kw):
    u, pi, xi, log_jac = physical(theta, kw)
    # Gaussian inertia prior (physical truncation in the chart's Jacobian term); uniform u on
    # the sphere (chart Jacobian), times the articulation-cone factor when chosen
    log_prior = -0.5 * jnp.sum(xi**2) + log_jac
    angle = jnp.arccos(jnp.clip(u[2], -1.0, 1.0))
    log_prior += -0.5 * kw["cone_weight"] * ((angle - kw["cone_angle"]) / kw["cone_sd"]) ** 2
    data = {k: kw[k] for k in _DATA_KEYS}
    return log_prior + _loglik(u, pi, kw["log_noise_hat"], **data)


def _log_density_rcs(theta, kw):
    """Log prior + log likelihood, RCS chart (module docstring)."""
    return _log_density_with(_physical_rcs, theta, kw)


def _log_density_rwa(theta, kw):
    """Log prior + log likelihood, direct chart (module docstring)."""
    return _log_density_with(_physical_rwa, theta, kw)


_DATA_KEYS = ("m_pi", "r_u", "k_h", "n_w", "t_aa", "j4", "known_cov", "nu_cols", "nu_sd",
              "nu_wheel")
_LOG_DENSITY = {"rcs": _log_density_rcs, "rwa": _log_density_rwa}
_PHYSICAL = {"rcs": _physical_rcs, "rwa": _physical_rwa}


@lru_cache(maxsize=None)
def rwa4_model(chart: str = "rwa"):
    """The NumPyro model of a chart (``Rwa4Problem.chart``); one function object per chart, so
    compiled samplers are reused.

    Call it with ``**Rwa4Problem.model_kwargs``. Posterior sites: ``u4_x``, ``u4_y``, ``u4_z``
    (the solved wheel's axis), ``Ixx … Iyz`` (kg m²) and the sampler's whitened ``w``
    (``θ = centre + tril w``).
    """
    log_density, physical = _LOG_DENSITY[chart], _PHYSICAL[chart]

    def model(*, centre, tril, **kw):
        w = numpyro.sample("w", dist.ImproperUniform(constraints.real_vector, (),
                                                     centre.shape))
        theta = centre + tril @ w
        numpyro.factor("log_density", log_density(theta, kw))
        u, pi, _, _ = physical(theta, kw)
        for i, name in enumerate(U4_NAMES):
            numpyro.deterministic(name, u[i])
        for i, name in enumerate(INERTIA_NAMES):
            numpyro.deterministic(name, pi[i])

    model.__name__ = f"rwa4_model_{chart}"
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


_log_factors = jax.jit(jax.vmap(_log_physical_factor, in_axes=(0, None)))


def sample_inertia_prior(key, mean, cov, n: int) -> np.ndarray:
    """``n`` draws (n, 6) kg m² of the stated inertia prior of both charts: ``Normal(mean, cov)``
    times the physical factor :func:`_log_physical_factor` (scale from ``mean`` as in
    :func:`prepare_rwa4`), by rejection: a Gaussian draw is kept with probability
    ``exp(_log_physical_factor)`` (0 when unphysical). The one sampler of this prior, used by
    :func:`sample_rwa4_prior` and the SBC truth draws."""
    mean = np.asarray(mean, float)
    chol = np.linalg.cholesky(np.asarray(cov, float))
    scale = _margin_scale(mean)
    kept, have = [], 0
    for r in range(1000):
        k_g, k_a = jax.random.split(jax.random.fold_in(key, r))
        pi = mean + np.asarray(jax.random.normal(k_g, (2 * n + 16, 6))) @ chol.T
        log_v = np.log(np.asarray(jax.random.uniform(k_a, (pi.shape[0],))))
        kept.append(pi[log_v < np.asarray(_log_factors(jnp.asarray(pi), scale))])
        have += kept[-1].shape[0]
        if have >= n:
            return np.concatenate(kept)[:n]
    raise InputError("the inertia prior puts almost no mass on physical tensors (< 1e-3 of "
                     "draws kept); check the prior mean and its uncertainties")


def sample_rwa4_prior(key, problem: Rwa4Problem, n: int) -> dict[str, np.ndarray]:
    """``n`` draws of ``u4`` and the inertia entries from the stated prior."""
    k_u, k_i = jax.random.split(key)
    u = _sample_u4(k_u, n, problem.prior == "cone")
    out = {name: u[:, i] for i, name in enumerate(U4_NAMES)}
    pi = sample_inertia_prior(k_i, problem.inertia.mean, problem.inertia.cov, n)
    out.update({name: pi[:, i] for i, name in enumerate(INERTIA_NAMES)})
    return out


# --------------------------------------------------------------------------------------------
# The fit
# --------------------------------------------------------------------------------------------

def axis_sensitivity(problem: Rwa4Problem) -> dict[str, float]:
    """RMS shift of the axis (deg) each nuisance effect of prior size would cause in a model that
    leaves it out (Lee §4.1 made quantitative, as :mod:`~cassini_bayes.inference.sensitivity`).

    Linearised at the Laplace centre ``θ*``: the data ``d`` (:func:`_balance`) gain ``D_e ν_e``
    from effect ``e``, which moves the idealised model's mode by
    ``Δθ = H⁻¹ Jᵀ C⁻¹ D_e ν_e`` (``H`` the idealised log density's negative Hessian, ``J`` =
    ∂d/∂θ, ``C`` the noise covariance); with ``ν_e ~ N(0, diag sd_e²)`` the axis shift ``U Δθ``
    (``U`` = ∂u/∂θ) has covariance ``U K diag(sd_e²) Kᵀ Uᵀ``, reported as √trace in degrees.
    """
    kw = dict(problem.model_kwargs)
    centre = kw.pop("centre")
    kw.pop("tril")
    ideal = {**kw, **_no_nuisance(len(problem.pairs))}
    physical = _PHYSICAL[problem.chart]
    log_density = _LOG_DENSITY[problem.chart]

    def balance(theta):
        u, pi, _, _ = physical(theta, kw)
        return _balance(u, pi, m_pi=kw["m_pi"], r_u=kw["r_u"], k_h=kw["k_h"],
                        j4=kw["j4"]).ravel()

    u, pi, _, _ = physical(centre, kw)
    hess = -np.asarray(jax.hessian(lambda th: log_density(th, ideal))(centre))
    jac = np.asarray(jax.jacfwd(balance)(centre))
    jac_u = np.asarray(jax.jacfwd(lambda th: physical(th, kw)[0])(centre))
    noise = jax.scipy.linalg.block_diag(*_noise_cov(
        u, pi, kw["log_noise_hat"], n_w=kw["n_w"], t_aa=kw["t_aa"], j4=kw["j4"],
        known_cov=kw["known_cov"]))
    cols = np.asarray(_nuisance_cols(u, r_u=kw["r_u"], j4=kw["j4"],
                                     nu_cols=problem.nuisance["nu_cols"],
                                     nu_wheel=problem.nuisance["nu_wheel"]))
    cols = cols.reshape(jac.shape[0], -1)
    gain = jac_u @ np.linalg.solve(hess, jac.T @ np.linalg.solve(np.asarray(noise), cols))
    out = {}
    for effect, sl in problem.layout.slices.items():
        k = gain[:, sl] * problem.layout.sd[sl]
        if k.size:
            out[effect] = float(np.degrees(np.sqrt(np.sum(k * k))))
    return out


def balance_misfit(problem: Rwa4Problem, u, pi) -> tuple[float, int]:
    """``χ² = dᵀ S⁻¹ d`` of the window-mean balances ``d`` (:func:`_balance`) at the axis ``u``
    (3,) and inertia ``pi`` (6,) kg m², with ``S`` the likelihood's covariance (white noise plus
    the integrated-out nuisance effects, :func:`_loglik`), and its degrees of freedom ``3G − 2``
    (the axis's two are fitted; an inertia the balance also informs makes χ² smaller still). A
    model that fits gives ``χ²`` about its dof; an unmodelled effect larger than its prior
    allows shows as a large one."""
    kw = problem.model_kwargs
    u = jnp.asarray(np.asarray(u, float) / np.linalg.norm(u))
    pi = jnp.asarray(pi, float)
    d = np.asarray(_balance(u, pi, m_pi=kw["m_pi"], r_u=kw["r_u"], k_h=kw["k_h"],
                            j4=kw["j4"])).ravel()
    cov = np.asarray(jax.scipy.linalg.block_diag(*_noise_cov(
        u, pi, kw["log_noise_hat"], n_w=kw["n_w"], t_aa=kw["t_aa"], j4=kw["j4"],
        known_cov=kw["known_cov"])))
    cols = np.asarray(_nuisance_cols(u, r_u=kw["r_u"], j4=kw["j4"], nu_cols=kw["nu_cols"],
                                     nu_wheel=kw["nu_wheel"])).reshape(d.size, -1)
    cols = cols * np.asarray(kw["nu_sd"])[None, :]
    chi2 = float(d @ np.linalg.solve(cov + cols @ cols.T, d))
    return chi2, max(d.size - 2, 1)


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
             prior_draws: int = 500, wheel: str = WHEEL, robust: bool = True,
             wheel_errors: str = "per_wheel") -> Rwa4Posterior:
    """Posterior of a wheel's spin axis (unit vector, body axes; default RWA4) with the inertia
    sampled jointly.

    Parameters
    ----------
    key : jax.random key.
    tel : the calibration telemetry.
    spacecraft : wheels and the inertia prior (the solved wheel's axis is not used).
    method : ``"rcs"`` (Brown Eq 1) or ``"rwa"`` (Brown Eq 3).
    pairs : ``[(A, B), …]`` windows (s); detected from quiet periods when ``None``.
    prior : ``"uniform"`` on the sphere or ``"cone"`` (articulation cone).
    inertia : Gaussian inertia prior (e.g. :func:`~cassini_bayes.inference.thrust.
        inertia_from_run`); default the spacecraft model's knowledge requirements.
    settings : :class:`~cassini_bayes.inference.runner.SamplerSettings`.
    wheel : the wheel solved for (``u4_*`` is its axis), e.g. ``"RWA1"`` for Brown's flight
        test with RWA2 and RWA3 known.
    robust : the robust model (default: gyro bias and scale factor, wheel spin-inertia scales,
        the known wheels' axis tilts and a body-fixed torque integrated out; module docstring)
        or, ``False``, Brown's idealised model.
    wheel_errors : ``"per_wheel"`` (default: one spin-inertia scale per wheel, the solved one
        included) or ``"common"`` (one scale for every wheel).

    Returns
    -------
    Rwa4Posterior
        ``idata`` groups ``posterior`` (``u4_*``, ``Ixx … Iyz``, sampler coordinates ``w``),
        ``sample_stats``, ``prior``, ``observed_data`` (window means: ``h_known_mean`` N m s,
        ``rho4_attitude_mean`` rad/s, ``n_samples``), ``constant_data`` (baseline axis,
        windows, spin change, inertia prior).
    """
    import xarray as xr

    from cassini_bayes.inference.runner import SamplerSettings, diagnostics, run_nuts

    settings = settings or SamplerSettings()
    problem = prepare_rwa4(tel, spacecraft, method=method, pairs=pairs, prior=prior,
                           inertia=inertia, wheel=wheel, robust=robust,
                           wheel_errors=wheel_errors)
    kw = problem.model_kwargs
    coords = {"w_dim": np.arange(_DIM)}
    dims = {"w": ["w_dim"]}
    idata = run_nuts(key, rwa4_model(problem.chart), model_kwargs=kw, settings=settings,
                     coords=coords, dims=dims, prior=lambda k, n: sample_rwa4_prior(k, problem, n),
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
