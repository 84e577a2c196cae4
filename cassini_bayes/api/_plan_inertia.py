"""Planning an inertia calibration: :func:`plan_inertia` (``cassini-bayes plan inertia``)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from cassini_bayes import __version__
from cassini_bayes._devices import jax_entry
from cassini_bayes.api._plan_format import format_table, prediction_block
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
from cassini_bayes.names import INERTIA_NAMES

__all__ = ["PlanResult", "plan_inertia"]

FLOOR_SHARE = 0.95
"""A plan whose largest ratio is within this share of its knowledge floor is said to be set by
that floor (warnings)."""


@dataclass(frozen=True)
class PlanResult(PlannedRun):
    """A planned calibration (``cassini-bayes plan inertia``).

    Attributes
    ----------
    plan : :class:`~cassini_bayes.plan.planner.InertiaPlan`: the scenario dict, its predicted
        posterior and the comparison's.
    config : inputs and options (``config.toml``).
    """

    def table(self) -> str:
        """The printed tables of the plan and its comparison."""
        p = self.plan
        return "\n\n".join([format_table(p.prediction, f"plan ({len(p.scenario['slew'])} slews)"),
                            format_table(p.baseline, p.baseline_name)])

    def scenario_toml(self) -> str:
        """The plan as scenario TOML text (``cassini-bayes simulate`` runs it)."""
        import tomli_w

        head = ("# Planned by cassini-bayes plan inertia (docs/planning.md): "
                f"{self.plan.limits.name}, target {self.plan.target}\n")
        return head + tomli_w.dumps(self.plan.scenario)

    def _report(self) -> str:
        from cassini_bayes.report.plan import plan_report

        return plan_report(self._summary, self.plan)


def _plan_warnings(plan: Any, goal: float | None) -> list[str]:
    """What the plan cannot reach (the goal, the knowledge floor) or does not respect."""
    out = []
    p = plan.prediction
    value = float(np.max(p.ratio if plan.target == "max_ratio" else p.ratio_data))
    if goal is not None and value > goal:
        out.append(f"the limits cannot reach the goal {plan.target} <= {goal:g}: the best plan "
                   f"found reaches {value:.3f} "
                   f"({INERTIA_NAMES[int(np.argmax(p.ratio))]})")
    floor = p.floor_ratio
    worst = int(np.argmax(p.ratio))
    if plan.target == "max_ratio" and floor[worst] >= FLOOR_SHARE * p.ratio[worst]:
        out.append(f"the largest sd/budget ({p.ratio[worst]:.3f}, {INERTIA_NAMES[worst]}) is "
                   f"set by the wheels' common spin-inertia knowledge ({100 * p.c_sd:.2f} % "
                   f"alone gives {floor[worst]:.3f}), which no manoeuvre informs: better "
                   "knowledge of the wheels, not another manoeuvre, would lower it")
    return out + limits_exceeded(p.usage)


def _inertia_summary(plan: Any, pi: PlannerInputs, target: str, goal: float | None,
                     warns: list[str]) -> dict[str, Any]:
    """``summary.json`` of an inertia plan: the target reached, the plan's and the comparison's
    predictions, the improvement, the knowledge floor and the search."""
    pred, base_pred = plan.prediction, plan.baseline
    value = float(np.max(pred.ratio if target == "max_ratio" else pred.ratio_data))
    return {
        **plan_header("plan inertia", "inertia", pi), "target": target, "target_value": value,
        "goal": None if goal is None else {"value": goal, "reached": value <= goal},
        "slews": plan.scenario["slew"],
        "plan": prediction_block(pred),
        "baseline": {"name": plan.baseline_name, **prediction_block(base_pred)},
        "improvement": {"max_ratio": float(np.max(base_pred.ratio) / np.max(pred.ratio)),
                        "max_ratio_data": float(np.max(base_pred.ratio_data)
                                                / np.max(pred.ratio_data))},
        "floor_ratio": dict(zip(INERTIA_NAMES, pred.floor_ratio.tolist())),
        "search": [{"slews": r.n, "objective": r.objective,
                    "max_ratio_planning_step": float(np.exp(r.max_log_ratio)),
                    "penalty": r.penalty, "iterations": r.iterations,
                    "evaluations": r.evaluations, "seconds": r.seconds}
                   for r in plan.search],
        "warnings": warns}


@jax_entry
def plan_inertia(spacecraft: PathArg, limits: PathArg, *,
                 target: Literal["max_ratio", "max_ratio_data"] = "max_ratio",
                 slews: int | Sequence[int] | None = None, baseline: PathArg | None = None,
                 goal: float | None = None, max_iter: int = 60,
                 progress: bool = False) -> PlanResult:
    """Plan an inertia calibration: the slews within ``limits`` that minimise ``target``, by
    gradients through the simulator and the robust model's predicted posterior
    (docs/planning.md).

    Parameters
    ----------
    spacecraft : the model file (path or shipped name): the plan's truth and the fit's prior.
    limits : the limits file (path or shipped name, ``experiments/limits/``).
    target : ``"max_ratio"`` (the largest predicted sd over its budget) or
        ``"max_ratio_data"`` (the same without the wheels' common spin-inertia scale, which no
        manoeuvre informs).
    slews : number of slews (an int or a list to search); default a search over 3, 4, 6, 8.
    baseline : scenario to compare with (path or shipped name); default Feldman & Lee's six
        slews within the same limits.
    goal : the value of ``target`` wanted; a plan that cannot reach it says so (a warning and
        ``summary()["goal"]["reached"] = False``) with the best it reaches.
    max_iter : L-BFGS iterations per slew count.
    progress : print the optimiser's steps on stderr.
    """
    from cassini_bayes.plan.optimise import TARGETS
    from cassini_bayes.plan.planner import plan_inertia_slews

    if target not in TARGETS:
        raise InputError(f"{arg('target', target)}: choose one of {', '.join(TARGETS)}")
    check_positive("goal", goal, "a positive number (sd over budget)")
    if isinstance(max_iter, bool) or not isinstance(max_iter, int) or max_iter < 1:
        raise InputError(f"{arg('max_iter', max_iter)}: give a positive whole number")
    counts = counts_of("slews", slews, 1, 24, "a number of slews from 1 to 24, or a list of them")
    pi = planner_inputs(spacecraft, limits)
    bl = load_baseline(baseline, pi.inputs)
    plan = plan_inertia_slews(pi.lim, pi.base, pi.ref, target=target, counts=counts, baseline=bl,
                              max_iter=max_iter, progress=progress_printer(progress))
    warns = _plan_warnings(plan, goal)
    summary = _inertia_summary(plan, pi, target, goal, warns)
    config = {"command": "plan inertia", "version": __version__,
              "inputs": inputs_config(pi, bl),
              "options": {"target": target, "slews": counts, "goal": goal,
                          "max_iter": max_iter}}
    emit_warnings(warns)
    return PlanResult(plan, config, summary, tuple(pi.inputs))
