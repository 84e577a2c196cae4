"""Options several commands share, with the ranges they accept."""

from __future__ import annotations

import typer

from cassini_bayes.api._limits import SEED_MAX


def seed_option(default: int | None, help: str) -> typer.models.OptionInfo:
    """A ``--seed`` option taking ``0 .. 2**63 - 1`` (anything else is a usage error, exit 2)."""
    return typer.Option(default, "--seed", min=0, max=SEED_MAX, help=help)


def check_seed(seed: int, source: str) -> int:
    """``seed`` (read from a file, ``source``) when in ``0 .. 2**63 - 1``, else an InputError."""
    from cassini_bayes.errors import InputError

    if not 0 <= seed <= SEED_MAX:
        raise InputError(f"seed {seed} is out of range: use an integer in 0 .. {SEED_MAX}",
                         path=source)
    return seed
