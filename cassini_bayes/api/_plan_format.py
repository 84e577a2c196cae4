"""How a planning prediction is recorded and printed: the ``summary.json`` blocks and the tables
of the inertia, wheel-axis and thrust predictions."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from cassini_bayes.names import INERTIA_NAMES

__all__ = ["usage_fields", "usage_lines", "prediction_block", "format_table", "axis_block",
           "format_axis_table", "thrust_block", "format_thrust_table", "window_options"]


def usage_fields(usage: Mapping[str, float], tol: float = 0.0) -> dict[str, Any]:
    """The limits a manoeuvre uses, as summary.json holds them: ``usage`` (largest fraction of
    each limit on the simulated telemetry) and ``limits_ok`` (each at most ``1 + tol``); empty
    without limits."""
    if not usage:
        return {}
    return {"usage": dict(usage), "limits_ok": bool(all(v <= 1.0 + tol for v in usage.values()))}


def usage_lines(usage: Mapping[str, float]) -> list[str]:
    """The printed line of the limits a manoeuvre uses (none without limits)."""
    if not usage:
        return []
    return ["limits used (largest fraction on the simulated telemetry): " + ", ".join(
        f"{k} {v:.2f}" for k, v in usage.items())]


def prediction_block(p: Any, names: Sequence[str] = INERTIA_NAMES) -> dict:
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
    out.update(usage_fields(p.usage))
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
    lines += usage_lines(p.usage)
    return "\n".join(lines)


def axis_block(p: Any) -> dict:
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
    out.update(usage_fields(p.usage))
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
    lines += usage_lines(p.usage)
    return "\n".join(lines)


def thrust_block(p: Any) -> dict:
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
           "duration_s": p.duration_s, "truths": p.truths}
    if p.site_sd_mode is not None:
        for n, sd in zip(p.sites, p.site_sd_mode):
            out["sites"][n]["sd_at_mode"] = float(sd)
    out["non_gaussian"] = list(p.non_gaussian)
    if p.truths:
        (lo, hi), (m_lo, m_hi) = p.site_sd_range, p.site_sd_interval
        for i, n in enumerate(p.sites):
            out["sites"][n].update(sd_nominal=float(p.site_sd_nominal[i]),
                                   sd_range=[float(lo[i]), float(hi[i])],
                                   sd_median_interval90=[float(m_lo[i]), float(m_hi[i])])
    out.update(usage_fields(p.usage, tol=1e-9))
    return out


def format_thrust_table(p: Any, title: str) -> str:
    """The predicted sd of each thrust site beside its budget and prior sd, as printed."""
    lines = [title, f"{p.n_pulses} pulses of widths "
             + ", ".join(f"{w:g}" for w in p.pulse_widths_s) + " s; fit mode " + p.mode]
    if p.truths:
        lines.append(f"predicted sd: the median over the nominal truth and {p.truths} drawn from "
                     "the model file's knowledge (each flown by its own controller)")
    span = p.site_sd_interval if p.truths else None
    span = span if span is not None and np.isfinite(span[0]).all() else None
    lines.append(f"{'':10s} {'predicted sd':>13s} {'sd/budget':>10s} {'budget':>10s} "
                 f"{'prior sd':>10s} {'sd/prior':>9s}"
                 + (f" {'median, 90 % interval':>23s}" if span else "") + "   (N, s, m, kg m^2)")
    for i, (n, sd, pr, b) in enumerate(zip(p.sites, p.site_sd, p.site_prior_sd, p.budget)):
        r = f"{sd / b:10.3f}" if np.isfinite(b) else f"{'-':>10s}"
        bs = f"{b:10.4g}" if np.isfinite(b) else f"{'-':>10s}"
        interval = f" {f'{span[0][i]:.4g}–{span[1][i]:.4g}':>23s}" if span else ""
        lines.append(f"{n:10s} {sd:13.4g} {r} {bs} {pr:10.4g} {sd / pr:9.3f}{interval}")
    for k, (sd, pr, b) in p.combinations.items():
        lines.append(f"{k:10s} {sd:13.4g} {sd / b:10.3f} {b:10.4g} {pr:10.4g} {sd / pr:9.3f}")
    if p.floored:
        lines.append(f"{p.floored} direction(s) of the fit's coordinates have no curvature at "
                     "the truth (left at a prior that is not log-concave there): given the "
                     "prior's order of sd, the Laplace prediction is rough for them")
    if p.non_gaussian:
        ratio = dict(zip(p.sites, p.sd_mode_ratio))
        ridge = bool(set(p.non_gaussian) & set(p.ridge_sites))
        lines.append("not Gaussian on this event: sd at the noise-free posterior's mode over sd "
                     "at the truth " + ", ".join(f"{n} {ratio[n]:.2f}" for n in p.non_gaussian)
                     + ("; these sites share the ridge of thrust and pulse shape, where each "
                        "flight's noise moves the fit: their predicted sd is indicative (more "
                        "pulse widths break the ridge)" if ridge else
                        ": their predicted sd is indicative"))
    lines.append(f"largest sd/budget {p.max_ratio:.3f} ({p.worst}); budgets: thrust "
                 "+-10 % (Feldman & Lee), time constants half the model file's manufacturer "
                 "range")
    lines += usage_lines(p.usage)
    return "\n".join(lines)


def window_options(pairs: Sequence[Any]) -> str:
    """The windows as ``fit wheel-axis`` options (``--window-a T0:T1 --window-b T0:T1`` …)."""
    return " ".join(f"--window-a {a[0]:.10g}:{a[1]:.10g} --window-b {b[0]:.10g}:{b[1]:.10g}"
                    for a, b in pairs)
