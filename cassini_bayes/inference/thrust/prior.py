"""The thrust model's prior, stated in the physical parameters: the thrust (log-normal about
the spacecraft model's prediction), the pulse time constants (:class:`TauPrior`), the noise scale
and the inertia (:func:`resolve_inertia`); draws from it, and the check that flags time constants
the data leave at their prior (:mod:`cassini_bayes.inference.thrust`, "Priors").
"""

from __future__ import annotations

from statistics import NormalDist
from typing import TYPE_CHECKING, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.errors import InputError, arg
from cassini_bayes.inference.inertia.knowledge import InertiaGaussian, inertia_prior_gaussian
from cassini_bayes.names import COM_NAMES, INERTIA_NAMES, TAU_NAMES, THRUST_MODES
from cassini_bayes.spacecraft import Spacecraft

if TYPE_CHECKING:
    from cassini_bayes.inference.thrust.data import ThrustProblem

__all__ = ["MODES", "THRUST_PRIOR_LOG_SD", "NOISE_PRIOR_LOG_SD", "TAG_SCALE_LOG_SD",
           "TAG_SCALE_KINK", "TAG_SCALE_WARN_MASS", "tag_log_scale", "tag_scale_warning",
           "resolve_inertia", "TauPrior",
           "tau_prior", "CONTRACTION_UNIDENTIFIED", "PRIOR_CONFLICT_MASS",
           "TauIdentificationWarning", "tau_identification", "draw_tau_prior", "thrust_names",
           "sample_thrust_prior", "COM_NAMES"]

MODES = THRUST_MODES
THRUST_PRIOR_LOG_SD = 0.3     # sd of log F (flight history 0.97 → 0.69 N, Feldman & Lee §V)
NOISE_PRIOR_LOG_SD = 1.0      # sd of log σ around the data's own noise level σ̂
NOISE_STEP = 0.1             # log σ per unit of the sampled noise coordinate
TAG_SCALE_LOG_SD = (1.5, 0.5)
"""sds of the log of the time tags' sd below and above the model file's stated one (its
median): the data correct the statement as they do the noise level, and a scale held at it
moves the thrusts where the tags differ. Tags far better than stated are common (exact clocks);
far worse is rarer than a misfit at the pulses that the scale would otherwise absorb."""
TAG_SCALE_KINK = 0.2
"""Width (in the sampler's coordinate) over which the log scale's slope turns from the lower sd
to the upper (:func:`tag_log_scale`)."""
TAG_SCALE_WARN_MASS = 0.05
"""A learned time-tag sd whose posterior median lies above its prior's ``1 −`` this quantile
is reported (:func:`tag_scale_warning`)."""


def tag_log_scale(z):
    """``log s`` of the time tags' sd over the stated one at the sampler coordinate ``z``
    (``N(0, 1)`` a priori): slope :data:`TAG_SCALE_LOG_SD` ``[0]`` below 0 and ``[1]`` above,
    joined smoothly over :data:`TAG_SCALE_KINK` (a kink would break the sampler's gradients)."""
    low, high = TAG_SCALE_LOG_SD
    eps = TAG_SCALE_KINK
    return 0.5 * (high + low) * z + 0.5 * (high - low) * (jnp.sqrt(z * z + eps * eps) - eps)


def tag_scale_warning(post, stated_s: float) -> list[str]:
    """One line where the learned ``time_tag_sd`` (posterior group) sits above its prior's
    upper :data:`TAG_SCALE_WARN_MASS` tail: a misfit at the pulses taken for tag errors."""
    if "time_tag_sd" not in post:
        return []
    median = float(np.median(np.asarray(post["time_tag_sd"].values)))
    z = NormalDist().inv_cdf(1.0 - TAG_SCALE_WARN_MASS)
    top = stated_s * float(jnp.exp(tag_log_scale(z)))
    if median <= top:
        return []
    return [f"time_tag_sd: posterior median {1e3 * median:.3g} ms lies above the prior's "
            f"{100 * (1 - TAG_SCALE_WARN_MASS):g} % ({1e3 * top:.3g} ms; stated "
            f"{1e3 * stated_s:.3g} ms, [telemetry_knowledge] time_tag_sd_s): a misfit at the "
            "pulses may be taken for time-tag errors; check the adequacy, the thrust mode and "
            "the pulse log"]


HALF_NORMAL_MEDIAN = 0.6744897501960817   # Φ⁻¹(3/4): median of a unit half-normal
_BRANCH_INDEX = np.array([0, 0, 0, 0, 1, 1, 1, 1])


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
        return np.r_[HALF_NORMAL_MEDIAN * self.delay_scale, np.exp(self.log_mean)]

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
    """Posterior sites of the thrust of a mode: ``F``; ``F_Z, F_Y`` (Cassini's branches);
    ``F`` along the dimension ``thruster`` (one per thruster of the model, summarised as
    ``F[<name>]``)."""
    if mode in ("mean", "thruster"):
        return ("F",)
    if mode == "branch":
        return ("F_Z", "F_Y")
    raise InputError(f"{arg('mode', mode, cli_quote=True)}: choose one of {', '.join(MODES)}")


def thrust_index(mode: str, n_thrusters: int) -> np.ndarray:
    """(M,) index of the thrust parameter that drives each thruster (``branch``: Cassini's eight
    of Feldman & Lee Eq 16, Z1..Z4 then Y1..Y4)."""
    return {"mean": lambda: np.zeros(n_thrusters, int), "branch": lambda: _BRANCH_INDEX,
            "thruster": lambda: np.arange(n_thrusters)}[mode]()


def sample_thrust_prior(key, problem: ThrustProblem, n: int) -> dict[str, np.ndarray]:
    """``n`` draws of the physical parameters from the stated prior (module docstring)."""
    k_f, k_t, k_s, k_i = jax.random.split(key, 4)
    kw = problem.data
    n_ev = kw.log_noise_hat.shape[0]
    n_f = problem.n_f
    f_z = jax.random.normal(k_f, (n, n_f + (3 if problem.mode == "thruster" else 0)))
    noise_z = jax.random.normal(k_s, (n, n_ev, 1)) * NOISE_PRIOR_LOG_SD / NOISE_STEP
    thrust = np.exp(np.log(problem.thrust_pred) + THRUST_PRIOR_LOG_SD * np.asarray(f_z[:, :n_f]))
    tau = np.asarray(draw_tau_prior(k_t, problem.tau, (n,)))
    if problem.mode == "thruster":
        out = {"F": thrust}
        com = float(kw.com_sd) * np.asarray(f_z[:, n_f:])
        out.update({name: com[:, i] for i, name in enumerate(COM_NAMES)})
    else:
        out = {name: thrust[:, i] for i, name in enumerate(problem.names)}
    out.update({name: tau[:, i] for i, name in enumerate(TAU_NAMES)})
    sig = np.exp(np.asarray(kw.log_noise_hat)[None] + NOISE_STEP * np.asarray(noise_z))
    out["sigma_omega"], out["sigma_rho"] = sig[..., 0], sig[..., 1]
    if kw.tag_sd is not None:
        z = np.asarray(jax.random.normal(jax.random.fold_in(k_s, 1), (n,)))
        out["time_tag_sd"] = float(kw.tag_sd[0]) * np.exp(np.asarray(tag_log_scale(z)))
    if problem.inertia is not None:
        z = np.asarray(jax.random.normal(k_i, (n, 6)))
        pi = np.asarray(problem.inertia.mean) + z @ np.linalg.cholesky(
            np.asarray(problem.inertia.cov) + 1e-9 * np.eye(6)).T
        out.update({name: pi[:, i] for i, name in enumerate(INERTIA_NAMES)})
    return out
