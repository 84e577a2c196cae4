"""Pages of ``cassini-bayes plan wheel-axis`` and of ``plan evaluate`` for a wheel-axis
scenario: the manoeuvre against time with its limits, the predicted spread of the axis and the
sd of each site beside the comparison's (docs/planning.md)."""

from __future__ import annotations

from collections.abc import Mapping

from cassini_bayes import __version__
from cassini_bayes.report.figures import png_bytes
from cassini_bayes.report.html import (badge, figure, html_page, page_header, paragraph, section,
                                       table)
from cassini_bayes.report.plan import _usage_table, manoeuvre_figure

__all__ = ["axis_evaluation_report", "axis_plan_report"]


def _fmt(x: float) -> str:
    return f"{x:.4g}"


def _direction_table(blocks: list[tuple[str, Mapping]]) -> str:
    rows = []
    for name, b in blocks:
        c = b["cone_deg"]
        rows.append([name, f"{b['sd_direction_deg']:.4g}", f"{c['50']:.3g}", f"{c['90']:.3g}",
                     f"{c['95']:.3g}", f"{b['cone90_over_budget']:.3f}",
                     str(len(b["windows_s"]))])
    return table(["manoeuvre", "largest angular sd (°)", "50 % cone (°)", "90 % cone (°)",
                  "95 % cone (°)", "90 % cone / Brown's 1°", "window pairs"], rows,
                 classes=[["", "", "", "", "", "bad" if b["cone90_over_budget"] > 1 else "", ""]
                          for _, b in blocks])


def _sites_table(blocks: list[tuple[str, Mapping]]) -> str:
    first = blocks[0][1]["sites"]
    rows = []
    for n in first:
        row = [n]
        for _, b in blocks:
            q = b["sites"][n]
            row += [_fmt(q["sd"]), f"{q['sd'] / q['prior_sd']:.3f}"]
        rows.append(row + [_fmt(first[n]["prior_sd"])])
    heads = ["parameter"]
    for name, _ in blocks:
        heads += [f"{name}: sd", f"{name}: sd/prior"]
    return table(heads + ["prior sd"], rows)


_NOTE = ("Predicted posterior of the robust RWA-method wheel-axis fit (Brown 2012 §III.C): the "
         "Laplace approximation of the fit's own density on the flight simulated without noise, "
         "with the scenario's sensor noise levels; the nuisance effects are integrated out as the "
         "fit integrates them. u4_*: components of the unit axis; Ixx…Iyz: kg m².")


def axis_plan_report(summary: Mapping, plan) -> str:
    """``report.html`` of ``cassini-bayes plan wheel-axis``."""
    p, b = summary["plan"], summary["baseline"]
    imp = summary["improvement"]
    goal = summary.get("goal")
    badges = " ".join([
        badge("limits respected" if p.get("limits_ok") else "limits exceeded",
              p.get("limits_ok")),
        badge(f"90 % cone {p['cone_deg']['90']:.3g}°", p["cone90_over_budget"] <= 1.0),
        badge(f"×{imp['sd_direction']:.2f} vs comparison (largest angular sd)", None),
        *([badge(f"goal {goal['cone90_deg']:g}° {'reached' if goal['reached'] else 'not reached'}",
                 goal["reached"])] if goal else [])])
    header = page_header(badges, f"cassini-bayes {__version__} plan wheel-axis · "
                                 f"{summary['spacecraft']} · {summary['wheel']} · limits "
                                 f"{summary['limits_file']}", summary.get("warnings", []))
    blocks = [("plan", p), ("comparison", b)]
    png = png_bytes(manoeuvre_figure([("plan", plan.prediction),
                                      (b["name"], plan.baseline)], plan.limits))
    slews = table(["#", "start (s)", "axis (body)", "angle (°)", "rate (mrad/s)",
                   "accel (mrad/s²)"],
                  [[str(i + 1), f"{r['t_start_s']:.1f}",
                    "[" + ", ".join(f"{x:+.3f}" for x in r["axis"]) + "]",
                    f"{r['angle_deg']:.2f}", f"{r['rate_mrad_s']:.4g}",
                    f"{r['accel_mrad_s2']:.4g}"] for i, r in enumerate(summary["slews"])])
    windows = table(["window", "from (s)", "to (s)"],
                    [[w["name"], f"{w['t0_s']:.0f}", f"{w['t1_s']:.0f}"]
                     for w in summary["windows"]])
    search = table(["pairs", "angle (°)", "rest factor", "wheel fraction", "phase (°)",
                    "largest sd (°)", "limits ok", "seconds"],
                   [[str(r["pairs"]), f"{r['angle_deg']:g}", f"{r['rest_factor']:g}",
                     f"{r['wheel_fraction']:g}", f"{r['phase_deg']:g}",
                     "–" if r["sd_direction_deg"] is None else f"{r['sd_direction_deg']:.4g}",
                     str(r.get("limits_ok", False)), f"{r['seconds']:.0f}"]
                    for r in summary["search"]])
    wheel_rpm = ", ".join(f"{k} {v:.0f} rpm" for k, v in summary["wheel_rpm"].items())
    sections = [
        section("Predicted posterior", [
            paragraph(f"Comparison: {b['name']}."), _direction_table(blocks),
            _sites_table(blocks), paragraph(_NOTE, note=True)]),
        section("Manoeuvre", [
            figure(png, "Body rates and wheel speeds of the plan and the comparison, simulated "
                        "without noise; dashed: the limits."),
            paragraph(f"Wheel speeds at the start: {wheel_rpm}. Fit with: fit wheel-axis "
                      f"--wheel {summary['wheel']} --method rwa {summary['fit_windows']}"),
            slews, windows]),
        section("Limits", [_usage_table(blocks), paragraph(
            "Largest fraction of each limit on the simulated telemetry.", note=True)]),
        section("Search", [search]),
    ]
    return html_page("cassini-bayes plan wheel-axis", sections, header=header)


def axis_evaluation_report(summary: Mapping, prediction, limits=None) -> str:
    """``report.html`` of ``cassini-bayes plan evaluate`` for a wheel-axis scenario."""
    p = summary["prediction"]
    badges = badge(f"90 % cone {p['cone_deg']['90']:.3g}°", p["cone90_over_budget"] <= 1.0)
    header = page_header(badges, f"cassini-bayes {__version__} plan evaluate · "
                                 f"{summary['scenario']} · {summary['spacecraft']} · "
                                 f"{p['wheel']} axis")
    png = png_bytes(manoeuvre_figure([(summary["scenario"], prediction)], limits))
    blocks = [("scenario", p)]
    sections = [section("Predicted posterior", [_direction_table(blocks), _sites_table(blocks),
                                                 paragraph(_NOTE, note=True)]),
                section("Manoeuvre", [figure(png, "Body rates and wheel speeds simulated "
                                                  "without noise.")])]
    if "usage" in p:
        sections.append(section("Limits", [_usage_table(blocks)]))
    return html_page("cassini-bayes plan evaluate", sections, header=header)
