"""Where the shipped data lives, and how a user's input path is resolved and checked.

The spacecraft models, the experiment files and the simulator's scenarios are package data under
``cassini_bayes/data/`` (``models/``, ``experiments/``, ``experiments/scenarios/``), found through
:mod:`importlib.resources`, so an installed wheel carries them; a clone's root-level ``models`` and
``experiments`` are links to the same folders.
"""

from __future__ import annotations

import atexit
import os
import shutil
import tempfile
from importlib.resources import files
from importlib.resources.abc import Traversable
from pathlib import Path

from cassini_bayes.errors import InputError, as_path


def _on_disk(data: Traversable) -> Path:
    """``data`` as a real directory: itself when the package sits on a file system (a wheel
    installed by pip, an editable install), else (a zip import) a copy of the tree, extracted
    once into a temporary directory that is removed at exit."""
    if isinstance(data, Path):
        return data
    dest = Path(tempfile.mkdtemp(prefix="cassini_bayes-data-"))
    atexit.register(shutil.rmtree, dest, ignore_errors=True)

    def copy(src: Traversable, dst: Path) -> None:
        for item in src.iterdir():
            if item.is_dir():
                (dst / item.name).mkdir()
                copy(item, dst / item.name)
            else:
                (dst / item.name).write_bytes(item.read_bytes())

    copy(data, dest)
    return dest


DATA_DIR = _on_disk(files("cassini_bayes") / "data")
MODELS_DIR = DATA_DIR / "models"
EXPERIMENTS_DIR = DATA_DIR / "experiments"
SCENARIOS_DIR = EXPERIMENTS_DIR / "scenarios"


def model_path(name: str | os.PathLike) -> Path:
    """Path of a spacecraft model: a file, or the name of a shipped one.

    ``name`` as given (or with ``.toml`` appended) when that file exists. Otherwise a bare name
    without a directory part (``cassini_post_probe`` or ``cassini_post_probe.toml``) is the
    shipped model of that name under ``models/``; a path with a directory part that does not
    exist is an :class:`InputError` naming it (never a silent fall-back to a shipped model).
    """
    p = as_path(name, "a spacecraft model .toml file or a shipped model's name").expanduser()
    candidates = [p] if p.suffix == ".toml" else [p, p.with_name(p.name + ".toml")]
    for c in candidates:
        if c.is_dir():
            raise InputError("is a directory; give a spacecraft model .toml file", path=str(name))
        if c.exists():
            return c
    if len(p.parts) == 1:
        return MODELS_DIR / candidates[-1].name
    raise InputError("spacecraft model not found (give the path of a .toml file, or the name of "
                     f"one in {MODELS_DIR})", path=str(name))


def text_file(path: str | os.PathLike, what: str) -> str:
    """The contents of a user's UTF-8 text input file; an :class:`InputError` naming it when it
    is missing, a directory, unreadable or not UTF-8 text."""
    p = Path(path)
    if p.is_dir():
        raise InputError(f"is a directory; give the {what} file itself", path=str(path))
    try:
        return p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(f"{what} not found; check the path", path=str(path)) from None
    except OSError as e:
        raise InputError(f"cannot read the {what} ({e.strerror})", path=str(path)) from None
    except UnicodeDecodeError:
        raise InputError(f"is not a UTF-8 text file; give the {what} (TOML)",
                         path=str(path)) from None
