"""What an experiment returns: its checks against the papers, figures, tables and summary.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cassini_bayes.analysis.paper_facts import fact
from cassini_bayes.diagnostics import ESS_BULK_MIN, R_HAT_MAX, Diagnostics
from cassini_bayes.errors import InputError


@dataclass(frozen=True)
class Check:
    """Our number for one row of the papers' facts (or a check of our own).

    Attributes
    ----------
    label : what was computed, in words.
    ours : our value (in ``unit``).
    unit : unit of ``ours``.
    fact_id : id of the :data:`~cassini_bayes.analysis.paper_facts.PAPER_FACTS` row it
        reproduces, or ``None`` for a check with no printed counterpart.
    paper : the paper's value as printed ("" when none).
    passed : ``True``/``False`` against the paper (printed precision or budget); ``None`` when
        there is nothing to pass (a reference row).
    decimals : decimals to show ``ours`` with.
    note : how the comparison was made, one line.
    """

    label: str
    ours: float
    unit: str = ""
    fact_id: str | None = None
    paper: str = ""
    passed: bool | None = None
    decimals: int = 4
    note: str = ""

    @property
    def ours_text(self) -> str:
        return f"{self.ours:.{self.decimals}f} {self.unit}".strip()

    def to_dict(self) -> dict[str, Any]:
        return {"label": self.label, "ours": self.ours, "unit": self.unit,
                "fact_id": self.fact_id, "paper": self.paper, "passed": self.passed,
                "note": self.note}


def convergence_check(what: str, diagnostics: Diagnostics, quick: bool = False) -> Check:
    """A check row saying whether a fit's sampler converged (the rule of
    :mod:`cassini_bayes.diagnostics`). Under ``--quick`` the runs are too short to judge: the
    row is shown but not counted (``passed=None``)."""
    d = diagnostics
    note = (f"min bulk ESS {d.min_ess_bulk:.0f}, {d.divergences} divergences "
            f"(R-hat ≤ {R_HAT_MAX}, ESS ≥ {ESS_BULK_MIN:g}, no divergences)")
    if quick:
        note += "; --quick: too few draws to judge, not counted"
    return Check(f"{what}: sampler converged", float(d.max_r_hat), "max R-hat", decimals=3,
                 passed=None if quick else bool(d.converged), note=note)


def coverage_check(label: str, covered: int, total: int, nominal: float = 0.90) -> Check:
    """A check row: do posterior intervals of nominal level ``nominal`` cover the truth at that
    rate? ``covered`` of ``total`` intervals contain the truth; the row passes when an exact
    two-sided binomial test does not reject ``p = nominal`` at the 5 % level (a calibrated
    posterior fails 5 % of the time with independent intervals). The note gives the binomial
    standard error."""
    from scipy.stats import binomtest

    if total <= 0:
        return Check(label, float("nan"), "%", passed=None, note="no intervals")
    rate = covered / total
    p_value = float(binomtest(covered, total, nominal).pvalue)
    se = (nominal * (1.0 - nominal) / total) ** 0.5
    return Check(label, 100.0 * rate, "%", decimals=0, passed=p_value >= 0.05,
                 note=f"{covered} of {total}; nominal {100 * nominal:g} % ± {100 * se:.0f} % "
                      f"(binomial sd); exact binomial p = {p_value:.2f} (fails below 0.05)")


def check_fact(fact_id: str, ours: float, *, label: str | None = None, note: str = "",
               decimals: int | None = None) -> Check:
    """A :class:`Check` of ``ours`` against the paper-facts row ``fact_id``.

    Passes when ``ours`` matches at the printed precision (value rows) or is within the bound
    (budget rows); shown with two more decimals than the paper prints unless ``decimals`` is given.
    """
    f = fact(fact_id)
    shown = decimals if decimals is not None else (f.decimals or 0) + 2
    return Check(label=label or f.description, ours=float(ours), unit=f.unit, fact_id=f.id,
                 paper=f.printed, passed=f.passes(ours), decimals=shown, note=note)


@dataclass(frozen=True)
class FigureOut:
    """A rendered figure: file stem ``name``, PNG bytes and a caption."""

    name: str
    png: bytes
    caption: str = ""


@dataclass(frozen=True)
class Table:
    """A small table for the report (cells already formatted as text)."""

    title: str
    columns: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    note: str = ""

    def to_dict(self) -> dict[str, Any]:
        return {"title": self.title, "columns": list(self.columns),
                "rows": [list(r) for r in self.rows], "note": self.note}


@dataclass(frozen=True)
class ExperimentOutput:
    """What an experiment kind returns; the framework writes it to the run directory.

    Attributes
    ----------
    summary : JSON-able results (units in the key names).
    checks : our numbers against the papers'.
    figures : rendered figures.
    tables : extra tables for the report.
    notes : paragraphs for the report (method, distributions used, caveats).
    links : (label, path relative to the run directory) of files or sub-runs written by the kind.
    """

    summary: Mapping[str, Any]
    checks: tuple[Check, ...] = ()
    figures: tuple[FigureOut, ...] = ()
    tables: tuple[Table, ...] = ()
    notes: tuple[str, ...] = ()
    links: tuple[tuple[str, str], ...] = ()


@dataclass(frozen=True)
class ExperimentContext:
    """What a kind may use besides its key and settings.

    Attributes
    ----------
    workdir : the (temporary) run directory being written; a kind may write sub-runs into it and
        list them in :attr:`ExperimentOutput.links`.
    quick : whether ``--quick`` was asked for.
    source : the experiment file, for error messages.
    progress : ``progress(fraction, message)`` reports progress within the experiment.
    """

    workdir: Path
    quick: bool = False
    source: str = "<experiment>"
    progress: Callable[[float, str], None] = lambda fraction, message="": None

    def error(self, message: str) -> InputError:
        """An :class:`InputError` naming the experiment file."""
        return InputError(message, path=self.source)


def png(fig, dpi: int = 90) -> bytes:
    """Render a matplotlib ``Figure`` to PNG bytes (palette-quantised like the run reports)."""
    from cassini_bayes.report.figures import png_bytes

    return png_bytes(fig, dpi=dpi)
