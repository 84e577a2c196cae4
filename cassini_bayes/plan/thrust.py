"""Predicted posterior of the robust thrust fit (Feldman & Lee 2006 §V) for a biasing event.

The fit (:mod:`cassini_bayes.inference.thrust`, ``fit thrust``) samples the thrust (one ``F``,
``F_Z``/``F_Y``, or one per thruster with the centre-of-mass offset), the pulse time constants
(through the rise deficit, its split and the long-pulse excess), a noise scale per event and the
inertia (the robust default); the offsets and the robust nuisance ``ν`` (gyro bias and scale,
wheel spin-inertia scales and tilts, body torques) are integrated out exactly in its density. The
prediction is that density's Laplace approximation on the event flown without noise:

1. the scenario is simulated with every sensor error off
   (:func:`~cassini_bayes.plan.wheel_axis.noise_free_telemetry`);
2. the fit's own preparation (:func:`~cassini_bayes.inference.thrust.prepare_thrust`: pulse
   layout, nuisance columns, time-tag rows, the per-thruster design) runs on it with the white-noise
   levels of the scenario's sensors (:func:`~cassini_bayes.plan.wheel_axis.scenario_noise`) in
   place of the levels it would estimate from noisy data, and a regular clock's grid errors
   at the model file's time-tag sd in place of the scatter noise-free labels lack;
3. the event's noise scale is held at 1 (``noise_z = 0``): on noise-free data its curvature is the
   prior's and its cross-curvature with every other coordinate vanishes at the truth (it multiplies
   residuals that are zero), so holding it changes no other sd;
4. the truth is mapped into the fit's sampler coordinates (:func:`truth_coordinates`, the inverse
   of :func:`~cassini_bayes.inference.thrust.coords.physical`), and the negative ``jax.hessian``
   of the fit's own log density there is the precision: on noise-free data the residuals vanish
   at the truth, so it is the expected Fisher information plus the prior's curvature (the
   dependence of the time-tag covariance on ``F`` and ``τ`` aside, second order). The truth,
   not the mode: on noise-free data the two differ by the prior's pull only;
5. every site (thrusts, ``com_*``, ``tau_*``, ``Ixx … Iyz``) follows by the delta method through
   the fit's own map to the physical parameters (``jax.jacfwd``); in mode ``thruster`` also each
   identified combination of thrusts (:class:`~cassini_bayes.inference.thrust.design.ThrustDesign`);
6. the fit's density holds the wheels at the model file's common spin-inertia scale ``u`` and
   reports its thrusts and inertia times ``1 + u``, ``u`` from its prior
   (:attr:`~cassini_bayes.inference.thrust.ThrustProblem.scale_free`): their covariance gains
   ``x xᵀ var(u)``, ``x`` the thrusts and inertia at the truth;
7. the same at the noise-free posterior's mode: a site whose sd there is not within
   :data:`NON_GAUSSIAN_SHARE` of its sd at the truth sits on a ridge the prior shapes (the
   thrust against the pulse shape where every pulse has one width), whose posterior is not
   Gaussian: each flight's noise puts the fit elsewhere on it, with another sd, so the
   prediction names the sites that are off as indicative, and every ridge site (thrusts, time
   constants) when one of them is (:attr:`ThrustPrediction.non_gaussian`).
"""

from __future__ import annotations

from dataclasses import replace
from functools import lru_cache
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.names import INERTIA_NAMES, TAU_NAMES
from cassini_bayes.plan import checks
from cassini_bayes.plan.budgets import thrust_budgets
from cassini_bayes.plan.limits import Limits
from cassini_bayes.plan.wheel_axis import noise_free_telemetry, scenario_noise
from cassini_bayes.simulate.scenario import Scenario

__all__ = ["ThrustPrediction", "evaluate_thrust", "noise_free_problem", "predict_thrust",
           "representable", "sd_at_mode", "truth_coordinates"]

_PRIOR_DRAWS = 4000       # prior draws for the sites' prior sd (fixed key)

NON_GAUSSIAN_SHARE = 0.25
"""Largest share by which a site's predicted sd at the noise-free posterior's mode may differ
from the one at the truth (either way) before the prediction calls the posterior not Gaussian
(module docstring, step 7): the ±25 % to which a prediction is held against fits."""


class ThrustPrediction(NamedTuple):
    """Predicted posterior of the robust thrust fit of one biasing event (SI: N, s, m, kg m²).

    mode : the fit's thrust mode. sites : the thrust sites (``F``; ``F_Z``, ``F_Y``; or
    ``F[<name>]`` per thruster, then ``com_x … com_z``), then ``tau_delay … tau_fall``, then
    ``Ixx … Iyz``. site_sd, site_prior_sd : predicted posterior sd and prior sd per site.
    budget : the budget of each site (NaN where none: the inertia, the centre of mass);
    truth : each site's true value. combinations : ``{label: (sd, prior sd, budget)}`` of
    the thrust combinations the design identifies (mode ``thruster``). noise : (2,) the white-noise
    levels used (σ_ω, σ_ρ rad/s). usage : largest fraction of each limit on the simulated
    telemetry (empty without limits). n_pulses, pulse_widths_s : the pulses fired and their
    distinct widths. duration_s; t, omega, wheel_rpm, wheel_names, pulse_t, pulse_width,
    pulse_thruster : the noise-free flight for the report's figure. floored : the directions
    whose curvature at the truth was below :data:`CURVATURE_MIN` (given unit curvature).
    site_sd_mode : each site's sd at the noise-free posterior's mode (nominal truth; ``None``
    where not checked); see :attr:`non_gaussian`.
    truths : the truths drawn from the model file's knowledge besides the nominal one
    (:func:`evaluate_thrust`); site_sd is the median over them and the nominal truth,
    site_sd_nominal the nominal truth's, site_sd_truths (truths + 1, sites) each one's.
    """

    mode: str
    sites: tuple[str, ...]
    site_sd: np.ndarray
    site_prior_sd: np.ndarray
    budget: np.ndarray
    truth: np.ndarray
    combinations: dict
    noise: np.ndarray
    usage: dict
    n_pulses: int
    pulse_widths_s: tuple[float, ...]
    duration_s: float
    t: np.ndarray
    omega: np.ndarray
    wheel_rpm: np.ndarray
    wheel_names: tuple[str, ...]
    pulse_t: np.ndarray
    pulse_width: np.ndarray
    pulse_thruster: tuple[str, ...]
    floored: int = 0
    truths: int = 0
    site_sd_nominal: np.ndarray | None = None
    site_sd_truths: np.ndarray | None = None
    site_sd_mode: np.ndarray | None = None

    @property
    def site_sd_range(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Each site's least and largest sd over the truths (``None`` where not kept)."""
        if self.site_sd_truths is None:
            return None
        return self.site_sd_truths.min(axis=0), self.site_sd_truths.max(axis=0)

    @property
    def site_sd_interval(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Each site's interval of the median sd over the truths' population, at least 90 %
        (:func:`~cassini_bayes.plan.truths.median_interval`: NaN below 5 truths; ``None``
        where not kept): how far :attr:`site_sd` may be from the median of more truths."""
        from cassini_bayes.plan.truths import median_interval

        return None if self.site_sd_truths is None else median_interval(self.site_sd_truths)

    @property
    def sd_mode_ratio(self) -> np.ndarray | None:
        """Each site's sd at the noise-free posterior's mode over its sd at the nominal truth."""
        if self.site_sd_mode is None:
            return None
        nominal = self.site_sd if self.site_sd_nominal is None else self.site_sd_nominal
        return self.site_sd_mode / nominal

    @property
    def non_gaussian(self) -> tuple[str, ...]:
        """The sites whose :attr:`sd_mode_ratio` is outside ``1 ± NON_GAUSSIAN_SHARE`` (module
        docstring, step 7), their predicted sd indicative; where one is a thrust or
        time-constant site, every thrust and time-constant site (they share the ridge of thrust
        and pulse shape)."""
        r = self.sd_mode_ratio
        if r is None:
            return ()
        off = {n for n, x in zip(self.sites, r)
               if abs(np.log(x)) > np.log1p(NON_GAUSSIAN_SHARE)}
        ridge = set(self.ridge_sites)
        named = off | ridge if off & ridge else off
        return tuple(n for n in self.sites if n in named)

    @property
    def ridge_sites(self) -> tuple[str, ...]:
        """The thrust and time-constant sites: one pulse width leaves them on one ridge."""
        return tuple(n for n in self.sites if n in TAU_NAMES or n.startswith("F"))

    @property
    def ratio(self) -> np.ndarray:
        """``sd / budget`` per site (NaN where no budget)."""
        return self.site_sd / self.budget

    @property
    def max_ratio(self) -> float:
        """The largest ``sd / budget`` over the sites with a budget (and the combinations)."""
        r = [x for x in self.ratio if np.isfinite(x)]
        r += [sd / b for sd, _, b in self.combinations.values() if np.isfinite(b)]
        return float(max(r))

    @property
    def worst(self) -> str:
        """The site (or combination) of :attr:`max_ratio`."""
        r = {n: x for n, x in zip(self.sites, self.ratio) if np.isfinite(x)}
        r.update({k: sd / b for k, (sd, _, b) in self.combinations.items() if np.isfinite(b)})
        return max(r, key=r.get)


@lru_cache(maxsize=None)
def _held_density(n_f: int, n_c: int, sample_inertia: bool, n_ev: int):
    """The fit's log density with every event's noise coordinate and the time tags' scale
    held at 0 (the data's noise, the stated tag sd: variances, which noise-free data do not
    inform): ``f(x, kw)``, ``x`` the sampler vector without them (one function object per
    layout: compiled once)."""
    from cassini_bayes.inference.thrust.coords import n_tag
    from cassini_bayes.inference.thrust.model import log_density

    def f(x, kw):
        return log_density(_unheld(x, n_f, n_c, n_ev, n_tag(kw)), kw, n_f, n_c, sample_inertia)

    return f


def _unheld(x, n_f: int, n_c: int, n_ev: int, n_tags: int):
    """The fit's sampler vector from ``x`` (:func:`_held_density`'s): the noise and tag-scale
    coordinates put back at 0; the inverse of :func:`_held`."""
    k = n_f + n_c + 3
    return jnp.concatenate([x[:k], jnp.zeros(n_ev), x[k:], jnp.zeros(n_tags)])


def _held(theta: np.ndarray, n_f: int, n_c: int, n_ev: int, n_tags: int) -> np.ndarray:
    k = n_f + n_c + 3
    return np.concatenate([theta[:k], theta[k + n_ev:theta.size - n_tags]])


class _Laplace(NamedTuple):
    centre: np.ndarray
    cov: np.ndarray
    site_cov: np.ndarray
    site_mean: np.ndarray
    floored: int = 0


CURVATURE_MIN = 1e-2
"""Least curvature of the log density in the sampler's coordinates (whose prior sds are 0.3-3)
taken as information: a direction below it (the density not concave at the truth: the data leave
it, e.g. the split of the rise deficit into delay and rise on 1-s telemetry, at a prior that is
not log-concave there) gets unit curvature, the prior's order of sd, instead of none; the
prediction says how many (``ThrustPrediction.floored``)."""


def truth_coordinates(problem, thrust, com, tau, inertia) -> np.ndarray:
    """The sampler vector of the fit (noise and tag-scale coordinates left out,
    :func:`_held_density`) at the physical parameters ``thrust`` (n_f,) N, ``com`` (3,) m (mode
    ``thruster``), ``tau`` (3,) s and ``inertia`` (6,) kg m² (when sampled): the inverse of the
    fit's ``coords.physical`` and ``coords.tau_from_z``."""
    from cassini_bayes.inference.thrust.coords import A_LOG_SCALE, C_SCALE_S, log_bit_shift
    from cassini_bayes.inference.thrust.prior import THRUST_PRIOR_LOG_SD

    kw = problem.data
    t_d, t_r, t_f = (max(float(tau[0]), 1e-7), float(tau[1]), float(tau[2]))
    f_z = (np.log(np.asarray(thrust, float)) - np.asarray(kw.f_mu, float)) / THRUST_PRIOR_LOG_SD
    if kw.bit_width is not None:      # impulse-bit coordinates (coords.physical)
        shift = np.asarray(log_bit_shift(jnp.asarray([t_d, t_r, t_f]), kw))
        f_z = f_z + shift / THRUST_PRIOR_LOG_SD
    parts = [f_z]
    if problem.n_c:
        x = np.concatenate([f_z, np.asarray(com, float) / float(kw.com_sd)])
        y = np.asarray(kw.f_basis, float).T @ x          # f_basis is orthogonal
        parts = [y[:problem.n_f], y[problem.n_f:]]
    b = t_r * np.exp(-t_d / t_r)                         # rise deficit's part after the delay
    a = t_d + b                                          # coords.rise_deficit
    s_split = np.log(t_d / b)                            # τd/b = e^s
    parts.append(np.array([np.arcsinh(s_split), np.log(a / float(kw.a_mu)) / A_LOG_SCALE,
                           (t_f - b - float(kw.c_mu)) / C_SCALE_S]))
    if problem.inertia is not None:
        parts.append(np.linalg.solve(np.asarray(kw.inertia_tril, float),
                                     np.asarray(inertia, float) - np.asarray(kw.inertia_mean)))
    return np.concatenate(parts)


def predict_thrust(problem, sigmas, at=None) -> _Laplace:
    """Laplace approximation of the fit's posterior for the prepared ``problem`` with the
    white-noise levels ``sigmas`` (2,) rad/s of every event and its noise scale held at 1 (module
    docstring), at the sampler vector ``at`` (:func:`truth_coordinates`; default the mode, found
    by :func:`~cassini_bayes.inference.laplace.laplace`): the point, the covariance of the
    sampler coordinates, and the sites' covariance (thrusts, ``com_*``, ``tau_*``, the inertia
    when sampled) by the delta method."""
    from cassini_bayes.inference.thrust.coords import n_tag, physical

    kw0 = problem.data
    n_ev = kw0.log_noise_hat.shape[0]
    kw = kw0._replace(log_noise_hat=jnp.log(jnp.broadcast_to(jnp.asarray(sigmas, float),
                                                             (n_ev, 2))))
    n_f, n_c, si = problem.n_f, problem.n_c, problem.inertia is not None
    f = _held_density(n_f, n_c, si, n_ev)
    if at is None:
        from cassini_bayes.inference.laplace import laplace

        x0 = _held(np.asarray(kw0.centre, float), n_f, n_c, n_ev, n_tag(kw0))
        at, _ = laplace(f, x0, kw)
    centre = jnp.asarray(at, float)
    hess = -np.asarray(jax.hessian(f)(centre, kw))
    lam, vec = np.linalg.eigh(0.5 * (hess + hess.T))
    flat = lam < CURVATURE_MIN
    cov = (vec / np.where(flat, 1.0, lam)) @ vec.T
    floored = int(np.sum(flat))

    def sites(x):
        p = physical(_unheld(x, n_f, n_c, n_ev, n_tag(kw)), kw, n_f, n_c, si)
        parts = [p.thrust, p.com, p.tau] + ([p.inertia] if si else [])
        return jnp.concatenate(parts)

    jac = np.asarray(jax.jacfwd(sites)(centre))
    mean = np.asarray(sites(centre))
    site_cov = jac @ cov @ jac.T
    if problem.scale_free:     # the fit's draws times 1 + u, u the wheels' common scale
        scaled = np.r_[mean[:n_f], np.zeros(n_c + 3), mean[n_f + n_c + 3:]]
        site_cov = site_cov + problem.layout.common_scale_sd**2 * np.outer(scaled, scaled)
    return _Laplace(np.asarray(centre), cov, site_cov, mean, floored)


def _site_names(problem) -> list[str]:
    from cassini_bayes.inference.thrust import COM_NAMES

    if problem.mode == "thruster":
        thrust = [f"F[{n}]" for n in problem.thrusters] + list(COM_NAMES)
    else:
        thrust = list(problem.names)
    return thrust + list(TAU_NAMES) + (list(INERTIA_NAMES) if problem.inertia is not None else [])


def _prior_sd(problem, names: list[str]) -> np.ndarray:
    """Each site's prior sd from fixed-key draws of the fit's own prior."""
    from cassini_bayes.inference.thrust import sample_thrust_prior

    d = sample_thrust_prior(jax.random.key(0), problem, _PRIOR_DRAWS)
    out = []
    for n in names:
        if n.startswith("F["):
            out.append(np.std(d["F"][:, list(problem.thrusters).index(n[2:-1])]))
        else:
            out.append(np.std(d[n]))
    return np.asarray(out, float)


def _truth(s: Scenario, problem, names: list[str]) -> np.ndarray:
    """The scenario's true value of each site (the thrust mean for a common ``F``)."""
    from cassini_bayes.physics.momentum import inertia_vector

    tr = s.truth
    per = np.broadcast_to(np.asarray(s.thrust_n, float), (len(problem.thrusters),))
    pulse = tr.pulse
    values = {"tau_delay": pulse.tau_delay, "tau_rise": pulse.tau_rise,
              "tau_fall": pulse.tau_fall}
    values.update(zip(INERTIA_NAMES, np.asarray(inertia_vector(tr.inertia), float)))
    com = np.asarray(tr.com_m, float) - np.asarray(s.prior.com_m, float)
    values.update({"com_x": com[0], "com_y": com[1], "com_z": com[2]})
    values.update({f"F[{n}]": per[i] for i, n in enumerate(problem.thrusters)})
    values.update({n: float(np.mean(per)) for n in problem.names if not n.startswith("F[")})
    return np.asarray([values.get(n, np.nan) for n in names], float)


def representable(s: Scenario, mode: str) -> Scenario:
    """``s`` with its truth moved into the fit's model where the mode cannot hold it: one thrust
    for every thruster (the mean of the true ones) and the model file's centre of mass, unless
    the mode is ``thruster`` (which has both). At a truth the model holds, the noise-free
    residuals vanish and the Hessian there is the Fisher information; at one it does not hold,
    the residuals' curvature makes it indefinite (a common ``F`` for thrusters 4 % apart)."""
    if mode == "thruster":
        return s
    thrust = np.broadcast_to(np.asarray(s.thrust_n, float), (len(s.truth.thrusters),))
    truth = replace(s.truth, com_m=np.asarray(s.prior.com_m, float))
    return replace(s, thrust_n=tuple(float(np.mean(thrust)) for _ in thrust), truth=truth)


def noise_free_problem(s: Scenario, mode: str = "mean"):
    """The event of ``s`` flown without noise and prepared by the fit (the default robust model,
    the inertia sampled from the model file's knowledge) with the scenario's sensors' noise
    levels: ``(SimResult, ThrustProblem, (σ_ω, σ_ρ) rad/s)``."""
    from cassini_bayes.errors import InputError
    from cassini_bayes.inference.thrust import prepare_thrust, resolve_inertia

    sim, tel = noise_free_telemetry(representable(s, mode))
    if sim.pulses is None or sim.pulses.t_on.size == 0:
        raise InputError(f"scenario {s.name!r}: no thruster fires, so there is no thrust to "
                         "calibrate (give [[wheel_ramp]]s under control = \"rcs\" or "
                         "[[pulse]]s)", path=s.source)
    sig = np.asarray(scenario_noise(s)[:2], float)
    sc = s.prior
    problem = prepare_thrust([(tel, sim.pulses)], sc, mode=mode,
                             inertia=resolve_inertia(None, sc, True), robust=True,
                             noise_hat=sig[None], flex="off",
                             clock_sd_s=sc.knowledge.time_tag_sd_s)
    return sim, problem, sig


def evaluate_thrust(s: Scenario, mode: str = "mean", limits: Limits | None = None, *,
                    truths: int = 0, seed: int = 0, check_mode: bool = True) -> ThrustPrediction:
    """Predicted posterior of the default robust thrust fit (inertia sampled from the model
    file's knowledge, per-wheel scales) of the biasing event of scenario ``s`` in thrust
    ``mode`` (module docstring).

    ``truths`` > 0: the prediction is also made on that many truths drawn from the model file's
    knowledge (:func:`~cassini_bayes.plan.truths.knowledge_truths`, stream ``seed``), each flown
    by its own controller, and each site's sd is the median over them and the nominal truth (a
    closed-loop event's pulses, and so what it tells, follow the truth); ``site_sd_nominal`` and
    ``site_sd_truths`` keep the nominal and every truth's. ``check_mode``: also the sd at the
    noise-free posterior's mode (module docstring, step 7; one more mode search)."""
    from cassini_bayes.plan.truths import knowledge_truths

    sim, problem, sig = noise_free_problem(s, mode)
    s = representable(s, mode)
    sc = s.prior
    names = _site_names(problem)
    truth = _truth(s, problem, names)
    prior_sd = _prior_sd(problem, names)
    lap = predict_thrust(problem, sig, at=_truth_vector(problem, names, truth))
    sds = [np.sqrt(np.diag(lap.site_cov))]
    combos = [_combinations(problem, lap.site_cov, prior_sd)]
    for t in knowledge_truths(s, truths, seed):      # drawn from ``s``: representable already
        _, p_t, sig_t = noise_free_problem(t, mode)
        lap_t = predict_thrust(p_t, sig_t, at=_truth_vector(p_t, names, _truth(t, p_t, names)))
        sds.append(np.sqrt(np.diag(lap_t.site_cov)))
        combos.append(_combinations(p_t, lap_t.site_cov, prior_sd))
    sd_mode = sd_at_mode(problem, sig) if check_mode else None
    sd_all = np.array(sds)
    sd = np.median(sd_all, axis=0)
    combo = {k: (float(np.median([c[k][0] for c in combos if k in c])), v[1], v[2])
             for k, v in combos[0].items()}
    arr = sim.arrays
    usage = {}
    if limits is not None:
        usage = checks.largest_usage(arr.t, arr.omega, arr.wheel_rates, sc.wheel_axes,
                                     sc.wheel_inertias, np.asarray(s.wheels_on, float), limits)
    rpm = np.where(np.asarray(s.wheels_on)[None, :], np.asarray(arr.wheel_rates) * 30.0 / np.pi,
                   np.nan)
    log = sim.pulses
    return ThrustPrediction(
        mode=mode, sites=tuple(names), site_sd=sd, site_prior_sd=prior_sd,
        budget=thrust_budgets(sc, names, problem.thrust_pred), truth=truth, combinations=combo,
        noise=sig, usage=usage, n_pulses=int(log.t_on.size),
        pulse_widths_s=tuple(float(x) for x in np.unique(np.round(log.width, 6))),
        duration_s=s.duration_s, t=np.asarray(arr.t), omega=np.asarray(arr.omega),
        wheel_rpm=rpm, wheel_names=tuple(s.wheel_names), pulse_t=np.asarray(log.t_on, float),
        pulse_width=np.asarray(log.width, float),
        pulse_thruster=tuple(log.thruster_names[i] for i in np.asarray(log.thruster)),
        floored=lap.floored, truths=truths, site_sd_nominal=sds[0],
        site_sd_truths=sd_all, site_sd_mode=sd_mode)


def sd_at_mode(problem, sig) -> np.ndarray | None:
    """Each site's predicted sd at the mode of the fit's density on the noise-free ``problem``
    (:func:`predict_thrust` from the fit's own start); ``None`` where no finite one is found."""
    sd = np.sqrt(np.diag(predict_thrust(problem, sig).site_cov))
    return sd if np.all(np.isfinite(sd)) and np.all(sd > 0) else None


def _combinations(problem, site_cov: np.ndarray, prior_sd: np.ndarray) -> dict:
    """``{label: (sd, prior sd, budget)}`` of the thrust combinations the design identifies
    (mode ``thruster``; a single thruster is its own site)."""
    from cassini_bayes.inference.thrust.design import combination_label

    if problem.design is None or not problem.design.combinations.size:
        return {}
    m = len(problem.thrusters)
    cf = site_cov[:m, :m]
    pred = np.asarray(problem.thrust_pred, float)
    prior_cov = np.diag(prior_sd[:m] ** 2)
    out = {}
    for w in problem.design.combinations:
        if np.count_nonzero(np.abs(w) > 1e-12) < 2:
            continue
        out[combination_label(w, problem.thrusters)] = (
            float(np.sqrt(w @ cf @ w)), float(np.sqrt(w @ prior_cov @ w)),
            float(0.01 * _thrust_pct() * abs(w @ pred)))
    return out


def _truth_vector(problem, names: list[str], truth: np.ndarray) -> np.ndarray:
    """:func:`truth_coordinates` from the sites' true values (:func:`_truth`)."""
    v = dict(zip(names, truth))
    thrust = truth[:problem.n_f]
    com = [v.get(n, 0.0) for n in ("com_x", "com_y", "com_z")]
    tau = [v[n] for n in TAU_NAMES]
    inertia = [v[n] for n in INERTIA_NAMES] if problem.inertia is not None else None
    return truth_coordinates(problem, thrust, com, tau, inertia)


def _thrust_pct() -> float:
    from cassini_bayes.analysis.paper_facts import fact

    return float(fact("thrust_accuracy_pct").value)
