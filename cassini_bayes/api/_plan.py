"""Planning a calibration before it flies: :func:`evaluate_plan` and :func:`plan_inertia`, what
``cassini-bayes plan evaluate`` and ``cassini-bayes plan inertia`` compute (docs/planning.md)."""

from __future__ import annotations

import os
import sys
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from cassini_bayes import __version__
from cassini_bayes._devices import jax_entry
from cassini_bayes.errors import InputError, arg
from cassini_bayes.names import INERTIA_NAMES

if TYPE_CHECKING:
    from cassini_bayes.simulate import Scenario

PathArg = str | os.PathLike
"""A file path or a shipped file's name."""

__all__ = ["PlanEvaluation", "PlanResult", "ThrustPlanResult", "WheelAxisPlanResult",
           "evaluate_plan", "plan_inertia", "plan_thrust", "plan_wheel_axis"]

CALIBRATIONS = ("inertia", "wheel-axis", "thrust")
"""What ``plan evaluate`` predicts: the robust inertia fit, the RWA-method wheel-axis fit, or
the robust thrust fit of a biasing event."""

FLOOR_SHARE = 0.95
"""A plan whose largest ratio is within this share of its knowledge floor is said to be set by
that floor (warnings)."""


def _model_reference(path: Path) -> str:
    """How a written scenario names a model file: ``models/NAME.toml`` for a shipped one (found
    from any directory), else its absolute path."""
    from cassini_bayes._paths import DATA_DIR

    p = path.resolve()
    try:
        return p.relative_to(Path(DATA_DIR).resolve()).as_posix()
    except ValueError:
        return str(p)


def _spacecraft_path(spacecraft: Any) -> Path:
    from cassini_bayes._paths import model_path
    from cassini_bayes.spacecraft import Spacecraft

    if isinstance(spacecraft, Spacecraft) or not isinstance(spacecraft, (str, os.PathLike)) \
            or not str(spacecraft):
        raise InputError(f"{arg('spacecraft')}: a plan is written as a scenario that names its "
                         "model file: give a model .toml path or a shipped model's name "
                         "(e.g. 'cassini_post_prm')")
    return model_path(spacecraft)


def _prediction_block(p: Any, names: Sequence[str] = INERTIA_NAMES) -> dict:
    """A prediction as summary.json holds it (kg m²; ratios are sd / budget)."""
    params = {n: {"sd": float(p.sd[i]), "sd_data": float(p.sd_data[i]),
                  "budget": float(p.budget[i]), "prior_sd": float(p.prior_sd[i]),
                  "ratio": float(p.ratio[i]), "ratio_data": float(p.ratio_data[i])}
              for i, n in enumerate(names)}
    out = {"parameters": params, "max_ratio": float(np.max(p.ratio)),
           "max_ratio_data": float(np.max(p.ratio_data)),
           "worst": names[int(np.argmax(p.ratio))],
           "worst_data": names[int(np.argmax(p.ratio_data))],
           "wheel_common_scale_sd": p.c_sd, "duration_s": p.duration_s,
           "sites": {n: {"sd": float(sd), "prior_sd": float(pr)}
                     for n, sd, pr in zip(p.sites, p.site_sd, p.site_prior_sd)}}
    if p.usage:
        out["usage"] = dict(p.usage)
        out["limits_ok"] = bool(all(v <= 1.0 for v in p.usage.values()))
    return out


def format_table(p: Any, title: str) -> str:
    """The predicted sd of each parameter beside its budget and prior sd, as printed."""
    lines = [title, (f"{'':5s} {'predicted sd':>13s} {'sd/budget':>10s} {'budget':>10s} "
                     f"{'prior sd':>10s} {'data part':>10s}   (kg m^2)")]
    for i, n in enumerate(INERTIA_NAMES):
        lines.append(f"{n:5s} {p.sd[i]:13.4g} {p.ratio[i]:10.3f} {p.budget[i]:10.4g} "
                     f"{p.prior_sd[i]:10.4g} {p.sd_data[i]:10.4g}")
    worst = int(np.argmax(p.ratio))
    lines.append(f"largest sd/budget {p.ratio[worst]:.3f} ({INERTIA_NAMES[worst]}); of it, "
                 f"{p.floor_ratio[worst]:.3f} is the wheels' common spin-inertia scale (sd "
                 f"{100 * p.c_sd:.2f} %), which no manoeuvre informs; 'data part': the sd with "
                 "that scale known")
    rest = [i for i, n in enumerate(p.sites) if n not in INERTIA_NAMES]
    if rest:
        lines.append(f"{'robust model, other parameters (SI)':36s} {'predicted sd':>13s} "
                     f"{'prior sd':>10s} {'sd/prior':>9s}")
        for i in rest:
            lines.append(f"{p.sites[i]:36s} {p.site_sd[i]:13.4g} {p.site_prior_sd[i]:10.4g} "
                         f"{p.site_sd[i] / p.site_prior_sd[i]:9.3f}")
    if p.usage:
        lines.append("limits used (largest fraction on the simulated telemetry): " + ", ".join(
            f"{k} {v:.2f}" for k, v in p.usage.items()))
    return "\n".join(lines)


def _axis_block(p: Any) -> dict:
    """A wheel-axis prediction as summary.json holds it (unit-vector components, kg m², deg)."""
    out = {"wheel": p.wheel, "axis": [float(x) for x in p.axis],
           "true_axis": [float(x) for x in p.true_axis],
           "sd_direction_deg": p.sd_direction_deg, "cone_deg": dict(p.cone_deg),
           "budget_deg": p.budget_deg, "cone90_over_budget": p.cone_deg["90"] / p.budget_deg,
           "sites": {n: {"sd": float(sd), "prior_sd": float(pr)}
                     for n, sd, pr in zip(p.sites, p.site_sd, p.site_prior_sd)},
           "windows_s": [[float(a[0]), float(a[1]), float(b[0]), float(b[1])] for a, b in p.pairs],
           "noise": {"gyro_rad_s": float(p.noise[0]), "wheel_rate_rad_s": float(p.noise[1])},
           "duration_s": p.duration_s, "variance_shares": dict(p.shares)}
    if p.usage:
        out["usage"] = dict(p.usage)
        out["limits_ok"] = bool(all(v <= 1.0 for v in p.usage.values()))
    return out


def format_axis_table(p: Any, title: str) -> str:
    """The predicted spread of the axis and the sd of each site, as printed."""
    c = p.cone_deg
    lines = [title,
             f"{p.wheel} axis: largest angular sd {p.sd_direction_deg:.4g} deg; cones "
             f"50/90/95 % {c['50']:.3g}/{c['90']:.3g}/{c['95']:.3g} deg (90 % cone over Brown's "
             f"expected {p.budget_deg:g} deg: {c['90'] / p.budget_deg:.3f})",
             f"{'':6s} {'predicted sd':>13s} {'prior sd':>10s} {'sd/prior':>9s}"]
    for n, sd, pr in zip(p.sites, p.site_sd, p.site_prior_sd):
        lines.append(f"{n:6s} {sd:13.4g} {pr:10.4g} {sd / pr:9.3f}")
    if p.shares:
        lines.append("share of the axis variance each effect carries (1 - var with it known / "
                     "var): " + ", ".join(f"{k} {v:.2f}" for k, v in p.shares.items()))
    lines.append("windows (Time A | Time B, s): " + "; ".join(
        f"{a[0]:.0f}-{a[1]:.0f} | {b[0]:.0f}-{b[1]:.0f}" for a, b in p.pairs))
    if p.usage:
        lines.append("limits used (largest fraction on the simulated telemetry): " + ", ".join(
            f"{k} {v:.2f}" for k, v in p.usage.items()))
    return "\n".join(lines)


def _thrust_block(p: Any) -> dict:
    """A thrust prediction as summary.json holds it (SI: N, s, m, kg m²; ratio = sd / budget)."""
    def num(x: float) -> float | None:
        return float(x) if np.isfinite(x) else None

    out = {"mode": p.mode,
           "sites": {n: {"sd": float(sd), "prior_sd": float(pr), "budget": num(b),
                         "ratio": num(sd / b), "truth": num(tr)}
                     for n, sd, pr, b, tr in zip(p.sites, p.site_sd, p.site_prior_sd, p.budget,
                                                 p.truth)},
           "combinations": {k: {"sd": v[0], "prior_sd": v[1], "budget": v[2],
                                "ratio": v[0] / v[2]} for k, v in p.combinations.items()},
           "max_ratio": p.max_ratio, "worst": p.worst, "n_pulses": p.n_pulses,
           "pulse_widths_s": list(p.pulse_widths_s), "floored_directions": p.floored,
           "noise": {"gyro_rad_s": float(p.noise[0]), "wheel_rate_rad_s": float(p.noise[1])},
           "duration_s": p.duration_s}
    if p.usage:
        out["usage"] = dict(p.usage)
        out["limits_ok"] = bool(all(v <= 1.0 + 1e-9 for v in p.usage.values()))
    return out


def format_thrust_table(p: Any, title: str) -> str:
    """The predicted sd of each thrust site beside its budget and prior sd, as printed."""
    lines = [title, f"{p.n_pulses} pulses of widths "
             + ", ".join(f"{w:g}" for w in p.pulse_widths_s) + " s; fit mode " + p.mode,
             f"{'':10s} {'predicted sd':>13s} {'sd/budget':>10s} {'budget':>10s} "
             f"{'prior sd':>10s} {'sd/prior':>9s}   (N, s, m, kg m^2)"]
    for n, sd, pr, b in zip(p.sites, p.site_sd, p.site_prior_sd, p.budget):
        r = f"{sd / b:10.3f}" if np.isfinite(b) else f"{'-':>10s}"
        bs = f"{b:10.4g}" if np.isfinite(b) else f"{'-':>10s}"
        lines.append(f"{n:10s} {sd:13.4g} {r} {bs} {pr:10.4g} {sd / pr:9.3f}")
    for k, (sd, pr, b) in p.combinations.items():
        lines.append(f"{k:10s} {sd:13.4g} {sd / b:10.3f} {b:10.4g} {pr:10.4g} {sd / pr:9.3f}")
    if p.floored:
        lines.append(f"{p.floored} direction(s) of the fit's coordinates have no curvature at "
                     "the truth (left at a prior that is not log-concave there): given the "
                     "prior's order of sd, the Laplace prediction is rough for them")
    lines.append(f"largest sd/budget {p.max_ratio:.3f} ({p.worst}); budgets: thrust "
                 "+-10 % (Feldman & Lee), time constants half the model file's manufacturer "
                 "range")
    if p.usage:
        lines.append("limits used (largest fraction on the simulated telemetry): " + ", ".join(
            f"{k} {v:.2f}" for k, v in p.usage.items()))
    return "\n".join(lines)


def window_options(pairs: Sequence[Any]) -> str:
    """The windows as ``fit wheel-axis`` options (``--window-a T0:T1 --window-b T0:T1`` …)."""
    return " ".join(f"--window-a {a[0]:.10g}:{a[1]:.10g} --window-b {b[0]:.10g}:{b[1]:.10g}"
                    for a, b in pairs)


def _write_dir(out: PathArg, *, force: bool, files: Mapping[str, str | bytes], summary: dict,
               config: dict, inputs: Sequence[Any] = ()) -> Path:
    """Write a planning run directory atomically: the text ``files`` and summary/config."""
    from cassini_bayes.rundir import RunDir, write_config, write_summary

    with RunDir(out, force=force, inputs=inputs) as rd:
        for name, text in files.items():
            target = rd.path / name
            if isinstance(text, bytes):
                target.write_bytes(text)
            else:
                target.write_text(text, encoding="utf-8")
        write_summary(rd.path, summary)
        write_config(rd.path, config)
    return rd.final


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
        return _write_dir(out, force=force, files={"report.html": html},
                          summary=self._summary, config=self.config, inputs=self._inputs)


@jax_entry
def evaluate_plan(scenario: PathArg | Scenario, *, spacecraft: PathArg | None = None,
                  limits: PathArg | None = None,
                  calibration: Literal["inertia", "wheel-axis", "thrust"] | None = None,
                  wheel: str | None = None,
                  prior: Literal["uniform", "cone"] = "uniform",
                  mode: Literal["mean", "branch", "thruster"] = "mean") -> PlanEvaluation:
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
    """
    from dataclasses import replace

    from cassini_bayes.plan.evaluate import evaluate_inertia
    from cassini_bayes.plan.limits import load_limits
    from cassini_bayes.simulate import Scenario, load_scenario
    from cassini_bayes.simulate.scenario import scenario_path
    from cassini_bayes.spacecraft import load_spacecraft

    if calibration is not None and calibration not in CALIBRATIONS:
        raise InputError(f"{arg('calibration', calibration)}: choose one of "
                         f"{', '.join(CALIBRATIONS)}")
    if prior not in ("uniform", "cone"):
        raise InputError(f"{arg('prior', prior)}: choose uniform or cone")
    from cassini_bayes.inference.thrust import MODES

    if mode not in MODES:
        raise InputError(f"{arg('mode', mode)}: choose one of {', '.join(MODES)}")
    inputs: list[Path] = []
    if isinstance(scenario, Scenario):
        s = scenario
    else:
        p = scenario_path(scenario)
        s = load_scenario(p)
        inputs.append(p)
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
    sc_path = s.prior_model_path
    if spacecraft is not None:
        sc_file = _spacecraft_path(spacecraft)
        model = load_spacecraft(sc_file)
        if model.wheel_names != s.truth.wheel_names:
            raise InputError(f"{arg('spacecraft', spacecraft)}: its wheels "
                             f"({', '.join(model.wheel_names)}) are not the scenario's "
                             f"({', '.join(s.truth.wheel_names)})")
        if calibration == "thrust" and model.thruster_names != s.truth.thruster_names:
            raise InputError(f"{arg('spacecraft', spacecraft)}: its thrusters "
                             f"({', '.join(model.thruster_names)}) are not the scenario's "
                             f"({', '.join(s.truth.thruster_names)})")
        s = replace(s, prior=model, prior_model_path=str(sc_file))
        sc_path = str(sc_file)
        inputs.append(sc_file)
    lim = None
    if limits is not None:
        lim, _ = load_limits(limits, sc_path, slews=calibration != "thrust")
        inputs.append(Path(lim.source))
    pred: Any
    if calibration == "wheel-axis":
        from cassini_bayes.plan.wheel_axis import evaluate_wheel_axis

        pred = evaluate_wheel_axis(s, wheel, lim, prior=prior)
        block = _axis_block(pred)
        block["fit_windows"] = window_options(pred.pairs)
    elif calibration == "thrust":
        from cassini_bayes.plan.thrust import evaluate_thrust
        from cassini_bayes.plan.thrust_planner import pulse_usage

        pred = evaluate_thrust(s, mode, lim)
        if lim is not None:
            pred = pred._replace(usage={**pred.usage, **pulse_usage(pred, lim)})
        block = _thrust_block(pred)
    else:
        pred = evaluate_inertia(s, lim)
        block = _prediction_block(pred)
    summary = {"kind": "plan", "command": "plan evaluate", "calibration": calibration,
               "version": __version__, "scenario": s.name, "spacecraft": sc_path,
               "limits": None if lim is None else lim.to_dict(),
               "prediction": block}
    config = {"command": "plan evaluate", "version": __version__,
              "inputs": {"scenario": s.source, "spacecraft": sc_path,
                         "limits": None if lim is None else lim.source},
              "options": {"calibration": calibration, "wheel": wheel, "prior": prior,
                          "mode": mode}}
    return PlanEvaluation(pred, s, config, lim, summary, tuple(inputs))


@dataclass(frozen=True)
class _PlannedRun:
    """What a planner returns: the plan, its ``config.toml`` and ``summary.json``, and the run
    directory ``save`` writes (a subclass gives the report and the scenario's header)."""

    plan: Any
    config: dict
    _summary: dict = field(repr=False)
    _inputs: tuple[Path, ...] = field(default=(), repr=False)

    @property
    def scenario(self) -> dict:
        """The plan as a scenario dict (``scenario.toml``)."""
        return self.plan.scenario

    @property
    def warnings(self) -> list[str]:
        """Lines on what the plan cannot reach or does not respect."""
        return list(self._summary["warnings"])

    def summary(self) -> dict:
        """``summary.json`` (a copy)."""
        import copy

        return copy.deepcopy(self._summary)

    def scenario_toml(self) -> str:
        raise NotImplementedError

    def _report(self) -> str:
        raise NotImplementedError

    def save(self, out: str | os.PathLike, *, force: bool = False) -> Path:
        """Write ``scenario.toml`` (the plan), ``summary.json``, ``config.toml`` and
        ``report.html`` (the manoeuvre against time, the limits as lines, the prediction beside
        the comparison's) into ``out``, atomically."""
        files = {"scenario.toml": self.scenario_toml(), "report.html": self._report()}
        if self.plan.baseline_scenario is not None:
            import tomli_w

            files["papers_scenario.toml"] = tomli_w.dumps(self.plan.baseline_scenario)
        return _write_dir(out, force=force, files=files, summary=self._summary,
                          config=self.config, inputs=self._inputs)


@dataclass(frozen=True)
class PlanResult(_PlannedRun):
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
    bad = {k: v for k, v in p.usage.items() if v > 1.0}
    if bad:
        out.append("the plan exceeds limits on its simulated telemetry: " + ", ".join(
            f"{k} {v:.3f} of the limit" for k, v in bad.items()))
    return out


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
    from cassini_bayes.plan.limits import load_limits
    from cassini_bayes.plan.optimise import TARGETS
    from cassini_bayes.plan.planner import plan_inertia_slews
    from cassini_bayes.simulate import load_scenario
    from cassini_bayes.simulate.scenario import scenario_path

    if target not in TARGETS:
        raise InputError(f"{arg('target', target)}: choose one of {', '.join(TARGETS)}")
    if goal is not None and (isinstance(goal, bool) or not isinstance(goal, (int, float))
                             or not np.isfinite(goal) or goal <= 0):
        raise InputError(f"{arg('goal', goal)}: give a positive number (sd over budget)")
    if isinstance(max_iter, bool) or not isinstance(max_iter, int) or max_iter < 1:
        raise InputError(f"{arg('max_iter', max_iter)}: give a positive whole number")
    counts = None
    if slews is not None:
        counts = [slews] if isinstance(slews, int) and not isinstance(slews, bool) else slews
        if not isinstance(counts, (list, tuple)) or not counts or any(
                isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= 24
                for n in counts):
            raise InputError(f"{arg('slews', slews)}: give a number of slews from 1 to 24, or "
                             "a list of them")
    sc_file = _spacecraft_path(spacecraft)
    ref = _model_reference(sc_file)
    lim, base = load_limits(limits, ref)
    inputs = [sc_file, Path(lim.source)]
    bl = None
    if baseline is not None:
        bp = scenario_path(baseline)
        bl = load_scenario(bp)
        inputs.append(bp)
    say = (lambda m: print(m, file=sys.stderr, flush=True)) if progress else None
    plan = plan_inertia_slews(lim, base, ref, target=target, counts=counts, baseline=bl,
                              max_iter=max_iter, progress=say)
    pred, base_pred = plan.prediction, plan.baseline
    warns = _plan_warnings(plan, goal)
    value = float(np.max(pred.ratio if target == "max_ratio" else pred.ratio_data))
    summary = {
        "kind": "plan", "command": "plan inertia", "calibration": "inertia",
        "version": __version__, "spacecraft": ref, "limits_file": lim.source,
        "limits": lim.to_dict(), "target": target, "target_value": value,
        "goal": None if goal is None else {"value": goal, "reached": value <= goal},
        "slews": plan.scenario["slew"],
        "plan": _prediction_block(pred),
        "baseline": {"name": plan.baseline_name, **_prediction_block(base_pred)},
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
    config = {"command": "plan inertia", "version": __version__,
              "inputs": {"spacecraft": str(sc_file), "limits": lim.source,
                         "baseline": None if bl is None else bl.source},
              "options": {"target": target, "slews": counts, "goal": goal,
                          "max_iter": max_iter}}
    for w in warns:
        warnings.warn(w, stacklevel=2)
    return PlanResult(plan, config, summary, tuple(inputs))


@dataclass(frozen=True)
class WheelAxisPlanResult(_PlannedRun):
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
    from cassini_bayes.plan.limits import load_limits
    from cassini_bayes.plan.wheel_axis import solved_wheel
    from cassini_bayes.simulate import load_scenario
    from cassini_bayes.simulate.scenario import scenario_path

    if prior not in ("uniform", "cone"):
        raise InputError(f"{arg('prior', prior)}: choose uniform or cone")
    if goal_deg is not None and (isinstance(goal_deg, bool)
                                 or not isinstance(goal_deg, (int, float))
                                 or not np.isfinite(goal_deg) or goal_deg <= 0):
        raise InputError(f"{arg('goal_deg', goal_deg)}: give a positive angle (deg)")
    counts = None
    if pairs is not None:
        counts = [pairs] if isinstance(pairs, int) and not isinstance(pairs, bool) else pairs
        if not isinstance(counts, (list, tuple)) or not counts or any(
                isinstance(n, bool) or not isinstance(n, int) or not 2 <= n <= 12
                for n in counts):
            raise InputError(f"{arg('pairs', pairs)}: give a number of slew pairs from 2 to 12 "
                             "(one pair leaves the axis unseen along its slew axis), or a list")
    sc_file = _spacecraft_path(spacecraft)
    ref = _model_reference(sc_file)
    lim, base = load_limits(limits, ref)
    wheel = solved_wheel(base, wheel)
    inputs = [sc_file, Path(lim.source)]
    bl = None
    if baseline is not None:
        bp = scenario_path(baseline)
        bl = load_scenario(bp)
        inputs.append(bp)
    say = (lambda m: print(m, file=sys.stderr, flush=True)) if progress else None
    plan = plan_axis(lim, base, ref, wheel, prior=prior, pairs=counts, baseline=bl,
                     progress=say)
    pred, base_pred = plan.prediction, plan.baseline
    warns = []
    if goal_deg is not None and pred.cone_deg["90"] > goal_deg:
        warns.append(f"the limits cannot reach the goal of a {goal_deg:g}° 90 % cone: the best "
                     f"plan found reaches {pred.cone_deg['90']:.3g}°")
    bad = {k: v for k, v in pred.usage.items() if v > 1.0}
    if bad:
        warns.append("the plan exceeds limits on its simulated telemetry: " + ", ".join(
            f"{k} {v:.3f} of the limit" for k, v in bad.items()))
    summary = {
        "kind": "plan", "command": "plan wheel-axis", "calibration": "wheel-axis",
        "version": __version__, "spacecraft": ref, "limits_file": lim.source,
        "limits": lim.to_dict(), "wheel": wheel, "prior": prior,
        "choice": plan.choice._asdict(),
        "wheel_rpm": plan.scenario["initial"]["wheel_rpm"],
        "slews": plan.scenario["slew"], "windows": plan.scenario["window"],
        "fit_windows": window_options(pred.pairs),
        "plan": _axis_block(pred),
        "baseline": {"name": plan.baseline_name, **_axis_block(base_pred)},
        "improvement": {"sd_direction": base_pred.sd_direction_deg / pred.sd_direction_deg,
                        "cone90": base_pred.cone_deg["90"] / pred.cone_deg["90"]},
        "goal": None if goal_deg is None else {"cone90_deg": goal_deg,
                                               "reached": pred.cone_deg["90"] <= goal_deg},
        "search": list(plan.search), "warnings": warns}
    config = {"command": "plan wheel-axis", "version": __version__,
              "inputs": {"spacecraft": str(sc_file), "limits": lim.source,
                         "baseline": None if bl is None else bl.source},
              "options": {"wheel": wheel, "prior": prior, "pairs": counts,
                          "goal_deg": goal_deg}}
    for w in warns:
        warnings.warn(w, stacklevel=2)
    return WheelAxisPlanResult(plan, config, summary, tuple(inputs))


@dataclass(frozen=True)
class ThrustPlanResult(_PlannedRun):
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


@jax_entry
def plan_thrust(spacecraft: PathArg, limits: PathArg, *,
                mode: Literal["mean", "branch", "thruster"] = "mean",
                target: Literal["max_ratio", "max_ratio_thrust"] = "max_ratio",
                baseline: PathArg | None = None, goal: float | None = None,
                progress: bool = False) -> ThrustPlanResult:
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
    progress : print the search's steps on stderr.
    """
    from cassini_bayes.inference.thrust import MODES
    from cassini_bayes.plan.limits import load_limits
    from cassini_bayes.plan.thrust_planner import THRUST_TARGETS, plan_thrust_event
    from cassini_bayes.simulate import load_scenario
    from cassini_bayes.simulate.scenario import scenario_path

    if mode not in MODES:
        raise InputError(f"{arg('mode', mode)}: choose one of {', '.join(MODES)}")
    if target not in THRUST_TARGETS:
        raise InputError(f"{arg('target', target)}: choose one of {', '.join(THRUST_TARGETS)}")
    if goal is not None and (isinstance(goal, bool) or not isinstance(goal, (int, float))
                             or not np.isfinite(goal) or goal <= 0):
        raise InputError(f"{arg('goal', goal)}: give a positive number (sd over budget)")
    sc_file = _spacecraft_path(spacecraft)
    ref = _model_reference(sc_file)
    lim, base = load_limits(limits, ref, slews=False)
    inputs = [sc_file, Path(lim.source)]
    bl = None
    if baseline is not None:
        from dataclasses import replace

        from cassini_bayes.spacecraft import load_spacecraft

        bp = scenario_path(baseline)
        bl = load_scenario(bp)
        bl = replace(bl, prior=load_spacecraft(sc_file), prior_model_path=str(sc_file))
        inputs.append(bp)
    say = (lambda m: print(m, file=sys.stderr, flush=True)) if progress else None
    plan = plan_thrust_event(lim, base, ref, mode=mode, target=target, baseline=bl,
                             progress=say)
    from cassini_bayes.plan.thrust_planner import target_value

    pred = plan.prediction
    value = target_value(pred, target)
    warns = []
    if goal is not None and value > goal:
        warns.append(f"the limits cannot reach the goal {target} <= {goal:g}: the best event "
                     f"found reaches {value:.3f} ({pred.worst})")
    summary = {
        "kind": "plan", "command": "plan thrust", "calibration": "thrust",
        "version": __version__, "spacecraft": ref, "limits_file": lim.source,
        "limits": lim.to_dict(), "mode": mode, "target": target, "target_value": value,
        "goal": None if goal is None else {"value": goal, "reached": value <= goal},
        "choice": plan.choice._asdict(), "wheel_ramp": plan.scenario["wheel_ramp"],
        "rcs_controller": plan.scenario["rcs_controller"],
        "plan": _thrust_block(pred),
        "baseline": (None if plan.baseline is None
                     else {"name": plan.baseline_name, **_thrust_block(plan.baseline)}),
        "improvement": (None if plan.baseline is None
                        else {target: target_value(plan.baseline, target) / value}),
        "search": list(plan.search), "warnings": warns}
    config = {"command": "plan thrust", "version": __version__,
              "inputs": {"spacecraft": str(sc_file), "limits": lim.source,
                         "baseline": None if bl is None else bl.source},
              "options": {"mode": mode, "target": target, "goal": goal}}
    for w in warns:
        warnings.warn(w, stacklevel=2)
    return ThrustPlanResult(plan, config, summary, tuple(inputs))
