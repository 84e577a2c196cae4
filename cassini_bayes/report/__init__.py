"""Posterior diagnostic reports: one self-contained HTML page per run directory.

``build_report(run_dir)`` reads ``posterior.nc``, ``summary.json`` and ``config.toml`` of a run
directory (docs/design.md §4.4) and writes ``report.html`` beside them, atomically. The page opens
offline: figures are embedded as base64 PNG, the style sheet is inline, there is no script.

The page-building helpers (``html_page``, ``section``, ``table``, ``figure``, ...) are public so
that summary pages (``cassini-bayes reproduce``) share the same look and can link to each run's
report.
"""

import json
import warnings
from collections.abc import Mapping
from pathlib import Path

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
)
from cassini_bayes.report.rundata import RunData, load_run

__all__ = [
    "build_report",
    "write_report",
    "minimal_report_html",
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
    "esc",
    "Raw",
]


def minimal_report_html(summary: Mapping) -> str:
    """A small self-contained HTML page with the diagnostics table (fallback report)."""
    from html import escape

    d = summary.get("diagnostics", {})
    rows = "".join(f"<tr><td>{escape(str(k))}</td><td>{escape(str(v))}</td></tr>"
                   for k, v in d.items())
    prow = "".join(
        f"<tr><td>{escape(k)}</td>" + "".join(
            f"<td>{escape(str(v.get(c)))}</td>"
            for c in ("mean", "sd", "q05", "q95", "r_hat", "ess_bulk")) + "</tr>"
        for k, v in summary.get("parameters", {}).items())
    return ("<!DOCTYPE html><html><head><meta charset='utf-8'><title>cassini-bayes run</title>"
            "</head><body><h1>cassini-bayes: " + escape(str(summary.get("kind", "run"))) +
            "</h1><h2>Diagnostics</h2><table>" + rows + "</table><h2>Parameters</h2><table>"
            "<tr><th>name</th><th>mean</th><th>sd</th><th>q05</th><th>q95</th><th>r_hat</th>"
            "<th>ess_bulk</th></tr>" + prow + "</table></body></html>\n")


def write_report(run_dir: Path, *, display_dir: Path | None = None,
                 summary: Mapping | None = None) -> Path:
    """``report.html`` from :func:`cassini_bayes.report.build_report`; a minimal page if that fails.

    A failure of the report never loses a finished fit: it is turned into a warning and the
    minimal page (diagnostics and parameter tables from ``summary``) is written instead.
    """
    p = Path(run_dir) / "report.html"
    try:
        kwargs = {"display_dir": display_dir} if display_dir is not None else {}
        build_report(run_dir, **kwargs)
        if p.exists():
            return p
    except Exception as e:  # report broken: keep the run, say so
        warnings.warn(f"report.html: the full report failed ({type(e).__name__}: {e}); "
                      "wrote a minimal one", stacklevel=2)
    if summary is None:
        summary = json.loads((Path(run_dir) / "summary.json").read_text())
    p.write_text(minimal_report_html(summary))
    return p
