"""Assemble a fit run directory's ``report.html`` (docs/design.md §4.4) from its files.

The page opens with the answer: the verdicts as badges (converged, adequate, within the papers'
budgets), then the answer table — each calibrated quantity with its unit, posterior mean, sd and
90 % interval, the model file's prediction and the prior sd, the papers' least squares, the
papers' budget with pass/fail — and one figure of the posteriors at their own scale beside the
least-squares values (for RWA4 the spin-axis table and sky plot). Below: per-pulse impulses
(thrust), model adequacy, residuals, sensitivity, the sampler diagnostics (trace and rank plots of
the calibrated parameters, their posterior correlations; the per-variable table of the nuisance
folded away) and the configuration. A section whose data the run lacks says so instead of
disappearing, so every report of a kind has the same outline.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from cassini_bayes import __version__
from cassini_bayes.diagnostics import ESS_BULK_MIN, R_HAT_MAX
from cassini_bayes.names import U4_NAMES
from cassini_bayes.report import figures
from cassini_bayes.report.adequacy import adequacy_badge, adequacy_section
from cassini_bayes.report.html import (
    Raw,
    Section,
    badge,
    details,
    esc,
    figure,
    html_page,
    not_available,
    page_header,
    paragraph,
    preformatted,
    section,
    table,
)
from cassini_bayes.files import finite_or_none, write_text
from cassini_bayes.report.rundata import RunData, flatten_draws, load_run
from cassini_bayes.report.tables import (
    BFMI_MIN,
    BudgetCheck,
    DiagnosticTable,
    ParameterRow,
    decimals_for,
    derived_rows,
    diagnostics,
    fmt,
    lookup,
    parameter_names,
    parameter_rows,
)

__all__ = ["build_report", "render_report", "verdict_badges"]

MAX_RESIDUAL_FIGURES = 1
RWA1_REQUIREMENT_DEG = 2.0  # Brown (2012) §I: RWA4 must sit within ±2° of the RWA1 axis
REQUIREMENT_PROB = 0.95     # a requirement is called met (or not) at this posterior probability
KIND_TITLES = {
    "inertia": "inertia tensor from reaction-wheel slews (momentum model, Feldman & Lee Eqs 2-11)",
    "thrust": "thrust and pulse time constants from wheel-biasing events "
              "(impulse model, Feldman & Lee Eqs 14-23)",
    "rwa4": "RWA4 spin axis (Brown 2012)",
}
RESIDUAL_LABELS = {
    "inertia": "residual (N m s)",
    "thrust": "residual (N m s)",
    "rwa4": "residual",
}


def build_report(
    run_dir: str | Path,
    *,
    out: str | Path | None = None,
    display_dir: str | Path | None = None,
) -> Path:
    """Write the self-contained report of a fit's run directory.

    Parameters
    ----------
    run_dir : str or Path
        Directory holding ``posterior.nc`` and normally ``summary.json`` and ``config.toml``.
    out : str or Path, optional
        Where to write; default ``run_dir / "report.html"``. Written atomically.
    display_dir : str or Path, optional
        The directory named on the page, when it differs from ``run_dir`` (a fit building its
        run in a temporary directory that is renamed to the final name afterwards).

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    InputError
        ``run_dir`` or its ``posterior.nc`` is missing or unreadable.
    """
    run = load_run(run_dir)
    out = Path(out) if out is not None else run.run_dir / "report.html"
    return write_text(out, render_report(run, display_dir=display_dir))


def render_report(run: RunData, *, display_dir: str | Path | None = None) -> str:
    """The report of a loaded run as an HTML string (see :func:`build_report`)."""
    shown = Path(display_dir) if display_dir is not None else run.run_dir
    names = parameter_names(run)
    diag = diagnostics(run, names)
    rows = parameter_rows(run, names, diag)
    derived = derived_rows(run)
    problems: list[str] = []  # figures that could not be drawn

    def fig(title: str, draw: Callable[[], object], caption: str) -> str:
        try:
            return figure(figures.png_bytes(draw()), caption, alt=title)
        except Exception as e:  # a figure must never cost the whole report
            problems.append(f"{title} could not be drawn ({type(e).__name__}: {e})")
            return not_available(f"{title} could not be drawn ({type(e).__name__}: {e})")

    sections = [_answer_section(run, names, rows, derived, fig)]
    if run.kind == "thrust":
        sections.append(_pulses_section(run, fig))
    sections += [adequacy_section(run.summary), _residuals_section(run, fig)]
    from cassini_bayes.report.sensitivity import sensitivity_section
    sections += [s for s in [sensitivity_section(run.summary)] if s is not None]
    sections += [_diagnostics_section(run, names, diag, rows, fig), _config_section(run)]

    checks = [r.budget for r in rows if r.budget] + [b for *_, b in derived if b]
    header = _header(run, diag, rows, checks, problems, shown)
    title = f"cassini-bayes {run.kind} run — {shown.name}"
    footer = (f"Built by cassini-bayes {esc(__version__)} from {esc(shown / 'posterior.nc')}."
              " Posterior summaries from the full posterior; the sampler diagnostics are the "
              "fit's (ArviZ, summary.json); plots may show thinned draws.")
    return html_page(title, sections, header=header, footer=footer)


# --------------------------------------------------------------------------------------------
# header


def verdict_badges(summary: dict, *, converged: bool | None = None,
                   checks: list[BudgetCheck] | None = None) -> str:
    """The verdict badges that open every report: converged (a sampled fit), adequate (from
    ``summary["adequacy"]``: a fit always, any other run when it has the block), within the
    papers' budgets (``checks``)."""
    out = []
    if converged is not None:
        out.append(badge("CONVERGED" if converged else "NOT CONVERGED", converged))
    if converged is not None or isinstance(summary.get("adequacy"), dict):
        out.append(adequacy_badge(summary))
    if checks:
        failed = [c for c in checks if not c.passed]
        out.append(badge("WITHIN THE PAPERS' BUDGETS" if not failed else
                         f"OUTSIDE THE PAPERS' BUDGETS ({len(failed)} of {len(checks)})",
                         not failed))
    return " ".join(out)


def _header(run: RunData, diag: DiagnosticTable, rows: list[ParameterRow],
            checks: list[BudgetCheck], problems: list[str], shown: Path) -> str:
    cfg = run.config
    seed = run.summary.get("seed", cfg.get("seed", "–"))
    version = run.summary.get("version", cfg.get("version", "–"))
    src = "fit" if diag.converged_summary is not None else "recomputed"
    meta = (f"{run.kind} — {KIND_TITLES.get(run.kind, 'unknown kind')} · {shown} · seed {seed} · "
            f"cassini-bayes {version} · {diag.chains} chains × {diag.draws} draws")
    badges = (f"{verdict_badges(run.summary, converged=diag.converged, checks=checks)}"
              f' <span class="na">({esc(src)} verdict: max R-hat ≤ {R_HAT_MAX}, min bulk ESS ≥ '
              f"{ESS_BULK_MIN:g}, no divergences)</span>")
    return page_header(badges, meta, _warnings(run, diag, rows) + problems)


def _warnings(run: RunData, diag: DiagnosticTable, rows: list[ParameterRow]) -> list[str]:
    w = [str(x) for x in (run.summary.get("warnings") or [])]
    w += list(run.notes)
    if diag.divergences:
        w.append(f"{diag.divergences} divergent transitions: the posterior may be biased")
    if np.isfinite(diag.overall.max_r_hat) and diag.overall.max_r_hat > R_HAT_MAX:
        w.append(f"max R-hat {diag.overall.max_r_hat:.4f} > {R_HAT_MAX}: chains disagree")
    if np.isfinite(diag.overall.min_ess_bulk) and diag.overall.min_ess_bulk < ESS_BULK_MIN:
        w.append(f"min bulk ESS {diag.overall.min_ess_bulk:.0f} < {ESS_BULK_MIN:g}")
    if diag.bfmi is not None and np.any(diag.bfmi < BFMI_MIN):
        w.append(f"energy BFMI below {BFMI_MIN} in chain(s) "
                 f"{', '.join(str(i) for i in np.flatnonzero(diag.bfmi < BFMI_MIN))}")
    if diag.converged_summary is not None and diag.converged_summary != diag.overall.converged:
        w.append(f"the fit's verdict (converged = {diag.converged_summary}) differs from this "
                 f"report's check on posterior.nc (R-hat ≤ {R_HAT_MAX}, bulk ESS ≥ {ESS_BULK_MIN:g}, "
                 "no divergences)")
    weak = [r.label for r in rows if r.flag]
    if weak:
        w.append("weakly identified (posterior/prior contraction < 0.5): " + ", ".join(weak))
    # keep order, drop repeats
    return list(dict.fromkeys(w))


# --------------------------------------------------------------------------------------------
# the answer


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


def _answer_section(run: RunData, names, rows, derived, fig) -> Section:
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


def _direction_table(run: RunData) -> str:
    mean, cones = _direction(run)
    if mean is None:
        return not_available("RWA4 direction (no u4 draws and no direction in summary.json)")
    truth = _axis_vec(run.summary.get("truth"))
    base = _axis_vec(run.summary.get("baseline"))
    to_rwa1 = _angle_deg(mean, figures.RWA1_AXIS)
    rows = [
        ["posterior mean direction", "[" + ", ".join(f"{x:.6f}" for x in mean) + "]"],
        ["angle from +Z (articulation cone 54.7356°)", f"{_angle_deg(mean, [0, 0, 1]):.3f}°"],
        ["angle to RWA1 target [0, 0.816497, 0.577350]", f"{to_rwa1:.3f}°"],
    ]
    draws = _axis_draws(run)
    requirement = "within ±2° of RWA1 (replacement requirement, Brown §I)"
    if draws is not None:
        u = draws / np.linalg.norm(draws, axis=1, keepdims=True)
        t = figures.RWA1_AXIS / np.linalg.norm(figures.RWA1_AXIS)
        p_req = float(np.mean(np.degrees(np.arccos(np.clip(u @ t, -1, 1))) <= RWA1_REQUIREMENT_DEG))
        rows.append([requirement, _requirement_verdict(p_req)])
        rows.append(["posterior probability of being within 2° of RWA1", f"{p_req:.3f}"])
    else:    # no draws: only the mean axis to go by
        rows.append([requirement + ", by the mean axis",
                     "yes" if to_rwa1 <= RWA1_REQUIREMENT_DEG else "no"])
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
    return fig("spin-axis sky plot",
               lambda: figures.axis_sky_figure(draws, mean=mean, cones_deg=cones, truth=truth,
                                               baseline=base),
               "RWA4 spin-axis posterior. Left: body azimuth/elevation of the draws, the "
               "articulation cone and the RWA1 target axis. Middle: azimuthal-equidistant view "
               "about the posterior mean at the budgets' scale, the dotted circles true 1°, 2° "
               "and 3° cones (the papers' ±1° RWA-method and 3° RCS-method budgets). Right: the "
               "same view at the posterior's own scale, the solid circles the posterior "
               "50/90/95 % cones, the least-squares axis (and truth) marked; an axis beyond a "
               "view's edge is written with its distance instead.")


# --------------------------------------------------------------------------------------------
# per-pulse impulses, residuals


def _pulses_section(run: RunData, fig) -> Section:
    g = run.groups.get("pulse_impulses")
    if g is None or "measured" not in g:
        return section("Per-pulse impulses", not_available(
            "per-pulse impulses (posterior.nc has no pulse_impulses group: a run written before "
            "they were stored; re-run the fit)"), id="pulses")
    n = len(g["measured"].values)
    body = fig("per-pulse impulses", lambda: figures.pulse_impulse_figure(g),
               f"{n} pulse groups (the pulses between two telemetry samples, joined while one "
               "is still acting). Left: the angular impulse measured across each group (the "
               "momentum's change along the predicted direction; bar: 90 % of the telemetry "
               "noise) against the impulse model's prediction (Feldman & Lee Eq 17 and §V; bar: "
               "posterior 90 %). Right: their misfit against the group's commanded on-time: a "
               "trend with pulse length means the pulse time constants are off.")
    return section("Per-pulse impulses", body, id="pulses")


def _residuals_section(run: RunData, fig) -> Section:
    if not run.has_group("residuals"):
        return section("Residuals",
                       not_available("model residuals (posterior.nc has no residuals group)"),
                       id="residuals")
    ds = run.groups["residuals"]
    # the posterior-mean residual first, then any companions (e.g. the whitened residual)
    names = sorted(ds.vars, key=lambda v: (v != "residual", str(v)))[:MAX_RESIDUAL_FIGURES]
    model = {"inertia": "momentum model (Feldman & Lee Eq 11)",
             "thrust": "impulse model (Feldman & Lee Eq 17)"}.get(run.kind, "model")
    body = []
    for var in names:
        attrs = ds[var].attrs
        desc = str(attrs.get("description") or attrs.get("long_name") or "")
        units = str(attrs.get("units", ""))
        if var == "residual":
            label = RESIDUAL_LABELS.get(run.kind, "residual")
            if "(" not in label:
                label = f"{label} ({units or 'unit not recorded'})"
        else:
            label = f"{var} ({'dimensionless' if units in ('1', '') else units})"
        frame = f", {attrs['frame']} axes" if attrs.get("frame") else ""
        what = desc or ("posterior-mean residual" if var == "residual" else str(var))
        body.append(fig(
            f"residuals: {var}",
            lambda var=var, label=label: figures.residuals_figure(ds, var=str(var), ylabel=label),
            f"{what[:1].upper()}{what[1:]} of the {model} against time{frame}. Structure "
            "(drifts, steps at slew or pulse times) points at an unmodelled effect; white noise "
            "at the telemetry noise level (or of unit variance, when whitened) is what a good fit "
            "leaves."))
    return section("Residuals", body, id="residuals")


# --------------------------------------------------------------------------------------------
# sampler diagnostics


def _cls_rhat(x: float) -> str:
    return "" if not np.isfinite(x) else ("bad" if x > R_HAT_MAX else "good")


def _cls_ess(x: float) -> str:
    return "" if not np.isfinite(x) else ("bad" if x < ESS_BULK_MIN else "good")


def _ok_badge(cls: str) -> Raw:
    return Raw(badge("ok" if cls == "good" else ("n/a" if not cls else "check"),
                     None if not cls else cls == "good"))


def _overview_table(diag: DiagnosticTable) -> str:
    bfmi_txt = ("–" if diag.bfmi is None else ", ".join(f"{b:.2f}" for b in diag.bfmi))
    bfmi_ok = None if diag.bfmi is None else bool(np.all(diag.bfmi >= BFMI_MIN))
    div_txt = "not recorded" if diag.divergences is None else str(diag.divergences)
    return table(
        ["check", "value", "threshold", "status"],
        [
            ["max R-hat", fmt(diag.overall.max_r_hat, 4), f"≤ {R_HAT_MAX}",
             _ok_badge(_cls_rhat(diag.overall.max_r_hat))],
            ["min bulk ESS", fmt(diag.overall.min_ess_bulk, 0), f"≥ {ESS_BULK_MIN:g}",
             _ok_badge(_cls_ess(diag.overall.min_ess_bulk))],
            ["min tail ESS", fmt(diag.overall.min_ess_tail, 0), f"≥ {ESS_BULK_MIN:g} (advisory)",
             _ok_badge(_cls_ess(diag.overall.min_ess_tail))],
            ["divergences", div_txt, "0",
             Raw(badge("ok" if diag.divergences == 0 else
                       ("n/a" if diag.divergences is None else "check"),
                       None if diag.divergences is None else diag.divergences == 0))],
            ["energy BFMI (per chain)", bfmi_txt, f"≥ {BFMI_MIN}",
             Raw(badge("n/a" if bfmi_ok is None else ("ok" if bfmi_ok else "check"), bfmi_ok))],
        ],
    )


def _per_variable_table(diag: DiagnosticTable) -> str:
    rows, classes = [], []
    for r in diag.rows:
        d = decimals_for(r.sd)
        rows.append([r.label, r.role, fmt(r.mean, d), fmt(r.sd, d + 1),
                     fmt(r.contraction, 3), fmt(r.r_hat, 4), fmt(r.ess_bulk, 0),
                     fmt(r.ess_tail, 0)])
        classes.append(["", "", "", "", "", _cls_rhat(r.r_hat), _cls_ess(r.ess_bulk),
                        _cls_ess(r.ess_tail)])
    out = table(["variable", "role", "mean", "sd", "contraction", "R-hat", "bulk ESS",
                 "tail ESS"], rows, left=2, classes=classes)
    if diag.sampler:
        listed = ", ".join(f"{k} ({n})" for k, n in diag.sampler.items())
        out += paragraph(f"Sampler coordinates, not judged (each parameter is a function of "
                         f"them; no diagnostics computed): {listed}.", note=True)
    return out


def _correlation_table(post: dict[str, np.ndarray]) -> str:
    labels = list(post)
    x = np.stack([np.asarray(post[k], float).ravel() for k in labels])
    with np.errstate(invalid="ignore", divide="ignore"):
        c = np.corrcoef(x)
    rows, classes = [], []
    for i, a in enumerate(labels):
        rows.append([a] + ["" if j == i else f"{c[i, j]:+.2f}" for j in range(len(labels))])
        classes.append([""] + ["" if j == i or not np.isfinite(c[i, j]) else
                               ("warn" if abs(c[i, j]) >= 0.9 else "")
                               for j in range(len(labels))])
    return table([""] + labels, rows, left=1, classes=classes)


def _diagnostics_section(run: RunData, names, diag: DiagnosticTable, rows: list[ParameterRow],
                         fig) -> Section:
    post = flatten_draws(run.posterior, names)
    units = {r.label: r.unit for r in rows}
    n_nuis = sum(1 for r in diag.rows if not r.of_interest)
    body = [_overview_table(diag)]
    if post:
        body.append(fig(
            "trace and rank plots",
            lambda: figures.trace_rank_figure(post, units),
            "Left: each chain's draws of each calibrated parameter against iteration (thinned "
            f"to at most {figures.MAX_TRACE_DRAWS} per chain): chains should overlap and look "
            "like stationary noise. Right: each chain's histogram of its draws' ranks among all "
            "chains (Vehtari et al. 2021), dashed the flat count of chains that mix; a chain "
            "sitting high or low did not explore the same distribution."))
    if len(post) > 1:
        body += ["<h3>Posterior correlations of the calibrated parameters</h3>",
                 _correlation_table(post),
                 paragraph("Pearson correlations over all draws; |ρ| ≥ 0.9 highlighted: the data "
                           "determine that combination better than either parameter alone.",
                           note=True)]
    body.append(details(
        f"Per-variable diagnostics: {len(diag.rows) - n_nuis} parameters, {n_nuis} nuisance "
        "components", _per_variable_table(diag)))
    src = ("the fit's, from summary.json" if not diag.computed else
           f"the fit's from summary.json; computed here with ArviZ for {len(diag.computed)} "
           "components it lacks")
    body.append(paragraph(
        "Rank-normalised split R-hat and bulk/tail effective sample sizes (Vehtari et al. 2021), "
        f"{src}; E-BFMI (Betancourt 2016) from posterior.nc. The extremes cover the parameters and "
        "the nuisance, as the fit's verdict does. Tail ESS is advisory: it is not part of the "
        "verdict.", note=True))
    return section("Sampler diagnostics", body, id="diagnostics")


def _config_section(run: RunData) -> Section:
    if run.config_text is None:
        return section("Configuration", not_available("config.toml"), id="configuration")
    return section("Configuration",
                   details("config.toml (resolved inputs, seed and version)",
                           preformatted(run.config_text)),
                   id="configuration")
