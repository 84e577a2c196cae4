"""Thrust and pulse time constants from biasing events: :func:`fit_thrust` and its summary."""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, cast

from cassini_bayes._devices import jax_entry
from cassini_bayes.api._inputs import (
    WHEEL_ERRORS,
    check_seed,
    choice,
    pulse_inputs,
    sampler_settings,
    shows_progress,
    spacecraft_input,
    telemetry_inputs,
)
from cassini_bayes.api._result import FitResult, collect_warnings, fit_config
from cassini_bayes.errors import InputError, arg, as_flag
from cassini_bayes.names import FLEX_CHOICES, a_kind

if TYPE_CHECKING:
    from cassini_bayes.api._inputs import (
        FitArg,
        PulseLogsArg,
        SpacecraftArg,
        TelemetriesArg,
        WheelErrors,
    )
    from cassini_bayes.spacecraft import Spacecraft
    from cassini_bayes.telemetry import PulseLog, Telemetry

__all__ = ["fit_thrust", "thrust_baseline", "thrust_sensitivity", "thrust_summary"]


def thrust_baseline(events, spacecraft, mode: str, inertia=None,
                    combinations=None) -> tuple[dict | None, list[str]]:
    """Feldman & Lee's least squares (Eqs 19-23) with the pulse-dynamics correction at the
    spacecraft model's nominal time constants, all events stacked; ``None`` when unavailable.
    Mode ``thruster`` (any layout): one thrust per thruster from all three rows of Eq 17
    (:func:`~cassini_bayes.estimators.thrust.fit_per_thruster`), and the Bayesian fit's
    identified ``combinations`` (C, M) where the thrusters fire only in them.
    The inertia is the model's prediction, or the mean of ``inertia`` (an inertia posterior's
    :class:`~cassini_bayes.inference.thrust.InertiaGaussian`) when given, as the RWA4 baseline
    does."""
    import numpy as np

    from cassini_bayes.estimators import thrust as est
    from cassini_bayes.estimators.baseline import wheel_momentum
    from cassini_bayes.physics.momentum import inertia_matrix

    q = spacecraft.moment_matrix
    p = spacecraft.pulse
    i_body = (np.asarray(inertia_matrix(inertia.mean), float) if hasattr(inertia, "mean")
              else spacecraft.inertia)
    vs, js = [], []
    try:
        for tel, log in events:
            h = wheel_momentum(tel, spacecraft)
            v, j = est.regression_inputs(tel.t, tel.omega, h, i_body,
                                         pulses=(log.t_on, log.thruster, log.width),
                                         tau=(p.tau_delay, p.tau_rise, p.tau_fall),
                                         n_thrusters=len(spacecraft.thrusters))
            vs.append(v)
            js.append(j)
        v, j = np.concatenate(vs), np.concatenate(js)
    except Exception as e:  # the baseline must never sink the Bayesian fit
        return None, [f"baseline unavailable: {' '.join(str(e).split())}"]
    out, msgs = {}, []
    if mode == "thruster":
        try:
            f = est.fit_per_thruster(v, j, q, spacecraft.thruster_names, combinations)
        except Exception as e:
            return None, [f"baseline unavailable: {' '.join(str(e).split())}"]
        return ({n: float(x) for n, x in zip(f.names, f.estimate)} or None,
                [f"baseline: {w}" for w in f.warnings])
    by_mode: dict[str, list[tuple[str, Callable[..., Any], str | None]]] = {
        "mean": [("F", est.fit_mean, None)],
        "branch": [("F_Z", est.fit_z_thrusters, "mean"), ("F_Y", est.fit_y_mean, None)]}
    fits = by_mode[mode]
    for name, fn, how in fits:
        try:
            f = fn(v, j, q)
        except Exception as e:
            msgs.append(f"baseline {name}: {' '.join(str(e).split())}")
            continue
        if how == "mean":
            out[name] = float(np.mean(f.estimate))
        else:
            out[name] = float(f.estimate[0])
    return (out or None), msgs


def thrust_sensitivity(post) -> dict:
    """``sensitivity`` block of a robust thrust fit: how far each nuisance effect of prior size
    would move the thrust and time constants if it were left out (posterior regression,
    :func:`cassini_bayes.inference.sensitivity.posterior_sensitivity`)."""
    import numpy as np

    from cassini_bayes.inference.nuisance import EFFECTS, site_prior_sd
    from cassini_bayes.inference.sensitivity import posterior_sensitivity
    from cassini_bayes.inference.thrust import TAU_NAMES

    post_ds = post.idata.posterior
    layout = post.problem.layout

    def flat(name):
        v = np.asarray(post_ds[name].values, float)
        return v.reshape(v.shape[0] * v.shape[1], -1)

    pb = post.problem
    targets = {}
    for n in pb.names:
        x = flat(n)
        if x.shape[1] == 1:
            targets[n] = x[:, 0]
        else:                        # mode thruster: F along the thrusters
            targets.update({f"{n}[{s}]": x[:, i] for i, s in enumerate(pb.thrusters)})
    thrust_labels = list(targets)
    targets.update({n: flat(n)[:, 0] for n in TAU_NAMES})
    prior_sd = site_prior_sd(layout)
    groups = {e: (flat(EFFECTS[e]), prior_sd[EFFECTS[e]])
              for e in layout.sites if EFFECTS[e] in post_ds}
    units = {n: ("N" if n in thrust_labels else "s") for n in targets}
    return posterior_sensitivity(targets, groups, units)


def thrust_summary(post, *, seed: int, mode: str, robust: bool, wheel_errors: str,
                   baseline: dict | None, warnings: Sequence[str] = ()) -> dict:
    """``summary.json`` of a thrust posterior (``ThrustPosterior``): parameters (thrust and
    ``tau_*``; mode ``thruster``: ``F[<name>]`` per thruster, ``com_x``, ``com_y``, ``com_z``
    and ``F_combination[<label>]`` per identified combination; ``bit[<name>]``, N s, where
    every thruster fires at one width), baseline, diagnostics,
    adequacy, nuisance, ``mode``, ``model``, ``wheel_errors``, (robust fits) ``sensitivity``
    and (mode ``thruster``) ``thrust_design``: the impulse design's rank, singular values,
    identified thrusters, combinations with their weights, and whether the centre of mass is
    told by the events (:class:`~cassini_bayes.inference.thrust.design.ThrustDesign`), and
    where every thruster fires at one width the impulse bits they identify instead of the
    thrusts (``impulse_bits``: width and posterior per thruster)."""
    from cassini_bayes.inference.adequacy import thrust_adequacy
    from cassini_bayes.inference.nuisance import EFFECTS
    from cassini_bayes.inference.summary import CONTRACTION_WEAK, build_summary
    from cassini_bayes.inference.thrust import COM_NAMES, TAU_NAMES, thrust_names
    from cassini_bayes.physics.momentum import INERTIA_NAMES

    names = list(thrust_names(mode))
    if "F_combination" in post.idata.posterior:      # mode thruster, thrusters told in combination
        names.append("F_combination")
    if "bit" in post.idata.posterior:                # mode thruster, every thruster at one width
        names.append("bit")
    if mode == "thruster":
        names += list(COM_NAMES)
    names += list(TAU_NAMES)
    nuisance = ["sigma_omega", "sigma_rho"]
    if "time_tag_sd" in post.idata.posterior:   # the robust model learns the tags' sd
        nuisance.append("time_tag_sd")
    if "Ixx" in post.idata.posterior:   # the inertia was sampled
        nuisance += list(INERTIA_NAMES)
    if robust:
        nuisance += [EFFECTS[e] for e in post.problem.layout.sites]
    # the learned scales are not judged against their priors: the noise's is the data's own, and
    # tags far better than stated are a pessimistic statement, not a misfit (far worse warns)
    priored = names + [n for n in nuisance
                       if not n.startswith("sigma_") and n != "time_tag_sd"]
    summary = build_summary("thrust", post.idata, parameters=names,
                            diagnostics=post.diagnostics, baseline=baseline, seed=seed,
                            nuisance=nuisance, warnings=list(warnings),
                            adequacy=thrust_adequacy(post, priored))
    summary["mode"] = mode
    summary["model"] = "robust" if robust else "idealised"
    summary["wheel_errors"] = wheel_errors if robust else None
    search = post.problem.flex_mode
    summary["flex_mode"] = None if search is None else search.to_dict()
    clock = post.problem.clock
    summary["clock"] = None if clock is None else [
        {"telemetry": src[0], **grid.to_dict()} for src, grid in zip(post.problem.sources, clock)]
    if search is not None and search.found and search.modelled:
        summary["warnings"].append(
            f"the events ring with a flexible or slosh mode at {search.freq_hz:.4g} Hz (damping "
            f"{search.damping:.2g}, log Bayes factor {search.log_bayes_factor:.3g} against "
            f"{search.log_cells:.3g} for the frequencies searched): its momentum is integrated "
            "out (site flex_inertia, kg m^2)")
    if robust:
        summary["sensitivity"] = thrust_sensitivity(post)
    design = post.problem.design
    if design is not None:
        block = design.to_dict()
        params = summary["parameters"]
        for c in block["combinations"]:
            c["posterior"] = params.get(f"F_combination[{c['label']}]")
        block["com_told"] = {n: (params.get(n) or {}).get("contraction") is not None
                             and params[n]["contraction"] >= CONTRACTION_WEAK
                             for n in COM_NAMES}
        if "bit" in post.idata.posterior:
            block["impulse_bits"] = _impulse_bits_block(post.idata.posterior["bit"], params)
        summary["thrust_design"] = block
        quiet = [n for n, told in block["com_told"].items() if not told]
        if quiet:
            summary["warnings"].append(
                f"{', '.join(quiet)}: the events do not tell the centre of mass along these axes "
                f"(posterior/prior contraction < {CONTRACTION_WEAK:g}; only firings with a net "
                "force move it): prior-dominated, from [center_of_mass] sd_m")
    return summary


def _impulse_bits_block(bit, params: dict) -> dict:
    """``thrust_design["impulse_bits"]``: the events fire every thruster at one width, so what
    they identify per thruster is its impulse bit ``F j(Δ; τ)`` at that width (``bit[<name>]``,
    N s), and ``F`` only as well as the pulse shape (docs/thrust_any_layout.md)."""
    names = [str(n) for n in bit["bit_thruster"].values]
    return {"width_s": dict(zip(names, (float(w) for w in bit.attrs["width_s"]))),
            "posterior": {n: params.get(f"bit[{n}]") for n in names},
            "rule": "one commanded pulse width per thruster: the events identify the impulse "
                    "bit F j(width; tau) (Feldman & Lee §V); the thrusts F trade against the "
                    "pulse shape and are known only as well as the time constants"}


def _inertia_knowledge(inertia_posterior, fix_inertia: bool):
    """``(the inference's inertia argument, config.toml inputs entry, input paths)``."""
    from cassini_bayes.inference.thrust import inertia_from_idata, inertia_from_run

    if inertia_posterior is None:
        return ("fixed" if fix_inertia else None), {}, []
    if fix_inertia:
        raise InputError(f"{arg('fix_inertia')} and {arg('inertia_posterior')} exclude each "
                         "other; give one")
    if isinstance(inertia_posterior, FitResult):
        if inertia_posterior.kind != "inertia":
            raise InputError(f"{arg('inertia_posterior')}: {a_kind(inertia_posterior.kind)} "
                             "fit; give the result (or run directory) of an inertia fit")
        cfg = inertia_posterior.config
        entry = {"command": cfg["command"], "seed": cfg["seed"], "inputs": cfg["inputs"]}
        return (inertia_from_idata(inertia_posterior.idata, "inertia_posterior"),
                {"inertia_posterior": entry}, [])
    if not isinstance(inertia_posterior, (str, os.PathLike)):
        raise InputError(f"{arg('inertia_posterior')}: give an inertia fit's FitResult or run "
                         "directory")
    from cassini_bayes.rundir import file_record

    path = Path(inertia_posterior)
    knowledge = inertia_from_run(path)     # refuses a folder without an inertia posterior.nc
    # the run and its posterior's hash: a re-run can tell when the run was replaced since
    entry = {"run": str(path.resolve()), "posterior": file_record(path / "posterior.nc")}
    return knowledge, {"inertia_posterior": entry}, [path]


@jax_entry
@shows_progress
def fit_thrust(telemetry: TelemetriesArg, pulses: PulseLogsArg, spacecraft: SpacecraftArg, *,
               mode: Literal["mean", "branch", "thruster"] = "mean",
               inertia_posterior: FitArg | None = None, fix_inertia: bool = False, seed: int = 0,
               chains: int = 4, warmup: int = 1000, draws: int = 1000,
               target_accept: float = 0.9, robust: bool = True,
               wheel_errors: WheelErrors = "per_wheel",
               flex: Literal["check", "model", "off"] = "check",
               progress: bool = False) -> FitResult:
    """Posterior of the thrust and the pulse time constants from biasing events (``cassini-bayes
    fit thrust``); several events share the time constants and the thrust.

    Parameters
    ----------
    telemetry : each event's :class:`~cassini_bayes.telemetry.Telemetry` or CSV path, or a list.
    pulses : each event's pulse log (``t_on`` s, ``thruster``, ``width`` s): a
        :class:`~cassini_bayes.telemetry.PulseLog` or a CSV path, or a list in the order of
        ``telemetry``.
    spacecraft : a :class:`~cassini_bayes.spacecraft.Spacecraft`, a model TOML path or a shipped
        model's name.
    mode : thrust in N: ``"mean"`` (``F`` for all thrusters, the papers' Eq 23), ``"branch"``
        (``F_Z``, ``F_Y``; Cassini's Eq 16) or ``"thruster"`` (``F[<name>]`` for any layout,
        the centre-of-mass offset ``com_x, com_y, com_z`` in m, and the identified combinations
        where the events do not separate the thrusters: ``summary["thrust_design"]``).
    inertia_posterior : an inertia fit (its :class:`FitResult` or run directory): its posterior
        becomes the inertia prior (default: the spacecraft model's inertia and its stated
        uncertainty).
    fix_inertia : hold the inertia at the model's prediction (the papers' practice; the default
        when ``robust=False``).
    seed, chains, warmup, draws, target_accept, progress : as :func:`fit_inertia`.
    robust : gyro, wheel and external-torque errors as nuisance parameters; ``False`` is the
        papers' idealised model.
    wheel_errors : robust model's wheel spin-inertia errors: ``"per_wheel"`` or ``"common"``.
    flex : robust model's flexible mode: ``"check"`` searches the events for one
        (``summary["flex_mode"]``) and judges it (adequacy check ``flex_ringing``),
        ``"model"`` also integrates out the momentum it holds where they show it (site
        ``flex_inertia``, kg m²), ``"off"`` does not look.

    Returns
    -------
    FitResult
        ``kind = "thrust"``; parameters the thrust (N) and ``tau_delay``, ``tau_rise``,
        ``tau_fall`` (s).
    """
    import jax

    from cassini_bayes.consistency import check_thrust_data
    from cassini_bayes.inference.progress import step
    from cassini_bayes.inference.thrust import MODES
    from cassini_bayes.inference.thrust import fit_thrust as sample_thrust

    seed = check_seed(seed)
    robust, fix_inertia = as_flag(robust, "robust"), as_flag(fix_inertia, "fix_inertia")
    mode = choice("mode", mode, MODES)
    wheel_errors = choice("wheel_errors", wheel_errors, WHEEL_ERRORS)
    flex = choice("flex", flex, FLEX_CHOICES)
    settings = sampler_settings(chains, warmup, draws, target_accept, progress)
    sc, sc_record, sc_paths = spacecraft_input(spacecraft)
    sc.require_thrusters("fit thrust" + (" --mode branch" if mode == "branch" else ""),
                         eq16=(mode == "branch"))
    inertia, inertia_input, inertia_paths = _inertia_knowledge(inertia_posterior, fix_inertia)
    events, (tel_records, log_records), (tel_paths, log_paths) = _events(telemetry, pulses, sc)
    with step("checking the data"), collect_warnings() as check_warns:
        check_thrust_data(events, sc)  # units, conventions, pulse log vs on_*, by the physics
    with collect_warnings() as warns:   # after the data checks' (a gyro bias beyond [gyro])
        post = sample_thrust(jax.random.key(seed), events, sc, mode=mode, inertia=inertia,
                             settings=settings, robust=robust, wheel_errors=wheel_errors,
                             flex=flex)
    with step("summaries, baseline and adequacy checks"):
        baseline, summary = _baseline_and_summary(
            post, events, sc, inertia, check_warns + warns, seed=seed, mode=mode, robust=robust,
            wheel_errors=wheel_errors)
    config = fit_config("fit thrust", seed=seed, spacecraft=sc, settings=settings,
                        inputs={"telemetry": tel_records, "pulses": log_records,
                                "spacecraft": sc_record, **inertia_input},
                        options={"mode": mode, "model": "robust" if robust else "idealised",
                                 "inertia": _inertia_option(inertia_posterior, post),
                                 "wheel_errors": wheel_errors,
                                 "flex": flex if robust else None})
    return FitResult("thrust", post, baseline, summary.get("sensitivity"), config, summary,
                     (*tel_paths, *log_paths, *sc_paths, *inertia_paths))


def _baseline_and_summary(post: Any, events, sc: Spacecraft, inertia, warnings: list[str], *,
                          seed: int, mode: str, robust: bool,
                          wheel_errors: str) -> tuple[dict | None, dict]:
    """The least-squares baseline (with the fit's identified combinations) and the summary,
    its warnings joined to the fit's without repeats."""
    design = post.problem.design
    baseline, base_warns = thrust_baseline(
        events, sc, mode, inertia, None if design is None else design.combinations)
    summary = thrust_summary(post, seed=seed, mode=mode, robust=robust,
                             wheel_errors=wheel_errors, baseline=baseline,
                             warnings=list(dict.fromkeys(warnings + base_warns)))
    return baseline, summary


def _inertia_option(inertia_posterior: FitArg | None, post: Any) -> str:
    """How the fit treated the inertia (``config.toml``): its prior from an inertia
    ``posterior``, ``sampled`` from the model's knowledge, or ``fixed`` at its prediction."""
    if inertia_posterior is not None:
        return "posterior"
    return "sampled" if "Ixx" in cast(Any, post.idata).posterior else "fixed"


def _events(telemetry: TelemetriesArg, pulses: PulseLogsArg, sc: Spacecraft
            ) -> tuple[list[tuple[Telemetry, PulseLog]], tuple[list[dict], list[dict]],
                       tuple[list[Path], list[Path]]]:
    """The ``(telemetry, pulse log)`` of each event, with the records and paths of both inputs;
    :class:`InputError` unless there is one pulse log per telemetry."""
    tels, tel_records, tel_paths = telemetry_inputs(telemetry, spacecraft=sc)
    logs, log_records, log_paths = pulse_inputs(pulses, spacecraft=sc)
    if not logs:
        raise InputError(f"fit_thrust needs the pulse log of each event: {arg('pulses')} "
                         "(columns t_on, thruster, width)")
    if len(logs) != len(tels):
        raise InputError(f"{len(tels)} telemetry but {len(logs)} pulse log(s); give one pulse "
                         "log per telemetry, in the same order")
    return list(zip(tels, logs)), (tel_records, log_records), (tel_paths, log_paths)
