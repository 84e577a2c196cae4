"""``report.html`` of ``monitor leak``: the adequacy verdict and both monitors' answers."""

from __future__ import annotations

__all__ = ["leak_page", "LEAK_NOTE"]

LEAK_NOTE = ("Self-checks of the Bayesian monitor's model on this stretch, under the hypothesis "
             "most probable at the last check: residual_fit, the residual momentum left by the "
             "offset, torque, thrust errors (and the leak) against the noise level the monitor "
             "assumed; prior_data_conflict, the torque and the thrust errors in their prior sd; "
             "residual_autocorrelation, a slow wander the white model does not hold. "
             "Thresholds and the false-alarm rates measured on clean stretches: docs/leak.md.")


def leak_page(summary: dict, files) -> str:
    """The page: the adequacy badge and section, then the Bayesian monitor's probabilities at
    the last check and its detection, Lee's threshold monitor, and the input ``files``."""
    from cassini_bayes.report.adequacy import adequacy_section, verdict_header
    from cassini_bayes.report.html import bullet_list, html_page, section, table
    from cassini_bayes.report.tables import fmt

    b, lee = summary["bayes"], summary["lee"]

    def when(x):
        return "never" if x is None else f"{x:.0f} s"

    rows = [[h, fmt(p, 3)] for h, p in b["p_hypothesis"].items()]
    bayes = [table(["hypothesis", "P at the last check"], rows),
             bullet_list([f"detection (P(leak) ≥ {b['p_detect']:g}): {when(b['detection_time_s'])}",
                          f"isolation: {when(b['isolation_time_s'])}, thruster "
                          f"{b['thruster'] or 'none'}",
                          f"leak fraction {fmt(b['fraction_mean'], 3)} ± "
                          f"{fmt(b['fraction_sd'], 3)}, onset {b['onset_s']:.0f} s",
                          "noise sd per axis " + ", ".join(fmt(x, 3) for x in b["noise_sd_nms"])
                          + " N m s"])]
    lee_items = [f"detection: {when(lee['detection_time_s'])}, axis {lee['axis'] or '–'}, "
                 f"thruster {lee['thruster'] or 'none'}",
                 f"R_T {lee['threshold_nms']:g} N m s, T_limit {lee['t_limit_s'] / 3600:g} h, "
                 f"η {lee['eta']:g}"]
    return html_page("Thruster-leak monitor", [
        adequacy_section(summary, LEAK_NOTE),
        section("Bayesian monitor", bayes),
        section("Lee's threshold monitor", bullet_list(lee_items)),
        section("Inputs", bullet_list([str(f) for f in files]))],
        header=verdict_header(summary))
