"""JAX's persistent compilation cache for cassini-bayes: on by default, one place to move it.

Without it every process compiles its XLA programs from scratch, the second call as long as
the first. :func:`enable` points JAX's persistent compilation cache at a folder, so a later
process with the same shapes loads the compiled programs instead (docs/performance.md).

Where the cache lives, first match wins:

1. the ``cassini-bayes --jax-cache DIR|off`` option (the CLI calls :func:`enable` with it, and
   exports it as the environment variable below so that worker processes follow);
2. the environment variable ``CASSINI_BAYES_JAX_CACHE`` = ``DIR`` or ``off``;
3. a folder already set through JAX itself (``JAX_COMPILATION_CACHE_DIR`` or
   ``jax.config.update("jax_compilation_cache_dir", ...)`` before cassini_bayes first computes);
4. ``$XDG_CACHE_HOME/cassini-bayes/jax``, else ``~/.cache/cassini-bayes/jax``.

:func:`cassini_bayes.setup_jax`, which every entry point calls before it computes (the command
line, the API functions that compute, the experiments, SBC), calls :func:`enable_once`, so the
library and the CLI alike use the cache; importing the package does not. A library user switches
it off with ``CASSINI_BAYES_JAX_CACHE=off`` in the environment, or moves it with
``enable("/some/dir")`` before the first fit. Every program is kept
(``jax_persistent_cache_min_compile_time_secs = 0``, ``jax_persistent_cache_min_entry_size_bytes
= -1``: no size floor, and JAX may not raise it); programs that call back into Python (the
progress bar) are never cached by JAX. Nothing is evicted: delete the folder to reclaim the space.
A cached program is the very executable a fresh compilation gives, so the draws are bit-identical
with and without the cache (tests/test_jax_cache.py).

:func:`stats` counts, since the process started, the programs loaded from the cache (``hits``),
those compiled although the cache was consulted (``misses``) and, of those, the ones whose entry
was on disk but was not used (``rejected``). Some jaxlib CPU builds reject every entry they wrote
themselves (a CPU-feature mismatch they report only in log lines): after two rejections and no
hit, one warning says so and the cache is switched off for the rest of the process, instead of
silently recompiling (and re-reading) everything.
"""

from __future__ import annotations

import logging
import os
import threading
import warnings
from pathlib import Path
from typing import NamedTuple

__all__ = ["ENV", "OFF", "CacheStats", "resolve", "enable", "enable_once",
           "stats"]

ENV = "CASSINI_BAYES_JAX_CACHE"
OFF = "off"
_OFF_WORDS = frozenset({"off", "0", "false", "no", "none", "disable", "disabled"})
_REJECTIONS_TO_WARN = 2  # rejected entries (and no hit) before the cache is declared unusable

_HITS = "/jax/compilation_cache/cache_hits"
_REQUESTS = "/jax/compilation_cache/compile_requests_use_cache"
_MISS_LOG = "PERSISTENT COMPILATION CACHE MISS"  # jax._src.compiler.log_persistent_cache_miss


class CacheStats(NamedTuple):
    """What this process did with the compilation cache (counts since the process started).

    dir : the cache folder, or ``None`` when the cache is off.
    hits : XLA programs loaded from the cache instead of compiled.
    misses : programs compiled although the cache was consulted (then written to it, unless
        they call back into Python).
    rejected : of the misses, those whose entry was already on disk (unreadable or refused).
    """

    dir: Path | None
    hits: int
    misses: int
    rejected: int

    def to_dict(self) -> dict:
        """The ``[jax_cache]`` table of a fit's ``config.toml``: ``dir`` (or ``"off"``),
        ``hits``, ``misses``, ``rejected``."""
        return {"dir": str(self.dir) if self.dir is not None else OFF, "hits": self.hits,
                "misses": self.misses, "rejected": self.rejected}

    def line(self) -> str:
        """One line for ``--verbose``."""
        if self.dir is None:
            return "jax cache: off"
        return (f"jax cache: dir={self.dir}, hits={self.hits}, misses={self.misses}"
                + (f", rejected={self.rejected}" if self.rejected else ""))


_lock = threading.Lock()
_state: dict = {"dir": None, "hits": 0, "requests": 0, "rejected": 0, "warned": False,
                "listening": False, "jax_own": None}


def _default_dir() -> Path:
    """``$XDG_CACHE_HOME/cassini-bayes/jax`` (when set to an absolute path), else
    ``~/.cache/cassini-bayes/jax``."""
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    base = Path(xdg) if xdg and os.path.isabs(xdg) else Path.home() / ".cache"
    return base / "cassini-bayes" / "jax"


def resolve(setting: str | os.PathLike | None = None) -> Path | None:
    """The cache folder for ``setting`` (a folder, ``"off"``, or ``None``: the environment
    variable, then JAX's own setting, then :func:`_default_dir`); ``None`` means off."""
    if setting is None:
        setting = os.environ.get(ENV) or None
    if setting is None:
        own = _state["jax_own"]
        return Path(own) if own else _default_dir()
    text = str(setting).strip()
    if text.lower() in _OFF_WORDS or not text:
        return None
    return Path(text).expanduser().absolute()


def enable(setting: str | os.PathLike | None = None) -> Path | None:
    """Point JAX's persistent compilation cache at :func:`resolve` (``setting``); returns the
    folder, or ``None`` when off.

    Call it before the first compilation; calling it again moves the cache (later compilations
    use the new folder). JAX creates the folder when it first writes to it; one that cannot be
    created or written gives one warning and no cache.
    """
    import jax
    from jax.experimental.compilation_cache import compilation_cache as cc

    with _lock:
        if not _state["listening"]:  # first call: remember a folder the user gave JAX itself
            _state["jax_own"] = jax.config.jax_compilation_cache_dir
        _listen()
    try:
        path = resolve(setting)
        problem = None if path is None else _unusable(path)
    except RuntimeError as e:  # no home folder to put ~/.cache in
        path, problem = None, str(e)
    if problem:
        warnings.warn(f"JAX compilation cache: cannot use {path or 'the default folder'} "
                      f"({problem}); running without it (set {ENV} to a writable folder, or "
                      "to off)", stacklevel=2)
        path = None
    with _lock:
        if path is not None:
            jax.config.update("jax_compilation_cache_dir", str(path))
            jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
            jax.config.update("jax_persistent_cache_min_entry_size_bytes", -1)
        jax.config.update("jax_enable_compilation_cache", path is not None)
        if path != _state["dir"]:
            cc.reset_cache()  # JAX decides once per process whether (and where) to cache
        _state["dir"] = path
    return path


def enable_once() -> Path | None:
    """:func:`enable` with the default setting, unless this process has set the cache up already
    (through either function): what :func:`cassini_bayes.setup_jax` calls."""
    with _lock:
        done = _state["listening"]
    return _state["dir"] if done else enable()


def _unusable(path: Path) -> str | None:
    """Why JAX could not create or write ``path`` (it creates it at the first compilation), or
    ``None``; nothing is created here."""
    existing = path
    while not existing.exists() and existing.parent != existing:
        existing = existing.parent
    if not existing.is_dir():
        return f"{existing} is not a folder"
    if not os.access(existing, os.W_OK | os.X_OK):
        return f"{existing} is not writable"
    return None


def stats() -> CacheStats:
    """The cache folder and this process's hits, misses and rejected entries so far."""
    with _lock:
        return CacheStats(dir=_state["dir"], hits=_state["hits"],
                          misses=max(0, _state["requests"] - _state["hits"]),
                          rejected=_state["rejected"])


def _on_event(event: str, **_kw) -> None:
    if event == _HITS:
        _state["hits"] += 1
    elif event == _REQUESTS:
        _state["requests"] += 1


class _MissFilter(logging.Filter):
    """Sees JAX's (debug-level) "persistent cache miss" records to tell a rejected entry (its file
    exists) from a new program; passes on only the records the logger would have shown anyway."""

    def __init__(self, logger: logging.Logger) -> None:
        super().__init__()
        self.logger = logger
        self.own_level = logger.level  # the level set before this filter lowered it

    def filter(self, record: logging.LogRecord) -> bool:
        if (isinstance(record.msg, str) and record.msg.startswith(_MISS_LOG)
                and len(record.args or ()) == 2):
            _on_miss(str(record.args[1]))
        parent = self.logger.parent
        shown = self.own_level or (parent.getEffectiveLevel() if parent else logging.WARNING)
        return record.levelno >= shown


def _on_miss(key: str) -> None:
    path = _state["dir"]
    if path is None or not (path / f"{key}-cache").exists():
        return
    _state["rejected"] += 1
    if _state["rejected"] >= _REJECTIONS_TO_WARN and _state["hits"] == 0 and not _state["warned"]:
        _state["warned"] = True
        warnings.warn(f"the JAX compilation cache in {path} refuses the programs it stored "
                      "(some jaxlib CPU builds reject their own entries, e.g. over a CPU-feature "
                      "mismatch, and say so only in log lines): every run recompiles; switched "
                      f"off for this run — set {ENV}=off (or --jax-cache off) to silence this",
                      stacklevel=2)
        import jax
        from jax.experimental.compilation_cache import compilation_cache as cc

        jax.config.update("jax_enable_compilation_cache", False)
        cc.reset_cache()  # JAX decided once per process to use the cache: make it decide again


def _listen() -> None:
    """Register the event listener and the miss filter once per process."""
    if _state["listening"]:
        return
    from jax import monitoring

    _state["listening"] = True
    monitoring.register_event_listener(_on_event)
    logger = logging.getLogger("jax._src.compiler")
    logger.addFilter(_MissFilter(logger))
    if logger.getEffectiveLevel() > logging.DEBUG:
        logger.setLevel(logging.DEBUG)  # the filter drops what was not shown before
