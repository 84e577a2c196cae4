"""The thruster-leak report (``report.html`` of ``monitor leak``): the answer first — is a
thruster leaking, which, since when, how much — beside Lee's threshold monitor (a "–" column
where the thrusters are not Cassini's Eq 16 layout, to which it applies) and his requirement,
then each hypothesis's probability against time, the adequacy verdict and the
inputs.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

__all__ = ["leak_figure", "leak_report_html", "ISOLATE_BEFORE_NMS", "LEAK_NOTE"]

ISOLATE_BEFORE_NMS = 100.0  # Lee §3.2: isolate a leak before 100 N m s build up on any axis
LEAK_NOTE = ("Self-checks of the Bayesian monitor's model on this stretch, under the hypothesis "
             "most probable at the last check: residual_fit, the residual momentum left by the "
             "offset, torque, thrust errors (and the leak) against the noise level the monitor "
             "assumed; prior_data_conflict, the torque and the thrust errors in their prior sd; "
             "residual_autocorrelation, a slow wander the white model does not hold. "
             "Thresholds and the false-alarm rates measured on clean stretches: docs/leak.md.")


def leak_figure(post, lee, hypotheses) -> Figure:
    """Posterior probability of each hypothesis (``none`` and one leaking thruster each) at
    every check, the alarm level, and the detection times of both monitors (``lee`` ``None``:
    the Bayesian monitor's alone)."""
    from cassini_bayes.report.figures import CHAIN_COLORS, tidy_ticks

    fig = Figure(figsize=(11.0, 3.6))
    ax = fig.subplots()
    span = float(np.ptp(post.t_check)) if len(post.t_check) else 0.0
    scale, unit = (3600.0, "h") if span > 3 * 3600.0 else (60.0, "min")
    t_h = np.asarray(post.t_check, float) / scale
    prob = np.asarray(post.prob, float)
    for j, name in enumerate(hypotheses):
        if name == "none":
            ax.plot(t_h, prob[:, j], color="#555555", linestyle="--", linewidth=1.2,
                    label="no leak")
        elif prob[:, j].max() >= 0.01:
            ax.plot(t_h, prob[:, j], color=CHAIN_COLORS[j % len(CHAIN_COLORS)], linewidth=1.4,
                    label=f"{name} leaks")
    ax.axhline(post.p_detect, color="firebrick", linewidth=0.8, linestyle=":",
               label=f"alarm level {post.p_detect:g}")
    for t, name, style in ((post.detection_time_s, "Bayesian detection", "-"),
                           (None if lee is None else lee.detection_time_s,
                            "Lee's threshold detection", "-.")):
        if t is not None:
            ax.axvline(t / scale, color="#222222", linestyle=style, linewidth=0.9, label=name)
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel(f"time since the stretch's first sample ({unit})", fontsize=8)
    ax.set_ylabel("posterior probability (dimensionless)", fontsize=8)
    ax.legend(fontsize=7, loc="center right")
    ax.grid(alpha=0.3)
    tidy_ticks(ax, x=8, y=5)
    fig.subplots_adjust(left=0.07, right=0.98, bottom=0.14, top=0.95)
    return fig


def _pm(mean: float, sd: float) -> str:
    """``mean ± sd`` with two significant digits of the sd."""
    from cassini_bayes.report.tables import decimals_for

    d = decimals_for(sd)
    return f"{mean:.{d}f} ± {sd:.{d}f}"


def _t(x) -> str:
    return "never" if x is None else f"{x:.0f}"


def leak_report_html(res) -> str:
    """The self-contained ``report.html`` of a leak monitor run
    (:class:`~cassini_bayes.api.LeakResult`): the answer table and the figure, each hypothesis,
    the adequacy verdict, the inputs."""
    from cassini_bayes import __version__
    from cassini_bayes.report.adequacy import adequacy_section
    from cassini_bayes.report.build import verdict_badges
    from cassini_bayes.report.figures import png_bytes
    from cassini_bayes.report.html import (badge, bullet_list, figure, html_page, page_header,
                                           paragraph, section, table)

    s, post, lee = res.summary(), res.posterior, res.lee
    b, lee_s = s["bayes"], s["lee"]
    hypotheses = post.hypotheses
    lee_on = lee_s.get("applies", True)
    leaking = b["detection_time_s"] is not None
    answer = _answer_table(b, lee_s, hypotheses)
    per = table(["hypothesis", "P at the last check", "P ≥ alarm first at (s)"],
                [[h, f"{p:.4f}", _t(next((float(t) for t, q in zip(post.t_check, post.prob[:, j])
                                          if q >= post.p_detect), None))]
                 for j, (h, p) in enumerate(b["p_hypothesis"].items())], left=1)
    call = (badge(f"LEAK: {b['thruster']}" if b["thruster"] else "LEAK, NOT ISOLATED", False)
            if leaking else badge("NO LEAK", True))
    header = page_header(f"{verdict_badges(s)} {call}",
                         f"{s['command']} · cassini-bayes {__version__} · [{s['t_start_s']:.0f}, "
                         f"{s['t_end_s']:.0f}] s · {b['n_checks']} checks · alarm at P ≥ "
                         f"{b['p_detect']:g}", s.get("warnings") or [])
    fig = figure(png_bytes(leak_figure(post, lee, hypotheses)),
                 "Posterior probability of each hypothesis given the data up to each check "
                 "(thrusters that never reach 1 % not drawn), the alarm level, and when each "
                 "monitor detected the leak.", alt="leak probabilities")
    lee_text = (f"Lee's monitor: the residual momentum against R_T = "
                f"{lee_s['threshold_nms']:g} N m s within T_limit = "
                f"{lee_s['t_limit_s'] / 3600:g} h, thrust variation η = {lee_s['eta']:g} "
                "(Lee §3.2, Eq 11). " if lee_on else f"{lee_s['reason']} (its column: –). ")
    sections = [
        section("Answer", [answer, paragraph(
            "The Bayesian monitor: the posterior of no leak or a leak of one of the model's "
            f"{len(hypotheses) - 1} thrusters from an unknown onset (docs/leak.md); detection "
            "when P(leak) reaches the alarm level, isolation when one thruster's probability "
            "does. " + lee_text + "Requirement: the momentum the leak's torque builds up on its "
            "worst axis between the onset and the isolation.",
            note=True), fig], id="answer"),
        adequacy_section(s, LEAK_NOTE),
        section("Hypotheses", per, id="hypotheses"),
        section("Inputs", bullet_list(str(f) for f in res.files), id="inputs"),
    ]
    return html_page("cassini-bayes thruster-leak monitor", sections, header=header)


def _answer_table(b: dict, lee_s: dict, hypotheses) -> str:
    """The answer table: the Bayesian monitor's verdict beside Lee's threshold monitor, and the
    isolation requirement (the momentum the leak built up by then, Lee §3.2)."""
    from cassini_bayes.report.html import Raw, badge, table

    lee_on = lee_s.get("applies", True)

    def lee_cell(value):
        return (value or "none") if lee_on else "–"

    leaking = b["detection_time_s"] is not None
    torque = np.asarray(b["torque_nm"], float)
    req_cells, req_cls = ["–", "–"], ["", ""]
    if leaking and b["isolation_time_s"] is not None:
        # momentum the leak built up on its worst axis by the time it was isolated
        built = float(np.max(np.abs(torque)) * max(b["isolation_time_s"] - b["onset_s"], 0.0))
        ok = built <= ISOLATE_BEFORE_NMS
        req_cells = [f"{built:.3g} N m s (isolate before {ISOLATE_BEFORE_NMS:g} N m s, Lee §3.2)",
                     Raw(badge("pass" if ok else "FAIL", ok))]
        req_cls = ["good" if ok else "bad", ""]
    most = max((h for h in hypotheses if h != "none"), key=lambda h: b["p_hypothesis"][h])
    who = b["thruster"] or most
    rows = [
        ["P(a leak in the stretch)", "–", f"{b['p_leak']:.4f}", "–", "–", "–"],
        ["leaking thruster", "–",
         f"{b['thruster'] or 'none isolated'} (P {b['p_hypothesis'][who]:.4f})",
         lee_cell(lee_s.get("thruster")), "–", "–"],
        ["detection time", "s", _t(b["detection_time_s"]),
         _t(lee_s["detection_time_s"]) if lee_on else "–", "–", "–"],
        ["detection axis", "–", "–", (lee_s["axis"] or "–") if lee_on else "–", "–", "–"],
        ["isolation time", "s", _t(b["isolation_time_s"]), "–", *req_cells],
        [f"leak fraction of {who}'s thrust", "%",
         _pm(100 * b["fraction_mean"], 100 * b["fraction_sd"]), "–", "–", "–"],
        [f"leak torque of {who} (x, y, z)", "N m",
         "[" + ", ".join(f"{x:.3g}" for x in torque) + "]", "–",
         "detect ≥ 0.005 N m in cruise (Lee §3.2)", "–"],
        ["onset (posterior mean)", "s", f"{b['onset_s']:.0f}", "–", "–", "–"],
        ["residual noise sd (x, y, z)", "N m s",
         "[" + ", ".join(f"{x:.3g}" for x in b["noise_sd_nms"]) + "]", "–", "–", "–"],
    ]
    classes = [[""] * 6 for _ in rows]
    classes[4] = ["", "", "", "", *req_cls]
    answer = table(["quantity", "unit", "Bayesian monitor (posterior)",
                    "Lee's threshold monitor (paper)", "requirement", "verdict"], rows, left=1,
                   classes=classes)
    return answer
