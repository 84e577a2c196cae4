"""The adequacy verdict on the command line: the result line's ending and ``--strict``.

Every command that writes a summary with an ``adequacy`` block (``fit inertia|thrust|rwa4``,
``fit health``, ``monitor leak``, ``budget``; docs/adequacy.md) ends its result line with
:func:`verdict_text` and, under ``--strict``, calls :func:`enforce_adequacy` after its outputs
are written (exit 3, as for a fit that did not converge).
"""

from __future__ import annotations

import typer

__all__ = ["STRICT_ADEQUACY", "failed_checks", "verdict_text", "enforce_adequacy"]

STRICT_ADEQUACY = typer.Option(False, "--strict", help="Exit non-zero (3) when an adequacy "
                                                       "check failed (outputs are still "
                                                       "written).")


def failed_checks(summary: dict) -> list[str] | None:
    """The names of the failed checks of ``summary["adequacy"]``; None without a block."""
    block = summary.get("adequacy")
    if not isinstance(block, dict):
        return None
    return [n for n, c in block.get("checks", {}).items() if not c.get("ok", True)]


def verdict_text(summary: dict) -> str:
    """``"; adequacy ok"`` or ``"; ADEQUACY FAILED: names"`` (Rich markup), ``""`` without a
    block."""
    failed = failed_checks(summary)
    if failed is None:
        return ""
    return ("; [green]adequacy ok[/green]" if not failed
            else f"; [red]ADEQUACY FAILED: {', '.join(failed)}[/red]")


def enforce_adequacy(summary: dict, final, *, strict: bool, what: str, hint: str) -> None:
    """Under ``strict``, raise :class:`~cassini_bayes.errors.InadequateModelError` (exit 3) when
    a check of ``summary`` failed; ``what`` says what does not fit (``"the model does not fit
    the data"``), ``hint`` what to look for. Call it after the outputs are written."""
    from cassini_bayes.errors import InadequateModelError

    failed = failed_checks(summary)
    if strict and failed:
        raise InadequateModelError(
            f"{final}: {what}: adequacy check(s) {', '.join(failed)} failed (summary.json "
            f"\"adequacy\"); outputs written — {hint}")
