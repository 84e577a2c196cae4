"""Assembling the InferenceData of a fit: the groups beyond the sampler's own."""

from __future__ import annotations

import warnings

__all__ = ["replace_groups"]


def replace_groups(idata, groups: dict) -> None:
    """Add ``groups`` (name → ``xarray.Dataset``) to ``idata``, replacing any of those names it
    already has (ArviZ warns about non-standard names such as ``residuals``: silenced)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        for name in groups:
            if name in idata.groups():
                del idata[name]
        idata.add_groups(groups)

