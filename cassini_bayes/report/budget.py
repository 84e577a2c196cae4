"""The budget report (``report.html`` of ``cassini-bayes budget``, docs/budgets.md): every line's
posterior interval beside the paper's number, with pass/fail against the paper's budget and its
attribution to the calibrated parameters as percentages.

A line judged against a budget of the papers (:data:`~cassini_bayes.analysis.paper_facts.
PAPER_FACTS` rows of kind ``"budget"``) passes when its 95th percentile is within the bound, as
the ``error_budgets`` experiment judges it; Lee's RSS rows carry no verdict (his Table 2's own
entries root-sum-square to 1.186 / 0.244 mrad, he prints 1.18 / 0.23); a line no posterior enters
keeps the paper's value.
"""

from __future__ import annotations

__all__ = ["budget_report_html", "BUDGET_NOTE"]

BUDGET_NOTE = ("Are the input runs fit to be combined? input_convergence and input_adequacy "
               "count the runs whose own summary.json says they did not converge or failed "
               "their adequacy checks; spacecraft_models counts the models they were fitted "
               "with; shared_inertia compares the inertia of every run that sampled it (one "
               "spacecraft, one inertia). docs/budgets.md.")


def _attribution(iv) -> str:
    """Each parameter's share of the line's variance when it alone varies, in percent, with a
    note when the one-at-a-time shares do not add up to the whole (docs/budgets.md)."""
    shown = sorted(((v, k) for k, v in iv.shares.items() if v >= 0.005), reverse=True)
    if not shown:
        return "–"
    if len(iv.shares) > 1 and not 0.5 <= iv.share_sum <= 2.0:
        text = ", ".join(f"{k} {100 * v / iv.share_sum:.0f} %" for v, k in shown)
        return f"{text} (relative: alone they spread the line {iv.share_sum:.3g}× its variance)"
    text = ", ".join(f"{k} {100 * v:.0f} %" for v, k in shown)
    if len(iv.shares) > 1 and abs(iv.share_sum - 1.0) > 0.05:
        text += f" (sum {100 * iv.share_sum:.0f} %)"
    return text


def _budget_rows(budget) -> tuple[list[str], list[list], list[list[str]]]:
    """Headers, cells and cell classes of the budget table
    (:class:`~cassini_bayes.analysis.posterior_budgets.PosteriorBudget`): one row per line, the
    budget named on its first line only."""
    from cassini_bayes.analysis.paper_facts import fact
    from cassini_bayes.report.html import Raw, badge, esc

    headers = ["budget", "line (inputs)", "paper", "posterior median", "90 % interval",
               "95th percentile", "verdict", "variance share, each parameter alone"]
    rows, classes = [], []
    previous = None
    for r in budget.rows:
        iv = r.interval
        f = fact(r.fact_id) if r.fact_id else None
        unit = "°" if r.unit == "deg" else f" {r.unit}"
        line = Raw(f'{esc(r.line)}<br><span class="na">{esc(r.inputs)}</span>')
        name = r.budget if r.budget != previous else ""
        previous = r.budget
        if iv is None:
            cells = [name, line, r.paper or "–", f"{r.value:.4g}{unit} (kept)", "–", "–",
                     "no posterior", "–"]
            cls = ["w", "w", "", "", "", "", "", ""]
        else:
            if f is not None and f.kind == "budget":
                ok = bool(f.passes(iv.high))
                verdict, vcls = Raw(badge("pass" if ok else "FAIL", ok)), ("good" if ok else "bad")
            elif f is not None and f.kind == "value":
                verdict, vcls = "no verdict †", ""
            else:
                verdict, vcls = "no budget", ""
            cells = [name, line, r.paper or "–", f"{iv.median:.3g}{unit}",
                     f"[{iv.low:.3g}, {iv.high:.3g}]{unit}", f"{iv.high:.3g}{unit}", verdict,
                     _attribution(iv)]
            cls = ["w", "w", "", "", "", vcls, "", "w"]
        rows.append(cells)
        classes.append(cls)
    return headers, rows, classes


def budget_report_html(res) -> str:
    """The self-contained ``report.html`` of a budget
    (:class:`~cassini_bayes.api.BudgetResult`): the budget lines, the adequacy verdict on the
    input runs, the inputs."""
    from cassini_bayes import __version__
    from cassini_bayes.report.adequacy import adequacy_section
    from cassini_bayes.report.build import verdict_badges
    from cassini_bayes.report.html import (badge, bullet_list, html_page, page_header,
                                           paragraph, section, table)

    s, bud = res.summary(), res.budget
    headers, rows, classes = _budget_rows(bud)
    verdicts = [c[6] for c in rows if "pass" in str(c[6]) or "FAIL" in str(c[6])]
    failed = sum("FAIL" in str(v) for v in verdicts)
    call = (badge("WITHIN THE PAPERS' BUDGETS" if not failed else
                  f"OUTSIDE THE PAPERS' BUDGETS ({failed} of {len(verdicts)})", not failed)
            if verdicts else badge("NO LINE JUDGED", None))
    header = page_header(f"{verdict_badges(s)} {call}",
                         f"{s.get('command', 'budget')} · cassini-bayes {__version__} · "
                         f"{bud.n_draws} joint draws · seed {s.get('seed', '–')}",
                         s.get("warnings") or [])
    sections = [
        section("Budget lines", [
            table(headers, rows, left=2, classes=classes, fit=True),
            paragraph(
                "Each line propagated from the posterior draws of the runs below, each draw read "
                "as the truth and the posterior mean as the estimate: median and 90 % credible "
                "interval, beside the paper's number. Verdict: the 95th percentile against the "
                "paper's budget. Lines without a calibrated input keep the paper's value. "
                "Variance share: the percentage of the line's posterior variance each parameter "
                "causes when it alone varies, the others at their posterior medians; read it as "
                "which parameter moves the line (docs/budgets.md). † Lee's root-sum-square: his "
                "Table 2's own entries give 1.186 / 0.244 mrad, he prints 1.18 / 0.23.",
                note=True)],
            id="lines"),
        adequacy_section(s, BUDGET_NOTE),
        section("Inputs", bullet_list(f"{k}: {v}" for k, v in res.runs.items()), id="inputs"),
    ]
    return html_page("cassini-bayes budgets from posteriors", sections, header=header)
