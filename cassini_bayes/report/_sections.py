"""The sections below the answer in a fit's report: per-pulse impulses, residuals, the sampler
diagnostics and the configuration.
"""

from __future__ import annotations

import numpy as np

from cassini_bayes.diagnostics import ESS_BULK_MIN, R_HAT_MAX
from cassini_bayes.report import figures
from cassini_bayes.report.html import (
    Raw,
    Section,
    badge,
    details,
    not_available,
    paragraph,
    preformatted,
    section,
    table,
)
from cassini_bayes.report.rundata import RunData, flatten_draws
from cassini_bayes.report.tables import (
    BFMI_MIN,
    DiagnosticTable,
    ParameterRow,
    decimals_for,
    fmt,
)

MAX_RESIDUAL_FIGURES = 1
RESIDUAL_LABELS = {
    "inertia": "residual (N m s)",
    "thrust": "residual (N m s)",
    "rwa4": "residual",
}


def pulses_section(run: RunData, fig) -> Section:
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


def thrust_design_section(summary: dict) -> Section | None:
    """What the events tell about each thruster (``summary["thrust_design"]`` of ``fit thrust
    --mode thruster``): the impulse design's rank and singular values, the thrusters identified
    one by one, the identified combinations of the others with their posterior, and whether
    the centre of mass is told, and where every thruster fires at one width the impulse bits
    they identify (docs/thrust_any_layout.md). ``None`` for the other modes."""
    d = summary.get("thrust_design")
    if not d:
        return None
    sv = ", ".join(f"{x:.3g}" for x in d["singular_values"])
    body = [paragraph(
        f"Impulse design (Feldman & Lee Eq 17 linearised at the prior's centre, prior- and "
        f"noise-whitened): rank {d['rank']} of {d['parameters']} (singular values ≥ 1: the data "
        f"know the direction at least as well as the prior; {sv}); {d['thrust_rank']} of "
        f"{len(d['thrusters'])} thrust directions identified. Identified one by one: "
        f"{', '.join(d['identified']) or 'none'}."
        + (f" Never fired: {', '.join(d['not_fired'])}." if d["not_fired"] else ""))]
    if d["combinations"]:
        rows = []
        for c in d["combinations"]:
            p = c.get("posterior") or {}
            rows.append([c["label"], fmt(p.get("mean"), 4), fmt(p.get("sd"), 4),
                         fmt(p.get("q05"), 4), fmt(p.get("q95"), 4)])
        body.append(paragraph("The other thrusters are told only in these combinations "
                              "(weights of the thrusts, N per N):"))
        body.append(table(["combination", "mean N", "sd N", "5 %", "95 %"], rows))
    bits = d.get("impulse_bits")
    if bits:
        rows = []
        for n, w in bits["width_s"].items():
            p = bits["posterior"].get(n) or {}
            rows.append([n, f"{1e3 * w:g}", fmt(p.get("mean"), 4), fmt(p.get("sd"), 4),
                         fmt(p.get("q05"), 4), fmt(p.get("q95"), 4)])
        body.append(paragraph(
            "Every thruster fires at one pulse width: the events identify each one's impulse "
            "bit F j(width; τ) (Feldman & Lee §V), and the thrusts F only as well as the pulse "
            "shape (the time constants). The identified quantity:"))
        body.append(table(["thruster", "width ms", "bit mean N s", "sd N s", "5 %", "95 %"],
                          rows))
    told = d.get("com_told") or {}
    quiet = [n for n, ok in told.items() if not ok]
    body.append(paragraph(
        "Centre of mass (com_x, com_y, com_z: true minus the model file's): "
        + ("told by the events on every axis." if not quiet else
           f"{', '.join(quiet)} not told by the events (no net-force firings along them): "
           "prior-dominated.")))
    return section("What the events tell about each thruster", body, id="thrust-design")


def residuals_section(run: RunData, fig) -> Section:
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


def diagnostics_section(run: RunData, names, diag: DiagnosticTable, rows: list[ParameterRow],
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


def config_section(run: RunData) -> Section:
    if run.config_text is None:
        return section("Configuration", not_available("config.toml"), id="configuration")
    return section("Configuration",
                   details("config.toml (resolved inputs, seed and version)",
                           preformatted(run.config_text)),
                   id="configuration")
