"""Assemble a fit run directory's ``report.html`` (docs/design.md §4.4) from its files.

The page opens with the answer: the verdicts as badges (converged, adequate, within the papers'
budgets), then the answer table — each calibrated quantity with its unit, posterior mean, sd and
90 % interval, the model file's prediction and the prior sd, the papers' least squares, the
papers' budget with pass/fail — and one figure of the posteriors at their own scale beside the
least-squares values (for RWA4 the spin-axis table and sky plot). Below: per-pulse impulses
(thrust), model adequacy, residuals, sensitivity, the sampler diagnostics (trace and rank plots of
the calibrated parameters, their posterior correlations; the per-variable table of the nuisance
folded away) and the configuration. A section whose data the run lacks says so instead of
disappearing, so every report of a kind has the same outline.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from cassini_bayes import __version__
from cassini_bayes.files import write_text
from cassini_bayes.report import figures
from cassini_bayes.report._answer import answer_section
from cassini_bayes.report._page_header import report_header, verdict_badges
from cassini_bayes.report._sections import (
    config_section,
    diagnostics_section,
    pulses_section,
    residuals_section,
    thrust_design_section,
)
from cassini_bayes.report.adequacy import adequacy_section
from cassini_bayes.report.html import (
    esc,
    figure,
    html_page,
    not_available,
)
from cassini_bayes.report.rundata import RunData, load_run
from cassini_bayes.report.tables import (
    derived_rows,
    diagnostics,
    parameter_names,
    parameter_rows,
)

__all__ = ["build_report", "render_report", "verdict_badges"]

def build_report(
    run_dir: str | Path,
    *,
    out: str | Path | None = None,
    display_dir: str | Path | None = None,
) -> Path:
    """Write the self-contained report of a fit's run directory.

    Parameters
    ----------
    run_dir : str or Path
        Directory holding ``posterior.nc`` and normally ``summary.json`` and ``config.toml``.
    out : str or Path, optional
        Where to write; default ``run_dir / "report.html"``. Written atomically.
    display_dir : str or Path, optional
        The directory named on the page, when it differs from ``run_dir`` (a fit building its
        run in a temporary directory that is renamed to the final name afterwards).

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    InputError
        ``run_dir`` or its ``posterior.nc`` is missing or unreadable.
    """
    run = load_run(run_dir)
    out = Path(out) if out is not None else run.run_dir / "report.html"
    return write_text(out, render_report(run, display_dir=display_dir))


def render_report(run: RunData, *, display_dir: str | Path | None = None) -> str:
    """The report of a loaded run as an HTML string (see :func:`build_report`)."""
    shown = Path(display_dir) if display_dir is not None else run.run_dir
    names = parameter_names(run)
    diag = diagnostics(run, names)
    rows = parameter_rows(run, names, diag)
    derived = derived_rows(run)
    problems: list[str] = []  # figures that could not be drawn

    def fig(title: str, draw: Callable[[], object], caption: str) -> str:
        try:
            return figure(figures.png_bytes(draw()), caption, alt=title)
        except Exception as e:  # a figure must never cost the whole report
            problems.append(f"{title} could not be drawn ({type(e).__name__}: {e})")
            return not_available(f"{title} could not be drawn ({type(e).__name__}: {e})")

    sections = [answer_section(run, names, rows, derived, fig)]
    if run.kind == "thrust":
        sections += [s for s in [thrust_design_section(run.summary)] if s is not None]
        sections.append(pulses_section(run, fig))
    sections += [adequacy_section(run.summary), residuals_section(run, fig)]
    from cassini_bayes.report.sensitivity import sensitivity_section
    sections += [s for s in [sensitivity_section(run.summary)] if s is not None]
    sections += [diagnostics_section(run, names, diag, rows, fig), config_section(run)]

    checks = [r.budget for r in rows if r.budget] + [b for *_, b in derived if b]
    header = report_header(run, diag, rows, checks, problems, shown)
    title = f"cassini-bayes {run.kind} run — {shown.name}"
    footer = (f"Built by cassini-bayes {esc(__version__)} from {esc(shown / 'posterior.nc')}."
              " Posterior summaries from the full posterior; the sampler diagnostics are the "
              "fit's (ArviZ, summary.json); plots may show thinned draws.")
    return html_page(title, sections, header=header, footer=footer)
