"""Errors a user can act on.

Every problem with a user's input (a file, a column, a row, a setting) is raised as
:class:`InputError` with a one-line message that names where the problem is and what to do. The
CLI prints that line and exits non-zero; it never shows a traceback for these.

A message names the argument to change as its caller spelled it (:func:`spelled`, :func:`arg`):
``method='rcs'`` or ``force=True`` when the library is called from Python, ``--method rcs`` or
``--force`` under the ``cassini-bayes`` command, which runs inside :func:`command_line`.
"""

from __future__ import annotations

import contextlib
import contextvars
import os
from pathlib import Path
from typing import Iterator

_COMMAND_LINE = contextvars.ContextVar("cassini_bayes_command_line", default=False)
_NO_VALUE = object()


@contextlib.contextmanager
def command_line() -> Iterator[None]:
    """Inside this block error messages name command-line options instead of arguments."""
    token = _COMMAND_LINE.set(True)
    try:
        yield
    finally:
        _COMMAND_LINE.reset(token)


def spelled(option: str, argument: str) -> str:
    """``option`` (e.g. ``"--out"``) under the command line, else ``argument`` (``"out"``)."""
    return option if _COMMAND_LINE.get() else argument


def arg(name: str, value: object = _NO_VALUE, *, cli_quote: bool = False) -> str:
    """An argument as the caller spelled it: ``--window-a`` / ``--method rcs`` (``--method
    'rcs'`` with ``cli_quote``) on the command line, ``window_a`` / ``method='rcs'`` from Python
    (``name`` is the Python argument name)."""
    if _COMMAND_LINE.get():
        flag = "--" + name.replace("_", "-")
        if value is _NO_VALUE:
            return flag
        return f"{flag} {value!r}" if cli_quote else f"{flag} {value}"
    return name if value is _NO_VALUE else f"{name}={value!r}"


def with_article(phrase: str) -> str:
    """``phrase`` after ``a`` or ``an`` as it is spoken: ``an inertia``, ``a thrust``, ``an event
    scenario``, ``an RWA4`` (an initialism is read letter by letter: ``an`` before A E F H I L M N
    O R S X)."""
    word = phrase.split(" ", 1)[0]
    initialism = len(word) > 1 and word[:2].isupper()
    an = word[:1] in ("AEFHILMNORSX" if initialism else "aeiouAEIOU")
    return f"{'an' if an else 'a'} {phrase}"


class CassiniError(Exception):
    """Base class of the package's own errors."""


class InputError(CassiniError, ValueError):
    """Bad user input: the message is one line naming the file/column/row and the fix."""

    def __init__(self, message: str, *, path: str | None = None):
        message = " ".join(str(message).split())  # always one line
        if path is not None and not message.startswith(f"{path}:"):  # named once, first
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


def as_path(value: object, what: str) -> Path:
    """``value`` as a :class:`~pathlib.Path` when it is a non-empty ``str`` or ``os.PathLike``,
    else an :class:`InputError` saying what was expected (``what``, e.g. ``"a telemetry
    file"``)."""
    if isinstance(value, (str, os.PathLike)) and str(value):
        return Path(value)
    got = repr(value) if isinstance(value, str) else type(value).__name__
    raise InputError(f"expected the path of {what}, got {got}")


def as_flag(value: object, name: str) -> bool:
    """``value`` when it is a bool (NumPy's included), else an :class:`InputError` naming the
    argument ``name``: a string such as ``"no"`` is truthy and would silently pick the other
    branch."""
    if isinstance(value, bool) or type(value).__name__ == "bool_":
        return bool(value)
    raise InputError(f"{arg(name, value)}: use True or False")
