"""Thrust and pulse time-constant posterior from wheel-biasing events (Feldman & Lee 2006 §V).

Model
-----
Event ``e`` (one telemetry file and its pulse log) obeys the integrated Euler equation
(Feldman & Lee Eq 17, :mod:`cassini_bayes.physics.impulse`)

    V_e(t_i) = I Δω(t_i) + ΔH_RWA(t_i) + ΔG(t_i) = Q · (F ⊙ j_e(t_i; τd, τr, τf)),

where ``j_s(t_i)`` is the *actual* impulse per newton that thruster ``s`` has delivered by
``t_i``: every commanded pulse of width ``Δ`` contributes the integral of the thrust profile of
:mod:`cassini_bayes.physics.pulse` (Feldman & Lee §V closed form once the pulse has decayed), so
the likelihood depends on the time constants directly rather than through the paper's ratio
``R``. The time constants are shared by all events (same thrusters, same valves); the thrust is
one mean ``F`` (Eq 23, the papers' reproduction), one per branch ``F_Z``/``F_Y`` (Cassini's
layout of Eq 16), or one per thruster of any layout (mode ``thruster``, "Per-thruster model"
below), shared by the events too (pool only events of one epoch).

Per-thruster model (mode ``thruster``, any thruster layout)
-----------------------------------------------------------
``F`` has one entry per thruster of the model file (``summary.json``: ``F[<name>]``), each
``log F_s ~ Normal(log F_pred,s, 0.3)`` about its own ``F`` or the model's ``[thrust]``; ``Q`` is
built from each thruster's position and direction about the sampled centre of mass,
``Q_s = (r_s − e − δ) × d_s`` (Feldman & Lee Eq 16 for any layout), ``δ`` = (``com_x``,
``com_y``, ``com_z``) m the true centre of mass minus the model file's, ``δ_k ~ Normal(0,
[center_of_mass] sd_m)``. Only firings with a net force (``Σ F_s d_s j_s ≠ 0``) tell ``δ``. The
sampler's thrust and offset coordinates are the prior-whitened ``(log F, δ)`` rotated into the
singular directions of the linearised impulse design
(:mod:`~cassini_bayes.inference.thrust.design`): the combinations the events determine are
coordinate axes, those they leave at the prior the others, with nothing named by hand. The
design's rank, the thrusters identified one by one and the identified combinations of the others
(Cassini's Y pairs fired together, with the Y thrusters in the centre of mass's plane, give the
pair means of Eq 21) are on ``ThrustProblem.design``; ``F_combination`` (N) along
``combination`` holds each combination's posterior.

Error model (why the cumulative form, with a free offset)
---------------------------------------------------------
With white gyro noise ``n_i`` and wheel-rate noise ``ν_i`` the measured left side is
``V(t_i) = V_true(t_i) + [I n_i + Σ J_k ν_ki g_k] − [I n_0 + Σ J_k ν_k0 g_k] + δG_i``. The bracket
at ``t_0`` is common to every sample of the event: it is an unknown constant offset ``b_e``, not
a random walk. With ``b_e`` a free parameter the residuals ``V − Q J − b_e`` are independent,
``N(0, B_e)`` with ``B_e = σ_ω² I I + σ_ρ² Σ_k J_k² g_k g_kᵀ`` — the calibrated model. (Increments
between samples would instead be MA(1)-correlated with lag-one correlation −½.) ``δG_i``, the
error of the gyroscopic impulse integrated from noisy rates, is a random walk but ~10× below the
gyro term on the shipped scenarios (|H_RWA| ≤ 30 N m s, 1 µrad/s gyro noise); it is neglected.
``ΔG`` is the trapezoid on the samples (:func:`~cassini_bayes.physics.impulse.gyroscopic_impulse`),
exact for rates linear between samples; a pulse steps the rate between two samples, and the
likelihood adds back what the trapezoid misses across each step
(:func:`~cassini_bayes.physics.impulse.rate_step_correction`: linear in ``F``, at the pulses'
centroids for the prior-median time constants), and at second order the steps' moments and
the rate's bend inside each interval by Euler's equation
(:mod:`~cassini_bayes.physics.rate_step_moments`). Without them a spacecraft whose wheels hold
newton-metre-seconds while its dead band fires has residuals far above its sensor noise, and
its thrusts, centre of mass, noise levels and wheel scales absorb them
(docs/thrust_any_layout.md).
``b_e`` has a flat prior and is integrated out analytically:

    log p(V_e | θ) = Σ_i log N(r_i − r̄; 0, B_e) + (3/2) log 2π + ½ log|B_e| − (3/2) log n_e.

Priors, stated in the physical parameters
-----------------------------------------
* ``log F ~ Normal(log F_pred, 0.3)`` per thrust parameter, ``F_pred`` the spacecraft model's
  predicted thrust: the flight history (0.97 N at launch, 0.75 N at SOI, 0.69 N at the Probe
  relay) moves by ~30 %.
* Pulse time constants, from the spacecraft model's ``[pulse]`` section (:func:`tau_prior`). The
  papers' profile (delay, exponential rise, hold, exponential fall;
  :mod:`~cassini_bayes.physics.pulse`) contains real valves that the manufacturer's ranges (delay
  3-7 ms, rise 15-25 ms, fall 40-90 ms) exclude: a first-order valve (no delay, one time
  constant ``τ`` for rise and fall; docs/robust/README.md) is ``τd = 0``, ``τr = τf = τ``. The
  prior covers it:

  - ``τd ~ HalfNormal(σ_d)``, ``σ_d`` = the upper end of ``tau_delay_range`` (7 ms): largest
    density at ``τd = 0`` (a valve that opens at once), median 4.7 ms ≈ the nominal 5 ms, 85 %
    below 10 ms, the 3-7 ms range 35 %. A log-normal (the earlier prior, or one on ``τd + ε``) has
    no density, or an arbitrary ``ε``, at 0.
  - ``log τr``, ``log τf ~ Normal(log √(lo·hi), max(ln(hi/lo)/4, tau_log_sd_min))``, centred on
    the manufacturer's range ``[lo, hi]``; ``tau_log_sd_min`` = 0.45 by default widens the
    ranges' ±2σ (sd 0.13 and 0.20) so that the rise prior's ±2σ is 7.9-48 ms and the fall's
    24-148 ms: ``τr = τf = 45 ms`` has prior density 0.17 × the mode's along ``τr`` (it was
    ``e^{−22}``, 6.6σ out). On 1-s telemetry the data hardly resolve the shape, so this prior is
    what the shape terms of short pulses average over (section "Pulse family" below).
* Noise, per event: ``(σ_ω, σ_ρ) = s_e (σ̂_ω, σ̂_ρ)`` with ``log s_e ~ Normal(0, 1)``, ``σ̂`` the
  data's own white-noise levels (:func:`rate_noise_levels`). One scale, not two: the gyro term of
  ``B_e`` outweighs the wheel term ~100× on the shipped scenarios, so a free ``σ_ρ`` is
  unidentified below ``σ̂_ρ`` and cut off sharply above it — a one-sided cliff NUTS handles badly
  (docs/performance.md, "Thrust model choices, measured"); the mix of the two comes from the
  data, the overall level is learned.
* Inertia: sampled jointly from a Gaussian — the model file's knowledge (±10 % moments, ±75 kg m²
  products; the robust model's default) or an inertia run's posterior — or fixed at the model
  file's prediction (the papers' idealised model). The likelihood then carries the Jacobian
  ``|det I|`` per sample that maps the data (rates) to ``V`` (``likelihood.event_loglik``).

Sampler coordinates
-------------------
Pulse logs of widths ≥ 125 ms pin the thrust and the long-pulse excess
``c = τf − τr e^{−τd/τr}`` (:func:`long_pulse_excess`; a long pulse delivers ``F (Δ + c)``) to
~1e-4 of their prior widths, and leave ``τd``, ``τr`` near their prior: the posterior of
``log τ`` is a ridge a few microseconds wide along a curved surface, on which NUTS stalls
(docs/performance.md). The sampler therefore sees
``f_z`` (prior-whitened ``log F``), ``a_z`` (the rise deficit ``a = τd + τr e^{−τd/τr}`` =
``a_mu e^{0.4 a_z}``, :func:`rise_deficit`: a pulse still on has delivered ``F (t − a)``, so the
samples inside pulses pin it), ``s_z = asinh s`` (``s`` its split, ``τd = a σ(s)``,
``a − τd = a σ(−s)``, σ the logistic function; the ``asinh`` folds the long tail of ``s`` towards
``τd → 0`` that the half-normal delay prior leaves) and ``c_z`` (``c = c_mu + 0.01 s · c_z``);
``τr``, ``τf`` follow in closed form,
the prior carried over by the Jacobian (``coords.tau_from_z``). With the delay free over 0-10 ms
the earlier coordinates ``(log τd, log τr, c)`` left a second curved ridge (``a`` fixed), and
sampling ``a`` additively beside the delay (``a − τd`` free to reach 0) put a wall at ``τr = 0``
into the sampler's space, behind a density spike (docs/performance.md, "Thrust model choices,
measured").
Where the events fire every thrust parameter at one pulse width (an ESPA-class bus's dead band
at 125 ms), they measure its impulse bit ``F j(Δ; τ)`` and leave ``F`` to trade against the
pulse shape along the curved ridge ``F j(τ) = const``; there ``f_z`` is the prior-whitened
``log F + log j(Δ; τ) − log j(Δ; τ̃)`` instead (``τ̃`` the prior median), the ridge a coordinate
axis, the prior carried over exactly (a unit-triangular map,
:func:`~cassini_bayes.inference.thrust.coords.physical`), and the fit
adds the impulse bits ``bit`` (N s) to the posterior. Events with several widths (Cassini's
125/250/500 ms) keep ``log F``.
``noise_z`` (``log s_e`` in units of 0.1) and ``inertia_z`` (whitened by the
Gaussian's Cholesky factor); then ``w`` with ``θ = centre + tril w``, ``centre``/``tril`` a
Laplace approximation of the posterior (:func:`cassini_bayes.inference.laplace.laplace`). The
density is exact in ``θ``; the maps only condition the geometry.

Robust model (``robust=True``, the default; Lee 003 §4.1, Psiaki 2005)
-------------------------------------------------------------------------
Nuisance parameters ``ν`` with zero-mean Normal priors from the spacecraft model's knowledge
sections (:func:`cassini_bayes.inference.nuisance.nuisance_layout`, the same layout and priors as
the robust inertia model), each entering the predicted left side of Eq 17 linearly:

* body-fixed external torque ``T_e`` (N m, per event): ``+ T_e (t − t_0)`` (the attitude is held in
  the dead-band, so body and inertial axes agree to milliradians), and its rate ``Ṫ_e`` (N m/s,
  per event; site ``T_N_rate``, prior ``[torque_knowledge] rate_sd_nm_per_h``):
  ``+ ½ Ṫ_e (t − t_0)²``: a small spacecraft's environment torque changes within an event, and
  unmodelled its drift moves the centre of mass and the inertia;
* gyro bias ``b_e`` (rad/s, per event): the integrated gyroscopic term gains
  ``∫ (b × (I ω + H_w) + ω × I b) dt`` (the constant ``I b`` is absorbed by the offset);
* gyro scale factors ``s``: ``+ I δω`` and the same ``ΔG`` terms, ``δω = s ∘ ω_meas``; both
  with the rate-step correction's part (:mod:`~cassini_bayes.inference.thrust.columns`), so
  every column is the derivative of the left side as the model computes it;
* wheel spin-inertia errors ``c_k``, one per active wheel (``wheel_errors="per_wheel"``, the
  default): the true wheel momentum is ``H_w + Σ_k c_k J_k ρ_k g_k``, so the left side computed
  with the model's wheels is ``Q F j − Σ_k c_k (J_k ρ_k g_k + ∫ ω × J_k ρ_k g_k dt)`` (the wheel
  momentum enters ``ΔG``, Eq 15, too, and the trapezoid's correction across the pulses' rate
  steps, ``Σ δθ × δH_m``, :func:`~cassini_bayes.inference.thrust.columns.rotation_errors`);
  ``"common"``: one ``c`` for all, ``− c (H_w + ∫ ω × H_w dt)``, and its rate-step term;
* wheel spin-axis tilts ``a_k``: ``− Σ_j a_kj (J_k ρ_k u_kj + ∫ ω × J_k ρ_k u_kj dt)``, and its
  rate-step term;
* telemetry time-tag errors (white, sd ``σ_t``: ``Knowledge.time_tag_sd_s``, 10 ms by default,
  times a scale the sampler learns, log-normal-like with median 1 and log sds 1.5 below and 0.5
  above, :data:`~cassini_bayes.inference.thrust.prior.TAG_SCALE_LOG_SD`; posterior site
  ``time_tag_sd``, s; a statement held fixed pulls the thrusts of a single-width event along the
  ridge ``F j(τ) = const`` wherever it differs from the telemetry's):
  a sample tagged ``δ`` late is compared with the impulse delivered by ``t_i + δ``, off by the
  thrusters' torque at ``t_i`` times ``δ`` — noise only on the samples taken during a pulse, which
  carry the timing information of the time constants, so it enters the sample's covariance
  instead of a parameter (:func:`time_tag_rates`: the impulse rates evaluated once, at the
  prior's time constants, times the sampled thrust, so that it keeps the likelihood's invariance
  under the common scale of ``I``, ``F`` and the wheels). Without it the time constants'
  intervals miss under the telemetry's real jitter (docs/performance.md, "Thrust model choices,
  measured"). Where a pulse's edge lies within a tag's reach of a sample, a first-order
  expansion fails: there the rate is its expectation over the tag (statistical linearisation,
  :func:`~cassini_bayes.inference.thrust.likelihood.tag_expectation`, chosen by
  :func:`~cassini_bayes.inference.thrust.time_tags.with_tag_expectation`). The same error moves
  the left side's ``ΔG`` (Eq 15, with its correction across the rate steps): at the sample, a
  second rank-one term, and at every later sample a random walk stepping at the pulses, one
  column of ``ν`` per sample whose step matters
  (:mod:`~cassini_bayes.inference.thrust.time_tags`; none on Cassini, whose gyroscopic torque is
  far below its noise).
* or, where the model file states a regular clock (``Knowledge.regular_clock``), in place of
  the white tags: each event's labels put on their least-squares grid, and the grid's offset
  and period error, two columns of ``ν`` per event (:mod:`~cassini_bayes.inference.thrust.
  clock`): white tags at a pulse's edge are far from linear, and the grid alone leaves its
  offset in the delay (docs/planning.md, "A regular clock").

``ν`` enters the residuals linearly with a Gaussian prior, so it is **integrated out exactly**
rather than sampled (as in the robust RWA4 model): per event the offset is removed
(:func:`offset_marginal`), leaving a log-likelihood quadratic in ``ν``; the events' terms add,
and :func:`nuisance_marginal` integrates the Gaussian (an R × R Cholesky; R = 22 for one
event with three wheels). The sampler keeps the idealised model's coordinates (5 for one event
and one ``F``) and the time tags' scale; :func:`fit_thrust` then draws ``ν`` from its exact
Gaussian conditional at each draw, so the posterior's nuisance sites are joint posterior
draws. Sampled instead (21 coordinates on one event), the time-tag term left a banana: the
conditional mean of the torque about Z moved with ``τr²`` by about one conditional sd per unit of
whitened ``τr``, which no affine whitening removes; integrated out, it leaves none
(docs/performance.md, "Thrust model choices, measured").

The common part of the wheel scales is confounded with the thrust scale (``F`` balances the
wheel momentum the event builds). With the inertia sampled (the robust default) Eq 17 is
homogeneous in the inertia, the thrusts, the torques and every wheel's spin inertia, so the data
cannot tell their common scale ``u``: the likelihood holds the wheels at the model file's common
scale (``ν`` keeps each wheel's deviation from it,
:func:`~cassini_bayes.inference.nuisance.without_common_scale`), and :func:`fit_thrust` draws
``u`` from its prior (``√(σ_s² + 1/Σ_k σ_k⁻²)``, 0.58 % for three wheels at the defaults) and
reports the thrusts, the inertia and the torques times ``1 + u``
(:attr:`ThrustProblem.scale_free`). A common-scale column in ``ν`` instead would leave the
left side's wheel-rate noise and its rate-step corrections at the file's wheels while the column
scaled them, which tilts the ridge where the tachometers' noise is as large in momentum as the
gyro's (docs/planning.md, "The fit's density did not keep that ridge flat"). With the inertia
fixed the common scale is one column of ``ν`` like the others. The idealised model claims
0.01 % on clean data.

Pulse family (what the data can and cannot say about the shape)
---------------------------------------------------------------
The profile of :mod:`~cassini_bayes.physics.pulse` with ``τd = 0`` and ``τr = τf = τ`` is a
first-order valve, whose pulse impulse is exactly ``F Δ`` for every width: from impulses alone
only ``F`` and ``c`` (here 0) are learned, not ``τ``. ``F`` rests on what is shape-free: two
pulses much longer than every time constant (500 and 750 ms) differ in impulse by
``F (Δ1 − Δ2)`` whatever the shape, which the sampled ``c`` expresses (every long pulse delivers
``F (Δ + c)``, ``c`` free). What remains shape-dependent is the ``e^{−Δ/τr}`` part of short
pulses (``e^{−125/45} = 6 %`` of a 125-ms pulse's rise for a 45-ms valve) and the samples taken
during a pulse, which are what resolves ``τr`` on 1-s telemetry. The earlier prior (every range
±2σ of a log-normal) put ``c = 0`` at ~7σ (``τf`` ≈ 15 ms), so on an event whose widths cannot
separate ``F`` from ``c`` it moves ``F`` instead (reported on an independent simulator's
first-order valve: −2.1 % and −1.1 % at sd 0.17 %; on this package's 1-s simulations the samples
inside pulses overrode it, docs/robust/README.md "Thrust pulse family").
:func:`tau_identification` names in ``summary["warnings"]`` (through
:class:`TauIdentificationWarning`) each time constant the data leave at its prior (contraction
< 0.1) or pull outside the prior's central 99 % (the data disagree with the ``[pulse]`` ranges).

Identification
--------------
Combinations of thrusts the data cannot separate keep their prior: a thruster that never fires,
or in the paper's Z-row-only regression the pairs ``F_Y1``/``F_Y3``, ``F_Y2``/``F_Y4`` that fire
together (Eq 20). Here all three torque axes are used, so the X torque of a pair
(``Lzy (F_Y1 − F_Y3)``) separates pair members where the data resolve it; what is not resolved
shows as a posterior equal to the prior (``ThrustProblem.fired`` lists which thrusters fired).
"""

from cassini_bayes.inference.gaussian import inv3_spd
from cassini_bayes.inference.inertia.knowledge import (InertiaGaussian, inertia_from_idata,
                                                       inertia_from_run, inertia_prior_gaussian)
from cassini_bayes.inference.noise import rate_noise_levels
from cassini_bayes.inference.thrust.coords import (A_LOG_SCALE, C_SCALE_S, long_pulse_excess,
                                                   rise_deficit)
from cassini_bayes.inference.thrust.data import ThrustData, ThrustProblem, prepare_thrust
from cassini_bayes.inference.thrust.design import ThrustDesign, thrust_design
from cassini_bayes.inference.thrust.fit import RESIDUAL_DRAWS, ThrustPosterior, fit_thrust
from cassini_bayes.inference.thrust.likelihood import (thruster_impulse, impulse_residuals,
                                                       pulse_layout, time_tag_rates)
from cassini_bayes.inference.thrust.model import thrust_model
from cassini_bayes.inference.thrust.prior import (COM_NAMES, CONTRACTION_UNIDENTIFIED, MODES,
                                                  NOISE_PRIOR_LOG_SD, PRIOR_CONFLICT_MASS,
                                                  THRUST_PRIOR_LOG_SD, TauIdentificationWarning,
                                                  TauPrior, draw_tau_prior, resolve_inertia,
                                                  sample_thrust_prior, tau_identification,
                                                  tau_prior, thrust_names)
from cassini_bayes.names import TAU_NAMES

__all__ = [
    "TAU_NAMES",
    "MODES",
    "THRUST_PRIOR_LOG_SD",
    "NOISE_PRIOR_LOG_SD",
    "A_LOG_SCALE",
    "C_SCALE_S",
    "InertiaGaussian",
    "inertia_from_run",
    "inertia_from_idata",
    "inertia_prior_gaussian",
    "resolve_inertia",
    "TauPrior",
    "tau_prior",
    "draw_tau_prior",
    "tau_identification",
    "TauIdentificationWarning",
    "CONTRACTION_UNIDENTIFIED",
    "PRIOR_CONFLICT_MASS",
    "thrust_names",
    "COM_NAMES",
    "ThrustDesign", "thrust_design",
    "ThrustData", "ThrustProblem",
    "prepare_thrust",
    "pulse_layout",
    "thruster_impulse",
    "time_tag_rates",
    "impulse_residuals",
    "inv3_spd",
    "long_pulse_excess",
    "rise_deficit",
    "rate_noise_levels",
    "thrust_model",
    "sample_thrust_prior",
    "RESIDUAL_DRAWS",
    "ThrustPosterior",
    "fit_thrust",
]
