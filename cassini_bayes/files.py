"""Every file and folder the package writes: atomically, with one durability and one mode rule,
and the one conversion of results to JSON and TOML.

The rules (all writers, run directories included):

- **Atomic.** A file is written to a hidden temporary sibling (``.NAME.…tmp``, same file
  system) and renamed over ``NAME`` only when complete; a folder likewise
  (:func:`make_temp_dir`, :func:`publish_dir`). A reader never sees half a file, and a failed
  write leaves the old one (if any) untouched.
- **Durable.** The data are ``fsync``-ed before the rename that publishes them, and the parent
  folder after it: a power cut leaves the old or the new content under ``NAME``, never an empty
  file (the rename alone can reach the disk before the data do).
- **Mode.** What ``open``/``mkdir`` would give under the user's umask (``0o666``/``0o777`` less
  the umask): ``tempfile``, behind every atomic write, makes its files and folders private.
- **JSON.** NaN and infinities are written as ``null`` (JSON has neither); arrays and NumPy or
  JAX scalars as lists and numbers (:func:`json_clean`). **TOML** has no null: ``None`` entries
  are dropped (:func:`_toml_clean`).

No heavy imports: any layer may use this module.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import json
import math
import os
import shutil
import tempfile
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

__all__ = [
    "atomic_path",
    "exchange_dirs",
    "finite_or_none",
    "json_clean",
    "json_text",
    "make_temp_dir",
    "publish_dir",
    "toml_text",
    "write_bytes",
    "write_text",
]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _default_file_mode() -> int:
    """``0o666`` less the process's umask (what ``open`` gives a new file)."""
    return 0o666 & ~_umask()


def _default_dir_mode() -> int:
    """``0o777`` less the process's umask (what ``mkdir`` gives a new folder)."""
    return 0o777 & ~_umask()


def _sync_dir(path: str | os.PathLike) -> None:
    """``fsync`` the folder ``path`` (its entries: a rename in it reaches the disk); ignored where
    the OS cannot open a folder for it."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        with contextlib.suppress(OSError):
            os.fsync(fd)
    finally:
        os.close(fd)


def _sync_file(path: str | os.PathLike) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` to write to (by any writer: NumPy, pandas, h5py);
    on a clean exit it is synced and renamed over ``path`` (module docstring), on an error
    removed."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        os.chmod(tmp, _default_file_mode())
        yield Path(tmp)
        _sync_file(tmp)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    _sync_dir(path.parent)


def write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically; returns ``path``."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; returns ``path``."""
    return write_bytes(path, text.encode("utf-8"))


def finite_or_none(x: Any) -> float | None:
    """``float(x)`` when it is a finite number, else ``None`` (JSON nulls, NaN, strings)."""
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def json_clean(x: Any) -> Any:
    """``x`` as JSON can hold it: mappings with string keys, lists for tuples and arrays,
    Python numbers for NumPy/JAX scalars, ``None`` for NaN and infinities."""
    if isinstance(x, Mapping):
        return {str(k): json_clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [json_clean(v) for v in x]
    if hasattr(x, "tolist"):          # NumPy and JAX arrays and scalars
        return json_clean(x.tolist())
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def _toml_clean(x: Any) -> Any:
    """``x`` as TOML can hold it: ``None`` entries dropped (TOML has no null), arrays as lists."""
    if isinstance(x, Mapping):
        return {str(k): _toml_clean(v) for k, v in x.items() if v is not None}
    if isinstance(x, (list, tuple)):
        return [_toml_clean(v) for v in x if v is not None]
    if hasattr(x, "tolist"):
        return _toml_clean(x.tolist())
    return x


def json_text(obj: Any) -> str:
    """``obj`` as the package writes JSON: :func:`json_clean`, indented by 2, a final newline."""
    return json.dumps(json_clean(obj), indent=2, allow_nan=False) + "\n"


def toml_text(obj: Mapping[str, Any]) -> str:
    """``obj`` as the package writes TOML (:func:`_toml_clean`)."""
    import tomli_w

    return tomli_w.dumps(_toml_clean(dict(obj)))




def make_temp_dir(parent: str | os.PathLike, prefix: str) -> Path:
    """A new hidden folder ``PREFIX…`` in ``parent`` with the default folder mode (``mkdtemp``
    makes it private; what is published from it is not)."""
    path = Path(tempfile.mkdtemp(prefix=prefix, dir=parent))
    try:
        os.chmod(path, _default_dir_mode())
    except BaseException:
        shutil.rmtree(path, ignore_errors=True)
        raise
    return path


def _sync_tree(root: str | os.PathLike) -> None:
    """``fsync`` every file and folder under ``root`` (before it is published by a rename)."""
    for here, _, names in os.walk(os.fspath(root)):
        for name in names:
            p = os.path.join(here, name)
            if not os.path.islink(p):
                _sync_file(p)
        _sync_dir(here)


def exchange_dirs(a: Path, b: Path) -> bool:
    """Swap the folders ``a`` and ``b`` in one atomic step (Linux ``renameat2``).

    Returns False where the OS or file system cannot (the caller falls back to two renames).
    """
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                          ctypes.c_uint]
    at_fdcwd, rename_exchange = -100, 2  # <fcntl.h>, <linux/fs.h>
    rc = renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange)
    if rc == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.EINVAL, errno.ENOSYS, errno.ENOTSUP, errno.EOPNOTSUPP):
        return False
    raise OSError(err, os.strerror(err), str(b))


def publish_dir(tmp: Path, final: Path, *,
                discard_old: Callable[[Path], None] | None = None) -> None:
    """Make the finished folder ``tmp`` (a sibling of ``final``) the folder ``final``: synced,
    then renamed into place; an existing ``final`` is swapped out in one step where the OS can
    (else renamed aside just before) and then removed (``discard_old``, default
    ``shutil.rmtree``). A kill at any moment leaves the old or the new folder under ``final``."""
    _sync_tree(tmp)
    discard = discard_old or (lambda p: shutil.rmtree(p, ignore_errors=True))
    if final.exists() and any(final.iterdir()):
        if exchange_dirs(tmp, final):
            _sync_dir(final.parent)
            discard(tmp)                       # now holds the old folder
            return
        old = Path(tempfile.mkdtemp(prefix=f".{final.name}.old-", dir=final.parent))
        os.rmdir(old)
        os.replace(final, old)
        try:
            os.replace(tmp, final)
        except BaseException:
            os.replace(old, final)  # put the old folder back
            raise
        _sync_dir(final.parent)
        shutil.rmtree(old, ignore_errors=True)
        return
    os.replace(tmp, final)  # new, or an empty folder
    _sync_dir(final.parent)
