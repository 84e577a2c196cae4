"""A wheel's spin-axis posterior on the sphere (Brown 2012 §III.B, §III.C, made Bayesian): any
wheel of the spacecraft model, Cassini's RWA4 by default (the package keeps Brown's name).

Model
-----
Both of Brown's methods rest on the conservation of the total inertial angular momentum between
quiet windows (no thruster firing). Per sample ``i`` of window group ``g`` (an "A"/"B" window
pair)

    A(q_i)ᵀ c_i = H_g,    c_i = I ω_i + Σ_known J_k ρ_k,i g_k + J_4 ρ_4,i u4      (Brown Eqs 1, 3)

(``A(q)`` inertial→body, Brown Eq 2; ``I`` kg m²; ``ρ`` rad/s; ``J`` kg m²). Brown averages each
window and solves the difference for ``u4``; so does the likelihood here (:func:`loglik`): the
change of the window-mean inertial momentum is zero up to the noise of the means. Not a
per-sample likelihood: the drift samples carry inertia information that a simulator's dynamics
do not match to the gyro-noise level, so the window means, Brown's own information, are used
(docs/performance.md, "Other model choices, measured").

* RCS method (Eq 1): one pair, "Time A" before and "Time B" after the RWA4 spin-up while the
  spacecraft drifts; RWA4 is the only wheel and ``I ω`` carries the balance, so the inertia matters.
* RWA method (Eq 3): one pair per slew pair (quiescent windows at two attitudes), RWA2 and RWA3
  known; ``I ω`` is small but kept. Each quiet window adds its momentum's least-squares *slope*
  against time, ``s_w = Σ_i w_i A(q_i)ᵀ c_i``, ``w_i = (t_i − t̄_w)/Σ(t − t̄_w)²`` (N m): under
  RWA control the wheels absorb the external torque, so ``dH/dt = T`` (Euler's law, Feldman &
  Lee Eq 2 with the wheels' momentum) makes ``s_w`` the torque at the window, zero for a perfect
  model (:func:`~cassini_bayes.inference.rwa4.likelihood.slopes`). The means see a torque only
  through its integral between the windows, known as well as its prior; the slopes measure it.
  Not for the RCS method, whose Time B drifts with thrusters and dead-band.

Noise: linearising the gyro (``σ_ω``) and wheel-rate (``σ_ρ``) errors gives the body covariance
``B = σ_ω² I I + σ_ρ² Σ_k J_k² g_k g_kᵀ`` (``g_4 = u4``) per sample, rotated to inertial axes and
averaged over each window (a slope: weighted by ``w_i²``); the levels are fixed at the data's own
white-noise estimates σ̂ (three numbers per pair cannot estimate them). The normalising
determinant takes that covariance at the prior-mean inertia and the chart's centre axis: the
noise in ``d`` already moves with ``I`` and ``u4``, so a determinant at the sampled ones would
count it twice and pull the inertia low (:func:`loglik`). A window's mean and slope
weights are orthogonal (``Σ_i (t_i − t̄_w) = 0``), so their noise is uncorrelated to first order
(exactly for a constant ``A_iᵀ B A_i``) and the covariance is block diagonal.

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
pairs and slopes together (one effect is shared by every row; a slope row's columns are the
slopes of the same per-sample columns, so a torque enters it as its value at the window). The
RWA method feels them most: 0.2° tilts of RWA2 and RWA3, whose momenta match RWA4's, move
Brown's axis by tenths of a degree, 20–50× the idealised posterior's width on
``rwa4_rwa_real``; :func:`axis_sensitivity` reports each effect's shift. ``robust=False`` is
Brown's idealised model.

Priors
------
* ``u4`` (the solved wheel's axis, whatever its name): uniform on the sphere, or concentrated
  on the wheel's articulation cone when the spacecraft model gives one (``[[wheel]]``
  ``cone_axis``, ``cone_deg``, ``cone_sd_deg``; :class:`~cassini_bayes.spacecraft.WheelCone`):
  angle ``θ`` from the cone's axis within ``Normal(cone_deg, cone_sd_deg)``, any articulation
  angle, a factor ``−½ ((θ(u4) − cone_deg)/cone_sd_deg)²``
  (:func:`~cassini_bayes.inference.rwa4.prior.cone_log_factor`). Cassini's RWA4: 54.7356° from
  +Z, 1° (the mechanical cant tolerance we assume; the 1/8 s articulation-command resolution,
  ≈ 1.5°, Brown §I, moves the azimuth, not the cant). A model without a cone for the wheel
  allows the uniform prior only.
* Inertia: the spacecraft model's predicted tensor with its knowledge requirements as 1σ (the
  prior of :mod:`cassini_bayes.inference.inertia`), or a Gaussian (an inertia run's posterior);
  sampled jointly, so the mass-property error is part of the posterior (Brown's Monte Carlo
  analysis, ≤ 1.5°, comes out of the posterior instead of being added afterwards). The stated
  prior, the same in both charts and in :func:`sample_inertia_prior` (SBC truths included), is
  this Gaussian times the physical factor ``1 − exp(−(m/s)³)`` (:func:`log_physical_factor`):
  ``m`` the smallest eigenvalue of the second moment ``½ tr(I) 1 − I`` (positive exactly for
  positive-definite tensors obeying the triangle inequalities), ``s`` half its value at the
  prior mean. The factor is 0 for unphysical tensors, 1 − 3e-4 at the mean, 0.63 half-way to
  the boundary: a stated softening of the truncation near the boundary, which NUTS needed
  while the RCS chart kept the boundary at a finite distance (``docs/robust/README.md``).

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
  change of ``⟨ρ₄ Aᵀ⟩``, ``M π`` that of ``⟨Aᵀ I ω⟩``), ``z = a + K ξ`` linear: the data fix
  ``z = −u``, i.e. ``|z| = 1`` and the direction of ``z``. In Cartesian ``π`` and ``u`` this is a
  narrow curved ridge that NUTS cannot follow, so the chart makes the two constraints
  coordinates: ``θ = (δ, ρ, y)`` with ``ρ = log|z|`` and ``u = g(v_z + δ)``, ``v_z`` the chart
  coordinates of ``−z``; the data say ``ρ ≈ 0``, ``δ ≈ 0``, linearly. Along the ridge ``u`` and
  ``ξ`` move together (the axis is limited by the inertia prior), into the physical boundary;
  the five coordinates ``y`` therefore cover exactly the physical tensors, the boundary at
  infinity. ``π`` is a positive multiple of ``ξ − ξ_a`` (``ξ_a = −L⁻¹μ``, zero inertia, where
  ``z = z_a``): writing ``z − z_a = t ζ(s)`` (``ζ`` the gnomonic chart about ``−u0``, ``t > 0``
  set by ``|z| = e^ρ``) and the prior-only complements ``w − w_a = t ω/√(1 + |s|²)``,
  ``π = (t/√(1 + |s|²)) P [1; s; ω]``, so the physical tensors are one convex region
  ``A(x) ≻ 0`` of ``x = (s, ω)`` (``A`` affine: the second moment of ``P [1; x]``), whatever
  ``ρ`` and ``δ``. A radial map from the prior mean's ``x`` (:func:`~cassini_bayes.inference.
  rwa4.model._radial`), the identity up to half-way to the wall along each ray, sends ``y ∈ R⁵``
  onto it; beyond the knee the density falls exponentially in ``y``, a slope instead of the
  physical factor's log barrier, which NUTS's leapfrog steps jumped over (divergences).
  Jacobian ``(1 + |v|²)^(−3/2) · t² e^{2ρ}/(t + z_a·ζ) (1 + |s|²)^(−3/2) · (t/√(1 + |s|²))³`` times
  the radial map's. The chart needs ``|z_a| < ½ |a|`` (``z_a = 0`` for RWA4 alone; other wheels
  running move it), else the RWA chart is used.

Finally the sampler sees ``w`` with ``θ = centre + tril w``, ``centre``/``tril`` a Laplace
approximation (:func:`cassini_bayes.inference.laplace.laplace`). The density is exact in ``θ``;
the affine map only conditions the geometry (measured: ``docs/robust/README.md``, "RWA4 RCS
chart").
"""

from cassini_bayes.inference.rwa4.data import (MAX_SD_DIRECTION_DEG, METHODS, Rwa4Data,
                                               Rwa4Problem, prepare_rwa4)
from cassini_bayes.inference.rwa4.fit import Rwa4Posterior, axis_sensitivity, fit_rwa4
from cassini_bayes.inference.rwa4.likelihood import balance_misfit
from cassini_bayes.inference.rwa4.model import rwa4_model
from cassini_bayes.inference.rwa4.prior import (PRIORS, cone_log_factor, sample_inertia_prior,
                                                sample_rwa4_prior)
from cassini_bayes.inference.rwa4.windows import MIN_SPIN_CHANGE_RPM, WHEEL, detect_windows
from cassini_bayes.names import U4_NAMES

__all__ = [
    "U4_NAMES",
    "METHODS",
    "PRIORS",
    "cone_log_factor",
    "MIN_SPIN_CHANGE_RPM",
    "MAX_SD_DIRECTION_DEG",
    "WHEEL",
    "detect_windows",
    "balance_misfit",
    "Rwa4Data", "Rwa4Problem",
    "prepare_rwa4",
    "rwa4_model",
    "sample_rwa4_prior",
    "sample_inertia_prior",
    "Rwa4Posterior",
    "fit_rwa4",
    "axis_sensitivity",
]
