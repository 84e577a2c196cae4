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


def _label_axes(fig, xlabel: str, ylabel: str) -> None:
    """Every visible panel's axes labelled with their units (the analysis layer's plots label
    only the x-axis, without a unit)."""
    from cassini_bayes.report.figures import tidy_ticks

    for ax in fig.axes:
        if ax.get_visible():
            ax.set_xlabel(xlabel, fontsize=8)
            ax.set_ylabel(ylabel, fontsize=8)
            tidy_ticks(ax, x=5, y=4)
    fig.tight_layout()


def _cov_cell(c: dict) -> tuple[str, str]:
    """A coverage as ``observed ± se`` and its class: red beyond 3 standard errors of the
    nominal level, amber beyond 2."""
    z = abs(c["observed"] - c["nominal"]) / c["se"] if c["se"] > 0 else 0.0
    return (f"{c['observed']:.3f} ± {c['se']:.3f}",
            "bad" if z > 3 else ("warn" if z > 2 else "good"))


def _answer_table(parameters: dict, a: float) -> str:
    """Per parameter: its unit, the two uniformity p-values against ``a``, the 90 % coverage
    and the verdict."""
    from cassini_bayes.report.html import Raw, badge, table
    from cassini_bayes.report.tables import unit_of

    rows, cls = [], []
    for n, p in parameters.items():
        c90, c90_cls = _cov_cell(p["coverage"]["90"])
        rows.append([n, unit_of(n) or "–", f"{p['chi2']['p_value']:.3g}",
                     f"{p['ecdf']['p_value']:.3g}", c90,
                     Raw(badge("calibrated" if p["passed"] else "FAIL", p["passed"]))])
        cls.append(["", "", "bad" if p["chi2"]["p_value"] < a else "good",
                    "bad" if p["ecdf"]["p_value"] < a else "good", c90_cls, ""])
    return table(["parameter", "unit", "rank uniformity: χ² p", "ECDF p",
                  "90 % interval coverage", "verdict"], rows, classes=cls)


def _coverage_table(parameters: dict) -> str:
    """Per parameter: the two uniformity statistics and the coverage at every level."""
    from cassini_bayes.report.html import table

    crow, ccls = [], []
    for n, p in parameters.items():
        row, rc = [n, f"{p['chi2']['statistic']:.2f} ({p['chi2']['bins']} bins)",
                   f"{p['ecdf']['statistic']:.4f}"], ["", "", ""]
        for k in ("50", "80", "90", "95"):
            text, c = _cov_cell(p["coverage"][k])
            row.append(text)
            rc.append(c)
        crow.append(row)
        ccls.append(rc)
    return table(["parameter", "χ² statistic", "ECDF γ", "50 %", "80 %", "90 %", "95 %"], crow,
                 classes=ccls)


def sbc_report_html(sbc, summary: dict) -> str:
    """Self-contained HTML of a campaign's :class:`~cassini_bayes.analysis.sbc.SbcResult` and
    its ``summary.json`` dict: the answer first (per parameter, its unit, whether its ranks are
    uniform and how often its intervals cover the truth), then the coverage at every level and
    the rank plots."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from cassini_bayes.analysis.sbc import plot_ecdf_difference, plot_rank_histograms
    from cassini_bayes.report.build import verdict_badges
    from cassini_bayes.report.html import badge, figure, html_page, page_header, paragraph, section

    a = summary["alpha_per_parameter"]
    answer = _answer_table(summary["parameters"], a)
    cov = _coverage_table(summary["parameters"])
    header = page_header(
        f"{verdict_badges(summary)} "
        + badge("CALIBRATED: uniformity passed" if summary["passed"] else
                "NOT CALIBRATED: uniformity FAILED", summary["passed"]),
        f"model {summary['model']}, {summary['replicates']} replicates "
        f"({summary['failures']} failed, {summary['non_converged']} not "
        f"converged, {summary['ess']['below_draws']} with an effective sample "
        "size below the ranked draws), "
        f"{summary['draws_per_replicate']} thinned draws each, "
        f"seed {summary['seed']}, cassini-bayes {summary['version']}")
    L = summary["draws_per_replicate"]
    ranks = plot_rank_histograms(sbc)
    _label_axes(ranks, f"rank of the truth among {L} draws (count)", "replicates per bin (count)")
    ecdf = plot_ecdf_difference(sbc)
    _label_axes(ecdf, f"rank of the truth among {L} draws (count)",
                "ECDF − uniform CDF (dimensionless)")
    sections = [
        section("Answer", [
            answer,
            paragraph("Ranks of the true parameter among the thinned posterior draws are "
                      "discrete-uniform when the posterior is calibrated (Talts et al. 2018). "
                      f"Each parameter is tested at alpha = {a:.3g} (family-wise "
                      f"{summary['alpha_family']} per statistic, Bonferroni): Pearson chi-square "
                      "on binned ranks, and the ECDF simultaneous-band statistic of Säilynoja et "
                      "al. (2022) with a simulated null. Coverage: the fraction of replicates "
                      "whose truth lies in the posterior's central interval, ± the binomial "
                      "standard error; red beyond 3 standard errors, amber beyond 2.",
                      note=True)], id="answer"),
        section("Coverage of central intervals", cov, id="coverage"),
        section("Rank histograms", figure(
            _png(ranks),
            "Rank histograms; grey: 99 % pointwise binomial band of a uniform histogram.")),
        section("ECDF difference", figure(
            _png(ecdf),
            f"ECDF of the ranks minus the uniform CDF, with ArviZ's simultaneous "
            f"{100 * (1 - a):.2f} % band (Säilynoja et al. 2022).")),
    ]
    return html_page(f"SBC: {summary['model']}", sections, header=header)
