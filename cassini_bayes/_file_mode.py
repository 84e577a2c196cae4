"""The mode a new file or folder gets: what ``open``/``mkdir`` would give under the user's umask
(``tempfile.mkstemp``/``mkdtemp``, behind every atomic write, make theirs private)."""

from __future__ import annotations

import os

__all__ = ["default_file_mode", "default_dir_mode"]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def default_file_mode() -> int:
    """``0o666`` less the process's umask."""
    return 0o666 & ~_umask()


def default_dir_mode() -> int:
    """``0o777`` less the process's umask (``tempfile.mkdtemp`` makes its folder private)."""
    return 0o777 & ~_umask()
