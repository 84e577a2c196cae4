"""Report pieces: a run's adequacy verdict (summary ``adequacy``): a header badge, a section.

Reads the block every ``fit`` (and ``fit health``, ``monitor leak``, ``budget``) writes into
``summary.json`` (:mod:`cassini_bayes.inference.adequacy`): ``{"ok": b, "checks": {NAME:
{"statistic", "threshold", "ok", "parameter"?, "note"?}}}``. A run without the block (older
runs, ``sbc``, experiments) gets a neutral badge and a section that says so.
"""

from __future__ import annotations

from cassini_bayes.report.html import Section, badge, not_available, paragraph, section, table
from cassini_bayes.report.tables import fmt

__all__ = ["adequacy_badge", "adequacy_section"]

_LABELS = {"prior_data_conflict": "prior–data conflict (prior sd)",
           "held_out": "held-out prediction (normal deviate)",
           "residual_autocorrelation": "residual lag-1 autocorrelation |ρ̂₁|",
           "residual_regression": "residuals vs regressors (normal deviate)",
           "inertia_conflict": "events' thrust under their own inertia (event sd)",
           "residual_fit": "residuals vs the assumed noise (normal deviate)",
           "input_convergence": "input runs that did not converge",
           "input_adequacy": "input runs that failed their adequacy checks",
           "spacecraft_models": "spacecraft models among the input runs",
           "shared_inertia": "input runs' inertia agreement (normal deviate)"}
_FIT_NOTE = ("Self-checks of the fit that need no truth: a nuisance or physical parameter pulled "
             "far from its prior, a telemetry file the others do not predict, or residuals with "
             "structure in time or along the model's regressors mean the model leaves something "
             "out, and this run's intervals are not to be trusted as they stand. Each check fails "
             "when its statistic exceeds the threshold; the false-alarm rates measured on "
             "correctly specified simulations are in docs/adequacy.md.")


def _block(summary) -> dict | None:
    block = summary.get("adequacy") if isinstance(summary, dict) else None
    return block if isinstance(block, dict) and isinstance(block.get("checks"), dict) else None


def failed_checks(summary) -> list[str]:
    """Names of the failed checks (empty without a block)."""
    block = _block(summary)
    return [] if block is None else [n for n, c in block["checks"].items() if not c.get("ok")]


def adequacy_badge(summary) -> str:
    """``ADEQUATE`` (green), ``ADEQUACY FAILED: names`` (red) or ``ADEQUACY NOT CHECKED``."""
    block = _block(summary)
    if block is None:
        return badge("ADEQUACY NOT CHECKED", None)
    failed = failed_checks(summary)
    return badge("ADEQUATE" if not failed else f"ADEQUACY FAILED: {', '.join(failed)}",
                 not failed)


def adequacy_section(summary, note: str = _FIT_NOTE) -> Section:
    """The "Model adequacy" section: one row per check, and ``note`` (what the checks mean and
    where their false-alarm rates are; a fit's by default)."""
    block = _block(summary)
    if block is None:
        return section("Model adequacy", not_available(
            "this run has no adequacy block in summary.json"), id="adequacy")
    rows, classes = [], []
    for name, c in block["checks"].items():
        stat = c.get("statistic")
        rows.append([_LABELS.get(name, name), "not applicable" if stat is None else fmt(stat, 3),
                     fmt(c.get("threshold"), 3),
                     "ok" if c.get("ok") else "FAILED",
                     " — ".join(str(x) for x in (c.get("parameter"), c.get("note")) if x)])
        classes.append(["", "", "", "good" if c.get("ok") else "bad", ""])
    body = [
        table(["check", "statistic", "threshold", "verdict", "where / note"], rows, left=1,
              classes=[[*c[:4], "w"] for c in classes]),
        paragraph(note, note=True),
    ]
    return section("Model adequacy", body, id="adequacy")
