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
one mean ``F`` (Eq 23), one per branch ``F_Z``/``F_Y``, or one per thruster ``F_Z1 … F_Y4``
(Eqs 19-20), shared by the events too (pool only events of one epoch).

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
  constant ``τ`` for rise and fall, 38-54 ms measured on an independent simulator) is
  ``τd = 0``, ``τr = τf = τ``. The prior covers it:

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
  (measured: divergences and bulk ESS ~100 on two Table 2 events); the mix of the two comes from
  the data, the overall level is learned.
* Inertia: sampled jointly from a Gaussian — the model file's knowledge (±10 % moments, ±75 kg m²
  products; the robust model's default) or an inertia run's posterior — or fixed at the model
  file's prediction (the papers' idealised model). The likelihood then carries the Jacobian
  ``|det I|`` per sample that maps the data (rates) to ``V`` (:func:`_event_loglik`).

Sampler coordinates
-------------------
Pulse logs of widths ≥ 125 ms pin the thrust and the long-pulse excess
``c = τf − τr e^{−τd/τr}`` (:func:`long_pulse_excess`; a long pulse delivers ``F (Δ + c)``) to
~1e-4 of their prior widths, and leave ``τd``, ``τr`` near their prior: the posterior of
``log τ`` is a ridge a few microseconds wide along a curved surface, on which NUTS stalls (step
sizes 0.02, tree depth 6, R-hat 1.05 before this parameterisation). The sampler therefore sees
``f_z`` (prior-whitened ``log F``), ``a_z`` (the rise deficit ``a = τd + τr e^{−τd/τr}`` =
``a_mu e^{0.4 a_z}``, :func:`rise_deficit`: a pulse still on has delivered ``F (t − a)``, so the
samples inside pulses pin it), ``s`` (its split, ``τd = a σ(s)``, ``a − τd = a σ(−s)``, σ the
logistic function) and ``c_z`` (``c = c_mu + 0.01 s · c_z``); ``τr``, ``τf`` follow in closed form,
the prior carried over by the Jacobian (:func:`_tau_from_z`). With the delay free over 0-10 ms
the earlier coordinates ``(log τd, log τr, c)`` left a second curved ridge (``a`` fixed): 1-6
divergences, R-hat up to 1.048 and bulk ESS ~60 on the idealised fit of
``biasing_day028_first_order`` (2 × 300 + 300). Sampling ``a`` additively beside the delay
(``a − τd`` free to reach 0) put a wall at ``τr = 0`` into the sampler's space, behind a
density spike: the open-world papers'-profile campaign diverged on 8 of 20 seeds (up to 263).
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
  the dead-band, so body and inertial axes agree to milliradians);
* gyro bias ``b_e`` (rad/s, per event): the integrated gyroscopic term gains
  ``∫ b × H_w dt = −[C_t]_× b``, ``C_t = ∫_{t_0}^{t} H_w ds`` (the constant ``I b`` is absorbed by
  the offset);
* gyro scale factors ``s``: ``+ I diag(ω_meas) s``;
* wheel spin-inertia errors ``c_k``, one per active wheel (``wheel_errors="per_wheel"``, the
  default): the true wheel momentum is ``H_w + Σ_k c_k J_k ρ_k g_k``, so the left side computed
  with the model's wheels is ``Q F j − Σ_k c_k J_k ρ_k(t) g_k``; ``"common"``: one ``c`` for all,
  ``− c H_w(t)``;
* wheel spin-axis tilts ``a_k``: ``− Σ_j a_kj J_k ρ_k u_kj``;
* telemetry time-tag errors (white, sd ``σ_t`` = ``Knowledge.time_tag_sd_s``, 10 ms by default):
  a sample tagged ``δ`` late is compared with the impulse delivered by ``t_i + δ``, off by the
  thrusters' torque at ``t_i`` times ``δ`` — noise only on the samples taken during a pulse, which
  carry the timing information of the time constants, so it enters the sample's covariance
  (:func:`time_tag_columns`, evaluated once at the prior's time constants and the predicted
  thrust) instead of a parameter. Without it the robust fits of 20 error draws
  of ``biasing_day028_real`` (10 ms jitter, flexible mode) covered ``τr`` and ``τf`` in 6 of 20
  90 % intervals; refits without the flexible mode still missed (``τr`` up to 8.7 sd), refits
  without the jitter did not (≤ 2.7 sd).

``ν`` enters the residuals linearly with a Gaussian prior, so it is **integrated out exactly**
rather than sampled (as in the robust RWA4 model): per event the offset is removed
(:func:`offset_marginal`), leaving a log-likelihood quadratic in ``ν``; the events' terms add,
and :func:`nuisance_marginal` integrates the Gaussian (an R × R Cholesky; R = 16 for one
event with three wheels). The sampler keeps the idealised model's coordinates (5 for one event
and one ``F``); :func:`fit_thrust` then draws ``ν`` from its exact Gaussian conditional at each
draw, so the posterior's nuisance sites are joint posterior draws. Sampled instead
(21 coordinates on one event), the time-tag term left a banana: the conditional mean of the torque about Z moved with ``τr²`` by about one conditional
sd per unit of whitened ``τr``, which no affine whitening removes — 84 divergences and R-hat up
to 1.054 over 20 error draws of ``biasing_day028_real``; integrated out, the worst of those
(seed 14: 5 divergences, tree depth 4-5) has none, at tree depth 2-3.

The common part of the wheel scales is confounded with the thrust scale (``F`` balances the
wheel momentum the event builds): the thrust posterior widens by about its prior sd (0.5 % in the
common model; ``√(σ_s² + σ_J²/K)`` per wheel with K wheels built up, 0.58 % at the defaults)
instead of claiming the 0.01 % that the idealised model claims on clean data.

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

from __future__ import annotations

import warnings
from functools import lru_cache
from pathlib import Path
from typing import NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np
import numpyro
import numpyro.distributions as dist
from numpyro.distributions import constraints

from cassini_bayes.errors import InputError, arg, spelled
from cassini_bayes.frames import skew
from cassini_bayes.inference.laplace import laplace
from cassini_bayes.inference.nuisance import (EFFECTS, nuisance_layout, split_nuisance,
                                              wheel_scale_columns)
from cassini_bayes.physics.impulse import THRUSTER_NAMES, impulse_lhs, moment_matrix
from cassini_bayes.physics.momentum import INERTIA_NAMES, inertia_matrix, inertia_vector
from cassini_bayes.physics.pulse import pulse_impulse, pulse_impulse_until
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import (PulseAtStartWarning, PulseLog, Telemetry,
                                     check_pulses_in_span)

__all__ = [
    "TAU_NAMES",
    "MODES",
    "THRUST_PRIOR_LOG_SD",
    "InertiaGaussian",
    "inertia_from_run",
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
    "ThrustProblem",
    "prepare_thrust",
    "pulse_increments",
    "inv3_spd",
    "long_pulse_excess",
    "rise_deficit",
    "rate_noise_levels",
    "thrust_model",
    "sample_thrust_prior",
    "ThrustPosterior",
    "fit_thrust",
]

TAU_NAMES = ("tau_delay", "tau_rise", "tau_fall")
MODES = ("mean", "branch", "thruster")
THRUST_PRIOR_LOG_SD = 0.3     # sd of log F (flight history 0.97 → 0.69 N, Feldman & Lee §V)
NOISE_PRIOR_LOG_SD = 1.0      # sd of log σ around the data's own noise level σ̂
_NOISE_STEP = 0.1             # log σ per unit of the sampled noise coordinate
C_SCALE_S = 0.01              # long-pulse excess c (s) per unit of its sampler coordinate
A_LOG_SCALE = 0.4             # log of the rise deficit a per unit of its sampler coordinate
_HALF_NORMAL_MEDIAN = 0.6744897501960817   # Φ⁻¹(3/4): median of a unit half-normal
_NOISE_FLOORS = np.array([1e-9, 1e-7])
# A pulse's thrust is negligible (e^{-1.5 s / 90 ms} < 1e-7) 1.5 s after its command ends.
_TAIL_S = 1.5
_BRANCH_INDEX = np.array([0, 0, 0, 0, 1, 1, 1, 1])
_PULSE_BUCKET = 64


# --------------------------------------------------------------------------------------------
# Priors
# --------------------------------------------------------------------------------------------

class InertiaGaussian(NamedTuple):
    """Gaussian knowledge of the inertia entries ``(Ixx … Iyz)``: ``mean`` (6,) kg m², ``cov``
    (6, 6) (kg m²)²; e.g. an inertia run's posterior mean and covariance."""

    mean: np.ndarray
    cov: np.ndarray


def inertia_from_run(run_dir: str | Path) -> InertiaGaussian:
    """Posterior mean and covariance of ``Ixx … Iyz`` from an inertia run directory.

    Reads ``RUN_DIR/posterior.nc`` (an earlier ``cassini-bayes fit inertia``). Raises
    :class:`InputError` when the file is missing or holds no inertia draws.
    """
    import arviz as az

    path = Path(run_dir) / "posterior.nc"
    if not path.is_file():
        raise InputError(f"{arg('inertia_posterior', run_dir)}: no posterior.nc there; give the "
                         "run directory of an earlier 'cassini-bayes fit inertia'")
    try:
        idata = az.from_netcdf(path)
    except Exception as e:  # unreadable netCDF
        raise InputError(f"{path}: cannot read it ({type(e).__name__}); give the run directory "
                         "of an inertia fit") from None
    return inertia_from_idata(idata, str(path))


def inertia_from_idata(idata, source: str) -> InertiaGaussian:
    """Posterior mean and covariance of ``Ixx … Iyz`` from an inertia fit's InferenceData
    (``source`` names it in errors)."""
    try:
        post = idata.posterior
        draws = np.stack([np.asarray(post[n].values, float).ravel() for n in INERTIA_NAMES], -1)
    except (KeyError, AttributeError) as e:
        raise InputError(f"{source}: no inertia draws ({e.args[0]} missing); give the run "
                         "directory of an inertia fit") from None
    if draws.shape[0] < 10 or not np.all(np.isfinite(draws)):
        raise InputError(f"{source}: too few or non-finite inertia draws; re-run the inertia fit")
    cov = np.cov(draws, rowvar=False)
    return InertiaGaussian(draws.mean(0), 0.5 * (cov + cov.T))


def inertia_prior_gaussian(spacecraft: Spacecraft) -> InertiaGaussian:
    """The model file's inertia knowledge as a Gaussian: mean the predicted tensor, independent
    sd ``moi_uncertainty × moment`` and ``poi_uncertainty`` (the inertia model's prior,
    :func:`cassini_bayes.inference.inertia.inertia_prior`, without its truncation to physical
    tensors, which ±10 % about a physical prediction does not reach)."""
    from cassini_bayes.inference.inertia import inertia_prior

    prior = inertia_prior(spacecraft)
    return InertiaGaussian(prior.mean, np.diag(prior.sd ** 2))


def resolve_inertia(inertia: InertiaGaussian | str | None, spacecraft: Spacecraft,
                    robust: bool) -> InertiaGaussian | None:
    """The inertia's Gaussian, or ``None`` for a fixed inertia, from :func:`fit_thrust`'s
    ``inertia`` argument."""
    if inertia is None:
        inertia = "prior" if robust else "fixed"
    if isinstance(inertia, InertiaGaussian):
        return inertia
    if inertia == "prior":
        return inertia_prior_gaussian(spacecraft)
    if inertia == "fixed":
        return None
    raise InputError(f"inertia = {inertia!r}: give an InertiaGaussian, 'prior' or 'fixed'")


class TauPrior(NamedTuple):
    """Prior of ``(τd, τr, τf)`` (module docstring): ``τd ~ HalfNormal(delay_scale)`` (s);
    ``log τr``, ``log τf`` ~ ``Normal(log_mean, log_sd)``, ``log_mean`` (2,) log s and
    ``log_sd`` (2,) for rise and fall."""

    delay_scale: float
    log_mean: np.ndarray
    log_sd: np.ndarray

    def median(self) -> np.ndarray:
        """(3,) s: the prior medians of ``τd, τr, τf`` (half-normal median 0.6745 σ)."""
        return np.r_[_HALF_NORMAL_MEDIAN * self.delay_scale, np.exp(self.log_mean)]

    def central(self, mass: float) -> np.ndarray:
        """(3, 2) s: the central interval of each time constant holding ``mass`` of the prior."""
        from scipy.stats import norm

        z = np.array([-1.0, 1.0]) * norm.ppf(0.5 + 0.5 * mass)
        delay = self.delay_scale * norm.ppf([0.75 - 0.25 * mass, 0.75 + 0.25 * mass])
        lognormal = np.exp(self.log_mean[:, None] + z[None, :] * self.log_sd[:, None])
        return np.vstack([delay, lognormal])

    def variance(self) -> np.ndarray:
        """(3,) s²: the prior variances of ``τd, τr, τf`` (half-normal, log-normal)."""
        s2 = np.asarray(self.log_sd) ** 2
        return np.r_[self.delay_scale**2 * (1.0 - 2.0 / np.pi),
                     np.expm1(s2) * np.exp(2.0 * np.asarray(self.log_mean) + s2)]


def tau_prior(spacecraft: Spacecraft) -> TauPrior:
    """Prior of the time constants from the model's ``[pulse]`` section (module docstring)."""
    p = spacecraft.pulse
    ranges = np.array([p.tau_delay_range, p.tau_rise_range, p.tau_fall_range], float)
    lo, hi = ranges[:, 0], ranges[:, 1]
    if np.any(lo <= 0) or np.any(hi <= lo):
        raise InputError(f"spacecraft model {spacecraft.name!r}: [pulse] tau_*_range must be "
                         "positive [low, high] with low < high (s)", path=spacecraft.source or None)
    log_sd = np.maximum((np.log(hi[1:]) - np.log(lo[1:])) / 4.0, p.tau_log_sd_min)
    return TauPrior(float(hi[0]), 0.5 * (np.log(lo[1:]) + np.log(hi[1:])), log_sd)


CONTRACTION_UNIDENTIFIED = 0.1
"""Posterior/prior contraction ``1 − Var_post/Var_prior`` below which a time constant counts as
not identified by the data (its posterior is essentially its prior)."""
PRIOR_CONFLICT_MASS = 0.99
"""A posterior mean outside the prior's central interval of this mass is a prior-data conflict."""


class TauIdentificationWarning(UserWarning):
    """A pulse time constant is not identified by the data, or its posterior conflicts with its
    prior (:func:`tau_identification`)."""


def tau_identification(posterior, prior: TauPrior) -> list[str]:
    """One line per time constant the data cannot identify (posterior/prior contraction below
    :data:`CONTRACTION_UNIDENTIFIED`) or whose posterior mean lies outside the prior's central
    :data:`PRIOR_CONFLICT_MASS` (the data disagree with the spacecraft model's ``[pulse]``
    ranges). ``posterior``: a mapping of ``tau_delay, tau_rise, tau_fall`` to draws (s)."""
    var_prior = prior.variance()
    central = prior.central(PRIOR_CONFLICT_MASS)
    out = []
    for i, name in enumerate(TAU_NAMES):
        x = np.asarray(posterior[name], float).ravel()
        contraction = 1.0 - float(np.var(x, ddof=1)) / var_prior[i]
        if contraction < CONTRACTION_UNIDENTIFIED:
            out.append(f"{name}: not identified by the data (posterior/prior contraction "
                       f"{contraction:.2f} < {CONTRACTION_UNIDENTIFIED:g}); its posterior is "
                       "essentially the [pulse] prior, and the thrust's interval includes that "
                       "prior's spread")
        mean, (lo, hi) = float(np.mean(x)), central[i]
        if not lo <= mean <= hi:
            out.append(f"{name}: posterior mean {1e3 * mean:.3g} ms lies outside the prior's "
                       f"central {100 * PRIOR_CONFLICT_MASS:g} % ({1e3 * lo:.3g} to "
                       f"{1e3 * hi:.3g} ms): the data disagree with the spacecraft model's "
                       "[pulse] ranges; check the valve response and the prior")
    return out


def draw_tau_prior(key, prior: TauPrior, shape: tuple[int, ...] = ()):
    """Draws ``shape + (3,)`` (s) of ``(τd, τr, τf)`` from :class:`TauPrior` (JAX, traceable)."""
    z = jax.random.normal(key, shape + (3,))
    lead = (1,) * len(shape)
    mu = jnp.reshape(jnp.asarray(prior.log_mean), lead + (2,))
    sd = jnp.reshape(jnp.asarray(prior.log_sd), lead + (2,))
    t_d = prior.delay_scale * jnp.abs(z[..., :1])
    return jnp.concatenate([t_d, jnp.exp(mu + sd * z[..., 1:])], -1)


def thrust_names(mode: str) -> tuple[str, ...]:
    """Names of the thrust parameters of a mode: ``F``; ``F_Z, F_Y``; ``F_Z1 … F_Y4``."""
    if mode == "mean":
        return ("F",)
    if mode == "branch":
        return ("F_Z", "F_Y")
    if mode == "thruster":
        return tuple(f"F_{s}" for s in THRUSTER_NAMES)
    raise InputError(f"{arg('mode', mode, cli_quote=True)}: choose one of {', '.join(MODES)}")


def _thrust_index(mode: str) -> np.ndarray:
    """(8,) index of the thrust parameter that drives each thruster."""
    return {"mean": np.zeros(8, int), "branch": _BRANCH_INDEX,
            "thruster": np.arange(8)}[mode]


# --------------------------------------------------------------------------------------------
# Data preparation
# --------------------------------------------------------------------------------------------

class ThrustProblem(NamedTuple):
    """Everything the thrust model needs, prepared once (SI units).

    Attributes
    ----------
    model_kwargs : arrays for :func:`thrust_model` (events padded to common lengths).
    mode : ``"mean"``, ``"branch"`` or ``"thruster"``.
    names : thrust parameter names of the mode.
    thrust_pred : predicted thrust (prior centre), N.
    tau : :class:`TauPrior`.
    inertia : :class:`InertiaGaussian` when the inertia is sampled, else ``None``.
    inertia_fixed : (3, 3) kg m² used when not sampled.
    sources : ``(telemetry, pulses)`` file names per event.
    n_samples, n_pulses : per event.
    fired : (8,) bool, thrusters with at least one pulse in any event.
    noise_hat : (E, 2) data noise levels (σ_ω rad/s, σ_ρ rad/s).
    layout : the nuisance layout (:class:`~cassini_bayes.inference.nuisance.NuisanceLayout`)
        of the robust model, ``None`` for the idealised one.
    """

    model_kwargs: dict
    mode: str
    names: tuple[str, ...]
    thrust_pred: float
    tau: TauPrior
    inertia: InertiaGaussian | None
    inertia_fixed: np.ndarray
    sources: tuple[tuple[str, str], ...]
    n_samples: np.ndarray
    n_pulses: np.ndarray
    fired: np.ndarray
    noise_hat: np.ndarray
    layout: object = None


def _wheel_momentum(tel: Telemetry, spacecraft: Spacecraft):
    """Body wheel momentum (n, 3) N m s, the wheel noise matrix Σ J² g gᵀ (3, 3) and each active
    wheel's ``J_k ρ_k`` (n,) N m s."""
    h = np.zeros((tel.n, 3))
    wcov = np.zeros((3, 3))
    per_wheel = {}
    for name in tel.active_wheels():
        w = spacecraft.wheel(name)
        rate = np.nan_to_num(np.asarray(tel.wheel_rate(name), float))
        per_wheel[name] = w.inertia * rate
        h += w.inertia * rate[:, None] * w.axis[None, :]
        wcov += w.inertia**2 * np.outer(w.axis, w.axis)
    return h, wcov, per_wheel


def _nuisance_columns(layout, e: int, t: np.ndarray, omega: np.ndarray, inertia: np.ndarray,
                      h: np.ndarray, per_wheel: dict) -> np.ndarray:
    """(n, 3, R) columns of ``ν`` in the predicted left side of event ``e`` (module docstring)."""
    n = t.shape[0]
    cols = np.zeros((n, 3, layout.size))
    sl = layout.slices
    dt = (t - t[0])[:, None]
    c_t = np.concatenate([np.zeros((1, 3)),
                          np.cumsum(0.5 * (h[1:] + h[:-1]) * np.diff(t)[:, None], 0)])
    b0 = sl["gyro_bias"].start + 3 * e
    cols[:, :, b0:b0 + 3] = -np.asarray(skew(c_t))                        # ∫ b × H_w dt
    cols[:, :, sl["gyro_scale"]] = inertia[None] * omega[:, None, :]      # I diag(ω) s
    cols[:, :, layout.wheel_block] = -wheel_scale_columns(layout, h, per_wheel)  # −J_k ρ_k g_k
    a0 = sl["wheel_axes"].start
    for k, name in enumerate(layout.wheels):
        if name in per_wheel:
            for j in range(2):
                cols[:, :, a0 + 2 * k + j] = -per_wheel[name][:, None] * layout.tilt_u[k, j]
    t0 = sl["body_torque"].start + 3 * e
    cols[:, :, t0:t0 + 3] = dt[:, :, None] * np.eye(3)[None]              # T_e (t − t_0)
    return cols


def _second_diff_sd(x: np.ndarray) -> float:
    """Robust sd of white noise on a smooth signal: MAD of second differences / √6."""
    if x.shape[0] < 4:
        return 0.0
    d = np.diff(x, n=2, axis=0).ravel()
    d = d[np.isfinite(d)]
    if d.size == 0:
        return 0.0
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / np.sqrt(6.0))


def rate_noise_levels(tel: Telemetry) -> np.ndarray:
    """White-noise levels ``(σ_ω, σ_ρ)`` (rad/s) of the body and wheel rates of one file.

    Median absolute deviation of second differences ÷ √6 (the sd of white noise; the median
    ignores the few samples where a pulse or a wheel ramp bends the signal), floored at 1e-9 and
    1e-7 rad/s so noise-free data stay finite. Only the centre of a wide prior.
    """
    rates = np.asarray(tel.wheel_rates, float)
    active = np.any(np.isfinite(rates), axis=0)
    s_r = _second_diff_sd(rates[:, active]) if active.any() else 0.0
    s_w = _second_diff_sd(np.asarray(tel.omega, float))
    return np.maximum(np.array([s_w, s_r]), _NOISE_FLOORS)


def _pulse_slots(t: np.ndarray, log: PulseLog) -> np.ndarray:
    """Sample index of each pulse's first sample at or after its command (n when none)."""
    return np.searchsorted(t, log.t_on, side="left")


def prepare_thrust(events: Sequence[tuple[Telemetry, PulseLog]], spacecraft: Spacecraft, *,
                   mode: str = "mean", inertia: InertiaGaussian | None = None,
                   robust: bool = False, wheel_errors: str = "per_wheel") -> ThrustProblem:
    """Prepare the thrust problem from ``(telemetry, pulse log)`` pairs, one per biasing event.

    ``robust`` adds the nuisance parameters of the module docstring (sensor and wheel errors,
    external torque); ``wheel_errors`` (``"per_wheel"`` or ``"common"``) picks the wheel
    spin-inertia model.

    Raises
    ------
    InputError
        No event, a pulse log with no pulse inside its telemetry span (nothing to calibrate), an
        unknown mode, too few samples.
    """
    names = thrust_names(mode)
    if not events:
        raise InputError("no biasing event given; pass "
                         + spelled("--telemetry F.csv --pulses P.csv", "telemetry and pulses"))
    logs, tels = [], []
    for tel, log in events:
        if log is None:
            raise InputError("thrust calibration needs the pulse log of every event ("
                             + spelled("--pulses P.csv", "pulses")
                             + ", columns t_on, thruster, width)", path=tel.source)
        if tel.n < 10:
            raise InputError(f"only {tel.n} samples; a biasing event needs many", path=tel.source)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            log = check_pulses_in_span(log, tel, tail_s=_TAIL_S)
        for w in caught:   # the other span notes are for `check`; this one changes the model
            if issubclass(w.category, PulseAtStartWarning):
                warnings.warn(str(w.message), PulseAtStartWarning, stacklevel=2)
        if log.t_on.size == 0:
            raise InputError(f"no pulse of {log.source} falls inside the telemetry span "
                             f"{tel.t[0]:.10g}..{tel.t[-1]:.10g} s; thrust calibration needs an "
                             "event in which thrusters fire", path=tel.source)
        if not tel.active_wheels():
            raise InputError("no wheel rates (rwa1..rwa4, rpm); a biasing event needs them",
                             path=tel.source)
        logs.append(log)
        tels.append(tel)

    n_max = max(t.n for t in tels)
    # pulse arrays padded to a multiple of _PULSE_BUCKET: events whose pulse counts differ a
    # little (seeds of one scenario, SBC replicates) share shapes, so one compiled sampler
    m_max = -(-max(len(lg.t_on) for lg in logs) // _PULSE_BUCKET) * _PULSE_BUCKET
    dt_min = min(float(np.min(np.diff(t.t))) for t in tels)
    w_max = max(float(np.max(lg.width)) for lg in logs)
    # samples a pulse's thrust can still change after its first sample (≥ 1, static)
    k_slots = int(np.ceil((w_max + 0.02 + _TAIL_S) / dt_min)) + 1
    n_ev = len(tels)
    t_a = np.zeros((n_ev, n_max))
    w_a = np.zeros((n_ev, n_max, 3))
    h_a = np.zeros((n_ev, n_max, 3))
    mask = np.zeros((n_ev, n_max))
    ton = np.zeros((n_ev, m_max))
    thr = np.zeros((n_ev, m_max), int)
    wid = np.zeros((n_ev, m_max))
    slot = np.full((n_ev, m_max), n_max)
    wcov = np.zeros((n_ev, 3, 3))
    noise = np.zeros((n_ev, 2))
    fired = np.zeros(8, bool)
    i_fixed = np.asarray(spacecraft.inertia, float)
    i_lin = i_fixed if inertia is None else np.asarray(inertia_matrix(jnp.asarray(inertia.mean)))
    wheels = sorted({w for tel in tels for w in tel.active_wheels()})
    layout = nuisance_layout(spacecraft, n_ev, wheels if robust else (),
                             wheel_errors=wheel_errors)
    n_nu = layout.size if robust else 0
    nu_cols = np.zeros((n_ev, n_max, 3, n_nu))
    for e, (tel, log) in enumerate(zip(tels, logs)):
        n, m = tel.n, len(log.t_on)
        t = np.asarray(tel.t, float)
        h, wc, per_wheel = _wheel_momentum(tel, spacecraft)
        if robust:
            nu_cols[e, :n] = _nuisance_columns(layout, e, t, np.asarray(tel.omega, float), i_lin,
                                               h, per_wheel)
        # pad by repeating the last sample: Δt = 0 adds nothing to ΔG; masked out anyway
        t_a[e] = np.r_[t, np.full(n_max - n, t[-1])]
        w_a[e] = np.r_[tel.omega, np.repeat(tel.omega[-1:], n_max - n, 0)]
        h_a[e] = np.r_[h, np.repeat(h[-1:], n_max - n, 0)]
        mask[e, :n] = 1.0
        ton[e, :m] = log.t_on
        thr[e, :m] = log.thruster
        wid[e, :m] = log.width      # padded pulses: width 0 → no impulse, slot n_max → dropped
        slot[e, :m] = _pulse_slots(t, log)
        wcov[e] = wc
        noise[e] = rate_noise_levels(tel)
        fired[np.unique(log.thruster)] = True

    th = spacecraft.thrusters
    q_mat = np.asarray(moment_matrix(th.Lx, th.Ly, th.Lzy, th.Lzz, th.com))
    tp = tau_prior(spacecraft)
    if inertia is not None:
        tril = np.linalg.cholesky(np.asarray(inertia.cov) + 1e-9 * np.eye(6))
        i_mean, i_tril = np.asarray(inertia.mean, float), tril
    else:
        i_mean, i_tril = np.asarray(inertia_vector(i_fixed)), np.zeros((6, 6))
    kw = dict(
        t=jnp.asarray(t_a), omega=jnp.asarray(w_a), h_wheels=jnp.asarray(h_a),
        mask=jnp.asarray(mask), t_on=jnp.asarray(ton), thruster=jnp.asarray(thr),
        width=jnp.asarray(wid), slot=jnp.asarray(slot),
        slot_offsets=jnp.arange(k_slots), q_matrix=jnp.asarray(q_mat),
        wheel_cov=jnp.asarray(wcov), log_noise_hat=jnp.asarray(np.log(noise)),
        tau_delay_scale=jnp.asarray(tp.delay_scale),
        tau_mu=jnp.asarray(tp.log_mean), tau_sd=jnp.asarray(tp.log_sd),
        a_mu=jnp.asarray(float(rise_deficit(*tp.median()[:2]))),
        c_mu=jnp.asarray(float(long_pulse_excess(*tp.median()))),
        f_mu=jnp.asarray(np.log(spacecraft.thrust)), f_index=jnp.asarray(_thrust_index(mode)),
        inertia_mean=jnp.asarray(i_mean), inertia_tril=jnp.asarray(i_tril),
        nu_cols=jnp.asarray(nu_cols), nu_sd=jnp.asarray(layout.sd if robust else np.zeros(0)),
    )
    sd_t = spacecraft.knowledge.time_tag_sd_s if robust else 0.0
    kw["time_tag_cols"] = jax.vmap(
        time_tag_columns, in_axes=(0, 0, 0, 0, 0, None, None, None, None, None))(
        kw["t"], kw["t_on"], kw["thruster"], kw["width"], kw["slot"], kw["slot_offsets"],
        tuple(jnp.asarray(x) for x in tp.median()),
        jnp.full(8, float(spacecraft.thrust)), kw["q_matrix"], jnp.asarray(sd_t))
    n_f = len(names)
    dim = n_f + 3 + n_ev + (6 if inertia is not None else 0)
    centre, tril = laplace(_laplace_density(n_f, inertia is not None), np.zeros(dim), kw)
    kw["centre"], kw["tril"] = jnp.asarray(centre), jnp.asarray(tril)
    return ThrustProblem(
        model_kwargs=kw, mode=mode, names=names, thrust_pred=float(spacecraft.thrust), tau=tp,
        inertia=inertia, inertia_fixed=i_fixed,
        sources=tuple((t.source, lg.source) for t, lg in zip(tels, logs)),
        n_samples=np.array([t.n for t in tels]), n_pulses=np.array([len(lg.t_on) for lg in logs]),
        fired=fired, noise_hat=noise, layout=layout if robust else None)


# --------------------------------------------------------------------------------------------
# Model
# --------------------------------------------------------------------------------------------

def pulse_increments(t, t_on, thruster, width, slot, slot_offsets, tau_delay, tau_rise, tau_fall):
    """Accumulated actual impulse per newton (n, 8), s — the sparse form of
    :func:`~cassini_bayes.physics.impulse.impulse_from_pulses`.

    A pulse changes ``j`` only at its first ``K = len(slot_offsets)`` samples at or after its
    command (``slot`` (m,) = index of the first); there its increments are the differences of
    :func:`~cassini_bayes.physics.pulse.pulse_impulse_until`, and at sample ``slot + K`` the rest
    of the full pulse impulse (Feldman & Lee §V closed form, :func:`pulse_impulse`) is added. A
    cumulative sum over samples gives ``j``. ``O(m K)`` instead of ``O(n m)`` work; identical to
    the dense form when every pulse has decayed ``K`` samples after its command.
    """
    n = t.shape[0]
    idx = slot[:, None] + slot_offsets[None, :]                       # (m, K)
    t_s = t[jnp.clip(idx, 0, n - 1)]
    until = pulse_impulse_until(t_s - t_on[:, None], width[:, None], tau_delay, tau_rise,
                                tau_fall)
    until = jnp.where(idx < n, until, 0.0)
    inc = jnp.diff(until, axis=1, prepend=jnp.zeros_like(until[:, :1]))
    # Feldman & Lee §V: impulse of the whole pulse; what remains after the K samples
    full = pulse_impulse(width, tau_delay, tau_rise, tau_fall)
    rest = full - until[:, -1]
    idx_all = jnp.concatenate([idx, slot[:, None] + slot_offsets.shape[0]], 1)
    inc_all = jnp.concatenate([inc, rest[:, None]], 1)
    cols = jnp.broadcast_to(thruster[:, None], idx_all.shape)
    grid = jnp.zeros((n, 8)).at[idx_all, cols].add(inc_all, mode="drop")
    return jnp.cumsum(grid, 0)


def inv3_spd(b):
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


def _event_residual(inertia, f8, tau, t, omega, h_wheels, t_on, thruster, width, slot,
                    slot_offsets, q_matrix):
    """``r = V(t_i) − Q (F ⊙ j(t_i))`` (n, 3) N m s: Feldman & Lee Eq 17, left minus right."""
    v = impulse_lhs(t, omega, inertia, h_wheels)                      # Feldman & Lee Eq 17 (left)
    j = pulse_increments(t, t_on, thruster, width, slot, slot_offsets, *tau)
    return v - (j * f8[None, :]) @ q_matrix.T                        # Feldman & Lee Eq 17


def _event_loglik(inertia, f8, tau, log_sigma, t, omega, h_wheels, mask, t_on, thruster,
                  width, slot, slot_offsets, q_matrix, wheel_cov, nu_cols, time_tag_cols):
    """Offset-marginal statistics of one event (:func:`offset_marginal`) at ``ν = 0``.

    Residual ``r_i = V(t_i) − Q (F ⊙ j(t_i)) − cols_i ν − b`` (Feldman & Lee Eq 17 plus the
    robust terms) with covariance ``B + m_i m_iᵀ``: white gyro and wheel-rate noise ``B`` (module
    docstring) and the time-tag term ``m_i`` = ``time_tag_cols`` (:func:`time_tag_columns`). The
    offset ``b`` (flat prior) is integrated out here, the nuisance ``ν`` by
    :func:`nuisance_marginal` over all events.

    The measurements are the gyro rates, not ``V``: ``V`` is the rates mapped through ``I``, so
    the density of the data is that of ``V`` times the Jacobian ``|det I|`` per sample (for any
    ``B``, ``N(I⁻¹r; 0, I⁻¹ B I⁻ᵀ) = |det I| N(r; 0, B)``), less one for the offset's integral.
    With the inertia fixed this is a constant; with the inertia sampled it is what keeps the
    likelihood invariant under the unidentifiable common scale of ``I``, ``F`` and the wheel
    inertias. Without it the density of ``V`` alone grows as ``|det I|⁻ⁿ`` when all three shrink
    together: on a 480-sample event whose true inertia was 3 % above the model's, the sampled
    inertia went 4 % the wrong way, dragging ``F`` 3.5 % low and the wheel scale 7 prior sd.
    """
    r = _event_residual(inertia, f8, tau, t, omega, h_wheels, t_on, thruster, width, slot,
                        slot_offsets, q_matrix)
    st = offset_marginal(r, _noise_cov(inertia, log_sigma, wheel_cov), time_tag_cols, mask,
                         nu_cols)
    log_jacobian = (jnp.sum(mask) - 1.0) * jnp.linalg.slogdet(inertia)[1]
    return st._replace(loglik=st.loglik + log_jacobian)


def _noise_cov(inertia, log_sigma, wheel_cov):
    """``B = σ_ω² I I + σ_ρ² Σ_k J_k² g_k g_kᵀ`` (3, 3) (N m s)²: the white gyro and wheel-rate
    noise of one sample's left side (module docstring, "Error model")."""
    s2 = jnp.exp(2.0 * log_sigma)
    return s2[0] * inertia @ inertia + s2[1] * wheel_cov


def time_tag_columns(t, t_on, thruster, width, slot, slot_offsets, tau, f8, q_matrix,
                     time_tag_sd):
    """(n, 3) N m s: ``σ_t`` times the thrusters' torque at each sample, ``Q (F ⊙ ∂j/∂t)`` —
    the momentum a time-tag error of sd ``σ_t`` (s) puts between a sample and the impulse
    predicted for it (module docstring, "Robust model"). ``∂j/∂t`` is exact (forward-mode
    derivative of :func:`pulse_increments` in the sample times); ``τ`` (3,) s and ``f8`` (8,) N
    are the prior's median time constants and the predicted thrust: a variance term evaluated
    once, at the prior, so the sampler sees a fixed covariance (evaluated at each draw it made
    some fits take tens of minutes)."""
    _, j_dot = jax.jvp(lambda tt: pulse_increments(tt, t_on, thruster, width, slot,
                                                   slot_offsets, *tau), (t,), (jnp.ones_like(t),))
    return time_tag_sd * (j_dot * f8[None, :]) @ q_matrix.T


class OffsetMarginal(NamedTuple):
    """What :func:`offset_marginal` returns for one event."""

    loglik: object      # log ∫ Π_i N(r_i − β; 0, Σ_i) dβ at ν = 0
    info: object        # (R, R) Σ D̄_iᵀ P_i D̄_i: the event's information on ν, offset removed
    score: object       # (R,) Σ D̄_iᵀ P_i d_i: the linear term, ∂ loglik/∂ν at ν = 0
    resid: object       # (n, 3) r − β̂, N m s


def offset_marginal(r, b, m, mask, cols):
    """The flat offset ``β`` (3,) of one event integrated out, exactly, with per-sample
    covariances ``Σ_i = B + m_i m_iᵀ``; rows with ``mask`` 0 are left out.

    The per-sample precisions ``P_i`` come from Sherman–Morrison,
    ``(B + m mᵀ)⁻¹ = B⁻¹ − B⁻¹m mᵀB⁻¹/(1 + mᵀB⁻¹m)``; ``β̂ = (Σ P_i)⁻¹ Σ P_i r_i`` and the
    integral adds ``(3/2) log 2π − ½ log|Σ_i P_i|``. ``cols`` (n, 3, R) are the columns of the
    nuisance ``ν`` in the residual ``r_i − cols_i ν``: the log-likelihood is exactly quadratic in
    ``ν``, ``loglik − ½ νᵀ info ν + scoreᵀ ν`` (:class:`OffsetMarginal`), with the columns'
    offset part removed (``D̄_i = D_i − (Σ P)⁻¹ Σ P_j D_j``), so the events' terms add up.
    """
    # Products of the n 3×3 blocks are written as broadcasts and sums, not batched einsums,
    # which XLA on the CPU runs as n tiny GEMMs (measured, gradient of this function for 481
    # samples, R = 16, 4 chains vectorised: 4.4 ms with einsums, 3.3 ms as written).
    b_inv, logdet = inv3_spd(b)
    u = m @ b_inv
    g = 1.0 + jnp.sum(u * m, -1)
    prec = (b_inv[None] - u[:, :, None] * u[:, None, :] / g[:, None, None]) * mask[:, None, None]
    p_inv, p_logdet = inv3_spd(jnp.sum(prec, 0))
    d = r - (p_inv @ jnp.sum(prec * r[:, None, :], (0, 2)))[None, :]
    quad = jnp.sum(d[:, :, None] * prec * d[:, None, :], (1, 2))
    ll_i = -0.5 * (quad + logdet + jnp.log(g) + 3.0 * jnp.log(2.0 * jnp.pi))
    ll = jnp.sum(ll_i * mask) + 1.5 * jnp.log(2.0 * jnp.pi) - 0.5 * p_logdet
    flat = (3 * cols.shape[0], cols.shape[-1])
    pd = jnp.sum(prec[..., None] * cols[:, None, :, :], 2)           # P_i D_i (n, 3, R)
    s_bd = jnp.sum(pd, 0)                                             # Σ P_i D_i (3, R)
    info = cols.reshape(flat).T @ pd.reshape(flat) - s_bd.T @ p_inv @ s_bd
    score = pd.reshape(flat).T @ d.reshape(-1)
    return OffsetMarginal(ll, info, score, d)


def nuisance_marginal(info, score, nu_sd):
    """``log ∫ exp(scoreᵀν − ½ νᵀ info ν) N(ν; 0, diag(nu_sd²)) dν`` and the Gaussian
    conditional of the whitened ``z = ν / nu_sd``: its mean ``A⁻¹ s̃`` and the lower Cholesky
    factor ``L`` of ``A = diag(sd) info diag(sd) + I`` (the conditional covariance is
    ``A⁻¹ = L⁻ᵀ L⁻¹``). The integral is ``½ s̃ᵀ A⁻¹ s̃ − log|L|``, ``s̃ = sd ⊙ score``."""
    a = nu_sd[:, None] * info * nu_sd[None, :] + jnp.eye(nu_sd.shape[0])
    chol = jnp.linalg.cholesky(0.5 * (a + a.T))
    y = jax.scipy.linalg.solve_triangular(chol, nu_sd * score, lower=True)
    mean = jax.scipy.linalg.solve_triangular(chol.T, y, lower=False)
    return 0.5 * y @ y - jnp.sum(jnp.log(jnp.diag(chol))), mean, chol


_EVENT_AXES = (None, None, None, 0, 0, 0, 0, 0, 0, 0, 0, 0, None, None, 0, 0, 0)


def _unpack(theta, n_f: int, n_ev: int, sample_inertia: bool):
    """Split the sampler vector into ``f_z`` (n_f,), ``tau_z`` (3,) = ``(s, a_z, c_z)``,
    ``noise_z`` (E,) and ``inertia_z`` (6,) or ``None``."""
    f_z = theta[:n_f]
    tau_z = theta[n_f:n_f + 3]
    noise_z = theta[n_f + 3:n_f + 3 + n_ev]
    k = n_f + 3 + n_ev
    inertia_z = theta[k:k + 6] if sample_inertia else None
    return f_z, tau_z, noise_z, inertia_z


def long_pulse_excess(tau_delay, tau_rise, tau_fall):
    """``c = τf − τr e^{−τd/τr}`` (s): a pulse of width ``Δ ≫ τr`` delivers ``F (Δ + c)``.

    The limit ``e^{−Δ/τr} → 0`` of Feldman & Lee §V's closed form
    ``(Δ + τf) + τr (e^{−Δ/τr} − e^{−τd/τr}) − (τf + τd) e^{−Δ/τr}``; for the 125 ms minimum
    pulse ``e^{−Δ/τr} ≈ 0.002``. Pulse logs of widths ≥ 125 ms determine ``F`` and ``c`` and
    little else: the time constants lie on the curved surface ``c(τ) = const``.
    """
    return tau_fall - tau_rise * jnp.exp(-tau_delay / tau_rise)


def rise_deficit(tau_delay, tau_rise):
    """``a = τd + τr e^{−τd/τr}`` (s): a pulse has delivered ``F (t − a)`` by a time ``t ≫ τr``
    after its command while it is still on (Feldman & Lee §V profile, rising phase,
    :func:`~cassini_bayes.physics.pulse.pulse_impulse_until`). Samples taken during pulses pin
    ``a`` as the long pulses' impulses pin :func:`long_pulse_excess`."""
    return tau_delay + tau_rise * jnp.exp(-tau_delay / tau_rise)


def _lambert_w0(x):
    """Principal branch of Lambert's W for ``x ≥ 0`` (``w e^w = x``): Halley's iteration from
    ``l − log(1 + l) l/(1 + l)``, ``l = log(1 + x)`` (``≈ log x − log log x`` for large ``x``),
    converged to rounding in 4 steps for ``1e-14 ≤ x ≤ 1e12``; differentiable."""
    l = jnp.log1p(x)
    w = l - jnp.log1p(l) * l / (1.0 + l)
    for _ in range(4):
        ew = jnp.exp(w)
        f = w * ew - x
        w = w - f / (ew * (w + 1.0) - (w + 2.0) * f / (2.0 * w + 2.0))
    return w


def _tau_from_z(tau_z, kw):
    """Time constants (3,) s from the sampler's ``(s, a_z, c_z)`` and the log prior density
    of the sampler coordinates (exact: the Jacobians included).

    * ``a_z``: the rise deficit ``a = a_mu e^{A a_z}`` (:func:`rise_deficit`, ``A`` =
      :data:`A_LOG_SCALE`), pinned by the samples taken during pulses.
    * ``s``: how ``a`` splits between the delay and the rise, ``τd = a σ(s)`` and
      ``b = a − τd = τr e^{−τd/τr} = a σ(−s)``; ``τd/b = e^s``, so ``τr = b e^{W(e^s)}``
      (Lambert's W). ``τd → 0`` (a first-order valve) and ``τr → 0`` are the two tails
      ``s → ∓∞``, with no wall between them; the split is what only samples within a few
      ``τr`` of a command resolve.
    * ``c_z``: the long-pulse excess ``c = c_mu + C c_z`` (:func:`long_pulse_excess`, ``C`` =
      :data:`C_SCALE_S`), pinned by the long pulses' impulses; ``τf = c + b``.

    Sampling ``(a, c)`` instead of ``(τr, τf)`` turns the two narrow, curved ridges of the
    likelihood into coordinate axes. The prior of ``(τd, τr, τf)`` is carried over with
    ``|∂(τd, b)/∂(s, log a)| = a² σ(s) σ(−s)``, ``∂τr/∂b = e^u/(1 + u)`` (``u = τd/τr``) and the
    coordinates' scales. ``τf ≤ 0`` gives NaN.

    A first-order valve (``τd = 0``, ``τr = τf = τ``) is ``a = τ``, ``s → −∞``, ``c = 0``.
    """
    s = tau_z[0]
    a = kw["a_mu"] * jnp.exp(A_LOG_SCALE * tau_z[1])
    t_d = a * jax.nn.sigmoid(s)
    b = a * jax.nn.sigmoid(-s)
    u = _lambert_w0(jnp.exp(s))
    t_r = b * jnp.exp(u)
    t_f = kw["c_mu"] + C_SCALE_S * tau_z[2] + b
    t_f = jnp.where(t_f > 0.0, t_f, jnp.nan)
    log_tau = jnp.log(jnp.stack([t_r, t_f]))
    z_rf = (log_tau - kw["tau_mu"]) / kw["tau_sd"]
    std = dist.Normal(0.0, 1.0)
    sd_d = kw["tau_delay_scale"]
    log_prior_delay = jnp.log(2.0 / sd_d) + std.log_prob(t_d / sd_d)      # half-normal
    log_jac = (2.0 * jnp.log(a) + jax.nn.log_sigmoid(s) + jax.nn.log_sigmoid(-s)
               + jnp.log(A_LOG_SCALE) + u - jnp.log1p(u) + jnp.log(C_SCALE_S))
    log_prior = (log_prior_delay + jnp.sum(std.log_prob(z_rf) - jnp.log(kw["tau_sd"]) - log_tau)
                 + log_jac)
    return jnp.stack([t_d, t_r, t_f]), log_prior


def _physical(theta, kw, n_f: int, sample_inertia: bool):
    """Physical parameters of the non-dimensional vector: thrust (n_f,) N, its (8,) spread over
    the thrusters, ``τ`` (3,) s, ``log σ`` (E, 2) and ``π`` (6,) kg m²."""
    n_ev = kw["log_noise_hat"].shape[0]
    f_z, tau_z, noise_z, inertia_z = _unpack(theta, n_f, n_ev, sample_inertia)
    thrust = jnp.exp(kw["f_mu"] + THRUST_PRIOR_LOG_SD * f_z)
    tau, _ = _tau_from_z(tau_z, kw)
    log_sigma = kw["log_noise_hat"] + _NOISE_STEP * noise_z[:, None]
    pi = kw["inertia_mean"]
    if sample_inertia:
        pi = pi + kw["inertia_tril"] @ inertia_z
    return thrust, thrust[kw["f_index"]], tau, log_sigma, pi


def _event_stats(theta, kw, n_f: int, sample_inertia: bool) -> OffsetMarginal:
    """:class:`OffsetMarginal` of every event (leading axis E) at the sampler vector ``theta``."""
    _, f8, tau, log_sigma, pi = _physical(theta, kw, n_f, sample_inertia)
    return jax.vmap(_event_loglik, in_axes=_EVENT_AXES)(
        inertia_matrix(pi), f8, (tau[0], tau[1], tau[2]), log_sigma, kw["t"], kw["omega"],
        kw["h_wheels"], kw["mask"], kw["t_on"], kw["thruster"], kw["width"], kw["slot"],
        kw["slot_offsets"], kw["q_matrix"], kw["wheel_cov"], kw["nu_cols"], kw["time_tag_cols"])


def _log_density(theta, kw, n_f: int, sample_inertia: bool):
    """Log prior + log likelihood at the non-dimensional vector ``theta`` (module docstring);
    the offsets and the robust model's nuisance ``ν`` are integrated out exactly."""
    n_ev = kw["log_noise_hat"].shape[0]
    f_z, tau_z, noise_z, inertia_z = _unpack(theta, n_f, n_ev, sample_inertia)
    _, log_prior_tau = _tau_from_z(tau_z, kw)
    log_prior = (jnp.sum(dist.Normal(0.0, 1.0).log_prob(f_z)) + log_prior_tau
                 + jnp.sum(dist.Normal(0.0, NOISE_PRIOR_LOG_SD / _NOISE_STEP).log_prob(noise_z)))
    if sample_inertia:
        log_prior += jnp.sum(dist.Normal(0.0, 1.0).log_prob(inertia_z))
    st = _event_stats(theta, kw, n_f, sample_inertia)
    out = log_prior + jnp.sum(st.loglik)
    if kw["nu_sd"].shape[0]:
        out += nuisance_marginal(jnp.sum(st.info, 0), jnp.sum(st.score, 0), kw["nu_sd"])[0]
    return jnp.where(jnp.isfinite(out), out, -jnp.inf)


@lru_cache(maxsize=None)
def _nuisance_sampler(n_f: int, sample_inertia: bool):
    """Jitted ``(w (S, P), eps (S, R), kw) -> ν (S, R)``: a draw of ``ν`` from its exact Gaussian
    conditional given each draw of the sampled parameters (:func:`nuisance_marginal`), so that
    ``(θ, ν)`` are draws of the joint posterior. Batched to bound the memory (``n × 3 × R`` per
    draw)."""
    def one(args, kw):
        w, eps = args
        st = _event_stats(kw["centre"] + kw["tril"] @ w, kw, n_f, sample_inertia)
        _, mean, chol = nuisance_marginal(jnp.sum(st.info, 0), jnp.sum(st.score, 0), kw["nu_sd"])
        z = mean + jax.scipy.linalg.solve_triangular(chol.T, eps, lower=False)
        return kw["nu_sd"] * z

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


def _model(*, centre, tril, names: tuple[str, ...], sample_inertia: bool, **kw):
    w = numpyro.sample("w", dist.ImproperUniform(constraints.real_vector, (), centre.shape))
    theta = centre + tril @ w
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

    Call it with ``**ThrustProblem.model_kwargs``. Posterior sites: the thrust names of the mode
    (N), ``tau_delay``, ``tau_rise``, ``tau_fall`` (s), ``sigma_omega``, ``sigma_rho`` (event)
    rad/s, ``Ixx … Iyz`` (kg m²) when ``sample_inertia``, and the sampler's whitened ``w``
    (the robust model's nuisance ``ν`` is integrated out; :func:`fit_thrust` adds its draws).
    """
    names = thrust_names(mode)

    def model(**kwargs):
        return _model(names=names, sample_inertia=sample_inertia, **kwargs)

    model.__name__ = f"thrust_model_{mode}_{'inertia' if sample_inertia else 'fixed'}"
    return model


def sample_thrust_prior(key, problem: ThrustProblem, n: int) -> dict[str, np.ndarray]:
    """``n`` draws of the physical parameters from the stated prior (module docstring)."""
    k_f, k_t, k_s, k_i = jax.random.split(key, 4)
    kw = problem.model_kwargs
    n_ev = kw["log_noise_hat"].shape[0]
    f_z = jax.random.normal(k_f, (n, len(problem.names)))
    noise_z = jax.random.normal(k_s, (n, n_ev, 1)) * NOISE_PRIOR_LOG_SD / _NOISE_STEP
    thrust = np.exp(np.log(problem.thrust_pred) + THRUST_PRIOR_LOG_SD * np.asarray(f_z))
    tau = np.asarray(draw_tau_prior(k_t, problem.tau, (n,)))
    out = {name: thrust[:, i] for i, name in enumerate(problem.names)}
    out.update({name: tau[:, i] for i, name in enumerate(TAU_NAMES)})
    sig = np.exp(np.asarray(kw["log_noise_hat"])[None] + _NOISE_STEP * np.asarray(noise_z))
    out["sigma_omega"], out["sigma_rho"] = sig[..., 0], sig[..., 1]
    if problem.inertia is not None:
        z = np.asarray(jax.random.normal(k_i, (n, 6)))
        pi = np.asarray(problem.inertia.mean) + z @ np.linalg.cholesky(
            np.asarray(problem.inertia.cov) + 1e-9 * np.eye(6)).T
        out.update({name: pi[:, i] for i, name in enumerate(INERTIA_NAMES)})
    return out


@jax.jit
def _residuals_jit(i_m, f8, tau, log_sigma, nu, t, omega, h_wheels, mask, t_on, thruster, width,
                   slot, slot_offsets, q_matrix, wheel_cov, nu_cols, time_tag_cols):
    def one(log_sigma, t, omega, h_wheels, mask, t_on, thruster, width, slot, wheel_cov, nu_cols,
            time_tag_cols):
        r = _event_residual(i_m, f8, tau, t, omega, h_wheels, t_on, thruster, width, slot,
                            slot_offsets, q_matrix) - nu_cols @ nu
        return offset_marginal(r, _noise_cov(i_m, log_sigma, wheel_cov), time_tag_cols, mask,
                               nu_cols[..., :0]).resid

    return jax.vmap(one)(log_sigma, t, omega, h_wheels, mask, t_on, thruster, width, slot,
                         wheel_cov, nu_cols, time_tag_cols)


def impulse_residuals(problem: ThrustProblem, thrust, tau, sigma, pi=None,
                      nu=None) -> np.ndarray:
    """Offset-free residuals ``V − Q (F ⊙ j) − cols ν − b̂`` (E, n_max, 3) N m s at given
    parameters (thrust per parameter of the mode, ``tau`` (3,) s, ``sigma`` (E, 2), robust
    nuisance ``nu`` (R,), default 0); padded rows are 0."""
    kw = problem.model_kwargs
    idx = np.asarray(kw["f_index"])
    f8 = np.asarray(thrust, float)[idx]
    pi = np.asarray(kw["inertia_mean"]) if pi is None else np.asarray(pi, float)
    nu = np.zeros(kw["nu_sd"].shape[0]) if nu is None else np.asarray(nu, float)
    d = _residuals_jit(inertia_matrix(jnp.asarray(pi)), jnp.asarray(f8),
                       tuple(jnp.asarray(float(x)) for x in tau), jnp.log(jnp.asarray(sigma)),
                       jnp.asarray(nu), kw["t"], kw["omega"], kw["h_wheels"], kw["mask"],
                       kw["t_on"], kw["thruster"], kw["width"], kw["slot"], kw["slot_offsets"],
                       kw["q_matrix"], kw["wheel_cov"], kw["nu_cols"], kw["time_tag_cols"])
    return np.asarray(d) * np.asarray(kw["mask"])[..., None]


# --------------------------------------------------------------------------------------------
# The fit
# --------------------------------------------------------------------------------------------

class ThrustPosterior(NamedTuple):
    """Result of :func:`fit_thrust`: the InferenceData, its diagnostics and the problem."""

    idata: object
    diagnostics: object
    problem: ThrustProblem


def _add_nuisance_draws(key, idata, problem: ThrustProblem, sample_inertia: bool,
                        coords: dict, dims: dict) -> np.ndarray:
    """Add the robust model's nuisance sites (:func:`~cassini_bayes.inference.nuisance.
    split_nuisance`) to the posterior: one draw of ``ν`` from its exact conditional per draw of
    the sampler (:func:`_nuisance_sampler`), so the sites are draws of the joint posterior.
    Returns the draws of ``ν`` (chain × draw, R), in the posterior's flattened order."""
    import xarray as xr

    kw = problem.model_kwargs
    w = np.asarray(idata.posterior["w"].values)
    n_chain, n_draw, dim = w.shape
    n_nu = kw["nu_sd"].shape[0]
    eps = jax.random.normal(key, (n_chain * n_draw, n_nu))
    nu = np.asarray(_nuisance_sampler(len(problem.names), sample_inertia)(
        jnp.asarray(w.reshape(-1, dim)), eps, kw))
    for site, v in split_nuisance(nu.reshape(n_chain, n_draw, n_nu), problem.layout).items():
        site_dims = tuple(dims.get(site, ()))
        idata.posterior[site] = xr.DataArray(
            v, dims=("chain", "draw") + site_dims,
            coords={"chain": idata.posterior.chain, "draw": idata.posterior.draw,
                    **{d: coords[d] for d in site_dims}})
    return nu


RESIDUAL_DRAWS = 100
"""Posterior draws averaged into the stored residual (:func:`_posterior_mean_residuals`)."""


def _posterior_mean_residuals(problem: ThrustProblem, post, sample_inertia: bool,
                              nu_draws=None) -> np.ndarray:
    """The posterior mean of the impulse residuals, ``E[r(θ) | data]`` (E, n_max, 3) N m s,
    over :data:`RESIDUAL_DRAWS` evenly spaced draws, each with its own thrust, time constants,
    noise levels, inertia and nuisance. Not ``r(E[θ])``: with the inertia sampled, the draws lie
    on a curved ridge (``I``, ``F`` and the wheels' scale trade against each other), whose mean
    is off the ridge, and the residual at the mean carries a smooth misfit that no draw has
    (measured on correctly specified ``biasing_day028``: lag-1 autocorrelation 0.67–0.80 at the
    mean)."""
    def flat(name):
        v = np.asarray(post[name].values, float)
        return v.reshape(v.shape[0] * v.shape[1], -1)

    n_s = flat(problem.names[0]).shape[0]
    pick = np.unique(np.linspace(0, n_s - 1, min(RESIDUAL_DRAWS, n_s)).astype(int))
    f = np.concatenate([flat(n) for n in problem.names], 1)
    tau = np.concatenate([flat(n) for n in TAU_NAMES], 1)
    sig = np.stack([flat("sigma_omega"), flat("sigma_rho")], -1)          # (S, E, 2)
    pi = np.concatenate([flat(n) for n in INERTIA_NAMES], 1) if sample_inertia else None
    total = 0.0
    for i in pick:
        total = total + impulse_residuals(problem, f[i], tau[i], sig[i],
                                          None if pi is None else pi[i],
                                          None if nu_draws is None else nu_draws[i])
    return total / pick.size


def fit_thrust(key, events: Sequence[tuple[Telemetry, PulseLog]], spacecraft: Spacecraft, *,
               mode: str = "mean", inertia: InertiaGaussian | str | None = None, settings=None,
               prior_draws: int = 500, robust: bool = True,
               wheel_errors: str = "per_wheel") -> ThrustPosterior:
    """Posterior of the thrust and the pulse time constants from one or more biasing events.

    Parameters
    ----------
    key : jax.random key.
    events : ``(telemetry, pulse log)`` per biasing event; they share ``τ`` and the thrust.
    spacecraft : model giving the predicted thrust, time-constant ranges, geometry of Eq 16,
        wheels and the inertia's prediction and knowledge.
    mode : ``"mean"`` (``F``), ``"branch"`` (``F_Z``, ``F_Y``) or ``"thruster"`` (``F_Z1 … F_Y4``).
    inertia : how the spacecraft inertia enters. An :class:`InertiaGaussian` (e.g.
        :func:`inertia_from_run`, an inertia fit's posterior) or ``"prior"`` (the model file's
        knowledge, :func:`inertia_prior_gaussian`): sampled jointly. ``"fixed"``: held at the
        model file's prediction. ``None`` (default): ``"prior"`` for the robust model, ``"fixed"``
        for the idealised one (the papers' model). A fixed inertia that is not the truth is a
        closed world: the momentum the pulses put into the body rates is ``I Δω``, so a 3 %
        inertia error moved ``F`` 3 % (12 sd) on a Table 2 event, through the wheel scale.
    settings : :class:`~cassini_bayes.inference.runner.SamplerSettings`.
    prior_draws : number of prior draws stored in the ``prior`` group.
    robust : add the nuisance parameters (gyro bias and scale, wheel inertia scales and tilts,
        external torque; module docstring). The default, as on the CLI; ``False`` is the
        papers' idealised model (clean simulations, comparisons with the papers).
    wheel_errors : robust model's wheel spin-inertia errors: ``"per_wheel"`` (default, one scale
        per active wheel, site ``wheel_scale`` (wheel)) or ``"common"`` (one scalar scale).

    Returns
    -------
    ThrustPosterior
        ``idata`` with ``posterior`` (thrust names in N, ``tau_*`` in s, ``sigma_omega``,
        ``sigma_rho`` per event, inertia entries when sampled, sampler coordinates),
        ``sample_stats``, ``prior``, ``observed_data`` (``v``: the left side of Eq 17 at the
        fixed/prior-mean inertia, N m s), ``constant_data`` (prior centres and scales) and
        ``residuals`` (posterior-mean offset-free residuals, N m s).

    Warns
    -----
    TauIdentificationWarning
        One line per time constant the data do not identify or that conflicts with its prior
        (:func:`tau_identification`); the CLI puts them in ``summary["warnings"]``.
    PulseAtStartWarning
        A pulse acts on the first sample of an event (only its impulse after that sample is
        modelled: the event's free offset absorbs the rest).
    """
    import xarray as xr

    from cassini_bayes.inference.runner import SamplerSettings, diagnostics, run_nuts

    settings = settings or SamplerSettings()
    inertia = resolve_inertia(inertia, spacecraft, robust)
    problem = prepare_thrust(events, spacecraft, mode=mode, inertia=inertia, robust=robust,
                             wheel_errors=wheel_errors)
    unfired = [s for s, f in zip(THRUSTER_NAMES, problem.fired) if not f]
    if mode == "thruster" and unfired:
        warnings.warn(f"thrusters {', '.join(unfired)} never fire: their thrust is "
                      "prior-dominated", stacklevel=2)
    kw = problem.model_kwargs
    n_ev = len(problem.sources)
    sample_inertia = inertia is not None
    coords = {"event": np.arange(n_ev), "w_dim": np.arange(kw["centre"].shape[0])}
    dims = {"sigma_omega": ["event"], "sigma_rho": ["event"], "w": ["w_dim"]}
    if robust:
        coords.update({"axis": ["x", "y", "z"], "wheel": list(problem.layout.wheels),
                       "tilt": ["u1", "u2"]})
        dims.update({EFFECTS["gyro_bias"]: ["event", "axis"], EFFECTS["gyro_scale"]: ["axis"],
                     EFFECTS["wheel_axes"]: ["wheel", "tilt"],
                     EFFECTS["body_torque"]: ["event", "axis"],
                     **({EFFECTS["wheel_inertia"]: ["wheel"]}
                        if wheel_errors == "per_wheel" else {})})
    idata = run_nuts(key, thrust_model(mode, sample_inertia), model_kwargs=kw, settings=settings,
                     coords=coords, dims=dims,
                     prior=lambda k, n: sample_thrust_prior(k, problem, n),
                     prior_draws=prior_draws)
    nu_draws = None
    if robust:
        nu_draws = _add_nuisance_draws(jax.random.fold_in(key, 7), idata, problem,
                                       sample_inertia, coords, dims)
    post = idata.posterior
    d = _posterior_mean_residuals(problem, post, sample_inertia, nu_draws)
    m = np.asarray(kw["mask"]) > 0
    t_all = np.concatenate([np.asarray(kw["t"])[e][m[e]] for e in range(n_ev)])
    ev_all = np.concatenate([np.full(int(m[e].sum()), e) for e in range(n_ev)])
    r_all = np.concatenate([d[e][m[e]] for e in range(n_ev)])
    i_fix = inertia_matrix(jnp.asarray(kw["inertia_mean"]))
    v_all = np.concatenate([np.asarray(impulse_lhs(kw["t"][e], kw["omega"][e], i_fix,
                                                   kw["h_wheels"][e]))[m[e]]
                            for e in range(n_ev)])
    t_coord = {"t": ("t", t_all, {"units": "s"}), "axis": ["x", "y", "z"],
               "event": ("t", ev_all)}
    residuals = xr.Dataset(
        {"residual": (("t", "axis"), r_all, {"units": "N m s", "frame": "body",
                                             "description": "posterior-mean impulse residual "
                                                            "(Eq 17, offset removed)"})},
        coords=t_coord)
    observed = xr.Dataset({"v": (("t", "axis"), v_all, {"units": "N m s"})}, coords=t_coord,
                          attrs={"sources": [f"{a} + {b}" for a, b in problem.sources]})
    constant = xr.Dataset(
        {"tau_delay_prior_scale": ((), problem.tau.delay_scale, {"units": "s"}),
         "tau_prior_log_mean": ("tau_lognormal", problem.tau.log_mean),
         "tau_prior_log_sd": ("tau_lognormal", problem.tau.log_sd),
         "thrust_prior_median": ((), problem.thrust_pred, {"units": "N"}),
         "thrust_prior_log_sd": ((), THRUST_PRIOR_LOG_SD),
         "fired": ("thruster", problem.fired.astype(int)),
         "n_pulses": ("event", problem.n_pulses),
         "noise_hat": (("event", "noise"), problem.noise_hat)},
        coords={"tau_lognormal": list(TAU_NAMES[1:]), "thruster": list(THRUSTER_NAMES),
                "event": np.arange(n_ev), "noise": ["omega", "rho"]})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        for name in ("observed_data", "constant_data", "residuals"):
            if name in idata.groups():
                del idata[name]
        idata.add_groups({"observed_data": observed, "constant_data": constant,
                          "residuals": residuals})
    for line in tau_identification(post, problem.tau):
        warnings.warn(line, TauIdentificationWarning, stacklevel=2)
    names = list(problem.names) + list(TAU_NAMES) + ["sigma_omega", "sigma_rho"]
    if sample_inertia:
        names += list(INERTIA_NAMES)
    if robust:
        names += [EFFECTS[e] for e in problem.layout.slices]
    return ThrustPosterior(idata, diagnostics(idata, names), problem)
