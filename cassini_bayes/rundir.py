"""Output directories of every command: checked before any work, written atomically.

A run directory (``fit``, ``experiment``, ``sbc``, ``simulate``, ``reproduce``) is written into a
hidden temporary sibling (``.NAME.tmp-…``, same file system) which becomes ``NAME`` only when all
its files are complete, so a crash, a full disk or Ctrl-C never leaves a half-written run under the
final name.

What ``--out`` may be (:func:`check_out`, run before any work starts):

- a new path (missing parents are created at the end), or an empty directory;
- an existing non-empty directory only with ``force``, and only when this package wrote it
  (:func:`is_package_output`) and it holds nothing else: ``--force`` never deletes a user's
  folder, nor a file a user put into a run directory (each run directory lists the files it
  was written with in :data:`WRITTEN`; directories written before that list existed are
  replaced whole);
- never a directory holding (or being) one of the run's own input files, even with ``force``;
- its nearest existing ancestor must be a directory we can create entries in (tried by creating
  and removing a temporary directory there).

Replacing an old run (``force``) swaps the two directories with one atomic
``renameat2(RENAME_EXCHANGE)`` where the OS offers it, so a kill at any moment leaves either the
old or the new run under ``NAME``; elsewhere the old run is renamed aside just before the new one
is renamed in. The old run is deleted last.

A process killed outright (SIGKILL, a power cut) cannot remove its temporary directory. Each one
holds a note of its writer (:data:`TEMP_MARK`: host, process id and start time), and every
:class:`RunDir` first removes the temporary directories in its parent whose writer on this host
has ended (:func:`_sweep_stale`); a directory without the note, or written from another host or by
a process still running, is never touched.

Usage::

    check_out(out, force=force, inputs=[telemetry_csv, model_toml])  # before any work
    ...
    with RunDir(out, force=force) as rd:          # rd.path is the temporary directory
        write_posterior(rd.path, idata)
        write_summary(rd.path, summary)
        write_config(rd.path, config)
        write_report(rd.path, display_dir=rd.final)   # cassini_bayes.report
    # here `out` is complete
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import os
import shutil
import socket
import tempfile
import tomllib
import warnings
from collections.abc import Iterable, Mapping
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any, Literal

from cassini_bayes.errors import InputError, as_flag, spelled
from cassini_bayes.files import json_text, make_temp_dir, publish_dir, toml_text
from cassini_bayes.names import a_kind, unit_of

if TYPE_CHECKING:
    from arviz import InferenceData


WRITTEN = ".cassini-bayes-files"   # in every run directory: the files it was written with
TEMP_MARK = ".cassini-bayes-writer"  # in a temporary run directory while it is written: by whom


def _written_files(root: Path) -> list[str]:
    """Every file under ``root`` (relative POSIX paths, sorted), but :data:`WRITTEN` and
    :data:`TEMP_MARK`."""
    return sorted(p.relative_to(root).as_posix() for p in root.rglob("*")
                  if (p.is_file() or p.is_symlink()) and p.name not in (WRITTEN, TEMP_MARK))


def _process_start(pid: int) -> str | None:
    """When process ``pid`` started, as ``"BOOT_ID:TICKS"`` (Linux ``/proc``), or None where the
    system does not say: with the process id it names one process, even after the id is
    reused."""
    try:
        ticks = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[19]
        boot = Path("/proc/sys/kernel/random/boot_id").read_text().strip()
    except (OSError, IndexError):
        return None
    return f"{boot}:{ticks}"


def _mark(tmp: Path) -> None:
    """Note in the temporary directory ``tmp`` which process writes it (:func:`_sweep_stale`)."""
    (tmp / TEMP_MARK).write_text(json.dumps({"host": socket.gethostname(), "pid": os.getpid(),
                                             "started": _process_start(os.getpid())}) + "\n")


def _writer_ended(tmp: Path) -> bool:
    """Whether the process noted in ``tmp``'s :data:`TEMP_MARK` has ended: on this host, its id
    is gone or now names a process that started at another time. False when there is no note,
    it is unreadable, or it is another host's (nothing tells whether that process runs)."""
    try:
        mark = json.loads((tmp / TEMP_MARK).read_text(encoding="utf-8"))
        host, pid, started = mark["host"], mark["pid"], mark["started"]
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError):
        return False
    if host != socket.gethostname() or not isinstance(pid, int) or pid == os.getpid():
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except (PermissionError, OverflowError):
        return False   # (another user's process, running)
    now = _process_start(pid)
    return started is not None and now is not None and now != started


def _discard(tmp: Path) -> None:
    """Remove a temporary directory, its :data:`TEMP_MARK` last (a kill half-way leaves a
    directory that the next :func:`_sweep_stale` still recognises); errors are ignored."""
    try:
        entries = [p for p in tmp.iterdir() if p.name != TEMP_MARK]
    except OSError:
        entries = []
    for p in entries:
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p, ignore_errors=True)
        else:
            with contextlib.suppress(OSError):
                p.unlink()
    shutil.rmtree(tmp, ignore_errors=True)


def _sweep_stale(parent: Path) -> list[Path]:
    """Remove the temporary run directories (``.NAME.tmp-…``) in ``parent`` whose writer has
    ended without cleaning up (killed by SIGKILL, a crash of the machine); returns them. Only
    directories this package made (their :data:`TEMP_MARK`) and whose process on this host is
    gone (:func:`_writer_ended`) are removed."""
    removed: list[Path] = []
    try:
        entries = [p for p in Path(parent).iterdir()
                   if p.name.startswith(".") and ".tmp-" in p.name and p.is_dir()
                   and not p.is_symlink()]
    except OSError:
        return removed
    for p in entries:
        if _writer_ended(p):
            _discard(p)
            removed.append(p)
    return removed


def _foreign_files(root: Path) -> list[str]:
    """Files in the run directory ``root`` that its :data:`WRITTEN` list does not name (none
    when it has no list)."""
    try:
        listed = set((root / WRITTEN).read_text(encoding="utf-8").splitlines())
    except (OSError, UnicodeDecodeError):
        return []
    return [f for f in _written_files(root) if f not in listed]


def _out() -> str:
    return spelled("--out", "out directory")


def _force() -> str:
    return spelled("--force", "force=True")


__all__ = [
    "RunDir",
    "check_out",
    "check_writable",
    "file_record",
    "is_package_output",
    "read_posterior",
    "read_run_file",
    "run_command",
    "run_kind",
    "write_config",
    "write_posterior",
    "write_summary",
]


def read_run_file(run_dir: str | os.PathLike, name: str, *,
                  strict: bool = False) -> dict[str, Any] | None:
    """The run directory's JSON or TOML file ``name`` (by its suffix) as a dict; None when it is
    absent, or (unless ``strict``) unreadable or not a table. ``strict``: an unreadable file is an
    :class:`InputError` naming it."""
    path = Path(run_dir) / name
    toml = name.endswith(".toml")
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return None
    except (OSError, UnicodeDecodeError) as e:
        if strict:
            raise InputError(f"{path}: cannot be read ({e}); re-run the command that wrote "
                             "it") from None
        return None
    try:
        d = tomllib.loads(text) if toml else json.loads(text)
    except ValueError as e:        # (TOMLDecodeError and JSONDecodeError are ValueErrors)
        if strict:
            raise InputError(f"{path}: not valid {'TOML' if toml else 'JSON'} ({e}); re-run "
                             "the fit or fix the file") from None
        return None
    if not isinstance(d, dict):
        if strict:
            raise InputError(f"{path}: expected a JSON object at the top level")
        return None
    return d


def _text_field(run_dir: str | os.PathLike, name: str, key: str) -> str | None:
    value = (read_run_file(run_dir, name) or {}).get(key)
    return value if isinstance(value, str) else None


def run_kind(run_dir: str | os.PathLike) -> str | None:
    """The ``kind`` a fit run directory's ``summary.json`` records (``"inertia"``, ``"thrust"``,
    ``"rwa4"``), or None when there is none to read."""
    return _text_field(run_dir, "summary.json", "kind")


def run_command(run_dir: str | os.PathLike) -> str | None:
    """The command that wrote a run directory (``"fit inertia"``, ``"budget"``, ``"fit health"``
    …): its ``summary.json``'s ``command``, else its ``config.toml``'s; None when neither says."""
    return (_text_field(run_dir, "summary.json", "command")
            or _text_field(run_dir, "config.toml", "command"))


def read_posterior(run_dir: str | os.PathLike, kind: str | None = None,
                   where: str | None = None) -> InferenceData:
    """``posterior.nc`` of a fit's run directory (ArviZ InferenceData); refused, naming
    ``where`` (default the directory), when the directory or the file is missing, the run is a
    fit of another ``kind`` than asked (a thrust run carries inertia draws too), or the file
    cannot be read."""
    from cassini_bayes._arviz import load_arviz

    az = load_arviz()

    run_dir = Path(run_dir)
    where = where or str(run_dir)
    wanted = f"{a_kind(kind)} fit" if kind else "a fit"
    if not run_dir.is_dir():
        raise InputError(f"{where}: run directory not found; give the --out directory of "
                         f"{wanted}")
    nc = run_dir / "posterior.nc"
    if not nc.is_file():
        raise InputError(f"{where}: no posterior.nc there; give the --out directory of {wanted}")
    found = run_kind(run_dir)
    if kind is not None and found not in (None, kind):
        raise InputError(f"{where}: {a_kind(found)} fit; give the --out directory of {wanted}")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return az.from_netcdf(nc)
    except Exception as e:  # netCDF/HDF5 errors have many types
        raise InputError(f"{where}: posterior.nc cannot be read ({type(e).__name__}); re-run "
                         "the fit") from None


def is_package_output(path: str | os.PathLike) -> bool:
    """Whether the directory ``path`` was written by cassini-bayes (so ``--force`` may replace it).

    Recognised by the record each command writes, carrying the package ``version``:
    ``config.toml`` with ``command`` and ``version`` (``fit``, ``sbc``) or a ``[run]`` table with
    ``version`` (``experiment``); ``truth.json`` with ``scenario`` and ``version``
    (``simulate``); ``results.json`` with ``seed`` and ``version`` (``reproduce``).
    """
    p = Path(path)
    cfg = read_run_file(p, "config.toml") or {}
    if {"command", "version"} <= cfg.keys():
        return True
    if isinstance(cfg.get("run"), dict) and "version" in cfg["run"] and "kind" in cfg:
        return True
    truth = read_run_file(p, "truth.json") or {}
    if {"scenario", "version"} <= truth.keys():
        return True
    results = read_run_file(p, "results.json") or {}
    return {"seed", "version"} <= results.keys()


def check_writable(path: Path, out: str) -> None:
    """Refuse (naming ``out``) unless ``path``'s nearest existing ancestor is a directory we can
    create entries in: tried by creating and removing a temporary directory there."""
    anc = path
    while not anc.exists() and anc != anc.parent:
        anc = anc.parent
    if not anc.is_dir():
        raise InputError(f"cannot create it: {anc} is not a directory; choose another "
                         f"{_out()}", path=out)
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".cassini-bayes-probe-", dir=anc))
    except OSError as e:
        raise InputError(f"cannot write in {anc} ({e.strerror}); choose another {_out()}",
                         path=out) from None


def check_out(out: str | os.PathLike, *, force: bool = False,
              inputs: Iterable[str | os.PathLike] = ()) -> Path:
    """Refuse a bad ``--out`` before any work (module docstring); returns it, absolute.

    ``inputs`` are the run's input files and directories: ``out`` may not be, or contain, any of
    them, even with ``force``.
    """
    force = as_flag(force, "force")
    shown = str(out)
    final = Path(out).expanduser().resolve()
    for i in inputs:
        ip = Path(i).expanduser().resolve()
        if ip == final or final in ip.parents:
            raise InputError(f"holds this run's input {i}; {_out()} must be a new directory "
                             f"({_force()} never replaces the inputs)", path=shown)
    if final.exists():
        if not final.is_dir():
            raise InputError(f"exists and is not a directory; choose another {_out()}",
                             path=shown)
        if any(final.iterdir()):
            if not force:
                raise InputError(f"already exists and is not empty; choose another {_out()} "
                                 f"or pass {_force()} to replace it",
                                 path=shown)
            if not is_package_output(final):
                raise InputError("is not a cassini-bayes output directory (no config.toml, "
                                 f"truth.json or results.json written by cassini-bayes); "
                                 f"{_force()} replaces only those: choose another "
                                 f"{_out()}", path=shown)
            foreign = _foreign_files(final)
            if foreign:
                more = f" and {len(foreign) - 3} more" if len(foreign) > 3 else ""
                raise InputError("holds files cassini-bayes did not write "
                                 f"({', '.join(foreign[:3])}{more}); {_force()} would delete "
                                 "them: move them out or "
                                 f"choose another {_out()}", path=shown)
    check_writable(final.parent, shown)
    return final


class RunDir:
    """Context manager writing a run directory atomically (module docstring).

    Attributes
    ----------
    final : the directory's final path (absolute).
    path : the temporary directory to write into (inside the context).
    """

    def __init__(self, out: str | os.PathLike, *, force: bool = False,
                 inputs: Iterable[str | os.PathLike] = ()):
        self.final = check_out(out, force=force, inputs=inputs)
        self.force = force

    path: Path
    """The temporary directory to write into (set on entering the context)."""

    def __enter__(self) -> RunDir:
        parent = self.final.parent
        try:
            parent.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise InputError(f"cannot create the parent directory: {e.strerror}",
                             path=str(parent)) from None
        _sweep_stale(parent)   # what killed runs left here
        self.path = make_temp_dir(parent, f".{self.final.name}.tmp-")
        try:
            _mark(self.path)
        except BaseException:
            shutil.rmtree(self.path, ignore_errors=True)
            raise
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> Literal[False]:
        if exc_type is not None:
            _discard(self.path)
            return False
        try:
            self.commit()
        except BaseException:
            _discard(self.path)
            raise
        return False

    def commit(self) -> None:
        """Move the finished temporary directory to its final name (atomic swap if it exists),
        with the list of its files (:data:`WRITTEN`)."""
        (self.path / WRITTEN).write_text("".join(f + "\n" for f in _written_files(self.path)),
                                         encoding="utf-8")
        if self.final.exists() and any(self.final.iterdir()):
            # the old run may have appeared while this one was computed: check again
            check_out(self.final, force=self.force)
        (self.path / TEMP_MARK).unlink()
        publish_dir(self.path, self.final, discard_old=_discard_marked)


def _discard_marked(old: Path) -> None:
    """Delete an old run swapped out of its place, marked first (:func:`_sweep_stale` finishes
    the job should this process be killed half-way)."""
    _mark(old)
    _discard(old)


def file_record(path: str | os.PathLike) -> dict[str, str]:
    """``{"path": absolute path, "sha256": hex digest}`` of an input file, for ``config.toml``."""
    p = Path(path).resolve()
    h = hashlib.sha256()
    with open(p, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return {"path": str(p), "sha256": h.hexdigest()}


def write_posterior(run_dir: Path, idata: InferenceData) -> Path:
    """``posterior.nc``: the InferenceData, every group (custom ones such as ``residuals`` too).

    Refuses first, as a full disk (``ENOSPC``), when the file system has less room than the
    arrays take plus 16 MiB: the netCDF/HDF5 writer running out of space mid-file printed
    HDF5 tracebacks and could crash the process (the CLI audit's 300 KiB tmpfs)."""
    p = Path(run_dir) / "posterior.nc"
    need = sum(int(ds.nbytes) for ds in (idata[g] for g in idata.groups())) + (16 << 20)
    free = shutil.disk_usage(p.parent).free
    if free < need:
        where = p.parent.parent if p.parent.name.startswith(".") else p.parent  # (RunDir's temp)
        raise OSError(errno.ENOSPC, f"No space left on device: posterior.nc needs about "
                      f"{need >> 20} MiB, {free >> 20} MiB free", str(where))
    for group in ("posterior", "prior"):       # units of the calibration parameters
        if group in idata.groups():
            for name, da in idata[group].data_vars.items():
                if unit_of(str(name)) is not None and "units" not in da.attrs:
                    da.attrs["units"] = unit_of(str(name))
    idata.to_netcdf(str(p))
    return p


def write_summary(run_dir: Path, summary: Mapping) -> Path:
    """``summary.json`` (NaN and infinities written as ``null``)."""
    p = Path(run_dir) / "summary.json"
    p.write_text(json_text(dict(summary)))
    return p


def write_config(run_dir: Path, config: Mapping) -> Path:
    """``config.toml``: the resolved inputs, seed, sampler settings and package version."""
    p = Path(run_dir) / "config.toml"
    p.write_text(toml_text(config))
    return p
