"""What a fit is doing, shown on the terminal while it runs (rich): one line per step a person
waits on — checking the data, preparing the problem (least squares, the Laplace step),
compiling or loading the sampler, warm-up and sampling (a bar), the summaries and adequacy
checks, writing the run directory.

:func:`shown` opens the display around a whole fit (the CLI does, only when stderr is a
terminal; the library's ``progress=True`` does too); :func:`step` marks one step inside it and
does nothing at all when no display is open, so library code can mark its steps
unconditionally. Nothing here touches JAX: the sampler's bar is fed by
:mod:`cassini_bayes.inference.runner` (a callback compiled into the sampler only when the bar is
shown; programs with callbacks are not kept in the compilation cache, docs/performance.md).
"""

from __future__ import annotations

from contextlib import contextmanager
from typing import Iterator

__all__ = ["shown", "step", "active"]

_STATE: dict = {"progress": None}


def active():
    """The open ``rich.progress.Progress``, or ``None``."""
    return _STATE["progress"]


@contextmanager
def shown(enabled: bool = True) -> Iterator[None]:
    """Show the steps of the enclosed work on stderr (transient: the lines go when done).

    Nested calls, and ``enabled=False``, add nothing.
    """
    if not enabled or _STATE["progress"] is not None:
        yield
        return
    from rich.console import Console
    from rich.progress import BarColumn, Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

    with Progress(SpinnerColumn(), TextColumn("{task.description}"), BarColumn(),
                  TimeElapsedColumn(), console=Console(stderr=True), transient=True) as progress:
        _STATE["progress"] = progress
        try:
            yield
        finally:
            _STATE["progress"] = None


@contextmanager
def step(description: str, total: int | None = None) -> Iterator[object]:
    """Mark one step: a line with ``description`` (and a bar when ``total`` is given) while the
    block runs; yields the rich task id (``None`` when nothing is shown)."""
    progress = _STATE["progress"]
    if progress is None:
        yield None
        return
    task = progress.add_task(description, total=total)
    try:
        yield task
    finally:
        progress.remove_task(task)
