"""Pages of ``cassini-bayes plan``: the manoeuvre against time with its limits, and the predicted
posterior sd of each parameter beside its budget and the comparison's (docs/planning.md)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from matplotlib.figure import Figure

from cassini_bayes import __version__
from cassini_bayes.names import INERTIA_NAMES
from cassini_bayes.report.figures import png_bytes, tidy_ticks
from cassini_bayes.report.html import (
    badge,
    details,
    figure,
    html_page,
    page_header,
    paragraph,
    section,
    table,
)

__all__ = ["evaluation_report", "manoeuvre_figure", "plan_report"]

LIMIT_COLOR = "#c0392b"
AXIS_COLORS = ("C0", "C1", "C2")


def manoeuvre_figure(flights: list[tuple[str, object]], limits) -> Figure:
    """Body rates and wheel speeds against time, one column per flight, the limits as lines.

    ``flights``: ``(title, prediction)`` pairs (:class:`~cassini_bayes.plan.evaluate.
    InertiaPrediction`: ``t`` s, ``omega`` rad/s, ``wheel_rpm``); ``limits``:
    :class:`~cassini_bayes.plan.limits.Limits` or ``None``.
    """
    ncol = len(flights)
    fig = Figure(figsize=(5.2 * ncol, 5.6), layout="constrained")
    axes = fig.subplots(2, ncol, squeeze=False, sharex="col")
    for c, (title, p) in enumerate(flights):
        t_min = np.asarray(p.t) / 60.0
        ax = axes[0, c]
        w = np.asarray(p.omega) * 1e3
        for i, name in enumerate("XYZ"):
            ax.plot(t_min, w[:, i], color=AXIS_COLORS[i], lw=1.0, label=f"ω{name.lower()}")
        ax.plot(t_min, np.linalg.norm(w, axis=1), color="k", lw=0.8, ls=":", label="|ω|")
        if limits is not None:
            r = limits.rate_max_rad_s * 1e3
            for sgn in (1, -1):
                ax.axhline(sgn * r, color=LIMIT_COLOR, lw=1.0, ls="--")
            axis_max = np.asarray(limits.axis_rate_max_rad_s)
            if np.all(np.isfinite(axis_max)):
                for i in range(3):
                    if axis_max[i] * 1e3 < r:
                        ax.axhline(axis_max[i] * 1e3, color=AXIS_COLORS[i], lw=0.8, ls="--")
                        ax.axhline(-axis_max[i] * 1e3, color=AXIS_COLORS[i], lw=0.8, ls="--")
        ax.set_title(title, fontsize=9)
        ax.set_ylabel("body rate (mrad/s)")
        ax.legend(fontsize=7, loc="upper right", ncol=4)
        tidy_ticks(ax)
        ax = axes[1, c]
        rpm = np.asarray(p.wheel_rpm)
        for k in range(rpm.shape[1]):
            if np.any(np.isfinite(rpm[:, k])):
                names = getattr(p, "wheel_names", ()) or ()
                ax.plot(t_min, rpm[:, k], lw=1.0,
                        label=names[k] if k < len(names) else f"wheel {k + 1}")
        if limits is not None:
            m = limits.wheel_rate_max_rad_s * 30.0 / np.pi
            for sgn in (1, -1):
                ax.axhline(sgn * m, color=LIMIT_COLOR, lw=1.0, ls="--")
        ax.set_xlabel("time (min)")
        ax.set_ylabel("wheel speed (rpm)")
        ax.legend(fontsize=7, loc="upper right", ncol=4)
        tidy_ticks(ax)
    return fig


def _fmt(x: float) -> str:
    return f"{x:.4g}"


def _answer_table(blocks: list[tuple[str, Mapping]]) -> str:
    """Per parameter: each block's predicted sd and sd/budget, then budget and prior sd."""
    heads = ["parameter"]
    for name, _ in blocks:
        heads += [f"{name}: sd (kg m²)", f"{name}: sd/budget", f"{name}: data part"]
    heads += ["budget (kg m²)", "prior sd (kg m²)"]
    rows, classes = [], []
    first = blocks[0][1]["parameters"]
    for n in INERTIA_NAMES:
        row, cls = [n], [""]
        for _, b in blocks:
            q = b["parameters"][n]
            row += [_fmt(q["sd"]), f"{q['ratio']:.3f}", _fmt(q["sd_data"])]
            cls += ["", "bad" if q["ratio"] > 1.0 else "", ""]
        row += [_fmt(first[n]["budget"]), _fmt(first[n]["prior_sd"])]
        cls += ["", ""]
        rows.append(row)
        classes.append(cls)
    return table(heads, rows, classes=classes)


def _sites_table(blocks: list[tuple[str, Mapping]]) -> str:
    """Per parameter of the robust model other than the inertia (SI): each block's predicted sd,
    then the prior sd; folded below the answer, as a fit report folds its nuisances."""
    first = blocks[0][1].get("sites", {})
    names = [n for n in first if n not in INERTIA_NAMES]
    rows = []
    for n in names:
        row = [n]
        for _, b in blocks:
            q = b.get("sites", {}).get(n)
            row += ["–" if q is None else _fmt(q["sd"]),
                    "–" if q is None else f"{q['sd'] / q['prior_sd']:.3f}"]
        rows.append(row + [_fmt(first[n]["prior_sd"])])
    heads = ["parameter"]
    for name, _ in blocks:
        heads += [f"{name}: sd (SI)", f"{name}: sd/prior"]
    return details(f"The other {len(rows)} parameters of the robust model (nuisances)",
                   table(heads + ["prior sd (SI)"], rows))


def _usage_table(blocks: list[tuple[str, Mapping]]) -> str:
    names = sorted({k for _, b in blocks for k in b.get("usage", {})})
    rows, classes = [], []
    for k in names:
        vals = [b.get("usage", {}).get(k) for _, b in blocks]
        rows.append([k.replace("_", " ")] + ["–" if v is None else f"{v:.3f}" for v in vals])
        classes.append([""] + ["bad" if v is not None and v > 1.0 else "" for v in vals])
    return table(["limit"] + [f"{n}: largest fraction used" for n, _ in blocks], rows,
                 classes=classes)


def plan_report(summary: Mapping, plan) -> str:
    """``report.html`` of ``cassini-bayes plan inertia``."""
    p, b = summary["plan"], summary["baseline"]
    imp = summary["improvement"]
    goal = summary.get("goal")
    badges = " ".join([
        badge("limits respected" if p.get("limits_ok") else "limits exceeded",
              p.get("limits_ok")),
        badge(f"largest sd/budget {p['max_ratio']:.3f} ({p['worst']})", p["max_ratio"] <= 1.0),
        badge(f"×{imp['max_ratio']:.2f} vs comparison (data part ×{imp['max_ratio_data']:.2f})",
              None),
        *([badge(f"goal {goal['value']:g} {'reached' if goal['reached'] else 'not reached'}",
                 goal["reached"])] if goal else [])])
    header = page_header(badges, f"cassini-bayes {__version__} plan inertia · "
                                 f"{summary['spacecraft']} · limits {summary['limits_file']} · "
                                 f"target {summary['target']}", summary.get("warnings", []))
    blocks = [("plan", p), ("comparison", b)]
    png = png_bytes(manoeuvre_figure([("plan", plan.prediction),
                                      (b["name"], plan.baseline)], plan.limits))
    slews = table(["#", "start (s)", "axis (body)", "angle (°)", "rate (mrad/s)",
                   "accel (mrad/s²)"],
                  [[str(i + 1), f"{r['t_start_s']:.1f}",
                    "[" + ", ".join(f"{x:+.3f}" for x in r["axis"]) + "]",
                    f"{r['angle_deg']:.2f}", f"{r['rate_mrad_s']:.4g}",
                    f"{r['accel_mrad_s2']:.4g}"] for i, r in enumerate(summary["slews"])])
    search = table(["slews", "objective", "largest ratio (planning step)", "penalty",
                    "iterations", "evaluations", "seconds"],
                   [[str(r["slews"]), f"{r['objective']:.4f}",
                     f"{r['max_ratio_planning_step']:.4f}", f"{r['penalty']:.3g}",
                     str(r["iterations"]), str(r["evaluations"]), f"{r['seconds']:.0f}"]
                    for r in summary["search"]])
    sections = [
        section("Predicted posterior", [
            paragraph(f"Comparison: {b['name']}."),
            _answer_table(blocks),
            paragraph("sd: the predicted posterior sd of the robust fit (Laplace approximation "
                      "on the flight simulated without noise, nuisance parameters included); "
                      "data part: the same with the wheels' common spin-inertia scale known "
                      "(no manoeuvre informs it); budget: ±1 % of each moment (Feldman & Lee "
                      "§VI), the model file's product knowledge for the products.", note=True),
            _sites_table(blocks),
            paragraph("The other parameters of the robust model: momentum H0 (N m s), "
                      "torques (N m, N m/s), gyro bias (rad/s) and scale factor, wheel "
                      "spin-inertia scales, wheel-axis tilts (rad).", note=True)]),
        section("Manoeuvre", [figure(png, "Body rates and wheel speeds of the plan and the "
                                          "comparison, simulated without noise; dashed: the "
                                          "limits."), slews]),
        section("Limits", [_usage_table(blocks), paragraph(
            "Largest fraction of each limit on the simulated telemetry (wheel torque: the "
            "change of each wheel's momentum between samples).", note=True)]),
        section("Search", [search]),
    ]
    return html_page("cassini-bayes plan inertia", sections, header=header)


def evaluation_report(summary: Mapping, prediction, limits=None) -> str:
    """``report.html`` of ``cassini-bayes plan evaluate``."""
    p = summary["prediction"]
    badges = badge(f"largest sd/budget {p['max_ratio']:.3f} ({p['worst']})",
                   p["max_ratio"] <= 1.0)
    header = page_header(badges, f"cassini-bayes {__version__} plan evaluate · "
                                 f"{summary['scenario']} · {summary['spacecraft']}")
    png = png_bytes(manoeuvre_figure([(summary["scenario"], prediction)], limits))
    sections = [section("Predicted posterior", [_answer_table([("scenario", p)]),
                                                 _sites_table([("scenario", p)])]),
                section("Manoeuvre", [figure(png, "Body rates and wheel speeds simulated "
                                                  "without noise.")])]
    if "usage" in p:
        sections.append(section("Limits", [_usage_table([("scenario", p)])]))
    return html_page("cassini-bayes plan evaluate", sections, header=header)
