"""Assembling the InferenceData of a fit: the groups beyond the sampler's own."""

from __future__ import annotations

import warnings

__all__ = ["replace_groups", "quiet_arviz_shape_warnings"]


def replace_groups(idata, groups: dict) -> None:
    """Add ``groups`` (name → ``xarray.Dataset``) to ``idata``, replacing any of those names it
    already has (ArviZ warns about non-standard names such as ``residuals``: silenced)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        for name in groups:
            if name in idata.groups():
                del idata[name]
        idata.add_groups(groups)


def quiet_arviz_shape_warnings() -> None:
    """Silence ArviZ's log line "Shape validation failed" (a one-chain run: its R-hat is
    undefined, which ``summary.json`` and the command's result line say in words). ArviZ logs
    through its own ``Logger`` object, not one of the ``logging`` module's, so it is reached
    through the package."""
    import logging

    import arviz

    log = getattr(arviz, "_log", None)
    if isinstance(log, logging.Logger):
        log.setLevel(logging.ERROR)
