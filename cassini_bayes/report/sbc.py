"""The HTML report of an SBC campaign (``report.html`` of ``cassini-bayes sbc``): uniformity
tests, coverage, rank histograms and ECDF differences."""

from __future__ import annotations

__all__ = ["sbc_report_html"]


def _png(fig) -> bytes:
    import matplotlib.pyplot as plt

    from cassini_bayes.report.figures import png_bytes

    try:
        return png_bytes(fig, dpi=110)
    finally:
        plt.close(fig)


def sbc_report_html(sbc, summary: dict) -> str:
    """Self-contained HTML of a campaign's :class:`~cassini_bayes.analysis.sbc.SbcResult` and
    its ``summary.json`` dict."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from cassini_bayes.analysis.sbc import plot_ecdf_difference, plot_rank_histograms
    from cassini_bayes.report.html import badge, figure, html_page, paragraph, section, table

    a = summary["alpha_per_parameter"]
    rows, cls = [], []
    for n, p in summary["parameters"].items():
        rows.append([n, f"{p['chi2']['statistic']:.2f}", p["chi2"]["bins"],
                     f"{p['chi2']['p_value']:.3g}", f"{p['ecdf']['statistic']:.4f}",
                     f"{p['ecdf']['p_value']:.3g}", "pass" if p["passed"] else "FAIL"])
        cls.append(["", "", "", "bad" if p["chi2"]["p_value"] < a else "good", "",
                    "bad" if p["ecdf"]["p_value"] < a else "good",
                    "good" if p["passed"] else "bad"])
    uni = table(["parameter", "χ²", "bins", "χ² p", "ECDF γ", "ECDF p", "verdict"], rows,
                classes=cls)
    crow, ccls = [], []
    for n, p in summary["parameters"].items():
        row, rc = [n], [""]
        for k in ("50", "80", "90", "95"):
            c = p["coverage"][k]
            row.append(f"{c['observed']:.3f} ± {c['se']:.3f}")
            z = abs(c["observed"] - c["nominal"]) / c["se"]
            rc.append("bad" if z > 3 else ("warn" if z > 2 else "good"))
        crow.append(row)
        ccls.append(rc)
    cov = table(["parameter", "50 %", "80 %", "90 %", "95 %"], crow, classes=ccls)
    header = (badge("uniformity passed" if summary["passed"] else "uniformity FAILED",
                    summary["passed"])
              + paragraph(f"model {summary['model']}, {summary['replicates']} replicates "
                          f"({summary['failures']} failed, {summary['non_converged']} not "
                          f"converged, {summary['ess']['below_draws']} with an effective sample "
                          "size below the ranked draws), "
                          f"{summary['draws_per_replicate']} thinned draws each, "
                          f"seed {summary['seed']}, cassini-bayes {summary['version']}"))
    sections = [
        section("Uniformity of ranks", [
            uni,
            paragraph("Ranks of the true parameter among the thinned posterior draws are "
                      "discrete-uniform when the posterior is calibrated (Talts et al. 2018). "
                      f"Each parameter is tested at alpha = {a:.3g} (family-wise "
                      f"{summary['alpha_family']} per statistic, Bonferroni): Pearson chi-square "
                      "on binned ranks, and the ECDF simultaneous-band statistic of Säilynoja et "
                      "al. (2022) with a simulated null.", note=True)]),
        section("Coverage of central intervals", [
            cov,
            paragraph("Fraction of replicates whose truth lies in the posterior's central "
                      "interval, ± the binomial standard error at the nominal level; red beyond "
                      "3 standard errors, amber beyond 2.", note=True)]),
        section("Rank histograms", figure(
            _png(plot_rank_histograms(sbc)),
            "Rank histograms; grey: 99 % pointwise binomial band of a uniform histogram.")),
        section("ECDF difference", figure(
            _png(plot_ecdf_difference(sbc)),
            f"ECDF of the ranks minus the uniform CDF, with ArviZ's simultaneous "
            f"{100 * (1 - a):.2f} % band (Säilynoja et al. 2022).")),
    ]
    return html_page(f"SBC: {summary['model']}", sections, header=header)
