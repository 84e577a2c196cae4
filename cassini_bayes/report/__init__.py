"""Posterior diagnostic reports: one self-contained HTML page per run directory.

``build_report(run_dir)`` reads ``posterior.nc``, ``summary.json`` and ``config.toml`` of a run
directory (docs/design.md §4.4) and writes ``report.html`` beside them, atomically. The page opens
offline: figures are embedded as base64 PNG, the style sheet is inline, there is no script.

The page-building helpers (``html_page``, ``section``, ``table``, ``figure``, ...) are public so
that summary pages (``cassini-bayes reproduce``) share the same look and can link to each run's
report.
"""

from cassini_bayes.report.build import build_report, render_report
from cassini_bayes.report.html import (
    Raw,
    Section,
    badge,
    bullet_list,
    details,
    esc,
    figure,
    html_page,
    link,
    meta_list,
    not_available,
    paragraph,
    preformatted,
    section,
    table,
    write_atomic,
)
from cassini_bayes.report.rundata import RunData, load_run

__all__ = [
    "build_report",
    "render_report",
    "load_run",
    "RunData",
    "html_page",
    "Section",
    "section",
    "table",
    "figure",
    "badge",
    "paragraph",
    "bullet_list",
    "link",
    "meta_list",
    "not_available",
    "details",
    "preformatted",
    "write_atomic",
    "esc",
    "Raw",
]
