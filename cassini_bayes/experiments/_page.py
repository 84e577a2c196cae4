"""HTML of an experiment's ``report.html`` and the ``reproduce`` summary page.

Built from :mod:`cassini_bayes.report.html` so every page of the package looks the same;
figures are embedded as ``data:`` URIs and nothing external is loaded.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from cassini_bayes import __version__
from cassini_bayes.report.html import (
    Raw,
    badge,
    bullet_list,
    esc,
    figure,
    html_page,
    paragraph,
    preformatted,
    section,
    table,
)

__all__ = ["experiment_page", "reproduce_page"]


def _verdict_badge(passed: bool | None) -> str:
    """``pass`` / ``fail`` pill; ``info`` for a number shown without a verdict of its own."""
    return badge("info" if passed is None else ("pass" if passed else "fail"), passed)


def _checks_table(checks: Sequence[Any], *, link: str | None = None) -> str:
    """Our value beside the paper's for each check, with its verdict."""
    rows, classes = [], []
    for c in checks:
        row = [c.label, c.fact_id or "—", c.paper or "—", c.ours_text,
               Raw(_verdict_badge(c.passed)), c.note]
        if link is not None:
            row.append(Raw(f'<a href="{esc(link)}">report</a>'))
        rows.append(row)
        cls = "" if c.passed is None else ("good" if c.passed else "bad")
        classes.append(["", "", "", cls, "", ""] + ([""] if link is not None else []))
    headers = ["quantity", "fact", "paper", "ours", "verdict", "how compared"]
    if link is not None:
        headers.append("experiment")
    return table(headers, rows, left=2, classes=classes)


def _output_sections(output: Any, *, id_prefix: str = "") -> list:
    """Sections for an :class:`~cassini_bayes.experiments.ExperimentOutput`."""
    secs = []
    if output.checks:
        secs.append(section("Paper vs ours", _checks_table(output.checks), id=f"{id_prefix}checks"))
    for i, t in enumerate(output.tables):
        body = table(list(t.columns), [list(r) for r in t.rows])
        if t.note:
            body += paragraph(t.note, note=True)
        secs.append(section(t.title, body, id=f"{id_prefix}table-{i}"))
    if output.figures:
        secs.append(section("Figures", [figure(f.png, f.caption, alt=f.name)
                                        for f in output.figures], id=f"{id_prefix}figures"))
    if output.notes:
        secs.append(section("Method and notes", [paragraph(n) for n in output.notes],
                            id=f"{id_prefix}notes"))
    if output.links:
        items = [f'<a href="{esc(p)}">{esc(label)}</a>' for label, p in output.links]
        secs.append(section("Runs", bullet_list(items, raw=True), id=f"{id_prefix}runs"))
    return secs


def experiment_page(exp: Any, output: Any, settings: Mapping[str, Any], seed: int, quick: bool,
                    elapsed_s: float) -> str:
    """The self-contained ``report.html`` of one experiment run."""
    n_fail = sum(c.passed is False for c in output.checks)
    n_pass = sum(c.passed is True for c in output.checks)
    verdict = badge(f"{n_pass} pass, {n_fail} fail", n_fail == 0 if output.checks else None)
    meta = (f'<dl class="meta"><dt>experiment</dt><dd>{esc(exp.name)}</dd>'
            f"<dt>kind</dt><dd>{esc(exp.kind.name)}</dd><dt>seed</dt><dd>{seed}</dd>"
            f"<dt>mode</dt><dd>{'quick' if quick else 'full'}</dd>"
            f"<dt>time</dt><dd>{elapsed_s:.2f} s</dd>"
            f"<dt>version</dt><dd>cassini_bayes {esc(__version__)}</dd></dl>")
    header = meta + verdict + (paragraph(exp.description) if exp.description else "")
    secs = _output_sections(output)
    secs.append(section("Settings", preformatted(json.dumps(dict(settings), indent=2)),
                        id="settings"))
    return html_page(exp.title, secs, header=header,
                     footer=f"cassini_bayes {esc(__version__)} · experiment {esc(exp.source)}")


def _fact_rows(statuses: Sequence[Any], kinds: tuple[str, ...]) -> tuple[list, list]:
    """Rows (and cell classes) of the paper-vs-ours table for facts of the given kinds."""
    from cassini_bayes.analysis.paper_facts import PAPER_FACTS

    by_fact: dict[str, list] = {}
    for s in statuses:
        for c in (s.record.output.checks if s.record else ()):
            if c.fact_id is not None:
                by_fact.setdefault(c.fact_id, []).append((s.experiment.name, c))
    rows, classes = [], []
    for f in PAPER_FACTS:
        if f.kind not in kinds:
            continue
        for name, c in by_fact.get(f.id, ()):
            label = c.label if c.label != f.description else f.description
            rows.append([label, f.source, f.printed, c.ours_text, Raw(_verdict_badge(c.passed)),
                         Raw(f'<a href="{esc(name)}/report.html">{esc(name)}</a>')])
            cls = "" if c.passed is None else ("good" if c.passed else "bad")
            classes.append(["", "", "", cls, "", ""])
    return rows, classes


def reproduce_page(result: Any, seed: int, quick: bool) -> str:
    """The one-page ``reproduce`` summary: paper beside ours, budgets, every experiment."""
    from cassini_bayes.analysis.paper_facts import PAPER_FACTS

    statuses = result.statuses
    all_checks = [c for s in statuses if s.record for c in s.record.output.checks]
    n_pass = sum(c.passed is True for c in all_checks)
    n_fail = sum(c.passed is False for c in all_checks)
    n_err = sum(s.error is not None for s in statuses)
    covered = {c.fact_id for c in all_checks if c.fact_id}
    header = (
        f'<dl class="meta"><dt>experiments</dt><dd>{len(statuses)} run'
        f"{', ' + str(n_err) + ' failed' if n_err else ''}"
        f"{', ' + str(len(result.skipped)) + ' skipped' if result.skipped else ''}</dd>"
        f"<dt>seed</dt><dd>{seed}</dd><dt>mode</dt><dd>{'quick' if quick else 'full'}</dd>"
        f"<dt>time</dt><dd>{result.elapsed_s:.1f} s</dd>"
        f"<dt>paper facts</dt><dd>{len(covered)} of {len(PAPER_FACTS)} reproduced here</dd>"
        f"<dt>version</dt><dd>cassini_bayes {esc(__version__)}</dd></dl>"
        + badge(f"{n_pass} pass", True) + " "
        + badge(f"{n_fail} fail", n_fail == 0) + " "
        + (badge(f"{n_err} experiment(s) failed", False) if n_err else "")
    )
    headers = ["quantity", "source", "paper", "ours", "verdict", "experiment"]
    secs = []
    for title, kinds, note in (
        ("Computed values", ("value",),
         "Numbers the papers computed; ours pass when they agree at the printed precision."),
        ("Budgets", ("budget",), "Accuracy budgets; ours pass when within the bound."),
        ("References", ("reference",),
         "Outcomes of the papers' own test runs, shown beside ours; judged through the budgets."),
    ):
        rows, classes = _fact_rows(statuses, kinds)
        body = paragraph(note, note=True) + (table(headers, rows, left=2, classes=classes) if rows
                                             else '<p class="na">None computed yet.</p>')
        secs.append(section(title, body, id=title.lower().replace(" ", "-")))

    for s in statuses:
        name = s.experiment.name
        link_html = f'<p><a href="{esc(name)}/report.html">{esc(name)}/report.html</a></p>'
        if s.error is not None:
            body = (badge("failed", False) + f"<p>{esc(s.error)}</p>"
                    + f'<p class="note">Traceback: <a href="{esc(name)}/error.txt">'
                      f"{esc(name)}/error.txt</a></p>")
            secs.append(section(s.experiment.title, body, id=f"exp-{name}"))
            continue
        out = s.record.output
        n_f = sum(c.passed is False for c in out.checks)
        parts = [badge("all pass" if n_f == 0 else f"{n_f} fail", n_f == 0),
                 f'<span class="note"> {s.record.elapsed_s:.2f} s</span>', link_html]
        if out.checks:
            parts.append(_checks_table(out.checks))
        for t in out.tables:
            parts.append(f"<h3>{esc(t.title)}</h3>" + table(list(t.columns),
                                                             [list(r) for r in t.rows]))
        parts += [figure(f.png, f.caption, alt=f.name) for f in out.figures]
        if out.links:
            parts.append(bullet_list([f'<a href="{esc(name)}/{esc(p)}">{esc(label)}</a>'
                                      for label, p in out.links], raw=True))
        secs.append(section(s.experiment.title, parts, id=f"exp-{name}"))

    missing = [f for f in PAPER_FACTS if f.id not in covered]
    body = []
    if result.skipped:
        body.append("<h3>Experiment files not run</h3>" + bullet_list(
            [f"{Path(f).name}: {r}" for f, r in result.skipped]))
    if missing:
        body.append("<h3>Paper facts no experiment computes yet</h3>" + table(
            ["fact", "quantity", "paper", "source"],
            [[f.id, f.description, f.printed, f.source] for f in missing], left=2))
    if body:
        secs.append(section("Not covered", body, id="not-covered"))
    return html_page("cassini_bayes: the papers reproduced", secs, header=header,
                     footer=f"cassini_bayes {esc(__version__)} · cassini-bayes reproduce")


