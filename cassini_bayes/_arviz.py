"""ArviZ as the package imports it: once, without numba, its shape-validation log line quiet."""

from __future__ import annotations

import logging
import sys
from types import ModuleType

__all__ = ["load_arviz"]


def load_arviz() -> ModuleType:
    """``arviz``, imported on first use.

    Numba, where installed, is hidden from ArviZ's import: ArviZ would compile a numba ufunc for
    ECDF bands at import (most of a second of every fit's start-up) and route its diagnostics
    through numba kernels, one of which fails under NumPy 2 (``mcse(method="sd")``). Its NumPy
    paths compute the same diagnostics, as they do wherever numba is absent. A process that
    imported numba or ArviZ itself keeps them as they are, and numba stays importable afterwards.

    ArviZ's log line "Shape validation failed" is silenced: a one-chain run's R-hat is
    undefined, which ``summary.json`` and the command's result line say in words.
    """
    if "arviz" not in sys.modules and "numba" not in sys.modules:
        sys.modules["numba"] = None  # type: ignore[assignment]  # an ImportError for ArviZ
        try:
            import arviz
        finally:
            if sys.modules.get("numba", 0) is None:
                del sys.modules["numba"]
    import arviz

    log = getattr(arviz, "_log", None)  # ArviZ's own Logger object, not one of logging's
    if isinstance(log, logging.Logger):
        log.setLevel(logging.ERROR)
    return arviz
