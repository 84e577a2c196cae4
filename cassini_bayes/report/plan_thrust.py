"""Pages of ``cassini-bayes plan thrust`` and of ``plan evaluate`` for a biasing event: the
predicted sd of each thrust site beside its budget and the comparison's, the event against time
(body rates, wheel speeds, the pulses) with its limits as lines (docs/planning.md)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from matplotlib.figure import Figure

from cassini_bayes import __version__
from cassini_bayes.report.figures import png_bytes, tidy_ticks
from cassini_bayes.report.html import (badge, figure, html_page, page_header, paragraph, section,
                                       table)
from cassini_bayes.report.plan import LIMIT_COLOR, _usage_table, manoeuvre_figure

__all__ = ["pulse_figure", "thrust_evaluation_report", "thrust_plan_report"]


def _fmt(x) -> str:
    return "–" if x is None else f"{x:.4g}"


def pulse_figure(flights: list[tuple[str, object]], limits) -> Figure:
    """Each pulse's width against its command time, one panel per flight (thruster names as
    colours), the limits' shortest and longest pulse as lines."""
    fig = Figure(figsize=(5.2 * len(flights), 2.6), layout="constrained")
    axes = fig.subplots(1, len(flights), squeeze=False)[0]
    for ax, (title, p) in zip(axes, flights):
        names = sorted(set(p.pulse_thruster))
        for k, n in enumerate(names):
            m = np.array([x == n for x in p.pulse_thruster])
            ax.plot(np.asarray(p.pulse_t)[m] / 60.0, np.asarray(p.pulse_width)[m] * 1e3, "o",
                    ms=2.5, color=f"C{k % 10}", label=n)
        if limits is not None:
            for v in (limits.min_pulse_s, limits.max_pulse_s):
                ax.axhline(v * 1e3, color=LIMIT_COLOR, lw=1.0, ls="--")
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("time (min)")
        ax.set_ylabel("pulse width (ms)")
        ax.legend(fontsize=6, loc="upper right", ncol=4)
        tidy_ticks(ax)
    return fig


def _sites_table(blocks: list[tuple[str, Mapping]]) -> str:
    """Per site: each block's predicted sd and sd/budget, then the budget and prior sd."""
    first = blocks[0][1]
    heads = ["parameter"]
    for name, _ in blocks:
        heads += [f"{name}: sd", f"{name}: sd/budget"]
    heads += ["budget", "prior sd"]
    rows, classes = [], []
    entries = list(first["sites"].items()) + list(first["combinations"].items())
    for n, q0 in entries:
        row, cls = [n], [""]
        for _, b in blocks:
            q = b["sites"].get(n) or b["combinations"].get(n)
            r = None if q is None else q.get("ratio")
            row += [_fmt(None if q is None else q["sd"]), "–" if r is None else f"{r:.3f}"]
            cls += ["", "bad" if r is not None and r > 1.0 else ""]
        row += [_fmt(q0.get("budget")), _fmt(q0["prior_sd"])]
        cls += ["", ""]
        rows.append(row)
        classes.append(cls)
    return table(heads, rows, classes=classes)


_NOTE = ("Predicted posterior of the default robust thrust fit (fit thrust): the Laplace "
         "approximation of the fit's own density on the event simulated without noise, with the "
         "scenario's sensor noise levels; the nuisance effects (gyro bias and scale, wheel scales "
         "and tilts, torques) are integrated out as the fit integrates them and the inertia is "
         "sampled from the model file's knowledge. Units: N, s, m, kg m². Budgets: thrust ±10 % "
         "(Feldman & Lee §V); time constants half the model file's manufacturer range.")


def thrust_plan_report(summary: Mapping, plan) -> str:
    """``report.html`` of ``cassini-bayes plan thrust``."""
    p, b = summary["plan"], summary["baseline"]
    goal = summary.get("goal")
    imp = summary.get("improvement")
    badges = " ".join([
        badge("limits respected" if p.get("limits_ok") else "limits exceeded",
              p.get("limits_ok")),
        badge(f"largest sd/budget {p['max_ratio']:.3f} ({p['worst']})", p["max_ratio"] <= 1.0),
        *([badge(f"×{v:.2f} vs comparison ({k})", None) for k, v in imp.items()] if imp else []),
        *([badge(f"goal {goal['value']:g} {'reached' if goal['reached'] else 'not reached'}",
                 goal["reached"])] if goal else [])])
    header = page_header(badges, f"cassini-bayes {__version__} plan thrust · "
                                 f"{summary['spacecraft']} · mode {summary['mode']} · limits "
                                 f"{summary['limits_file']}", summary.get("warnings", []))
    blocks = [("plan", p)] + ([("comparison", b)] if b else [])
    flights = [("plan", plan.prediction)] + ([(b["name"], plan.baseline)] if b else [])
    ramps = table(["wheel", "start (s)", "target (rpm)", "torque (N m)"],
                  [[r["wheel"], f"{r['t_start_s']:.0f}", f"{r['target_rpm']:.0f}",
                    f"{r['torque_nm']:.3g}"] for r in summary["wheel_ramp"]])
    search = table(["pulse width (s)", "graded", "wheel fraction", "target", "worst", "pulses",
                    "limits ok", "seconds"],
                   [[f"{r['width_s']:g}", str(r["graded"]), f"{r['wheel_fraction']:g}",
                     f"{r['target_value']:.4g}", r["worst"], str(r["n_pulses"]),
                     str(r["limits_ok"]), f"{r['seconds']:.0f}"] for r in summary["search"]])
    sections = [
        section("Predicted posterior", [
            paragraph(f"Comparison: {b['name']}." if b else "No comparison event given."),
            _sites_table(blocks), paragraph(_NOTE, note=True)]),
        section("Event", [
            figure(png_bytes(manoeuvre_figure(flights, plan.limits)),
                   "Body rates and wheel speeds simulated without noise; dashed: the limits."),
            figure(png_bytes(pulse_figure(flights, plan.limits)),
                   "Pulses fired by the RCS controller; dashed: the shortest and longest "
                   "pulse allowed."),
            paragraph("RCS controller: " + ", ".join(
                f"{k} {v}" for k, v in summary["rcs_controller"].items())), ramps]),
        section("Limits", [_usage_table(blocks), paragraph(
            "Largest fraction of each limit on the simulated telemetry and pulse log.",
            note=True)]),
        section("Search", [search]),
    ]
    return html_page("cassini-bayes plan thrust", sections, header=header)


def thrust_evaluation_report(summary: Mapping, prediction, limits=None) -> str:
    """``report.html`` of ``cassini-bayes plan evaluate`` for a biasing event."""
    p = summary["prediction"]
    badges = badge(f"largest sd/budget {p['max_ratio']:.3f} ({p['worst']})",
                   p["max_ratio"] <= 1.0)
    header = page_header(badges, f"cassini-bayes {__version__} plan evaluate · "
                                 f"{summary['scenario']} · {summary['spacecraft']} · thrust "
                                 f"(mode {p['mode']})")
    flights = [(summary["scenario"], prediction)]
    blocks = [("scenario", p)]
    sections = [section("Predicted posterior", [_sites_table(blocks),
                                                 paragraph(_NOTE, note=True)]),
                section("Event", [
                    figure(png_bytes(manoeuvre_figure(flights, limits)),
                           "Body rates and wheel speeds simulated without noise."),
                    figure(png_bytes(pulse_figure(flights, limits)), "Pulses fired.")])]
    if "usage" in p:
        sections.append(section("Limits", [_usage_table(blocks)]))
    return html_page("cassini-bayes plan evaluate", sections, header=header)
