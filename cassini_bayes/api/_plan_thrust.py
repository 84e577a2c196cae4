"""Planning a thrust calibration: :func:`plan_thrust` (``cassini-bayes plan thrust``)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

from cassini_bayes import __version__
from cassini_bayes._devices import jax_entry
from cassini_bayes.api._plan_format import format_thrust_table, thrust_block
from cassini_bayes.api._plan_run import (
    PathArg,
    PlannedRun,
    PlannerInputs,
    check_positive,
    emit_warnings,
    inputs_config,
    load_baseline,
    plan_header,
    planner_inputs,
    progress_printer,
)
from cassini_bayes.errors import InputError, arg

__all__ = ["ThrustPlanResult", "plan_thrust"]


@dataclass(frozen=True)
class ThrustPlanResult(PlannedRun):
    """A planned thrust calibration (``cassini-bayes plan thrust``).

    Attributes
    ----------
    plan : :class:`~cassini_bayes.plan.thrust_planner.ThrustPlan`: the scenario dict, its
        predicted posterior, the choice, the comparison's prediction and the search.
    config : inputs and options (``config.toml``).
    """

    def table(self) -> str:
        """The printed tables of the plan and its comparison."""
        p = self.plan
        c = p.choice
        what = (f"graded pulses up to {c.width_s:g} s" if c.graded
                else f"{c.width_s:g} s pulses") + f", wheels to {c.wheel_fraction:g} of the limit"
        out = [format_thrust_table(p.prediction, f"plan ({what})")]
        if p.baseline is not None:
            out.append(format_thrust_table(p.baseline, p.baseline_name))
        return "\n\n".join(out)

    def scenario_toml(self) -> str:
        """The plan as scenario TOML text (``cassini-bayes simulate`` runs it)."""
        import tomli_w

        head = ("# Planned by cassini-bayes plan thrust (docs/planning.md): "
                f"{self.plan.limits.name}, target {self.plan.target}; fit it with\n"
                f"# fit thrust --mode {self.plan.mode}\n")
        return head + tomli_w.dumps(self.plan.scenario)

    def _report(self) -> str:
        from cassini_bayes.report.plan_thrust import thrust_plan_report

        return thrust_plan_report(self._summary, self.plan)


def _thrust_summary(plan: Any, pi: PlannerInputs, mode: str, target: str, value: float,
                    goal: float | None, warns: list[str]) -> dict[str, Any]:
    """``summary.json`` of a thrust plan: the target reached, the choice, the event, the
    plan's and the comparison's predictions, the improvement and the search."""
    from cassini_bayes.plan.thrust_planner import target_value

    return {
        **plan_header("plan thrust", "thrust", pi), "mode": mode, "target": target,
        "target_value": value,
        "goal": None if goal is None else {"value": goal, "reached": value <= goal},
        "choice": plan.choice._asdict(), "wheel_ramp": plan.scenario["wheel_ramp"],
        "rcs_controller": plan.scenario["rcs_controller"],
        "plan": thrust_block(plan.prediction),
        "baseline": (None if plan.baseline is None
                     else {"name": plan.baseline_name, **thrust_block(plan.baseline)}),
        "improvement": (None if plan.baseline is None
                        else {target: target_value(plan.baseline, target) / value}),
        "search": list(plan.search), "warnings": warns}


@jax_entry
def plan_thrust(spacecraft: PathArg, limits: PathArg, *,
                mode: Literal["mean", "branch", "thruster"] = "mean",
                target: Literal["max_ratio", "max_ratio_thrust"] = "max_ratio",
                baseline: PathArg | None = None, goal: float | None = None,
                truths: int = 0, progress: bool = False) -> ThrustPlanResult:
    """Plan a thrust calibration: the wheel-biasing event within ``limits`` (pulse widths,
    spin-up targets) that minimises ``target`` of the robust thrust fit's predicted posterior,
    by a documented search (:mod:`cassini_bayes.plan.thrust_planner`, docs/planning.md).

    Parameters
    ----------
    spacecraft : the model file (path or shipped name): the plan's truth and the fit's prior.
    limits : the limits file (path or shipped name, ``experiments/limits/``).
    mode : the thrust fit's mode (``fit thrust --mode``).
    target : ``"max_ratio"`` (the largest predicted sd over its budget, thrusts and time
        constants) or ``"max_ratio_thrust"`` (the thrusts only).
    baseline : scenario to compare with (path or shipped name; e.g. the shipped biasing event
        of the same duration).
    goal : the value of ``target`` wanted; a plan that cannot reach it says so.
    truths : every prediction (each candidate's, the plan's, the baseline's) is the median over
        the nominal truth and this many drawn from the model file's knowledge, so the search
        ranks on them too: a closed-loop event's pulses follow the truth (docs/planning.md).
        Each candidate then costs ``truths + 1`` predictions.
    progress : print the search's steps on stderr.
    """
    from dataclasses import replace

    from cassini_bayes.inference.thrust import MODES
    from cassini_bayes.plan.thrust_planner import THRUST_TARGETS, plan_thrust_event, target_value
    from cassini_bayes.spacecraft import load_spacecraft

    if mode not in MODES:
        raise InputError(f"{arg('mode', mode)}: choose one of {', '.join(MODES)}")
    if target not in THRUST_TARGETS:
        raise InputError(f"{arg('target', target)}: choose one of {', '.join(THRUST_TARGETS)}")
    check_positive("goal", goal, "a positive number (sd over budget)")
    if not isinstance(truths, int) or truths < 0:
        raise InputError(f"{arg('truths', truths)}: give a whole number of truths, 0 or more")
    pi = planner_inputs(spacecraft, limits, slews=False)
    bl = load_baseline(baseline, pi.inputs)
    if bl is not None:    # the comparison is fitted with the plan's model as its prior
        bl = replace(bl, prior=load_spacecraft(pi.sc_file), prior_model_path=str(pi.sc_file))
    plan = plan_thrust_event(pi.lim, pi.base, pi.ref, mode=mode, target=target, baseline=bl,
                             truths=truths, progress=progress_printer(progress))
    value = target_value(plan.prediction, target)
    warns = []
    if goal is not None and value > goal:
        warns.append(f"the limits cannot reach the goal {target} <= {goal:g}: the best event "
                     f"found reaches {value:.3f} ({plan.prediction.worst})")
    summary = _thrust_summary(plan, pi, mode, target, value, goal, warns)
    config = {"command": "plan thrust", "version": __version__,
              "inputs": inputs_config(pi, bl),
              "options": {"mode": mode, "target": target, "goal": goal, "truths": truths}}
    emit_warnings(warns)
    return ThrustPlanResult(plan, config, summary, tuple(pi.inputs))
