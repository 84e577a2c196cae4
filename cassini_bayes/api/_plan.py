"""Evaluating a planned manoeuvre: :func:`evaluate_plan` (``cassini-bayes plan evaluate``); the
planners live beside it (``_plan_inertia``, ``_plan_axis``, ``_plan_thrust``), docs/planning.md."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from cassini_bayes import __version__
from cassini_bayes._devices import jax_entry
from cassini_bayes.api._plan_format import (
    axis_block,
    format_axis_table,
    format_table,
    format_thrust_table,
    prediction_block,
    thrust_block,
    window_options,
)
from cassini_bayes.api._plan_run import PathArg, spacecraft_path, write_dir
from cassini_bayes.errors import InputError, arg

if TYPE_CHECKING:
    from cassini_bayes.simulate import Scenario

__all__ = ["PlanEvaluation", "evaluate_plan"]

CALIBRATIONS = ("inertia", "wheel-axis", "thrust")
"""What ``plan evaluate`` predicts: the robust inertia fit, the RWA-method wheel-axis fit, or
the robust thrust fit of a biasing event."""


@dataclass(frozen=True)
class PlanEvaluation:
    """The predicted posterior of a planned manoeuvre (``cassini-bayes plan evaluate``).

    Attributes
    ----------
    prediction : :class:`~cassini_bayes.plan.evaluate.InertiaPrediction` (kg m²).
    scenario : the evaluated scenario (:class:`~cassini_bayes.simulate.Scenario`).
    config : inputs and options (``config.toml``).
    """

    prediction: Any
    scenario: Any
    config: dict
    limits: Any = None
    _summary: dict = field(default_factory=dict, repr=False)
    _inputs: tuple[Path, ...] = field(default=(), repr=False)

    def summary(self) -> dict:
        """``summary.json``: per parameter the predicted sd, its data part, budget, prior sd
        and their ratios; the limits used when limits were given."""
        import copy

        return copy.deepcopy(self._summary)

    def table(self) -> str:
        """The printed table (:func:`format_table`, or :func:`format_axis_table` for a
        wheel-axis prediction)."""
        if self.config.get("options", {}).get("calibration") == "thrust":
            return format_thrust_table(self.prediction, "predicted posterior of the robust "
                                       f"thrust fit: {self.scenario.name} "
                                       f"({self.scenario.duration_s:g} s)")
        if self.config.get("options", {}).get("calibration") == "wheel-axis":
            return format_axis_table(self.prediction, "predicted posterior of the robust "
                                     f"wheel-axis fit (RWA method): {self.scenario.name} "
                                     f"({self.scenario.duration_s:g} s)")
        return format_table(self.prediction,
                            f"predicted posterior of the robust inertia fit: {self.scenario.name}"
                            f" ({self.scenario.duration_s:g} s)")

    def save(self, out: str | os.PathLike, *, force: bool = False) -> Path:
        """Write ``summary.json``, ``config.toml`` and ``report.html`` into ``out``
        (atomically; ``force`` replaces only a directory cassini-bayes wrote)."""
        calibration = self.config.get("options", {}).get("calibration")
        if calibration == "wheel-axis":
            from cassini_bayes.report.plan_axis import axis_evaluation_report as evaluation_report
        elif calibration == "thrust":
            from cassini_bayes.report.plan_thrust import (
                thrust_evaluation_report as evaluation_report)
        else:
            from cassini_bayes.report.plan import evaluation_report

        html = evaluation_report(self._summary, self.prediction, self.limits)
        return write_dir(out, force=force, files={"report.html": html},
                          summary=self._summary, config=self.config, inputs=self._inputs)


def _check_options(calibration: str | None, prior: str, mode: str) -> None:
    """The calibration, axis prior and thrust mode must be among the fits' own."""
    from cassini_bayes.inference.thrust import MODES

    if calibration is not None and calibration not in CALIBRATIONS:
        raise InputError(f"{arg('calibration', calibration)}: choose one of "
                         f"{', '.join(CALIBRATIONS)}")
    if prior not in ("uniform", "cone"):
        raise InputError(f"{arg('prior', prior)}: choose uniform or cone")
    if mode not in MODES:
        raise InputError(f"{arg('mode', mode)}: choose one of {', '.join(MODES)}")


def _load_scenario(scenario: PathArg | Scenario, inputs: list[Path]) -> Scenario:
    """The evaluated scenario: as given, or loaded (its file added to ``inputs``)."""
    from cassini_bayes.simulate import Scenario, load_scenario
    from cassini_bayes.simulate.scenario import scenario_path

    if isinstance(scenario, Scenario):
        return scenario
    p = scenario_path(scenario)
    inputs.append(p)
    return load_scenario(p)


def _calibration_of(s: Scenario, calibration: str | None, wheel: str | None) -> str:
    """The calibration to predict: as given, else wheel-axis when a wheel is named, thrust for a
    biasing event (thrusters fire, no slews), else inertia; inertia and wheel-axis need RWA
    slews."""
    if calibration is None:
        biasing = not s.slews and (s.control == "rcs" or bool(s.pulses))
        calibration = ("wheel-axis" if wheel is not None
                       else "thrust" if biasing else "inertia")
    if wheel is not None and calibration != "wheel-axis":
        raise InputError(f"{arg('wheel', wheel)}: a wheel is chosen for a wheel-axis "
                         "calibration only (--calibration wheel-axis)")
    if calibration != "thrust" and (not s.slews or s.control != "rwa"):
        raise InputError(f"scenario {s.name!r} has no RWA-controlled [[slew]]: an "
                         f"{'inertia' if calibration == 'inertia' else 'RWA-method wheel-axis'} "
                         "calibration is planned from RWA slews", path=s.source)
    return calibration


def _with_model(s: Scenario, spacecraft: PathArg, calibration: str,
                inputs: list[Path]) -> Scenario:
    """The scenario with ``spacecraft`` as the fit's model (its file added to ``inputs``); its
    wheels, and for thrust its thrusters, must be the scenario's."""
    from dataclasses import replace

    from cassini_bayes.spacecraft import load_spacecraft

    sc_file = spacecraft_path(spacecraft)
    model = load_spacecraft(sc_file)
    if model.wheel_names != s.truth.wheel_names:
        raise InputError(f"{arg('spacecraft', spacecraft)}: its wheels "
                         f"({', '.join(model.wheel_names)}) are not the scenario's "
                         f"({', '.join(s.truth.wheel_names)})")
    if calibration == "thrust" and model.thruster_names != s.truth.thruster_names:
        raise InputError(f"{arg('spacecraft', spacecraft)}: its thrusters "
                         f"({', '.join(model.thruster_names)}) are not the scenario's "
                         f"({', '.join(s.truth.thruster_names)})")
    inputs.append(sc_file)
    return replace(s, prior=model, prior_model_path=str(sc_file))


def _predict(s: Scenario, calibration: str, lim: Any, *, wheel: str | None, prior: str,
             mode: str, truths: int = 0) -> tuple[Any, dict[str, Any]]:
    """The calibration's predicted posterior and its ``summary.json`` block."""
    pred: Any
    if calibration == "wheel-axis":
        from cassini_bayes.plan.wheel_axis import evaluate_wheel_axis

        pred = evaluate_wheel_axis(s, wheel, lim, prior=prior)
        return pred, {**axis_block(pred), "fit_windows": window_options(pred.pairs)}
    if calibration == "thrust":
        from cassini_bayes.plan.thrust import evaluate_thrust
        from cassini_bayes.plan.thrust_planner import pulse_usage

        pred = evaluate_thrust(s, mode, lim, truths=truths)
        if lim is not None:
            pred = pred._replace(usage={**pred.usage, **pulse_usage(pred, lim)})
        return pred, thrust_block(pred)
    from cassini_bayes.plan.evaluate import evaluate_inertia

    pred = evaluate_inertia(s, lim)
    return pred, prediction_block(pred)


@jax_entry
def evaluate_plan(scenario: PathArg | Scenario, *, spacecraft: PathArg | None = None,
                  limits: PathArg | None = None,
                  calibration: Literal["inertia", "wheel-axis", "thrust"] | None = None,
                  wheel: str | None = None,
                  prior: Literal["uniform", "cone"] = "uniform",
                  mode: Literal["mean", "branch", "thruster"] = "mean",
                  truths: int = 0) -> PlanEvaluation:
    """Predicted posterior sd of every parameter of the robust inertia fit (inertia, momentum,
    torques and each nuisance parameter), or of the RWA-method wheel-axis fit (the axis and the
    inertia, the nuisances integrated out), for the manoeuvre of a scenario: the Laplace
    approximation of the fit on the scenario's telemetry simulated without noise
    (docs/planning.md).

    Parameters
    ----------
    scenario : a scenario TOML path or shipped name (``"slews_post_prm"``), or a loaded
        :class:`~cassini_bayes.simulate.Scenario`.
    spacecraft : the model file the fit would be given (its prior and wheels; default the
        scenario's ``[prior] model``): a path or shipped name.
    limits : optional limits file (path or shipped name): the table then shows the share of
        each limit the manoeuvre uses on its simulated telemetry.
    calibration : ``"inertia"``, ``"wheel-axis"`` or ``"thrust"``; default ``"wheel-axis"``
        when ``wheel`` is given, ``"thrust"`` for a biasing event (thrusters fire: RCS control
        or ``[[pulse]]``s, no slews), else ``"inertia"``.
    wheel : the wheel whose axis is calibrated (default: the one running wheel whose true axis
        differs from the model file's, else RWA4).
    prior : the wheel-axis fit's axis prior (``"uniform"`` or ``"cone"``).
    mode : the thrust fit's mode (``fit thrust --mode``): ``"mean"``, ``"branch"`` or
        ``"thruster"``.
    truths : thrust only: also predict on this many truths drawn from the model file's
        knowledge, each flown by its own controller, and give each site's median (a
        closed-loop biasing event's pulses follow the truth; docs/planning.md).
    """
    from cassini_bayes.plan.limits import load_limits

    _check_options(calibration, prior, mode)
    if not isinstance(truths, int) or truths < 0:
        raise InputError(f"{arg('truths', truths)}: give a whole number of truths, 0 or more")
    inputs: list[Path] = []
    s = _load_scenario(scenario, inputs)
    calib = _calibration_of(s, calibration, wheel)
    if spacecraft is not None:
        s = _with_model(s, spacecraft, calib, inputs)
    sc_path = s.prior_model_path
    lim = None
    if limits is not None:
        lim, _ = load_limits(limits, sc_path, slews=calib != "thrust")
        inputs.append(Path(lim.source))
    if truths and calib != "thrust":
        raise InputError(f"{arg('truths', truths)}: only a thrust prediction draws truths "
                         f"(this scenario is a {calib} calibration)")
    pred, block = _predict(s, calib, lim, wheel=wheel, prior=prior, mode=mode, truths=truths)
    summary = {"kind": "plan", "command": "plan evaluate", "calibration": calib,
               "version": __version__, "scenario": s.name, "spacecraft": sc_path,
               "limits": None if lim is None else lim.to_dict(),
               "prediction": block}
    config = {"command": "plan evaluate", "version": __version__,
              "inputs": {"scenario": s.source, "spacecraft": sc_path,
                         "limits": None if lim is None else lim.source},
              "options": {"calibration": calib, "wheel": wheel, "prior": prior,
                          "mode": mode, "truths": truths}}
    return PlanEvaluation(pred, s, config, lim, summary, tuple(inputs))
