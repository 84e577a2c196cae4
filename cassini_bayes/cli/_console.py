"""The Rich console every command reports through."""

from __future__ import annotations


def stderr_console():
    """A Rich console on stderr that never wraps: piped to a file or a CI log, each message and
    the fit's one-line result stay on one line (Rich otherwise wraps at 80 columns when stderr
    is not a terminal); a terminal wraps long lines itself."""
    from rich.console import Console

    return Console(stderr=True, highlight=False, soft_wrap=True)


def escape(text: str) -> str:
    """``text`` (a path, a name, a message) safe to print through the console: Rich would read
    ``run[red]1`` as markup and print ``run1``."""
    from rich.markup import escape as rich_escape

    return rich_escape(text)
