"""The inertia tensor from RWA slews: :func:`fit_inertia` and its summary."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from cassini_bayes._devices import jax_entry
from cassini_bayes.api._inputs import (
    WHEEL_ERRORS,
    check_seed,
    choice,
    sampler_settings,
    shows_progress,
    spacecraft_input,
    telemetry_inputs,
)
from cassini_bayes.api._result import FitResult, collect_warnings, fit_config
from cassini_bayes.errors import as_flag

if TYPE_CHECKING:
    from cassini_bayes.api._inputs import SpacecraftArg, TelemetriesArg, WheelErrors
    from cassini_bayes.inference.inertia import InertiaPosterior
    from cassini_bayes.spacecraft import Spacecraft
    from cassini_bayes.telemetry import Telemetry

__all__ = ["fit_inertia", "inertia_baseline", "inertia_summary"]


def inertia_baseline(telemetries: Sequence[Telemetry], spacecraft: Spacecraft
                     ) -> tuple[dict | None, list[str]]:
    """The paper's all-axes least squares (Feldman & Lee Eq 11) on the same data, or ``None``,
    with warning lines: :func:`cassini_bayes.estimators.baseline.fit_inertia_baseline` with
    ``method="all_axes"`` (several files: their Eq 11 systems, each anchored on its own first
    sample, stacked into one least-squares problem)."""
    from cassini_bayes.estimators.baseline import fit_inertia_baseline
    from cassini_bayes.physics.momentum import INERTIA_NAMES

    try:
        fit = fit_inertia_baseline(telemetries, spacecraft, method="all_axes")
    except Exception as e:  # the baseline must never sink the Bayesian fit
        return None, [f"baseline (Feldman & Lee Eq 11 least squares) unavailable: "
                      f"{' '.join(str(e).split())}"]
    return ({n: float(v) for n, v in zip(INERTIA_NAMES, fit.pi)},
            [f"baseline: {m}" for m in fit.warnings])


def inertia_summary(post: InertiaPosterior, *, seed: int, torque: bool, robust: bool,
                    wheel_errors: str, baseline: dict | None,
                    warnings: Sequence[str] = ()) -> dict:
    """``summary.json`` of an inertia posterior (``InertiaPosterior``): parameters, baseline,
    diagnostics, adequacy, nuisance, ``model``, ``wheel_errors`` and ``sensitivity``."""
    from cassini_bayes.inference.adequacy import inertia_adequacy
    from cassini_bayes.inference.inertia import NOISE_NAMES, robust_sites
    from cassini_bayes.inference.sensitivity import sensitivity_block
    from cassini_bayes.inference.summary import build_summary
    from cassini_bayes.physics.momentum import INERTIA_NAMES

    nuisance = robust_sites(post.problem.layout) if robust else []
    priored = (["T_N"] if torque else []) + nuisance
    summary = build_summary(
        "inertia", post.idata, parameters=INERTIA_NAMES, diagnostics=post.diagnostics,
        baseline=baseline, seed=seed, warnings=list(warnings),
        nuisance=["H0"] + (["T_N"] if torque else []) + ["noise_scale", *NOISE_NAMES]
        + nuisance,
        adequacy=inertia_adequacy(post, list(INERTIA_NAMES) + priored))
    post_sd = {n: float(post.idata.posterior[n].std()) for n in INERTIA_NAMES}
    summary["model"] = "robust" if robust else "idealised"
    summary["wheel_errors"] = wheel_errors if robust else None
    sens = post.problem.sensitivity        # (always set by prepare_inertia)
    summary["sensitivity"] = sensitivity_block(sens, post_sd) if sens is not None else None
    return summary


@jax_entry
@shows_progress
def fit_inertia(telemetry: TelemetriesArg, spacecraft: SpacecraftArg, *, seed: int = 0,
                chains: int = 4, warmup: int = 1000,
                draws: int = 1000, target_accept: float = 0.9, robust: bool = True,
                wheel_errors: WheelErrors = "per_wheel", torque: bool = True,
                progress: bool = False) -> FitResult:
    """Posterior of the inertia tensor from RWA slews (one inertia, each file its own momentum);
    what ``cassini-bayes fit inertia`` computes.

    Parameters
    ----------
    telemetry : slew telemetry: a :class:`~cassini_bayes.telemetry.Telemetry` or a CSV path, or
        a list of them (files share the inertia).
    spacecraft : the prior and the wheels: a :class:`~cassini_bayes.spacecraft.Spacecraft`, a
        model TOML path or a shipped model's name (``"cassini_post_probe"``).
    seed : seed of the run's ``jax.random`` key (0 .. 2**63 - 1).
    chains, warmup, draws : NUTS chains, warmup iterations and kept draws per chain.
    target_accept : NUTS target acceptance probability (raise it when the fit diverges).
    robust : include gyro bias/scale and wheel inertia/axis errors as nuisance parameters
        (priors from the model's ``[gyro]`` and ``[wheel_knowledge]``); ``False`` is the papers'
        idealised model (``--idealised``).
    wheel_errors : robust model's wheel spin-inertia errors: ``"per_wheel"`` or ``"common"``.
    torque : include a constant inertial external torque per file.
    progress : show the fit's steps (and the sampler's bar) on the terminal
        (:mod:`cassini_bayes.inference.progress`).

    Returns
    -------
    FitResult
        ``kind = "inertia"``; ``summary()["parameters"]`` has ``Ixx … Iyz`` in kg m².
    """
    import jax

    from cassini_bayes.consistency import check_inertia_data
    from cassini_bayes.inference.inertia import fit_inertia as sample_inertia
    from cassini_bayes.inference.progress import step
    from cassini_bayes.telemetry import without_stale_samples

    seed = check_seed(seed)
    robust, torque = as_flag(robust, "robust"), as_flag(torque, "torque")
    wheel_errors = choice("wheel_errors", wheel_errors, WHEEL_ERRORS)
    settings = sampler_settings(chains, warmup, draws, target_accept, progress)
    sc, sc_record, sc_paths = spacecraft_input(spacecraft)
    tels, records, paths = telemetry_inputs(telemetry, spacecraft=sc)
    with step("checking the data"), collect_warnings() as check_warns:
        tels = [without_stale_samples(t) for t in tels]   # a warning naming them
        check_inertia_data(tels, sc)  # units and conventions by the physics, before sampling
    key = jax.random.key(seed)  # the one place the seed becomes a key
    with collect_warnings() as warns:   # after the data checks' (a gyro bias beyond [gyro])
        post = sample_inertia(key, tels, sc, torque=torque, robust=robust, settings=settings,
                              wheel_errors=wheel_errors)
    with step("summaries, baseline and adequacy checks"):
        baseline, base_warns = inertia_baseline(tels, sc)
        summary = inertia_summary(post, seed=seed, torque=torque, robust=robust,
                                  wheel_errors=wheel_errors, baseline=baseline,
                                  warnings=list(dict.fromkeys(check_warns + warns + base_warns)))
    config = fit_config("fit inertia", seed=seed, spacecraft=sc, settings=settings,
                        inputs={"telemetry": records, "spacecraft": sc_record},
                        options={"torque": torque, "idealised": not robust,
                                 "wheel_errors": wheel_errors})
    return FitResult("inertia", post, baseline, summary["sensitivity"], config, summary,
                     tuple(Path(p) for p in [*paths, *sc_paths]))
