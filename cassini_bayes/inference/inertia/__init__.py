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
enter the likelihood at all: scaling ``I``, ``H_0``, ``T_N`` and every wheel inertia together leaves
every momentum balance unchanged (Psiaki 2005). Dividing the balance by ``1 + c`` shows what the
data see: ``π̃ = π/(1 + c)`` (likewise ``H_0``, ``T_N``) and the wheel scales relative to the common
one, ``δ_k = (c_k − c)/(1 + c)``, which enter linearly (column ``J_k ρ_k g_k``) and are exact:
``(1 + c_k)/(1 + c) = 1 + δ_k``. The model sets ``π = (1 + c) π̃`` and ``c_k = c + (1 + c) δ_k``;
``c`` keeps its prior and the moments' posterior sd carries it (prior sd ``√(σ_s² + σ_J²/K)``:
0.58 % for three wheels at the default 0.5 % shared and 0.5 % each; 0.5 % in the common model),
while the ``δ_k`` are learned from slews about several axes. The constant external torque ``T_N`` is
in both models (``torque=True``), prior sd the model file's ``[torque_knowledge] sd_nm`` per axis
(default 15 µN m, the Feldman & Lee App. A bound; Brown quotes solar/gas torques of the same
few-µN m order).

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
* ``H_0 ~ Normal(0, C)`` per axis, ``C`` the wheels' momentum capacity ``Σ_k J_k ρ_max,k``
  (:attr:`~cassini_bayes.spacecraft.Spacecraft.momentum_capacity_nms`; Cassini's four wheels
  hold 4 × 34 N m s, Brown §I): relative to the spacecraft, as every prior scale here.
* ``T_N ~ Normal(0, [torque_knowledge] sd_nm)`` per axis (default 15 µN m: Feldman & Lee App. A
  bound for March 2000).
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

from cassini_bayes.inference.inertia.data import (MIN_RATE_SNR, InertiaData, InertiaProblem,
                                                  noise_levels, prepare_inertia)
from cassini_bayes.inference.inertia.fit import (AXES, ROBUST_SITES, InertiaPosterior,
                                                 fit_inertia, robust_sites)
from cassini_bayes.inference.inertia.knowledge import (InertiaGaussian, inertia_from_idata,
                                                       inertia_from_run, inertia_prior_gaussian)
from cassini_bayes.inference.inertia.likelihood import momentum_residuals, noise_covariance
from cassini_bayes.inference.inertia.model import inertia_model, problem_model
from cassini_bayes.inference.inertia.prior import (NOISE_NAMES, NOISE_PRIOR_LOG_SD,
                                                   InertiaPrior, cholesky_params_from_pi,
                                                   inertia_prior, is_physical,
                                                   pi_from_cholesky_params, sample_prior)
from cassini_bayes.names import INERTIA_NAMES

__all__ = [
    "NOISE_PRIOR_LOG_SD",
    "NOISE_NAMES",
    "INERTIA_NAMES",
    "MIN_RATE_SNR",
    "AXES",
    "InertiaPrior",
    "InertiaData", "InertiaProblem",
    "InertiaGaussian",
    "inertia_prior",
    "inertia_prior_gaussian",
    "inertia_from_run",
    "inertia_from_idata",
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
    "noise_covariance",
    "InertiaPosterior",
    "fit_inertia",
    "ROBUST_SITES",
]
