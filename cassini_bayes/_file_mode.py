"""The mode a new file gets: what ``open`` would give under the user's umask (``tempfile.mkstemp``,
behind every atomic write, makes its file private, 0600)."""

from __future__ import annotations

import os

__all__ = ["default_file_mode"]


def default_file_mode() -> int:
    """``0o666`` less the process's umask."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask
