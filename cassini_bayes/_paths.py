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


def input_path(name: str | os.PathLike, what: str, shipped: Path | None = None,
               suffix: str | None = ".toml") -> Path:
    """The path of a user's input file: the one rule of every file argument (docs/cli.md).

    ``name`` as given, or with ``suffix`` appended, when that file exists. Otherwise, when
    ``shipped`` is a folder of shipped files, a bare name without a directory part
    (``cassini_post_probe`` or ``cassini_post_probe.toml``) is the shipped file of that name.
    Anything else is an :class:`InputError` naming ``name``: a path with a directory part is
    never a silent fall-back to a shipped file (``typo/slews_post_probe.toml`` is refused, not
    read as the shipped ``slews_post_probe``). ``what`` names the kind of file (``"spacecraft
    model"``), ``suffix`` its extension (``None``: any).
    """
    from cassini_bayes.errors import with_article

    kind = f"{what} {suffix} file" if suffix else f"{what} file"
    given = as_path(name, with_article(kind) + (f" or a shipped {what}'s name" if shipped
                                                 else "")).expanduser()
    candidates = [given] if not suffix or given.suffix == suffix else \
        [given, given.with_name(given.name + suffix)]
    for c in candidates:
        if c.is_dir():
            raise InputError(f"is a directory; give {with_article(kind)}", path=str(name))
        if c.exists():
            return c
    bare = not any(sep and sep in str(name) for sep in (os.sep, os.altsep))
    if shipped is not None and bare:
        own = shipped / candidates[-1].name
        if own.is_file():
            return own
        names = sorted(f.stem for f in shipped.glob(f"*{suffix or ''}") if f.is_file())
        raise InputError(f"no such file, and no shipped {what} of that name (shipped: "
                         f"{', '.join(names)})", path=str(name))
    missing = next((a for a in reversed(given.parents) if not a.exists()), None)
    where = f" (the folder {missing} does not exist)" if missing is not None else ""
    also = (f", or give the bare name of a shipped one (in {shipped.name}/)"
            if shipped is not None else "")
    raise InputError(f"{what} file not found{where}; check the path{also}", path=str(name))


def model_path(name: str | os.PathLike) -> Path:
    """Path of a spacecraft model: a file, or the name of one shipped in ``models/``
    (:func:`input_path`)."""
    return input_path(name, "spacecraft model", MODELS_DIR)


def not_utf8(path: str | os.PathLike, what: str) -> str:
    """Why the file ``path`` is not UTF-8 text, for a one-line error about ``what`` (``"telemetry
    CSV"``): compressed, UTF-16 or binary named as such, else the first byte that is not UTF-8,
    its line, and what it reads as in Latin-1 / Windows-1252 (the usual culprit: a file saved in
    a legacy encoding, ``é`` as the one byte 0xE9)."""
    import codecs

    try:
        with open(path, "rb") as f:
            head = f.read(8192)
            if head[:2] == b"\x1f\x8b":
                return f"is gzip-compressed; decompress it (gunzip) and give the {what}"
            if head[:4] == b"PK\x03\x04":
                return f"is a zip archive; extract the {what} from it"
            if head[:2] in (b"\xff\xfe", b"\xfe\xff"):
                return (f"is UTF-16 text, not UTF-8 (the expected encoding); save the {what} "
                        "as UTF-8")
            if b"\x00" in head:
                return f"is a binary file, not UTF-8 text; give the {what}"
            f.seek(0)
            decoder = codecs.getincrementaldecoder("utf-8")()
            line, chunk = 1, f.read(1 << 20)
            while chunk:
                try:
                    decoder.decode(chunk)
                except UnicodeDecodeError as e:
                    # e.object is the decoder's pending bytes (the end of the chunk before, no
                    # newline among them) followed by this chunk
                    bad = e.object[e.start]
                    line += chunk[:max(e.start - (len(e.object) - len(chunk)), 0)].count(b"\n")
                    char = bytes([bad]).decode("cp1252", errors="ignore") or chr(bad)
                    return (f"is not UTF-8 (the expected encoding) but looks like Latin-1 / "
                            f"Windows-1252: line {line} holds the byte 0x{bad:02X}, {char!r} in "
                            f"that encoding; save the {what} as UTF-8")
                line += chunk.count(b"\n")
                chunk = f.read(1 << 20)
    except OSError as e:
        return f"cannot be read ({e.strerror}); check the path and its permissions"
    return f"is not UTF-8 text (the expected encoding); save the {what} as UTF-8"


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
        raise InputError(not_utf8(p, f"{what} TOML"), path=str(path)) from None
