"""``cassini-bayes plan evaluate|inertia|wheel-axis``: plan a calibration before it flies
(docs/planning.md).

* ``plan evaluate SCENARIO.toml [--spacecraft M.toml] [--limits L.toml] [--out DIR]`` prints the
  predicted posterior sd of every parameter of the robust inertia fit (the inertia beside the
  papers' budget; the momentum, torques and each nuisance parameter beside the model file's prior
  sd); with ``--calibration wheel-axis`` (or ``--wheel NAME``) the RWA-method wheel-axis fit's
  (the axis's cones and sd, the inertia); with ``--out``, ``summary.json``, ``config.toml`` and
  ``report.html``.
* ``plan wheel-axis --spacecraft M.toml --wheel NAME --limits L.toml --out DIR`` chooses the
  slew pairs, windows and the wheel's bias speed (:func:`cassini_bayes.api.plan_wheel_axis`).
* ``plan evaluate BIASING.toml`` (a scenario whose thrusters fire and that has no slews, or
  ``--calibration thrust``) prints the predicted sd of the robust thrust fit's parameters (thrust,
  time constants; ``--mode thruster``: each thruster's and the centre-of-mass offset) beside the
  papers' thrust budget and the model file's prior.
* ``plan thrust --spacecraft M.toml --limits L.toml --out DIR`` chooses a wheel-biasing event
  (pulse widths, spin-up targets) within the limits (:func:`cassini_bayes.api.plan_thrust`).
* ``plan inertia --spacecraft M.toml --limits L.toml --out DIR`` chooses slews within the
  limits (:func:`cassini_bayes.api.plan_inertia`) and writes ``DIR/scenario.toml`` (the plan:
  ``cassini-bayes simulate`` runs it), ``summary.json``, ``config.toml`` and ``report.html``.
"""

# ruff: noqa: B008  (typer declares options as argument defaults)
from __future__ import annotations

import time
from pathlib import Path

import typer

from cassini_bayes.cli._console import escape, stderr_console
from cassini_bayes.rundir import check_out

ORDER = 75


def _evaluate_cmd(
    scenario: Path = typer.Argument(..., help="Scenario TOML with [[slew]]s, or a shipped "
                                              "scenario's name (slews_post_prm)."),
    spacecraft: str | None = typer.Option(None, "--spacecraft", help="Model TOML the fit "
                                          "would be given (default the scenario's prior)."),
    limits: str | None = typer.Option(None, "--limits", help="Limits TOML: also show the "
                                      "share of each limit used."),
    out: Path | None = typer.Option(None, "--out", help="Also write summary.json and "
                                    "report.html here (atomically)."),
    calibration: str | None = typer.Option(None, "--calibration", help="inertia, "
                                           "wheel-axis (the RWA-method fit) or thrust "
                                           "(default: thrust for a biasing event, else "
                                           "inertia)."),
    mode: str = typer.Option("mean", "--mode", help="Thrust fit's mode: mean, branch or "
                             "thruster (as fit thrust --mode)."),
    wheel: str | None = typer.Option(None, "--wheel", help="Wheel whose axis is calibrated "
                                     "(implies --calibration wheel-axis; default the one "
                                     "whose true axis is off the model's, else RWA4)."),
    prior: str = typer.Option("uniform", "--prior", help="Wheel-axis fit's axis prior: "
                              "uniform or cone."),
    truths: int = typer.Option(0, "--truths", min=0, help="Thrust: also predict on N truths "
                               "drawn from the model file's knowledge and give the median "
                               "(a closed-loop event flies differently for each)."),
    force: bool = typer.Option(False, "--force", help="Replace --out if it is a directory "
                               "cassini-bayes wrote."),
) -> None:
    """Predicted posterior sd of a scenario's manoeuvre, beside budgets and priors."""
    from cassini_bayes.api import evaluate_plan

    if out is not None:
        check_out(out, force=force, inputs=[scenario])
    res = evaluate_plan(str(scenario), spacecraft=spacecraft, limits=limits,
                        calibration=calibration, wheel=wheel, prior=prior, mode=mode,
                        truths=truths)
    typer.echo(res.table())
    if out is not None:
        res.save(out, force=force)
        stderr_console().print(f"[green]✓[/green] → {escape(str(out))}")


def _inertia_cmd(
    spacecraft: str = typer.Option(..., "--spacecraft", help="Spacecraft model TOML (the "
                                   "plan's truth and the fit's prior)."),
    limits: str = typer.Option(..., "--limits", help="Limits TOML (experiments/limits/)."),
    out: Path = typer.Option(..., "--out", help="Output directory (written atomically)."),
    target: str = typer.Option("max_ratio", "--target", help="max_ratio (largest sd over "
                               "its budget) or max_ratio_data (without the wheels' common "
                               "scale)."),
    slews: list[int] | None = typer.Option(None, "--slews", min=1, max=24,
                                           help="Number of slews (repeat to search "
                                                "several; default 3 4 6 8)."),
    baseline: str | None = typer.Option(None, "--baseline", help="Scenario to compare with "
                                        "(default Feldman & Lee's six slews)."),
    goal: float | None = typer.Option(None, "--goal", min=0.0, help="Target value wanted; "
                                      "a plan that cannot reach it says so."),
    max_iter: int = typer.Option(60, "--max-iter", min=1, max=10_000,
                                 help="L-BFGS iterations per slew count."),
    force: bool = typer.Option(False, "--force", help="Replace --out if it is a directory "
                               "cassini-bayes wrote."),
) -> None:
    """Choose the slews of an inertia calibration within limits (gradients through the
    simulator); write the plan as a scenario, with its report."""
    console = stderr_console()
    from cassini_bayes.api import plan_inertia

    check_out(out, force=force)
    t0 = time.perf_counter()
    res = plan_inertia(spacecraft, limits, target=target, slews=slews or None,
                       baseline=baseline, goal=goal, max_iter=max_iter, progress=True)
    s, mark = _saved(res, out, force)
    console.print(f"{mark} {len(s['slews'])} slews, {s['target']} {s['target_value']:.3f} "
                  f"(comparison ×{s['improvement'][s['target']]:.2f}) in "
                  f"{time.perf_counter() - t0:.0f} s → {escape(str(out))}")


def _thrust_cmd(
    spacecraft: str = typer.Option(..., "--spacecraft", help="Spacecraft model TOML (the "
                                   "plan's truth and the fit's prior)."),
    limits: str = typer.Option(..., "--limits", help="Limits TOML (experiments/limits/): "
                               "duration, pulse widths, wheel speed and momentum, "
                               "thrusters allowed."),
    out: Path = typer.Option(..., "--out", help="Output directory (written atomically)."),
    mode: str = typer.Option("mean", "--mode", help="Thrust fit's mode: mean, branch or "
                             "thruster (as fit thrust --mode)."),
    target: str = typer.Option("max_ratio", "--target", help="max_ratio (largest sd over "
                               "its budget: thrusts and time constants) or "
                               "max_ratio_thrust (the thrusts only)."),
    baseline: str | None = typer.Option(None, "--baseline", help="Scenario to compare with "
                                        "(e.g. the shipped biasing event of the same "
                                        "duration)."),
    goal: float | None = typer.Option(None, "--goal", min=0.0, help="Target value wanted; "
                                      "a plan that cannot reach it says so."),
    truths: int = typer.Option(0, "--truths", min=0, help="Rank the candidates, and predict "
                               "the plan and the comparison, as the median over the nominal "
                               "truth and N drawn from the model file's knowledge (N + 1 "
                               "predictions a candidate)."),
    force: bool = typer.Option(False, "--force", help="Replace --out if it is a directory "
                               "cassini-bayes wrote."),
) -> None:
    """Choose the pulse widths and wheel spin-up targets of a biasing event within limits
    (a search scored by the predicted posterior); write the plan as a scenario, with its
    report."""
    console = stderr_console()
    from cassini_bayes.api import plan_thrust

    check_out(out, force=force)
    t0 = time.perf_counter()
    res = plan_thrust(spacecraft, limits, mode=mode, target=target, baseline=baseline,
                      goal=goal, truths=truths, progress=True)
    s, mark = _saved(res, out, force)
    imp = s["improvement"]
    console.print(f"{mark} {s['target']} {s['target_value']:.3f} ({s['plan']['worst']})"
                  + (f", comparison ×{imp[s['target']]:.2f}" if imp else "")
                  + f" in {time.perf_counter() - t0:.0f} s → {escape(str(out))}")


def _wheel_axis_cmd(
    spacecraft: str = typer.Option(..., "--spacecraft", help="Spacecraft model TOML (the "
                                   "plan's truth and the fit's prior)."),
    wheel: str = typer.Option(..., "--wheel", help="The wheel whose axis is calibrated."),
    limits: str = typer.Option(..., "--limits", help="Limits TOML (experiments/limits/)."),
    out: Path = typer.Option(..., "--out", help="Output directory (written atomically)."),
    pairs: list[int] | None = typer.Option(None, "--pairs", min=2, max=12,
                                           help="Number of slew pairs (repeat to search "
                                                "several; default 2 3 4)."),
    prior: str = typer.Option("uniform", "--prior", help="The fit's axis prior: uniform or "
                              "cone."),
    baseline: str | None = typer.Option(None, "--baseline", help="Scenario to compare with "
                                        "(default Brown's slews within the limits)."),
    goal_deg: float | None = typer.Option(None, "--goal-deg", min=0.0, help="90 % cone "
                                          "wanted (deg); a plan that cannot reach it says "
                                          "so."),
    force: bool = typer.Option(False, "--force", help="Replace --out if it is a directory "
                               "cassini-bayes wrote."),
) -> None:
    """Choose the slew pairs, windows and bias speed of a wheel-axis calibration (RWA
    method) within limits; write the plan as a scenario, with its report."""
    console = stderr_console()
    from cassini_bayes.api import plan_wheel_axis

    check_out(out, force=force)
    t0 = time.perf_counter()
    res = plan_wheel_axis(spacecraft, limits, wheel=wheel, prior=prior,
                          pairs=pairs or None, baseline=baseline, goal_deg=goal_deg,
                          progress=True)
    s, mark = _saved(res, out, force)
    console.print(f"{mark} {s['choice']['pairs']} slew pairs, 90 % cone "
                  f"{s['plan']['cone_deg']['90']:.3g}° (comparison "
                  f"×{s['improvement']['sd_direction']:.2f}) in "
                  f"{time.perf_counter() - t0:.0f} s → {escape(str(out))}")


def _saved(res, out: Path, force: bool) -> tuple[dict, str]:
    """Write a plan's run directory, print its tables; its summary and the closing mark: a tick
    when the plan keeps its limits and reaches its goal."""
    res.save(out, force=force)
    typer.echo(res.table())
    s = res.summary()
    ok = s["plan"].get("limits_ok", True) and (s["goal"] is None or s["goal"]["reached"])
    return s, "[green]✓[/green]" if ok else "[yellow]![/yellow]"


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    """Add the ``plan`` group and its commands to ``app``."""
    plan = typer.Typer(help="Plan a calibration before it flies: predicted posterior sd, "
                            "optimised manoeuvres.", no_args_is_help=True)
    app.add_typer(plan, name="plan")
    plan.command("evaluate")(_evaluate_cmd)
    plan.command("inertia")(_inertia_cmd)
    plan.command("thrust")(_thrust_cmd)
    plan.command("wheel-axis")(_wheel_axis_cmd)
