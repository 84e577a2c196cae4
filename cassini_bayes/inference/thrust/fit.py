"""The thrust fit: NUTS on the prepared problem, the robust nuisance drawn from its exact
conditional, the posterior-mean residuals and the InferenceData (:func:`fit_thrust`).
"""

from __future__ import annotations

import warnings
from typing import NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.inference.idata import replace_groups
from cassini_bayes.inference.inertia.knowledge import InertiaGaussian
from cassini_bayes.inference.nuisance import split_nuisance
from cassini_bayes.inference.thrust.data import ThrustProblem, prepare_thrust
from cassini_bayes.inference.thrust.likelihood import impulse_residuals
from cassini_bayes.inference.thrust.model import nuisance_sampler, thrust_model
from cassini_bayes.inference.thrust.prior import (COM_NAMES, THRUST_PRIOR_LOG_SD,
                                                  TauIdentificationWarning,
                                                  resolve_inertia, sample_thrust_prior,
                                                  tag_scale_warning,
                                                  tau_identification)
from cassini_bayes.inference.thrust.pulses import pulse_impulses
from cassini_bayes.names import EFFECTS, INERTIA_NAMES, TAU_NAMES
from cassini_bayes.physics.flex_mode import MODE_ENTRIES
from cassini_bayes.physics.impulse import impulse_lhs
from cassini_bayes.physics.momentum import inertia_matrix
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import PulseLog, Telemetry

__all__ = ["ThrustPosterior", "RESIDUAL_DRAWS", "fit_thrust"]


class ThrustPosterior(NamedTuple):
    """Result of :func:`fit_thrust`: the InferenceData, its diagnostics and the problem."""

    idata: object
    diagnostics: object
    problem: ThrustProblem


def _add_nuisance_draws(key, idata, problem: ThrustProblem, sample_inertia: bool,
                        coords: dict, dims: dict) -> np.ndarray:
    """Add the robust model's nuisance sites (:func:`~cassini_bayes.inference.nuisance.
    split_nuisance`) to the posterior: one draw of ``ν`` from its exact conditional per draw of
    the sampler (:func:`nuisance_sampler`), so the sites are draws of the joint posterior.
    Returns the draws of ``ν`` (chain × draw, R), in the posterior's flattened order."""
    import xarray as xr

    kw = problem.data
    w = np.asarray(idata.posterior["w"].values)
    n_chain, n_draw, dim = w.shape
    n_nu = kw.nu_sd.shape[0]
    eps = jax.random.normal(key, (n_chain * n_draw, n_nu))
    nu = np.asarray(nuisance_sampler(problem.n_f, problem.n_c, sample_inertia)(
        jnp.asarray(w.reshape(-1, dim)), eps, kw))
    for site, v in split_nuisance(nu.reshape(n_chain, n_draw, n_nu), problem.layout).items():
        site_dims = tuple(dims.get(site, ()))
        idata.posterior[site] = xr.DataArray(
            v, dims=("chain", "draw") + site_dims,
            coords={"chain": idata.posterior.chain, "draw": idata.posterior.draw,
                    **{d: coords[d] for d in site_dims}})
    return nu


SCALED_EFFECTS = ("body_torque", "torque_rate", "flex_mode")
"""Nuisance effects in N m, N m/s or kg m²: with the inertia and the thrusts, the quantities the
wheels' common spin-inertia scale multiplies (:func:`_at_common_scale`)."""


def _at_common_scale(idata, problem: ThrustProblem, nu: np.ndarray) -> None:
    """Where the likelihood holds the wheels at the model file's common scale
    (:attr:`ThrustProblem.scale_free`), put the reported draws at the drawn one: each draw's
    thrusts, inertia and torques times ``1 + u``, ``u`` its common scale
    (:attr:`~cassini_bayes.inference.nuisance.NuisanceLayout.common_scale_weights` of its
    ``ν``, which the data leave at their prior). Feldman & Lee Eq 17 is homogeneous in them and
    the wheels' inertias, so the scaled draws fit the data as the held ones do."""
    import xarray as xr

    if not problem.scale_free:
        return
    lay = problem.layout
    post = idata.posterior
    u = nu[:, lay.wheel_block] @ lay.common_scale_weights
    one = xr.DataArray(1.0 + u.reshape(post.sizes["chain"], post.sizes["draw"]),
                       dims=("chain", "draw"))
    names = list(problem.names) + list(INERTIA_NAMES) + [EFFECTS[e] for e in SCALED_EFFECTS]
    for name in names:
        if name in post:
            post[name] = (post[name] * one).transpose(*post[name].dims).assign_attrs(
                post[name].attrs)


def _add_combinations(idata, problem: ThrustProblem) -> None:
    """Add ``F_combination`` (N) along ``combination`` to the posterior and prior groups: each
    identified combination ``Σ_s w_s F_s`` of thrusters the events do not separate
    (:class:`~cassini_bayes.inference.thrust.design.ThrustDesign`)."""
    import xarray as xr

    from cassini_bayes.inference.thrust.design import combination_label

    w = problem.design.combinations
    labels = [combination_label(row, problem.thrusters) for row in w]
    for group in ("posterior", "prior"):
        if group not in idata.groups():
            continue
        ds = getattr(idata, group)
        c = np.tensordot(np.asarray(ds["F"].values, float), w.T, 1)
        ds["F_combination"] = xr.DataArray(
            c, dims=("chain", "draw", "combination"),
            coords={"chain": ds.chain, "draw": ds.draw, "combination": labels},
            attrs={"units": "N"})


def _add_impulse_bits(idata, problem: ThrustProblem) -> None:
    """Mode ``thruster``: add ``bit`` (N s) to the posterior and prior groups
    where the events fire every thruster at one width (``problem.data.bit_width``): each one's
    impulse bit ``F_s j(Δ; τ)`` at that width (Feldman & Lee §V closed form,
    :func:`~cassini_bayes.physics.pulse.pulse_impulse`), the quantity one width identifies;
    ``F_s`` alone trades against the pulse shape. Fired thrusters only (dimension
    ``bit_thruster``); their widths are the attribute ``width_s``."""
    import xarray as xr

    from cassini_bayes.physics.pulse import pulse_impulse

    widths = np.asarray(problem.data.bit_width, float)                    # (M,) s, 0: unfired
    fired = np.flatnonzero(widths > 0)
    for group in ("posterior", "prior"):
        if group not in idata.groups():
            continue
        ds = getattr(idata, group)
        tau = [np.asarray(ds[n].values, float)[..., None] for n in TAU_NAMES]
        f = np.asarray(ds["F"].values, float)[..., fired]
        ds["bit"] = xr.DataArray(
            f * np.asarray(pulse_impulse(widths[fired][None, None], *tau)),
            dims=("chain", "draw", "bit_thruster"),
            coords={"chain": ds.chain, "draw": ds.draw,
                    "bit_thruster": [problem.thrusters[i] for i in fired]},
            attrs={"units": "N s", "width_s": [float(widths[i]) for i in fired]})


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
    com = (np.concatenate([flat(n) for n in COM_NAMES], 1) if problem.n_c else None)
    tau = np.concatenate([flat(n) for n in TAU_NAMES], 1)
    sig = np.stack([flat("sigma_omega"), flat("sigma_rho")], -1)          # (S, E, 2)
    pi = np.concatenate([flat(n) for n in INERTIA_NAMES], 1) if sample_inertia else None
    scale = (flat("time_tag_sd")[:, 0] / float(problem.data.tag_sd[0])
             if "time_tag_sd" in post else np.ones(n_s))
    total = 0.0
    for i in pick:
        total = total + impulse_residuals(problem, f[i], tau[i], sig[i],
                                          None if pi is None else pi[i],
                                          None if nu_draws is None else nu_draws[i],
                                          None if com is None else com[i], scale[i])
    return total / pick.size


def _data_groups(problem: ThrustProblem, d: np.ndarray) -> dict:
    """The ``observed_data``, ``constant_data`` and ``residuals`` groups of :func:`fit_thrust`
    (``d`` the posterior-mean residuals, :func:`_posterior_mean_residuals`)."""
    import xarray as xr

    kw = problem.data
    n_ev = len(problem.sources)
    m = np.asarray(kw.events.mask) > 0
    t_all = np.concatenate([np.asarray(kw.events.t)[e][m[e]] for e in range(n_ev)])
    ev_all = np.concatenate([np.full(int(m[e].sum()), e) for e in range(n_ev)])
    r_all = np.concatenate([d[e][m[e]] for e in range(n_ev)])
    i_fix = inertia_matrix(jnp.asarray(kw.inertia_mean))
    v_all = np.concatenate([np.asarray(impulse_lhs(kw.events.t[e], kw.events.omega[e], i_fix,
                                                   kw.events.h_wheels[e]))[m[e]]
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
         "thrust_prior_median": (("thruster",) if np.ndim(problem.thrust_pred) else (),
                                 problem.thrust_pred, {"units": "N"}),
         "thrust_prior_log_sd": ((), THRUST_PRIOR_LOG_SD),
         "fired": ("thruster", problem.fired.astype(int)),
         "n_pulses": ("event", problem.n_pulses),
         "noise_hat": (("event", "noise"), problem.noise_hat)},
        coords={"tau_lognormal": list(TAU_NAMES[1:]), "thruster": list(problem.thrusters),
                "event": np.arange(n_ev), "noise": ["omega", "rho"]})
    return {"observed_data": observed, "constant_data": constant, "residuals": residuals}


def fit_thrust(key, events: Sequence[tuple[Telemetry, PulseLog]], spacecraft: Spacecraft, *,
               mode: str = "mean", inertia: InertiaGaussian | str | None = None, settings=None,
               prior_draws: int = 500, robust: bool = True,
               wheel_errors: str = "per_wheel", flex="check") -> ThrustPosterior:
    """Posterior of the thrust and the pulse time constants from one or more biasing events.

    Parameters
    ----------
    key : jax.random key.
    events : ``(telemetry, pulse log)`` per biasing event; they share ``τ`` and the thrust.
    spacecraft : model giving the predicted thrust, time-constant ranges, geometry of Eq 16,
        wheels and the inertia's prediction and knowledge.
    mode : ``"mean"`` (``F``, one thrust for all thrusters), ``"branch"`` (``F_Z``, ``F_Y``,
        Cassini's eight of Eq 16) or ``"thruster"`` (``F`` along ``thruster``, one per thruster
        of any layout, with the centre-of-mass offset ``com_x``, ``com_y``, ``com_z``; the
        combinations the events identify: ``problem.design``).
    inertia : how the spacecraft inertia enters. An :class:`InertiaGaussian` (e.g.
        :func:`inertia_from_run`, an inertia fit's posterior) or ``"prior"`` (the model file's
        knowledge, :func:`inertia_prior_gaussian`): sampled jointly. ``"fixed"``: held at the
        model file's prediction (an inertia error then moves ``F`` with it: the pulses' momentum
        is ``I Δω``). ``None`` (default): ``"prior"`` for the robust model, ``"fixed"`` for the
        idealised one (the papers' model).
    settings : :class:`~cassini_bayes.inference.runner.SamplerSettings`.
    prior_draws : number of prior draws stored in the ``prior`` group.
    robust : add the nuisance parameters (gyro bias and scale, wheel inertia scales and tilts,
        external torque; module docstring). The default, as on the CLI; ``False`` is the
        papers' idealised model (clean simulations, comparisons with the papers).
    wheel_errors : robust model's wheel spin-inertia errors: ``"per_wheel"`` (default, one scale
        per active wheel, site ``wheel_scale`` (wheel)) or ``"common"`` (one scalar scale).
    flex : robust model's flexible mode: ``"check"`` (default) searches the events for one (on
        ``problem.flex_mode``; the adequacy check ``flex_ringing``); ``"model"`` also integrates
        out the momentum it holds where they show it (site ``flex_inertia`` (mode_entry), kg
        m²); ``"off"``; or ``(freq_hz, damping)`` to put one there
        (:mod:`~cassini_bayes.inference.thrust.flex`).

    Returns
    -------
    ThrustPosterior
        ``idata`` with ``posterior`` (thrust names in N, ``tau_*`` in s, ``sigma_omega``,
        ``sigma_rho`` per event, inertia entries when sampled, sampler coordinates),
        ``sample_stats``, ``prior``, ``observed_data`` (``v``: the left side of Eq 17 at the
        fixed/prior-mean inertia, N m s), ``constant_data`` (prior centres and scales),
        ``residuals`` (posterior-mean offset-free residuals, N m s) and ``pulse_impulses``
        (each pulse group's measured and predicted impulse, :func:`pulse_impulses`).

    Warns
    -----
    TauIdentificationWarning
        One line per time constant the data do not identify or that conflicts with its prior
        (:func:`tau_identification`); the CLI puts them in ``summary["warnings"]``.
    PulseAtStartWarning
        A pulse acts on the first sample of an event (only its impulse after that sample is
        modelled: the event's free offset absorbs the rest).
    PulsesDroppedWarning
        Pulses of a log act entirely outside their event's telemetry and are left out.
    """
    from cassini_bayes.inference.progress import step
    from cassini_bayes.inference.runner import SamplerSettings, diagnostics, run_nuts

    settings = settings or SamplerSettings()
    inertia = resolve_inertia(inertia, spacecraft, robust)
    with step("preparing: events, Laplace approximation (mode and curvature)"):
        problem = prepare_thrust(events, spacecraft, mode=mode, inertia=inertia, robust=robust,
                                 wheel_errors=wheel_errors, flex=flex)
    unfired = [s for s, f in zip(problem.thrusters, problem.fired) if not f]
    if mode == "thruster" and unfired:
        warnings.warn(f"thrusters {', '.join(unfired)} never fire: their thrust is "
                      "prior-dominated", stacklevel=2)
    kw = problem.data
    sample_inertia = inertia is not None
    coords, dims = _coords_dims(problem, mode, robust, wheel_errors)
    idata = run_nuts(key, thrust_model(mode, sample_inertia), model_kwargs={"data": kw},
                     settings=settings, coords=coords, dims=dims,
                     prior=lambda k, n: sample_thrust_prior(k, problem, n),
                     prior_draws=prior_draws)
    _complete(key, idata, problem, robust, sample_inertia, coords, dims)
    _warn_identification(idata.posterior, problem)
    return ThrustPosterior(idata, diagnostics(idata, _judged_names(problem, sample_inertia,
                                                                   robust)), problem)


def _warn_identification(post, problem: ThrustProblem) -> None:
    """Warn of the time constants the data leave at or against their prior, and of a learned
    time-tag sd far above the statement."""
    for line in tau_identification(post, problem.tau):
        warnings.warn(line, TauIdentificationWarning, stacklevel=3)
    if problem.data.tag_sd is not None:
        for line in tag_scale_warning(post, float(problem.data.tag_sd[0])):
            warnings.warn(line, stacklevel=3)


def _complete(key, idata, problem, robust: bool, sample_inertia: bool, coords, dims) -> None:
    """Add to the sampled ``idata`` what is computed from its draws: the robust model's nuisance
    draws (from their exact conditional), the posterior-mean residuals and the data groups, each
    pulse group's impulses (at the likelihood's wheels), the draws at the common wheel scale
    (:func:`_at_common_scale`), the identified thrust combinations and the impulse bits."""
    from cassini_bayes.inference.progress import step

    with step("nuisance draws and residuals"):
        nu_draws = None
        if robust:
            nu_draws = _add_nuisance_draws(jax.random.fold_in(key, 7), idata, problem,
                                           sample_inertia, coords, dims)
        post = idata.posterior
        d = _posterior_mean_residuals(problem, post, sample_inertia, nu_draws)
        groups = _data_groups(problem, d) | {"pulse_impulses": pulse_impulses(problem, post,
                                                                              nu_draws)}
    if robust:
        _at_common_scale(idata, problem, nu_draws)
    if problem.design is not None and problem.design.combinations.size:
        _add_combinations(idata, problem)
    if problem.mode == "thruster" and problem.data.bit_width is not None:
        _add_impulse_bits(idata, problem)
    replace_groups(idata, groups)


def _coords_dims(problem, mode: str, robust: bool, wheel_errors: str):
    """The ArviZ coordinates and dimensions of the thrust posterior's sites: per event, per
    thruster (mode ``thruster``) and, for the robust model, per axis, wheel and tilt."""
    coords = {"event": np.arange(len(problem.sources)),
              "w_dim": np.arange(problem.data.centre.shape[0]),
              "thruster": list(problem.thrusters)}
    dims = {"sigma_omega": ["event"], "sigma_rho": ["event"], "w": ["w_dim"],
            **({"F": ["thruster"]} if mode == "thruster" else {})}
    if robust:
        coords.update({"axis": ["x", "y", "z"], "wheel": list(problem.layout.wheels),
                       "tilt": ["u1", "u2"]})
        if problem.layout.slices.get("flex_mode") is not None:
            coords["mode_entry"] = list(MODE_ENTRIES)
            dims[EFFECTS["flex_mode"]] = ["mode_entry"]
        dims.update({EFFECTS["gyro_bias"]: ["event", "axis"], EFFECTS["gyro_scale"]: ["axis"],
                     EFFECTS["wheel_axes"]: ["wheel", "tilt"],
                     EFFECTS["body_torque"]: ["event", "axis"],
                     EFFECTS["torque_rate"]: ["event", "axis"],
                     **({EFFECTS["wheel_inertia"]: ["wheel"]}
                        if wheel_errors == "per_wheel" else {})})
    return coords, dims


def _judged_names(problem, sample_inertia: bool, robust: bool) -> list[str]:
    """The sites the fit's diagnostics judge: thrusts, centre-of-mass offsets, time constants,
    noise levels, the inertia entries when sampled and the nuisance effects when robust."""
    names = (list(problem.names) + list(COM_NAMES[:problem.n_c]) + list(TAU_NAMES)
             + ["sigma_omega", "sigma_rho"])
    if sample_inertia:
        names += list(INERTIA_NAMES)
    if robust:
        names += [EFFECTS[e] for e in problem.layout.sites]
    if problem.data.tag_sd is not None:
        names.append("time_tag_sd")
    return names
