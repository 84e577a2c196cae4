"""Planning a wheel-axis calibration: :func:`plan_wheel_axis` (``cassini-bayes plan
wheel-axis``)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

from cassini_bayes import __version__
from cassini_bayes._devices import jax_entry
from cassini_bayes.api._plan_format import axis_block, format_axis_table, window_options
from cassini_bayes.api._plan_run import (
    PathArg,
    PlannedRun,
    PlannerInputs,
    check_positive,
    counts_of,
    emit_warnings,
    inputs_config,
    limits_exceeded,
    load_baseline,
    plan_header,
    planner_inputs,
    progress_printer,
)
from cassini_bayes.errors import InputError, arg

__all__ = ["WheelAxisPlanResult", "plan_wheel_axis"]


@dataclass(frozen=True)
class WheelAxisPlanResult(PlannedRun):
    """A planned wheel-axis calibration (``cassini-bayes plan wheel-axis``).

    Attributes
    ----------
    plan : :class:`~cassini_bayes.plan.axis_planner.AxisPlan`: the scenario dict, its predicted
        posterior, the choice, the comparison's prediction and the search.
    config : inputs and options (``config.toml``).
    """

    def table(self) -> str:
        """The printed tables of the plan and its comparison."""
        p = self.plan
        c = p.choice
        return "\n\n".join([
            format_axis_table(p.prediction, f"plan ({c.pairs} slew pairs, {c.family} axes, "
                              f"angle {c.angle_deg:g} deg; {p.wheel} at "
                              f"{self._summary['wheel_rpm'].get(p.wheel, 0.0):.0f} rpm)"),
            format_axis_table(p.baseline, p.baseline_name)])

    def scenario_toml(self) -> str:
        """The plan as scenario TOML text (``cassini-bayes simulate`` runs it)."""
        import tomli_w

        head = ("# Planned by cassini-bayes plan wheel-axis (docs/planning.md): "
                f"{self.plan.limits.name}, wheel {self.plan.wheel}; fit it with\n"
                f"# fit wheel-axis --wheel {self.plan.wheel} --method rwa "
                f"{window_options(self.plan.prediction.pairs)}\n")
        return head + tomli_w.dumps(self.plan.scenario)

    def _report(self) -> str:
        from cassini_bayes.report.plan_axis import axis_plan_report

        return axis_plan_report(self._summary, self.plan)


def _axis_warnings(pred: Any, goal_deg: float | None) -> list[str]:
    """What the plan cannot reach (the goal cone) or does not respect (the limits)."""
    warns = []
    if goal_deg is not None and pred.cone_deg["90"] > goal_deg:
        warns.append(f"the limits cannot reach the goal of a {goal_deg:g}° 90 % cone: the best "
                     f"plan found reaches {pred.cone_deg['90']:.3g}°")
    return warns + limits_exceeded(pred.usage)


def _axis_summary(plan: Any, pi: PlannerInputs, wheel: str, prior: str,
                  goal_deg: float | None, warns: list[str]) -> dict[str, Any]:
    """``summary.json`` of a wheel-axis plan: the choice, the manoeuvre, the plan's and the
    comparison's predictions, the improvement, the goal and the search."""
    pred, base_pred = plan.prediction, plan.baseline
    return {
        **plan_header("plan wheel-axis", "wheel-axis", pi), "wheel": wheel, "prior": prior,
        "choice": plan.choice._asdict(),
        "wheel_rpm": plan.scenario["initial"]["wheel_rpm"],
        "slews": plan.scenario["slew"], "windows": plan.scenario["window"],
        "fit_windows": window_options(pred.pairs),
        "plan": axis_block(pred),
        "baseline": {"name": plan.baseline_name, **axis_block(base_pred)},
        "improvement": {"sd_direction": base_pred.sd_direction_deg / pred.sd_direction_deg,
                        "cone90": base_pred.cone_deg["90"] / pred.cone_deg["90"]},
        "goal": None if goal_deg is None else {"cone90_deg": goal_deg,
                                               "reached": pred.cone_deg["90"] <= goal_deg},
        "search": list(plan.search), "warnings": warns}


@jax_entry
def plan_wheel_axis(spacecraft: PathArg, limits: PathArg, *, wheel: str,
                    prior: Literal["uniform", "cone"] = "uniform",
                    pairs: int | Sequence[int] | None = None, baseline: PathArg | None = None,
                    goal_deg: float | None = None,
                    progress: bool = False) -> WheelAxisPlanResult:
    """Plan a wheel's spin-axis calibration by Brown's RWA method: the slew pairs, windows and
    the wheel's bias speed within ``limits`` that minimise the predicted largest angular sd of
    the axis (a documented search, docs/planning.md).

    Parameters
    ----------
    spacecraft : the model file (path or shipped name): the plan's truth and the fit's prior.
    limits : the limits file (path or shipped name, ``experiments/limits/``).
    wheel : the wheel whose axis is calibrated (one of the limits file's running wheels).
    prior : the fit's axis prior (``"uniform"`` or ``"cone"``).
    pairs : number of slew pairs (an int or a list to search); default 2, 3, 4.
    baseline : scenario to compare with; default Brown's slews within the same limits.
    goal_deg : the 90 % cone wanted (deg); a plan that cannot reach it says so.
    progress : print the search's steps on stderr.
    """
    from cassini_bayes.plan.axis_planner import plan_axis
    from cassini_bayes.plan.wheel_axis import solved_wheel

    if prior not in ("uniform", "cone"):
        raise InputError(f"{arg('prior', prior)}: choose uniform or cone")
    check_positive("goal_deg", goal_deg, "a positive angle (deg)")
    counts = counts_of("pairs", pairs, 2, 12, "a number of slew pairs from 2 to 12 (one pair "
                       "leaves the axis unseen along its slew axis), or a list")
    pi = planner_inputs(spacecraft, limits)
    wheel = solved_wheel(pi.base, wheel)
    bl = load_baseline(baseline, pi.inputs)
    plan = plan_axis(pi.lim, pi.base, pi.ref, wheel, prior=prior, pairs=counts, baseline=bl,
                     progress=progress_printer(progress))
    warns = _axis_warnings(plan.prediction, goal_deg)
    summary = _axis_summary(plan, pi, wheel, prior, goal_deg, warns)
    config = {"command": "plan wheel-axis", "version": __version__,
              "inputs": inputs_config(pi, bl),
              "options": {"wheel": wheel, "prior": prior, "pairs": counts,
                          "goal_deg": goal_deg}}
    emit_warnings(warns)
    return WheelAxisPlanResult(plan, config, summary, tuple(pi.inputs))
