"""A wheel's spin axis on the sphere: :func:`fit_wheel_axis` (any wheel of the model),
:func:`fit_rwa4` (Cassini's name for its RWA4) and their summary."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Literal

from cassini_bayes._devices import jax_entry
from cassini_bayes.api._inputs import (WHEEL_ERRORS, check_seed, choice, sampler_settings,
                                       shows_progress, spacecraft_input, telemetry_inputs)
from cassini_bayes.api._limits import RWA4_TARGET_ACCEPT
from cassini_bayes.api._result import FitResult, collect_warnings, fit_config
from cassini_bayes.api._thrust import _inertia_knowledge
from cassini_bayes.errors import InputError, arg, as_flag

TARGET_ACCEPT = RWA4_TARGET_ACCEPT  # 0.95, the other fits' 0.9 (cassini_bayes.api._limits)

RCS_BUDGET_DEG = 3.0
"""Brown §III.B: the RCS method's axis error is "< 3°" (testbed worst 1.4° plus 1.5° from the
mass properties), with a flight-calibrated inertia."""

if TYPE_CHECKING:
    from cassini_bayes.api._inputs import FitArg, SpacecraftArg, TelemetryArg, WheelErrors
    from cassini_bayes.inference.rwa4 import Rwa4Posterior
    from cassini_bayes.spacecraft import Spacecraft

__all__ = ["fit_wheel_axis", "fit_rwa4", "rwa4_sensitivity", "rwa4_summary", "wheel_block"]

Windows = Sequence[tuple[tuple[float, float], tuple[float, float]]]


def rwa4_sensitivity(post: Rwa4Posterior) -> dict:
    """``sensitivity`` block of an RWA4 fit: the RMS axis shift (deg) each nuisance effect of
    prior size causes in a model that leaves it out
    (:func:`cassini_bayes.inference.rwa4.axis_sensitivity`), and that shift over the posterior's
    RMS angle about its mean direction."""
    import numpy as np

    from cassini_bayes.inference.rwa4 import U4_NAMES, axis_sensitivity
    from cassini_bayes.inference.sphere import angles_deg

    draws = np.stack([post.idata.posterior[n].values.ravel() for n in U4_NAMES], -1)
    rms = float(np.sqrt(np.mean(angles_deg(draws, np.asarray(post.direction["mean"])) ** 2)))
    return {effect: {"modelled": post.problem.robust,
                     "parameters": {"axis": {"shift": shift,
                                             "shift_in_sd": shift / rms if rms > 0 else None,
                                             "units": "deg"}}}
            for effect, shift in axis_sensitivity(post.problem).items()}


def wheel_block(post: Rwa4Posterior, spacecraft: Spacecraft | None = None) -> dict:
    """``summary.json``'s ``wheel``: the calibrated wheel's ``name``, its articulation ``cone``
    (``{"axis", "deg", "sd_deg"}``, ``None`` when the model gives none) and its ``reference``
    wheel (``{"name", "axis", "tol_deg"}`` from ``spacecraft``'s entry; ``None`` without one),
    which the report judges the axis against."""
    pr = post.problem
    cone = None if pr.cone is None else {"axis": [float(x) for x in pr.cone.axis],
                                         "deg": pr.cone.angle_deg, "sd_deg": pr.cone.sd_deg}
    ref = None
    if spacecraft is not None:
        w = spacecraft.wheel(pr.wheel)
        if w.reference is not None:
            ref = {"name": w.reference,
                   "axis": [float(x) for x in spacecraft.wheel(w.reference).axis],
                   "tol_deg": w.reference_tol_deg}
    return {"name": pr.wheel, "cone": cone, "reference": ref}


def rwa4_summary(post: Rwa4Posterior, *, seed: int, method: str, prior: str, robust: bool,
                 wheel_errors: str, baseline: dict | None = None,
                 warnings: Sequence[str] = (), spacecraft: Spacecraft | None = None) -> dict:
    """``summary.json`` of a spin-axis posterior (``Rwa4Posterior``, any wheel): parameters
    ``u4_*`` (the calibrated wheel's axis, whatever its name), the baseline (default Brown's
    least squares of the prepared problem), diagnostics, adequacy, ``direction``, ``method``,
    ``prior``, ``windows``, ``model``, ``wheel_errors``, ``sensitivity`` and ``wheel``
    (:func:`wheel_block`; its reference wheel from ``spacecraft``, the model)."""
    from cassini_bayes.inference.adequacy import rwa4_adequacy
    from cassini_bayes.inference.rwa4 import U4_NAMES
    from cassini_bayes.inference.summary import build_summary
    from cassini_bayes.physics.momentum import INERTIA_NAMES

    pr = post.problem
    if baseline is None:
        baseline = {n: float(v) for n, v in zip(U4_NAMES, pr.baseline)}
    summary = build_summary(
        "rwa4", post.idata, parameters=U4_NAMES, diagnostics=post.diagnostics,
        baseline=baseline, seed=seed, warnings=list(warnings),
        nuisance=list(INERTIA_NAMES),
        extra={"direction": post.direction},
        adequacy=rwa4_adequacy(post, list(U4_NAMES) + list(INERTIA_NAMES)))
    summary["method"] = method
    summary["prior"] = prior
    summary["windows"] = [{"a": list(a), "b": list(b)} for a, b in pr.pairs]
    summary["model"] = "robust" if robust else "idealised"
    summary["wheel_errors"] = wheel_errors if robust else None
    summary["sensitivity"] = rwa4_sensitivity(post)
    summary["wheel"] = wheel_block(post, spacecraft)
    return summary


def rcs_budget_warning(method: str, has_inertia_posterior: bool, cone95_deg: float) -> str:
    """The warning (or ``""``) of an RCS fit whose 95 % cone exceeds Brown's 3° with only the
    model file's inertia knowledge: Brown §III's budget assumes "the inertia properties of both
    the spacecraft and reaction wheel are known quite accurately" (a flight calibration)."""
    if method != "rcs" or has_inertia_posterior or not cone95_deg > RCS_BUDGET_DEG:
        return ""
    return (f"the axis's 95 % cone is {cone95_deg:.2f}°, wider than the RCS method's "
            f"{RCS_BUDGET_DEG:g}° budget (Brown), which assumes a flight-calibrated inertia; this "
            "fit has only the model file's inertia knowledge: give an inertia fit's posterior "
            f"({arg('inertia_posterior')})")


def _window_pairs(windows: Any) -> list | None:
    """``[((a0, a1), (b0, b1)), …]`` floats (s) from the ``windows`` argument, or ``None``."""
    if windows is None:
        return None
    try:
        pairs = [((float(a[0]), float(a[1])), (float(b[0]), float(b[1]))) for a, b in windows]
    except (TypeError, ValueError, IndexError):
        raise InputError(f"{arg('windows')}: give [((A0, A1), (B0, B1)), …], the Time A and "
                         "Time B windows in seconds, one pair per slew pair") from None
    return pairs


@jax_entry
@shows_progress
def fit_wheel_axis(telemetry: TelemetryArg, spacecraft: SpacecraftArg, *, wheel: str,
                   method: Literal["rcs", "rwa"], windows: Windows | None = None,
                   prior: Literal["uniform", "cone"] = "uniform",
                   inertia_posterior: FitArg | None = None, seed: int = 0, chains: int = 4,
                   warmup: int = 1000, draws: int = 1000, target_accept: float = TARGET_ACCEPT,
                   robust: bool = True, wheel_errors: WheelErrors = "per_wheel",
                   progress: bool = False) -> FitResult:
    """Posterior of any wheel's spin axis, the inertia uncertainty sampled jointly; what
    ``cassini-bayes fit wheel-axis`` computes (Brown 2012 §III, for any spacecraft model).

    Parameters
    ----------
    telemetry : the calibration telemetry: a :class:`~cassini_bayes.telemetry.Telemetry` or a
        CSV path.
    spacecraft : a :class:`~cassini_bayes.spacecraft.Spacecraft`, a model TOML path or a shipped
        model's name. The calibrated wheel's axis in it is not used (that axis is the unknown);
        the other wheels' axes and every spin inertia are.
    wheel : the wheel whose axis is calibrated, one of the model's (case-insensitive).
    method : ``"rcs"`` (Brown Eq 1, RCS-controlled drift across a spin change of ``wheel``) or
        ``"rwa"`` (Brown Eq 3, slew pairs carried by the other wheels).
    windows : ``[((A0, A1), (B0, B1)), …]``: Time A and Time B windows in seconds, one pair (RCS)
        or one per slew pair (RWA); detected from the quiet periods when ``None``.
    prior : ``"uniform"`` on the sphere or ``"cone"``: the wheel's articulation cone, which the
        model's ``[[wheel]]`` entry must give (``cone_axis``, ``cone_deg``; docs/model_file.md).
    inertia_posterior : an inertia fit (its :class:`FitResult` or run directory): its posterior
        becomes the inertia prior (default: the model's knowledge requirements).
    seed, chains, warmup, draws, progress : as :func:`fit_inertia`.
    target_accept : NUTS target acceptance probability; 0.95 here (:data:`TARGET_ACCEPT`).
    robust : gyro, wheel and torque errors integrated out; ``False`` is Brown's idealised model.
    wheel_errors : robust model's wheel spin-inertia errors: ``"per_wheel"`` or ``"common"``.

    Returns
    -------
    FitResult
        ``kind = "rwa4"`` (the spin-axis fit, Brown's name); parameters ``u4_x, u4_y, u4_z``: the
        calibrated wheel's unit axis in body axes, whatever its name; the summary's
        ``direction`` holds the mean direction and its 50/90/95 % cones (deg), its ``wheel``
        names the wheel, its cone and reference wheel (:func:`wheel_block`).
    """
    return _fit_axis("fit wheel-axis", telemetry, spacecraft, wheel=wheel, method=method,
                     windows=windows, prior=prior, inertia_posterior=inertia_posterior,
                     seed=seed, chains=chains, warmup=warmup, draws=draws,
                     target_accept=target_accept, robust=robust, wheel_errors=wheel_errors,
                     progress=progress)


@jax_entry
@shows_progress
def fit_rwa4(telemetry: TelemetryArg, spacecraft: SpacecraftArg, *,
             method: Literal["rcs", "rwa"], windows: Windows | None = None,
             prior: Literal["uniform", "cone"] = "uniform",
             inertia_posterior: FitArg | None = None, seed: int = 0, chains: int = 4,
             warmup: int = 1000, draws: int = 1000, target_accept: float = TARGET_ACCEPT,
             robust: bool = True, wheel_errors: WheelErrors = "per_wheel",
             progress: bool = False) -> FitResult:
    """Cassini's RWA4 spin axis: :func:`fit_wheel_axis` with ``wheel="RWA4"`` (the same
    numbers); what ``cassini-bayes fit rwa4`` computes. Parameters and result as there."""
    return _fit_axis("fit rwa4", telemetry, spacecraft, wheel="RWA4", method=method,
                     windows=windows, prior=prior, inertia_posterior=inertia_posterior,
                     seed=seed, chains=chains, warmup=warmup, draws=draws,
                     target_accept=target_accept, robust=robust, wheel_errors=wheel_errors,
                     progress=progress)


def _fit_axis(command: str, telemetry: TelemetryArg, spacecraft: SpacecraftArg, *, wheel: str,
              method: str, windows: Windows | None, prior: str,
              inertia_posterior: FitArg | None, seed: int, chains: int, warmup: int, draws: int,
              target_accept: float, robust: bool, wheel_errors: str,
              progress: bool) -> FitResult:
    """The spin-axis fit behind :func:`fit_wheel_axis` and :func:`fit_rwa4` (``command``, the
    one config.toml records)."""
    import jax

    from cassini_bayes.consistency import check_rwa4_data
    from cassini_bayes.inference.progress import step
    from cassini_bayes.inference.rwa4 import METHODS, PRIORS, fit_rwa4 as sample_rwa4
    from cassini_bayes.inference.rwa4.data import check_cone_prior
    from cassini_bayes.telemetry import without_stale_samples

    seed = check_seed(seed)
    robust = as_flag(robust, "robust")
    method = choice("method", method, METHODS)
    prior = choice("prior", prior, PRIORS)
    wheel_errors = choice("wheel_errors", wheel_errors, WHEEL_ERRORS)
    settings = sampler_settings(chains, warmup, draws, target_accept, progress)
    pairs = _window_pairs(windows)
    sc, sc_record, sc_paths = spacecraft_input(spacecraft)
    wheel = _model_wheel(sc, wheel)
    check_cone_prior(sc, wheel, prior)     # before any data is read
    inertia, inertia_input, inertia_paths = _inertia_knowledge(inertia_posterior, False)
    tels, records, paths = telemetry_inputs(telemetry, spacecraft=sc)
    if len(tels) != 1:
        raise InputError(f"{arg('telemetry')}: the spin-axis calibration takes one telemetry, "
                         f"got {len(tels)}")
    with step("checking the data"), collect_warnings() as check_warns:
        tel = without_stale_samples(tels[0])               # a warning naming them
        # units, conventions, method vs data, by the physics; a fixed wheel's model axis is
        # good to a mounting error, well inside the checks' 30°-scale tolerance, so they keep it
        # and refuse a flipped tachometer sign (an articulated wheel's is taken as free)
        check_rwa4_data(tel, sc, method, wheel=wheel)
    key = jax.random.key(seed)  # the one place the seed becomes a key
    with collect_warnings() as warns:   # after the data checks' (a gyro bias beyond [gyro])
        post = sample_rwa4(key, tel, sc, method=method, pairs=pairs, prior=prior,
                           inertia=inertia, settings=settings, robust=robust,
                           wheel_errors=wheel_errors, wheel=wheel)
    budget = rcs_budget_warning(method, inertia_posterior is not None,
                                post.direction["cone_deg"]["95"])
    if budget:
        warns.append(budget)
    with step("summaries and adequacy checks"):
        summary = rwa4_summary(post, seed=seed, method=method, prior=prior, robust=robust,
                               wheel_errors=wheel_errors, spacecraft=sc,
                               warnings=list(dict.fromkeys(check_warns + warns)))
    pr = post.problem
    config = fit_config(command, seed=seed, spacecraft=sc, settings=settings,
                        inputs={"telemetry": records[0], "spacecraft": sc_record,
                                **inertia_input},
                        options={"wheel": wheel, "method": method, "prior": prior,
                                 "model": "robust" if robust else "idealised",
                                 "wheel_errors": wheel_errors,
                                 "window_a": [f"{a[0]:.10g}:{a[1]:.10g}" for a, _ in pr.pairs],
                                 "window_b": [f"{b[0]:.10g}:{b[1]:.10g}" for _, b in pr.pairs],
                                 "windows_detected": pairs is None})
    return FitResult("rwa4", post, summary["baseline"], summary["sensitivity"], config, summary,
                     (*paths, *sc_paths, *inertia_paths))


def _model_wheel(sc: Spacecraft, wheel: str) -> str:
    """The model's spelling of ``wheel``; a one-line InputError naming the model's wheels."""
    if not isinstance(wheel, str) or not wheel:
        raise InputError(f"{arg('wheel')}: name the wheel whose axis is calibrated, one of "
                         f"{', '.join(sc.wheel_names)}")
    names = {n.upper(): n for n in sc.wheel_names}
    if wheel.upper() not in names:
        raise InputError(f"{arg('wheel', wheel, cli_quote=True)}: the spacecraft model "
                         f"{sc.name!r} has no such wheel; it has {', '.join(sc.wheel_names)}")
    return names[wheel.upper()]
