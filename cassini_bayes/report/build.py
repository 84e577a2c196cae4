"""Assemble a run directory's ``report.html`` (docs/design.md §4.4) from its files.

The page, top to bottom: header (kind, directory, seed, version, convergence and adequacy badges,
warnings); model adequacy (the fit's self-checks); sampler diagnostics; parameter table (with
baseline, truth, prior sd, contraction and the weak-identification flag); trace, rank,
prior-vs-posterior and pair plots; model residuals against time; for RWA4 the spin-axis sky plot;
the energy plot; the resolved configuration. A section whose data the run lacks says so instead
of disappearing, so every report has the same outline.
"""

from __future__ import annotations

import tomllib
from collections.abc import Callable
from pathlib import Path

import numpy as np

from cassini_bayes import __version__
from cassini_bayes.names import F_NAMES, INERTIA_NAMES, TAU_NAMES, U4_NAMES
from cassini_bayes.report import figures
from cassini_bayes.report.adequacy import adequacy_badge, adequacy_section
from cassini_bayes.report.html import (
    Raw,
    Section,
    badge,
    bullet_list,
    details,
    esc,
    figure,
    html_page,
    meta_list,
    not_available,
    paragraph,
    preformatted,
    section,
    table,
    write_atomic,
)
from cassini_bayes.report.rundata import RunData, finite_or_none, flatten_draws, load_run
from cassini_bayes.report.tables import (
    BFMI_MIN,
    ESS_MIN,
    RHAT_MAX,
    Diagnostics,
    ParameterRow,
    decimals_for,
    diagnostics,
    fmt,
    lookup,
    parameter_names,
    parameter_rows,
)

__all__ = ["build_report", "render_report"]

MAX_NUISANCE_ROWS = 20
MAX_RESIDUAL_FIGURES = 3
RWA1_REQUIREMENT_DEG = 2.0  # Brown (2012) §I: RWA4 must sit within ±2° of the RWA1 axis
REQUIREMENT_PROB = 0.95     # a requirement is called met (or not) at this posterior probability
KIND_TITLES = {
    "inertia": "inertia tensor from reaction-wheel slews (momentum model, Feldman & Lee Eqs 2-11)",
    "thrust": "thrust and pulse time constants from wheel-biasing events "
              "(impulse model, Feldman & Lee Eqs 14-23)",
    "rwa4": "RWA4 spin axis (Brown 2012)",
}
RESIDUAL_LABELS = {
    "inertia": "momentum residual (N m s)",
    "thrust": "impulse residual (N m s)",
    "rwa4": "residual",
}


def build_report(
    run_dir: str | Path,
    *,
    out: str | Path | None = None,
    display_dir: str | Path | None = None,
) -> Path:
    """Write the self-contained diagnostic report of a run directory.

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
    from cassini_bayes.inference.idata import quiet_arviz_shape_warnings

    quiet_arviz_shape_warnings()
    run = load_run(run_dir)
    out = Path(out) if out is not None else run.run_dir / "report.html"
    return write_atomic(out, render_report(run, display_dir=display_dir))


def render_report(run: RunData, *, display_dir: str | Path | None = None) -> str:
    """The report of a loaded run as an HTML string (see :func:`build_report`)."""
    shown = Path(display_dir) if display_dir is not None else run.run_dir
    names = parameter_names(run)
    diag = diagnostics(run, names)
    rows = parameter_rows(run, names, diag)
    problems: list[str] = []  # figures that could not be drawn

    def fig(title: str, draw: Callable[[], bytes], caption: str) -> str:
        try:
            return figure(draw(), caption, alt=title)
        except Exception as e:  # a figure must never cost the whole report
            problems.append(f"{title} could not be drawn ({type(e).__name__}: {e})")
            return not_available(f"{title} could not be drawn ({type(e).__name__}: {e})")

    sections = [
        adequacy_section(run.summary),
        _diagnostics_section(diag),
        _parameters_section(run, rows),
        _trace_section(run, names, fig),
        _rank_section(run, names, fig),
        _prior_posterior_section(run, names, rows, fig),
    ]
    if run.kind in ("inertia", "thrust"):
        sections.append(_pair_section(run, fig))
    sections.append(_residuals_section(run, fig))
    from cassini_bayes.report.sensitivity import sensitivity_section
    sections += [s for s in [sensitivity_section(run.summary)] if s is not None]
    if run.kind == "rwa4":
        sections.append(_axis_section(run, fig))
    sections.append(_energy_section(run, diag, fig))
    sections.append(_config_section(run))

    header = _header(run, diag, rows, problems, shown)
    title = f"cassini-bayes {run.kind} run — {shown.name}"
    footer = (f"Built by cassini-bayes {esc(__version__)} from {esc(shown / 'posterior.nc')}."
              " Diagnostics computed with ArviZ from the full posterior; plots may show thinned"
              " draws.")
    return html_page(title, sections, header=header, footer=footer)


# --------------------------------------------------------------------------------------------
# header


def _config(run: RunData) -> dict:
    if not run.config_text:
        return {}
    try:
        return tomllib.loads(run.config_text)
    except tomllib.TOMLDecodeError:
        return {}


def _header(run: RunData, diag: Diagnostics, rows: list[ParameterRow], problems: list[str],
            shown: Path) -> str:
    cfg = _config(run)
    seed = run.summary.get("seed", cfg.get("seed", "–"))
    version = run.summary.get("version", cfg.get("version", "–"))
    conv = diag.converged
    src = "fit" if diag.converged_summary is not None else "recomputed"
    meta = [
        ("kind", f"{run.kind} — {KIND_TITLES.get(run.kind, 'unknown kind')}"),
        ("run directory", str(shown)),
        ("seed", seed),
        ("version", version),
        ("posterior", f"{diag.chains} chains × {diag.draws} draws"),
    ]
    out = [
        f'<p>{badge("CONVERGED" if conv else "NOT CONVERGED", conv)} '
        f'<span class="na">({esc(src)} verdict: max R-hat ≤ {RHAT_MAX}, min bulk ESS ≥ '
        f"{ESS_MIN:g}, no divergences)</span> {adequacy_badge(run.summary)}</p>",
        meta_list(meta),
    ]
    warns = _warnings(run, diag, rows) + problems
    if warns:
        out.append(f'<div class="warnings"><strong>Warnings</strong>{bullet_list(warns)}</div>')
    return "\n".join(out)


def _warnings(run: RunData, diag: Diagnostics, rows: list[ParameterRow]) -> list[str]:
    w = [str(x) for x in (run.summary.get("warnings") or [])]
    w += list(run.notes)
    if diag.divergences:
        w.append(f"{diag.divergences} divergent transitions: the posterior may be biased; "
                 "look at the pair plot for where they sit")
    if np.isfinite(diag.max_r_hat) and diag.max_r_hat > RHAT_MAX:
        w.append(f"max R-hat {diag.max_r_hat:.4f} > {RHAT_MAX}: chains disagree")
    if np.isfinite(diag.min_ess_bulk) and diag.min_ess_bulk < ESS_MIN:
        w.append(f"min bulk ESS {diag.min_ess_bulk:.0f} < {ESS_MIN:g}")
    if diag.bfmi is not None and np.any(diag.bfmi < BFMI_MIN):
        w.append(f"energy BFMI below {BFMI_MIN} in chain(s) "
                 f"{', '.join(str(i) for i in np.flatnonzero(diag.bfmi < BFMI_MIN))}")
    if diag.converged_summary is not None and diag.converged_summary != diag.converged_recomputed:
        w.append(f"the fit's verdict (converged = {diag.converged_summary}) differs from this "
                 f"report's check on posterior.nc (R-hat ≤ {RHAT_MAX}, bulk ESS ≥ {ESS_MIN:g}, "
                 "no divergences)")
    weak = [r.label for r in rows if r.flag]
    if weak:
        w.append("weakly identified (posterior/prior contraction < 0.5): " + ", ".join(weak))
    # keep order, drop repeats
    return list(dict.fromkeys(w))


# --------------------------------------------------------------------------------------------
# tables


def _cls_rhat(x: float) -> str:
    return "" if not np.isfinite(x) else ("bad" if x > RHAT_MAX else "good")


def _cls_ess(x: float) -> str:
    return "" if not np.isfinite(x) else ("bad" if x < ESS_MIN else "good")


def _diagnostics_section(diag: Diagnostics) -> Section:
    bfmi_txt = ("–" if diag.bfmi is None else ", ".join(f"{b:.2f}" for b in diag.bfmi))
    bfmi_ok = None if diag.bfmi is None else bool(np.all(diag.bfmi >= BFMI_MIN))
    div_txt = "not recorded" if diag.divergences is None else str(diag.divergences)
    overview = table(
        ["check", "value", "threshold", "status"],
        [
            ["max R-hat", fmt(diag.max_r_hat, 4), f"≤ {RHAT_MAX}",
             Raw(badge("ok" if _cls_rhat(diag.max_r_hat) == "good" else "check",
                       _cls_rhat(diag.max_r_hat) == "good"))],
            ["min bulk ESS", fmt(diag.min_ess_bulk, 0), f"≥ {ESS_MIN:g}",
             Raw(badge("ok" if _cls_ess(diag.min_ess_bulk) == "good" else "check",
                       _cls_ess(diag.min_ess_bulk) == "good"))],
            ["min tail ESS", fmt(diag.min_ess_tail, 0), f"≥ {ESS_MIN:g} (advisory)",
             Raw(badge("ok" if _cls_ess(diag.min_ess_tail) == "good" else "check",
                       _cls_ess(diag.min_ess_tail) == "good"))],
            ["divergences", div_txt, "0",
             Raw(badge("ok" if diag.divergences == 0 else
                       ("n/a" if diag.divergences is None else "check"),
                       None if diag.divergences is None else diag.divergences == 0))],
            ["energy BFMI (per chain)", bfmi_txt, f"≥ {BFMI_MIN}",
             Raw(badge("n/a" if bfmi_ok is None else ("ok" if bfmi_ok else "check"), bfmi_ok))],
        ],
    )
    interest = [r for r in diag.rows if r.of_interest]
    nuisance = [r for r in diag.rows if not r.of_interest]
    shown = interest + nuisance[:MAX_NUISANCE_ROWS]

    def _row(r):
        return [r.label, r.role, fmt(r.r_hat, 4),
                fmt(r.ess_bulk, 0), fmt(r.ess_tail, 0), f"{r.mcse_mean:.3g}"]

    per_var = table(
        ["variable", "role", "R-hat", "bulk ESS", "tail ESS", "MCSE(mean)"],
        [_row(r) for r in shown],
        left=2,
        classes=[["", "", _cls_rhat(r.r_hat), _cls_ess(r.ess_bulk), _cls_ess(r.ess_tail), ""]
                 for r in shown],
    )
    body = [overview, "<h3>Per variable</h3>", per_var]
    if len(nuisance) > MAX_NUISANCE_ROWS:
        rest = nuisance[MAX_NUISANCE_ROWS:]
        body.append(paragraph(
            f"{len(rest)} more components not listed (worst R-hat among them "
            f"{max(r.r_hat for r in rest):.4f}, min bulk ESS {min(r.ess_bulk for r in rest):.0f}).",
            note=True))
    body.append(paragraph(
        "Rank-normalised split R-hat and bulk/tail effective sample sizes (Vehtari et al. 2021) "
        "and E-BFMI (Betancourt 2016), all computed with ArviZ from posterior.nc. The extremes "
        "above, like the fit's verdict, cover the parameters and the nuisance in summary.json; "
        "a sampler coordinate (the whitened variables the sampler moves) is listed but not "
        "judged: each parameter is a function of them. Tail ESS is advisory: it is not part of "
        "the verdict.", note=True))
    return section("Diagnostics", body, id="diagnostics")


def _parameters_section(run: RunData, rows: list[ParameterRow]) -> Section:
    if not rows:
        return section("Parameters", not_available("no calibration parameters in the posterior"),
                       id="parameters")
    has_truth = any(r.truth is not None for r in rows)
    headers = ["parameter", "unit", "mean", "sd", "5 %", "95 %", "least squares"]
    if has_truth:
        headers += ["truth", "in 90 %"]
    headers += ["prior sd", "contraction", "identification"]
    body_rows, classes = [], []
    for r in rows:
        d = decimals_for(r.sd)
        cells = [r.label, r.unit, fmt(r.mean, d), fmt(r.sd, d + 1), fmt(r.q05, d), fmt(r.q95, d),
                 fmt(r.baseline, d)]
        cls = ["", "", "", "", "", "", ""]
        if has_truth:
            inside = (None if r.truth is None or r.q05 is None or r.q95 is None
                      else r.q05 <= r.truth <= r.q95)
            cells += [fmt(r.truth, d), "–" if inside is None else ("yes" if inside else "no")]
            cls += ["", "" if inside is None else ("good" if inside else "warn")]
        prior_sd = ("n/a" if r.prior_sd is None
                    else fmt(r.prior_sd, decimals_for(r.prior_sd)))  # 2 significant digits
        cells += [prior_sd,
                  fmt(r.contraction, 3), r.flag or "identified"]
        cls += ["", "warn" if r.flag else "", "warn" if r.flag else "good"]
        if r.contraction is None:
            cells[-1] = "unknown (no prior)"
            cls[-1] = ""
        body_rows.append(cells)
        classes.append(cls)
    body = [
        table(headers, body_rows, left=2, classes=classes),
        paragraph(
            "90 % interval = 5 % and 95 % posterior quantiles. Least squares = the papers' "
            "estimator on the same data (summary.json baseline). Contraction = 1 − Var(post) / "
            "Var(prior) (Betancourt 2018); below 0.5 the parameter is weakly identified (the data "
            "shrink its sd by less than 30 %), below 0.1 the posterior is essentially the prior.",
            note=True),
    ]
    if run.kind == "rwa4":
        body.append(_direction_table(run))
    return section("Parameters", body, id="parameters")


def _angle_deg(a, b) -> float:
    a = np.asarray(a, float) / np.linalg.norm(a)
    b = np.asarray(b, float) / np.linalg.norm(b)
    return float(np.degrees(np.arccos(np.clip(a @ b, -1.0, 1.0))))


def _axis_draws(run: RunData) -> np.ndarray | None:
    post = run.idata.posterior
    if not all(n in post.data_vars for n in U4_NAMES):
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


# --------------------------------------------------------------------------------------------
# figures


def _trace_section(run: RunData, names, fig) -> Section:
    body = fig("trace plot", lambda: figures.trace_png(run.idata, names),
               "Left: marginal posterior per chain; right: draws against iteration (thinned to at "
               "most 500 per chain). Chains should overlap and look like stationary noise.")
    return section("Trace plots", body, id="trace")


def _rank_section(run: RunData, names, fig) -> Section:
    body = fig("rank plot", lambda: figures.rank_png(run.idata, names),
               "Rank histograms per chain (Vehtari et al. 2021): all near-uniform when the chains "
               "mix; a chain sitting high or low did not explore the same distribution.")
    return section("Rank plots", body, id="rank")


def _prior_posterior_section(run: RunData, names, rows: list[ParameterRow], fig) -> Section:
    post = flatten_draws(run.idata.posterior, names)
    prior = flatten_draws(run.idata.prior, names) if run.has_group("prior") else {}
    by = {r.label: r for r in rows}
    body = []
    if not prior:
        body.append(not_available("prior draws (posterior.nc has no prior group); the posterior "
                                  "is shown alone"))
    body.append(fig(
        "prior vs posterior",
        lambda: figures.prior_posterior_png(
            post, prior,
            baseline={k: by[k].baseline for k in post if k in by},
            truth={k: by[k].truth for k in post if k in by},
            contraction={k: by[k].contraction for k in post if k in by},
            units={k: by[k].unit for k in post if k in by},
        ),
        "Prior (grey) and posterior (blue) densities, each scaled to a peak of 1; least-squares "
        "estimate dashed, truth red when known. A narrow posterior inside a wide prior means the "
        "data identify the parameter; overlapping curves mean the prior decides it."))
    return section("Prior vs posterior", body, id="prior-posterior")


def _pair_names(run: RunData) -> list[str]:
    post = run.idata.posterior
    if run.kind == "inertia":
        return [n for n in INERTIA_NAMES if n in post.data_vars]
    fs = [n for n in F_NAMES if n in post.data_vars]
    return fs + [n for n in TAU_NAMES if n in post.data_vars]


def _pair_section(run: RunData, fig) -> Section:
    names = _pair_names(run)
    what = "the six inertia entries" if run.kind == "inertia" else "thrust and time constants"
    if len(names) < 2:
        body = not_available(f"pair plot of {what} (fewer than two of them in the posterior)")
    else:
        body = fig(f"pair plot of {what}", lambda: figures.pair_png(run.idata, names),
                   f"Joint posterior of {what} (at most 1000 draws shown); divergent transitions, "
                   "if any, are marked. Strong correlations show which combinations the data "
                   "determine and which they trade off.")
    return section("Pair plot", body, id="pair")


def _residuals_section(run: RunData, fig) -> Section:
    if not run.has_group("residuals"):
        return section("Residuals",
                       not_available("model residuals (posterior.nc has no residuals group)"),
                       id="residuals")
    ds = run.idata.residuals
    # the posterior-mean residual first, then any companions (e.g. the whitened residual)
    names = sorted(ds.data_vars, key=lambda v: (v != "residual", str(v)))[:MAX_RESIDUAL_FIGURES]
    model = {"inertia": "momentum model (Feldman & Lee Eq 11)",
             "thrust": "impulse model (Feldman & Lee Eq 17)"}.get(run.kind, "model")
    body = []
    for var in names:
        attrs = ds[var].attrs
        desc = str(attrs.get("description") or attrs.get("long_name") or "")
        units = str(attrs.get("units", ""))
        if var == "residual":
            label = RESIDUAL_LABELS.get(run.kind, "residual")
            if units and "(" not in label:
                label = f"{label} ({units})"
        else:
            label = f"{var} ({'dimensionless' if units == '1' else units})" if units else str(var)
        frame = f", {attrs['frame']} axes" if attrs.get("frame") else ""
        what = desc or ("posterior-mean residual" if var == "residual" else str(var))
        body.append(fig(
            f"residuals: {var}",
            lambda var=var, label=label: figures.residuals_png(ds, var=str(var), ylabel=label),
            f"{what[:1].upper()}{what[1:]} of the {model} against time{frame}. Structure "
            "(drifts, steps at slew or pulse times) points at an unmodelled effect; white noise "
            "at the telemetry noise level (or of unit variance, when whitened) is what a good fit "
            "leaves."))
    return section("Residuals", body, id="residuals")


def _axis_section(run: RunData, fig) -> Section:
    draws = _axis_draws(run)
    mean, cones = _direction(run)
    if draws is None or mean is None:
        return section("Spin axis", not_available("u4_x, u4_y, u4_z draws in the posterior"),
                       id="axis")
    truth = _axis_vec(run.summary.get("truth"))
    base = _axis_vec(run.summary.get("baseline"))
    body = fig("spin-axis sky plot",
               lambda: figures.axis_sky_png(draws, mean=mean, cones_deg=cones, truth=truth,
                                            baseline=base),
               "RWA4 spin-axis posterior. Left: body azimuth/elevation of the draws, the "
               "articulation cone and the RWA1 target axis. Right: azimuthal-equidistant view "
               "about the posterior mean, so the dotted circles are true 1°, 2° and 3° cones (the "
               "papers' "
               "±1° RWA-method and ±3° RCS-method budgets) and the solid ones the posterior "
               "50/90/95 % cones.")
    return section("Spin axis", body, id="axis")


def _energy_section(run: RunData, diag: Diagnostics, fig) -> Section:
    if diag.bfmi is None:
        return section("Energy", not_available("energy plot (sample_stats has no energy)"),
                       id="energy")
    body = fig("energy plot", lambda: figures.energy_png(run.idata),
               "Marginal energy against energy transitions of the Hamiltonian sampler (Betancourt "
               "2016). When the transition distribution is much narrower than the marginal one "
               "(E-BFMI < 0.3) the sampler explores the tails poorly.")
    return section("Energy", body, id="energy")


def _config_section(run: RunData) -> Section:
    if run.config_text is None:
        return section("Configuration", not_available("config.toml"), id="configuration")
    return section("Configuration",
                   details("config.toml (resolved inputs, seed and version)",
                           preformatted(run.config_text)),
                   id="configuration")
