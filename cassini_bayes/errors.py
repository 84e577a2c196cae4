"""Errors a user can act on.

Every problem with a user's input (a file, a column, a row, a setting) is raised as
:class:`InputError` with a one-line message that names where the problem is and what to do. The
CLI prints that line and exits non-zero; it never shows a traceback for these.
"""

from __future__ import annotations


class CassiniError(Exception):
    """Base class of the package's own errors."""


class InputError(CassiniError, ValueError):
    """Bad user input: the message is one line naming the file/column/row and the fix."""

    def __init__(self, message: str, *, path: str | None = None):
        message = " ".join(str(message).split())  # always one line
        if path is not None and not message.startswith(str(path)):
            message = f"{path}: {message}"
        super().__init__(message)
        self.path = path


class UnidentifiableError(InputError):
    """The data cannot identify a parameter or combination (rank deficiency)."""


class NotConvergedError(CassiniError):
    """Sampler diagnostics failed and ``--strict`` was asked for."""


class Interrupted(CassiniError):
    """The user interrupted a run (Ctrl-C); the message says what was kept and how to go on."""


class InadequateModelError(NotConvergedError):
    """The fit's adequacy checks failed (the model does not fit its data) and ``--strict`` was
    asked for. A kind of :class:`NotConvergedError` so that every ``--strict`` failure is handled
    alike (exit 3, after the run directory is written)."""
