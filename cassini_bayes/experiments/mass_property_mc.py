"""Experiment kind ``mass_property_mc``: Brown (2012) §III.B, the two Monte Carlo analyses."""

from __future__ import annotations

import jax
import numpy as np

from cassini_bayes.analysis.mass_property import (
    RWA1_PHI_RAD,
    flight_estimate_box,
    mass_property_mc,
    mass_property_mc_posterior,
    plot_mass_property,
    requirement_box,
    summarise_errors,
)
from cassini_bayes.analysis.paper_facts import TABLE1, TABLE1_PARAMS, fact
from cassini_bayes.experiments import (
    Check,
    ExperimentOutput,
    FigureOut,
    Table,
    check_fact,
    png,
    register,
)
from cassini_bayes.experiments._posteriors import find_posterior
from cassini_bayes.spacecraft import load_spacecraft

_EPOCHS = (*TABLE1, "march_2000")


@register(
    "mass_property_mc",
    defaults={"spacecraft": "cassini_post_probe", "n_draws": 100_000, "distribution": "uniform",
              "axis": "cone", "phi_range_deg": [-30.0, 210.0],
              "flight_epochs": ["pre_soi", "post_prm", "post_probe"], "scale_points": 10,
              "inertia_posterior": "auto"},
    quick={"n_draws": 2000, "scale_points": 3},
    choices={"distribution": ("uniform", "normal"), "axis": ("cone", "rwa1")},
    order=45,  # after inertia_table1, whose Post-PROBE posterior analysis 3 reads
    description="Extra RWA4 axis error from mass-property uncertainty (Brown §III.B Monte Carlo)",
)
def mass_property(key, settings, ctx) -> ExperimentOutput:
    """Brown's two Monte Carlo analyses of the RCS method's extra axis error when Î ≠ I.

    Settings: ``spacecraft`` (true inertia and its knowledge requirements), ``n_draws``,
    ``distribution`` (``uniform`` within the bounds or ``normal`` with bounds = ±3σ), ``axis``
    (``cone``: true axis drawn on the articulation cone over ``phi_range_deg``; ``rwa1``: at RWA1),
    ``flight_epochs`` (Table 1 columns, or ``march_2000``, spanning analysis 2's range),
    ``scale_points`` (points of the 99th-percentile-vs-box-size curve), ``inertia_posterior``
    (run directory of an inertia fit for analysis 3, the Monte Carlo fed from its posterior;
    ``"auto"``: the Post-PROBE fit of ``inertia_table1`` in the same ``reproduce`` run; ``""``:
    none).
    """
    _check_settings(settings, ctx)
    phi_deg = settings["phi_range_deg"]
    sc = load_spacecraft(settings["spacecraft"])
    n, dist = settings["n_draws"], settings["distribution"]
    phi_range = (np.radians(phi_deg) if settings["axis"] == "cone"
                 else (RWA1_PHI_RAD, RWA1_PHI_RAD))
    boxes = {
        "1: pre-launch requirements": requirement_box(sc.moi_uncertainty, sc.poi_uncertainty),
        "2: range of flight estimates": flight_estimate_box(tuple(settings["flight_epochs"])),
    }
    key_1, key_2, key_s = jax.random.split(key, 3)
    draws = {label: mass_property_mc(k, sc.inertia, box, n, phi_range_rad=phi_range,
                                     distribution=dist)
             for (label, box), k in zip(boxes.items(), (key_1, key_2))}
    posterior = find_posterior(settings["inertia_posterior"], "inertia", "inertia_posterior", ctx)
    if posterior is not None:
        draws[_LABEL_3] = _posterior_draws(jax.random.fold_in(key, 3), posterior, n, phi_range)
    ctx.progress(0.5, "Monte Carlo draws done")
    stats = {label: summarise_errors(d.error_rad) for label, d in draws.items()}
    budget = fact("rwa4_mass_property_deg")
    scales, p99_scaled, scale_at_budget = _requirement_scale(
        key_s, sc, boxes["1: pre-launch requirements"], settings, phi_range, budget.value)
    # Which elements matter: each element perturbed alone (same key: common random numbers).
    p99_alone = {label: [summarise_errors(mass_property_mc(key_s, sc.inertia, box.only(i), n,
                                                           phi_range_rad=phi_range,
                                                           distribution=dist).error_rad).p99_deg
                         for i in range(6)]
                 for label, box in boxes.items()}
    ctx.progress(0.9, "element-by-element sensitivity done")
    checks = _checks(stats, draws, sc, n, dist, scale_at_budget, posterior)
    fig = plot_mass_property({f"analysis {k}": d for k, d in draws.items()}, budget.value)
    figures = (FigureOut("mass_property_mc", png(fig),
                         "Distribution of the extra RWA4 axis error of the RCS method (Brown Eq 1) "
                         "when the assumed inertia differs from the true one; dashed: the paper's "
                         "1.5°. Right: 99th percentile along the articulation cone."),)
    summary = _summary(settings, sc, boxes, stats, p99_alone, scales, p99_scaled,
                       scale_at_budget, posterior)
    return ExperimentOutput(
        summary=summary, checks=tuple(checks), figures=figures,
        tables=_tables(stats, boxes, p99_alone, scales, p99_scaled, sc, settings),
        notes=_notes(settings, sc, stats, budget.value, scale_at_budget, posterior))


_LABEL_3 = "3: inertia posterior"


def _check_settings(settings, ctx) -> None:
    """Raise ``ctx.error`` naming the first setting out of its range."""
    if settings["n_draws"] < 100:
        raise ctx.error("'settings.n_draws' must be at least 100")
    for e in settings["flight_epochs"]:
        if e not in _EPOCHS:
            raise ctx.error(f"'settings.flight_epochs' has unknown epoch {e!r}; known: "
                            f"{', '.join(_EPOCHS)}")
    phi_deg = settings["phi_range_deg"]
    if len(phi_deg) != 2 or phi_deg[0] > phi_deg[1]:
        raise ctx.error("'settings.phi_range_deg' must be [low, high] degrees with low <= high")
    if settings["scale_points"] < 2:
        raise ctx.error("'settings.scale_points' must be at least 2")


def _posterior_draws(key, posterior, n: int, phi_range):
    """Analysis 3: the extra axis error with the truth each (resampled) draw of the inertia
    ``posterior`` and the calibration assuming its mean."""
    from cassini_bayes.analysis.budget_lines import inertia_of
    from cassini_bayes.names import INERTIA_NAMES

    entries = np.stack([posterior.draws[k] for k in INERTIA_NAMES], -1)
    return mass_property_mc_posterior(key, inertia_of(entries), inertia_of(entries.mean(0)), n,
                                      phi_range_rad=phi_range)


def _requirement_scale(key_s, sc, req, settings, phi_range, budget_deg):
    """How large may a symmetric requirement box be for the 99th percentile to stay within the
    budget: the 99th percentile of the requirement box ``req`` scaled by 0.1 … 1 (same key),
    and the scale where it crosses ``budget_deg`` (NaN when it does not)."""
    n, dist = settings["n_draws"], settings["distribution"]
    scales = np.linspace(0.1, 1.0, settings["scale_points"])
    p99_scaled = np.array([
        summarise_errors(mass_property_mc(key_s, sc.inertia, req.scaled(s), n,
                                          phi_range_rad=phi_range, distribution=dist)
                         .error_rad).p99_deg for s in scales])
    inside = p99_scaled <= budget_deg
    scale_at_budget = (float(np.interp(budget_deg, p99_scaled, scales))
                       if inside.any() and not inside.all() else float("nan"))
    return scales, p99_scaled, scale_at_budget


def _checks(stats, draws, sc, n, dist, scale_at_budget, posterior) -> list[Check]:
    """Each analysis's 99th percentile against the paper's 1.5°, alone and with the testbed's
    worst error (linear, as the paper, and RSS); the box size at the budget; analysis 3."""
    budget = fact("rwa4_mass_property_deg")
    label_3 = _LABEL_3
    testbed_worst = fact("rwa4_rcs_worst_deg").value
    checks: list[Check] = []
    for label, s in stats.items():
        checks.append(check_fact("rwa4_mass_property_deg", s.p99_deg,
                                 label=f"analysis {label}: 99th percentile of the extra error",
                                 note=f"{n} draws, {dist}"))
        checks.append(check_fact("rwa4_rcs_total_deg", testbed_worst + s.p99_deg,
                                 label=f"analysis {label}: {testbed_worst:g}° testbed worst + "
                                       f"99th percentile",
                                 note="linear sum, as the paper"))
        checks.append(Check(f"analysis {label}: {testbed_worst:g}° ⊕ 99th percentile (RSS)",
                            float(np.hypot(testbed_worst, s.p99_deg)), "deg", decimals=2,
                            paper=fact("rwa4_rcs_total_deg").printed,
                            note="root-sum-square, for independent errors (the paper adds "
                                 "linearly); no verdict of its own"))
    if np.isfinite(scale_at_budget):
        checks.append(Check("moment uncertainty for which analysis 1's 99th percentile is 1.5°",
                            100 * scale_at_budget * sc.moi_uncertainty, "%", decimals=1,
                            note=f"products ±{scale_at_budget * sc.poi_uncertainty:.0f} kg m²; "
                                 "box scaled about zero"))

    if posterior is not None:
        checks.append(Check(f"analysis {label_3}: median [5 %, 95 %] of the extra error",
                            float(np.median(np.degrees(draws[label_3].error_rad))), "deg",
                            decimals=5, fact_id="rwa4_mass_property_deg",
                            paper=fact("rwa4_mass_property_deg").printed,
                            passed=bool(stats[label_3].p99_deg <= budget.value),
                            note="90 % interval [" + ", ".join(
                                f"{v:.3g}" for v in np.percentile(
                                    np.degrees(draws[label_3].error_rad), [5, 95]))
                                 + f"] deg; inertia posterior {posterior.source}"))
    return checks


def _tables(stats, boxes, p99_alone, scales, p99_scaled, sc, settings) -> tuple:
    """The error percentiles, the one-element sensitivities, the boxes and the scale curve."""
    n, dist, phi_deg = settings["n_draws"], settings["distribution"], settings["phi_range_deg"]
    pct = Table(
        "Extra axis error (deg)",
        ("analysis", "mean", "50 %", "95 %", "99 %", "max"),
        tuple((label, *(f"{v:.3f}" for v in (s.mean_deg, s.p50_deg, s.p95_deg, s.p99_deg,
                                              s.max_deg)))
              for label, s in stats.items()),
        note=f"{n} draws each; true inertia {sc.name}; true axis "
             + (f"uniform on the 54.7356° articulation cone, articulation {phi_deg[0]:g}° to "
                f"{phi_deg[1]:g}° (RWA1 at 90°)" if settings["axis"] == "cone" else "RWA1"))
    box_rows = []
    for label, box in boxes.items():
        for i, name in enumerate(TABLE1_PARAMS):
            lo, hi = ((box.moi_low[i] * 100, box.moi_high[i] * 100) if i < 3
                      else (box.poi_low[i - 3], box.poi_high[i - 3]))
            box_rows.append((label, name, f"{lo:+.2f}", f"{hi:+.2f}", "%" if i < 3 else "kg m²"))
    box_table = Table("Perturbation intervals of the assumed inertia Î − I",
                      ("analysis", "element", "low", "high", "unit"), tuple(box_rows),
                      note="Moments as a fraction of the true moment (Feldman & Lee Eq 12), "
                           "products in kg m² (Eq 13); each element drawn independently, "
                           + ("uniformly over its interval." if dist == "uniform"
                              else "normal with the interval as ±3σ."))
    scale_table = Table(
        "99th percentile against the size of the requirement box",
        ("scale", "moments ±%", "products ± kg m²", "99 % (deg)"),
        tuple((f"{s:.2f}", f"{100 * s * sc.moi_uncertainty:.1f}",
               f"{s * sc.poi_uncertainty:.0f}", f"{p:.3f}") for s, p in zip(scales, p99_scaled)))

    alone_table = Table(
        "99th percentile with one element perturbed at a time (deg)",
        ("analysis", *TABLE1_PARAMS),
        tuple((label, *(f"{v:.3f}" for v in vals)) for label, vals in p99_alone.items()),
        note="Each element drawn over its interval with the others at the truth (same key for "
             "all). Largest: " + "; ".join(
                 f"analysis {label.split(':')[0]}: {TABLE1_PARAMS[int(np.argmax(vals))]}"
                 for label, vals in p99_alone.items()) + ".")
    return pct, alone_table, box_table, scale_table


def _notes(settings, sc, stats, budget_deg, scale_at_budget, posterior) -> tuple:
    """What the Monte Carlo solves, which boxes it draws from, and the reading of its numbers."""
    return (
        "Over a short drift Brown's Eq 1 is momentum conservation in body axes, I Δω = −J Δρ u; "
        "solving it with the assumed inertia Î gives û ∝ Î I⁻¹ u, so the extra error is the angle "
        "between Î I⁻¹ u and u. It does not depend on the wheel momentum step or on noise.",
        "Analysis 1 varies Î within the pre-launch knowledge requirements (moments "
        f"±{100 * sc.moi_uncertainty:g} %, products ±{sc.poi_uncertainty:g} kg m²), the stated "
        "uncertainties available to us; Brown used the January 1997 mass-properties report, whose "
        "element uncertainties are not printed. Analysis 2 varies Î over the observed "
        "prediction − flight-estimate differences (Feldman & Lee Table 1"
        + (", March 2000 Eq 1 vs Eq 8" if "march_2000" in settings["flight_epochs"] else "")
        + ")."
        + (f" Analysis 3 replaces the box by the inertia posterior of {posterior.source}: the "
           "calibration assumes the posterior mean, the truth is each posterior draw (resampled), "
           "so its spread is what the calibrated inertia leaves of the mass-property error."
           if posterior is not None else " Analysis 3 (the Monte Carlo fed from an inertia "
           "posterior) needs settings.inertia_posterior or an inertia_table1 run before it in "
           "the same reproduce run: not run."),
        _reading(stats, budget_deg, scale_at_budget, sc.moi_uncertainty, sc.poi_uncertainty),
    )


def _summary(settings, sc, boxes, stats, p99_alone, scales, p99_scaled, scale_at_budget,
             posterior) -> dict:
    """``summary.json``'s numbers: every analysis's box and error percentiles, the combined
    errors, the one-element sensitivities and the requirement-scale curve."""
    n, dist, phi_deg = settings["n_draws"], settings["distribution"], settings["phi_range_deg"]
    label_3 = _LABEL_3
    testbed_worst = fact("rwa4_rcs_worst_deg").value
    return {
        "n_draws": n, "distribution": dist, "axis": settings["axis"],
        "phi_range_deg": list(phi_deg) if settings["axis"] == "cone" else [90.0, 90.0],
        "spacecraft": sc.name,
        "analyses": {label: {"box": boxes[label].to_dict(), "error_deg": stats[label].to_dict()}
                     for label in boxes}
        | ({label_3: {"inertia_posterior": posterior.source,
                      "error_deg": stats[label_3].to_dict()}} if posterior is not None else {}),
        "testbed_worst_deg": testbed_worst,
        "combined_linear_deg": {k: testbed_worst + s.p99_deg for k, s in stats.items()},
        "combined_rss_deg": {k: float(np.hypot(testbed_worst, s.p99_deg))
                             for k, s in stats.items()},
        "p99_one_element_deg": {label: dict(zip(TABLE1_PARAMS, vals))
                                for label, vals in p99_alone.items()},
        "requirement_scale": {"scale": scales.tolist(), "p99_deg": p99_scaled.tolist(),
                              "scale_at_budget": scale_at_budget},
    }


def _reading(stats, budget_deg, scale_at_budget, moi, poi) -> str:
    """One paragraph saying which analyses meet the paper's bound, from the numbers."""
    parts = []
    for label, st in stats.items():
        verdict = "within" if st.p99_deg <= budget_deg else "outside"
        parts.append(f"analysis {label}: 99th percentile {st.p99_deg:.2f}° ({verdict} the paper's "
                     f"{budget_deg:g}°)")
    text = "Reading: " + "; ".join(parts) + "."
    if np.isfinite(scale_at_budget):
        text += (f" A symmetric box meets {budget_deg:g}° only up to about "
                 f"±{100 * scale_at_budget * moi:.1f} % on the moments and "
                 f"±{scale_at_budget * poi:.0f} kg m² on the products, so Brown's bound implies "
                 "element uncertainties that much tighter than the ±10 % / ±75 kg m² requirement.")
    return text
