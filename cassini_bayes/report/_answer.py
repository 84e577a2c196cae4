"""The answer section of a fit's report: the answer table, the posterior figure, and for RWA4
the spin-axis table and sky plot with Brown's requirement.
"""

from __future__ import annotations

import numpy as np

from cassini_bayes.files import finite_or_none
from cassini_bayes.names import U4_NAMES
from cassini_bayes.report import figures
from cassini_bayes.report.html import (
    Raw,
    Section,
    badge,
    not_available,
    paragraph,
    section,
    table,
)
from cassini_bayes.report.rundata import RunData, flatten_draws
from cassini_bayes.report.tables import (
    BudgetCheck,
    ParameterRow,
    decimals_for,
    fmt,
    lookup,
)

# Brown (2012) §I: RWA4 must sit within ±2° of the RWA1 axis. What a summary.json written before
# the wheel-axis fit named its wheel (no ``wheel`` block) was: an RWA4 fit on Cassini's cone.
_CASSINI_RWA4 = {"name": "RWA4",
                 "cone": {"axis": [0.0, 0.0, 1.0], "deg": figures.ARTICULATION_CONE_DEG},
                 "reference": {"name": "RWA1", "axis": figures.RWA1_AXIS.tolist(),
                               "tol_deg": 2.0}}
REQUIREMENT_PROB = 0.95     # a requirement is called met (or not) at this posterior probability


def _sep(unit: str) -> str:
    return "" if unit == "°" else " "


def _budget_cells(b: BudgetCheck | None) -> tuple[list, list[str]]:
    if b is None:
        return ["–", "–", "–"], ["", "", ""]
    return ([f"{b.bound} ({b.source})", f"{b.error_q95:.3g}{_sep(b.unit)}{b.unit}",
             Raw(badge("pass" if b.passed else "FAIL", b.passed))],
            ["", "good" if b.passed else "bad", ""])


def _answer_table(rows: list[ParameterRow], derived=()) -> str:
    """The answer table: one row per calibrated quantity (then the papers' derived quantities:
    their error's median and 90 % interval), the answer's columns first."""
    has_truth = any(r.truth is not None for r in rows)
    headers = ["quantity", "unit", "posterior mean", "sd", "90 % interval",
               "model file (prior mean)", "prior sd", "least squares (papers)"]
    if has_truth:
        headers += ["truth", "truth in 90 %"]
    headers += ["identified (contraction)", "papers' budget", "error, 95th percentile",
                "verdict"]
    body, classes = [], []
    for r in rows:
        d = decimals_for(r.sd)
        interval = ("–" if r.q05 is None or r.q95 is None
                    else f"[{fmt(r.q05, d)}, {fmt(r.q95, d)}]")
        prior_sd = "–" if r.prior_sd is None else fmt(r.prior_sd, decimals_for(r.prior_sd))
        cells = [r.label, r.unit or "–", fmt(r.mean, d), fmt(r.sd, d + 1), interval,
                 fmt(r.prior_mean, d), prior_sd, fmt(r.baseline, d)]
        cls = [""] * len(cells)
        if has_truth:
            inside = (None if r.truth is None or r.q05 is None or r.q95 is None
                      else r.q05 <= r.truth <= r.q95)
            cells += [fmt(r.truth, d), "–" if inside is None else ("yes" if inside else "no")]
            cls += ["", "" if inside is None else ("good" if inside else "warn")]
        if r.contraction is None:
            cells.append("unknown (no prior)")
            cls.append("")
        else:
            cells.append(f"{r.flag or 'yes'} ({r.contraction:.3f})")
            cls.append("warn" if r.flag else "good")
        b_cells, b_cls = _budget_cells(r.budget)
        body.append(cells + b_cells)
        classes.append(cls + b_cls)
    for label, unit, err, check in derived:
        q05, med, q95 = np.quantile(err, [0.05, 0.5, 0.95])
        cells = [label, unit, f"{med:.3g} (median)", "", f"[{q05:.3g}, {q95:.3g}]", "–", "–",
                 "–"] + (["–", "–"] if has_truth else []) + ["–"]
        b_cells, b_cls = _budget_cells(check)
        body.append(cells + b_cells)
        classes.append(["w"] + [""] * (len(cells) - 1) + b_cls)
    return table(headers, body, left=1, classes=classes)


def answer_section(run: RunData, names, rows, derived, fig) -> Section:
    if not rows:
        return section("Answer", not_available("no calibration parameters in the posterior"),
                       id="answer")
    body = [_answer_table(rows, derived), paragraph(
        "Model file = the spacecraft model's prediction, the prior's centre (– where the model "
        "predicts none, e.g. an axis under a uniform prior); prior sd from the prior draws. Least "
        "squares = the papers' estimator on the same data (summary.json baseline). Identified: "
        "contraction = 1 − Var(post)/Var(prior) (Betancourt 2018), weakly identified below 0.5. "
        "Papers' budget: each posterior draw read as the truth and the posterior mean as the "
        "estimate; the error's 95th percentile must lie within the bound (docs/budgets.md).",
        note=True)]
    if run.kind == "rwa4":
        body.append(_direction_table(run))
        body.append(_axis_figure(run, fig))
    else:
        post = flatten_draws(run.posterior, names)
        panels = [figures.Panel(r.label, r.unit, post[r.label], r.baseline, r.truth, r.prior_mean)
                  for r in rows if r.label in post]
        body.append(fig(
            "posteriors beside the least squares",
            lambda: figures.answer_figure(panels),
            "Each parameter's posterior at its own scale (histogram of the draws, 90 % interval "
            "shaded, mean solid), the papers' least squares dashed, the truth red when known, the "
            "model file's prediction dotted; a value further than "
            f"{figures.WINDOW_SD:g} posterior sd away is written at the edge with its distance."))
    return section("Answer", body, id="answer")


def _angle_deg(a, b) -> float:
    a = np.asarray(a, float) / np.linalg.norm(a)
    b = np.asarray(b, float) / np.linalg.norm(b)
    return float(np.degrees(np.arccos(np.clip(a @ b, -1.0, 1.0))))


def _axis_draws(run: RunData) -> np.ndarray | None:
    post = run.posterior
    if not all(n in post for n in U4_NAMES):
        return None
    return np.stack([np.asarray(post[n].values, float).ravel() for n in U4_NAMES], -1)


def _axis_vec(mapping) -> np.ndarray | None:
    """An RWA4 axis from a baseline/truth mapping (components or a ``u4`` vector)."""
    comps = [lookup(mapping, n) for n in U4_NAMES]
    if all(c is not None for c in comps):
        v = np.array(comps, float)
        return v if np.linalg.norm(v) > 0 else None
    return None


def _direction(run: RunData) -> tuple[np.ndarray | None, dict[str, float]]:
    """Posterior mean direction and 50/90/95 % cones: summary.json's, else from the draws."""
    d = run.summary.get("direction") or {}
    draws = _axis_draws(run)
    mean = d.get("mean")
    mean = np.array(mean, float) if isinstance(mean, (list, tuple)) and len(mean) == 3 else None
    if mean is None and draws is not None:
        mean = draws.mean(0)
    if mean is not None:
        mean = mean / np.linalg.norm(mean)
    cones = {str(k): finite_or_none(v) for k, v in (d.get("cone_deg") or {}).items()}
    if not cones and draws is not None and mean is not None:
        u = draws / np.linalg.norm(draws, axis=1, keepdims=True)
        ang = np.degrees(np.arccos(np.clip(u @ mean, -1, 1)))
        cones = {k: float(np.quantile(ang, int(k) / 100)) for k in ("50", "90", "95")}
    return mean, cones


def _requirement_verdict(p: float) -> str:
    """A requirement met with posterior probability ``p``: "yes" at ≥ 0.95, "no" at ≤ 0.05,
    else undecided (the mean axis alone can sit inside while most of the posterior does not)."""
    if p >= REQUIREMENT_PROB:
        return f"yes (probability {p:.3f})"
    if p <= 1.0 - REQUIREMENT_PROB:
        return f"no (probability {p:.3f})"
    return f"undecided (probability {p:.3f}: the data do not settle it)"


def _wheel(run: RunData) -> dict:
    """summary.json's ``wheel`` block (name, articulation cone, reference wheel; each may be
    ``None``); Cassini's RWA4 for a summary written before the block existed."""
    w = run.summary.get("wheel")
    return w if isinstance(w, dict) else _CASSINI_RWA4


def _vec_text(v) -> str:
    return "[" + ", ".join("0" if x == 0 else f"{x:.6f}" for x in np.asarray(v, float)) + "]"


def _direction_table(run: RunData) -> str:
    mean, cones = _direction(run)
    wheel = _wheel(run)
    name = wheel.get("name") or "the wheel"
    if mean is None:
        return not_available(f"{name} direction (no u4 draws and no direction in summary.json)")
    truth = _axis_vec(run.summary.get("truth"))
    base = _axis_vec(run.summary.get("baseline"))
    rows = [["calibrated wheel", str(name)],
            ["posterior mean direction", "[" + ", ".join(f"{x:.6f}" for x in mean) + "]"]]
    cone, ref = wheel.get("cone"), wheel.get("reference")
    if cone:
        axis = np.asarray(cone["axis"], float)
        label = "+Z" if np.allclose(axis, [0, 0, 1]) else _vec_text(axis)
        rows.append([f"angle from {label} (articulation cone {cone['deg']:.4f}°)",
                     f"{_angle_deg(mean, axis):.3f}°"])
    if ref:
        target, tol = np.asarray(ref["axis"], float), float(ref["tol_deg"])
        to_ref = _angle_deg(mean, target)
        rows.append([f"angle to {ref['name']} target {_vec_text(target)}",
                     f"{to_ref:.3f}°"])
        requirement = f"within ±{tol:g}° of {ref['name']} (reference wheel, spacecraft model)"
        draws = _axis_draws(run)
        if draws is not None:
            u = draws / np.linalg.norm(draws, axis=1, keepdims=True)
            t = target / np.linalg.norm(target)
            p_req = float(np.mean(np.degrees(np.arccos(np.clip(u @ t, -1, 1))) <= tol))
            rows.append([requirement, _requirement_verdict(p_req)])
            rows.append([f"posterior probability of being within {tol:g}° of {ref['name']}",
                         f"{p_req:.3f}"])
        else:    # no draws: only the mean axis to go by
            rows.append([requirement + ", by the mean axis", "yes" if to_ref <= tol else "no"])
    for k in sorted(cones, key=float):
        rows.append([f"{k} % cone radius about the mean", fmt(cones[k], 3) + "°"])
    if base is not None:
        rows.append(["least-squares axis: angle to posterior mean",
                     f"{_angle_deg(base, mean):.3f}°"])
    if truth is not None:
        err = _angle_deg(truth, mean)
        rows.append(["posterior mean error (angle to truth)", f"{err:.3f}°"])
        c90 = cones.get("90")
        if c90 is not None:
            rows.append(["truth inside the 90 % cone", "yes" if err <= c90 else "no"])
        if base is not None:
            rows.append(["least-squares error (angle to truth)", f"{_angle_deg(truth, base):.3f}°"])
    return "<h3>Spin-axis direction</h3>\n" + table(["quantity", "value"], rows, left=1)


def _axis_figure(run: RunData, fig) -> str:
    draws = _axis_draws(run)
    mean, cones = _direction(run)
    if draws is None or mean is None:
        return not_available("spin-axis sky plot (no u4_x, u4_y, u4_z draws in the posterior)")
    truth = _axis_vec(run.summary.get("truth"))
    base = _axis_vec(run.summary.get("baseline"))
    wheel = _wheel(run)
    cone, ref = wheel.get("cone"), wheel.get("reference")
    shown = " and ".join(x for x, have in (("the articulation cone", cone),
                                            (f"the {ref['name']} target axis" if ref else "",
                                             ref)) if have)
    return fig("spin-axis sky plot",
               lambda: figures.axis_sky_figure(
                   draws, mean=mean, cones_deg=cones, truth=truth, baseline=base,
                   target=(ref["name"], np.asarray(ref["axis"], float)) if ref else None,
                   cone=(np.asarray(cone["axis"], float), float(cone["deg"])) if cone else None),
               f"{wheel.get('name') or 'Wheel'} spin-axis posterior. Left: body "
               f"azimuth/elevation of the draws{', ' + shown if shown else ''}. Middle: "
               "azimuthal-equidistant view "
               "about the posterior mean at the budgets' scale, the dotted circles true 1°, 2° "
               "and 3° cones (the papers' ±1° RWA-method and 3° RCS-method budgets). Right: the "
               "same view at the posterior's own scale, the solid circles the posterior "
               "50/90/95 % cones, the least-squares axis (and truth) marked; an axis beyond a "
               "view's edge is written with its distance instead.")
