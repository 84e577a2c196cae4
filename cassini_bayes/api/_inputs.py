"""The fit functions' arguments: objects or paths, checked once, errors naming the argument."""

from __future__ import annotations

import functools
import numbers
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, TypeAlias, TypeVar, cast

import numpy as np

from cassini_bayes.api._limits import MAX_CHAINS, MAX_DRAWS, SEED_MAX
from cassini_bayes.errors import InputError, arg, as_flag
from cassini_bayes.names import WHEEL_ERRORS
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import PulseLog, Telemetry

if TYPE_CHECKING:
    from cassini_bayes.api._result import FitResult
    from cassini_bayes.inference.runner import SamplerSettings

__all__ = ["WHEEL_ERRORS", "SEED_MAX", "spacecraft_input", "telemetry_inputs", "pulse_inputs",
           "one_telemetry", "one_pulse_log", "choice", "number", "sampler_settings",
           "check_seed", "shows_progress"]

PathLike = str | os.PathLike

# The public functions' argument types: an object, or a file (a shipped model or scenario by
# name) to read it from.
TelemetryArg: TypeAlias = "Telemetry | str | os.PathLike"
TelemetriesArg: TypeAlias = "TelemetryArg | Sequence[TelemetryArg]"
PulsesArg: TypeAlias = "PulseLog | str | os.PathLike"
PulseLogsArg: TypeAlias = "PulsesArg | Sequence[PulsesArg]"
SpacecraftArg: TypeAlias = "Spacecraft | str | os.PathLike"
FitArg: TypeAlias = "FitResult | str | os.PathLike"
"""An earlier fit: its result, or its run directory."""
WheelErrors = Literal["per_wheel", "common"]


_Fit = TypeVar("_Fit", bound=Callable[..., Any])


def shows_progress(fit: _Fit) -> _Fit:
    """Decorate a fit function: with ``progress=True`` its steps are shown on the terminal
    (:func:`cassini_bayes.inference.progress.shown`) while it runs."""
    @functools.wraps(fit)
    def wrapper(*args: Any, progress: bool = False, **kwargs: Any) -> Any:
        from cassini_bayes.inference.progress import shown

        with shown(as_flag(progress, "progress")):
            return fit(*args, progress=progress, **kwargs)

    return cast(_Fit, wrapper)


def _is_path(x: object) -> bool:
    return isinstance(x, (str, os.PathLike))


def _record(source: str) -> tuple[dict[str, str], list[Path]]:
    """config.toml's record of a loaded input and its file: path and sha256 when ``source`` is a
    file, else where it came from (and no file)."""
    from cassini_bayes.rundir import file_record

    if source and Path(source).is_file():
        return file_record(source), [Path(source)]
    return {"source": str(source)}, []


def spacecraft_input(spacecraft: Spacecraft | PathLike) -> tuple[Spacecraft, dict, list[Path]]:
    """``(model, config record, input paths)`` of a spacecraft argument: a
    :class:`~cassini_bayes.spacecraft.Spacecraft`, a TOML path or a shipped model's name."""
    from cassini_bayes._paths import model_path
    from cassini_bayes.rundir import file_record
    from cassini_bayes.spacecraft import load_spacecraft

    if isinstance(spacecraft, Spacecraft):  # no file: config.toml's [spacecraft] holds it all
        return spacecraft, {"model": spacecraft.name}, []
    if not _is_path(spacecraft) or not str(spacecraft):
        raise InputError(f"{arg('spacecraft')}: give a Spacecraft, a model .toml path or "
                         "a shipped model's name (e.g. 'cassini_post_probe')")
    path = model_path(spacecraft)
    sc = load_spacecraft(spacecraft)
    return sc, file_record(path), [path]


def _items(x: Any, name: str) -> list:
    if x is None:
        return []
    if _is_path(x) or isinstance(x, (Telemetry, PulseLog)):
        return [x]
    if isinstance(x, (list, tuple)):
        return list(x)
    raise InputError(f"{arg(name)}: give a path, a loaded object or a list of them, not "
                     f"{type(x).__name__}")


def telemetry_inputs(telemetry: TelemetriesArg, name: str = "telemetry",
                     spacecraft: Spacecraft | None = None
                     ) -> tuple[list[Telemetry], list[dict], list[Path]]:
    """``(telemetries, config records, input paths)`` of a telemetry argument: a
    :class:`~cassini_bayes.telemetry.Telemetry` or a file path, or a list of them; files are read
    with the columns of ``spacecraft``'s wheels and thrusters (Cassini's without one), and a
    Telemetry must name wheels of it."""
    from cassini_bayes.rundir import file_record
    from cassini_bayes.telemetry import (
        check_model_names,
        read_telemetry,
        read_telemetry_many,
        validate_telemetry,
    )

    items = _items(telemetry, name)
    if not items:
        raise InputError(f"{arg(name)}: give at least one telemetry file or Telemetry")
    if all(_is_path(x) for x in items):  # all files: read together (errors name the file)
        paths = [Path(x) for x in items]
        tels = read_telemetry_many(paths, spacecraft=spacecraft)
        return _once(tels, name), [file_record(p) for p in paths], paths
    tels, records, paths = [], [], []
    for x in items:
        if _is_path(x):
            tels.append(read_telemetry(x, spacecraft=spacecraft))
            records.append(file_record(x))
            paths.append(Path(x))
        elif isinstance(x, Telemetry):  # checked with the file rules, as a file would be
            record, files = _record(x.source)
            if spacecraft is not None:
                check_model_names(x, spacecraft)
            tels.append(validate_telemetry(x))
            records.append(record)
            paths += files
        else:
            raise InputError(f"{arg(name)}: {type(x).__name__} is not a telemetry file or "
                             "Telemetry")
    return _once(tels, name), records, paths


def _once(tels: list[Telemetry], name: str) -> list[Telemetry]:
    """``tels`` when no record is given twice (same times and rates), else an InputError: a
    fit counts each file as independent evidence, so a repeat would halve the variance of what
    it measures."""
    import hashlib

    seen: dict[str, str] = {}
    for tel in tels:
        digest = hashlib.sha256(np.ascontiguousarray(tel.t, float).tobytes()
                                + np.ascontiguousarray(tel.omega, float).tobytes()).hexdigest()
        if digest in seen:
            raise InputError(f"{arg(name)}: {tel.source} holds the same samples as "
                             f"{seen[digest]}; each file counts as independent evidence, so "
                             "give it once")
        seen[digest] = tel.source
    return tels


def one_telemetry(telemetry: TelemetryArg, name: str = "telemetry", *, check_units: bool = True,
                  spacecraft: Spacecraft | None = None) -> Telemetry:
    """One telemetry argument, a :class:`~cassini_bayes.telemetry.Telemetry` or a file path,
    read or checked with the file rules (``check_units``: the rpm-vs-rad/s heuristics; columns
    of ``spacecraft``'s wheels and thrusters, Cassini's without one)."""
    from cassini_bayes.telemetry import check_model_names, read_telemetry, validate_telemetry

    check_units = as_flag(check_units, "check_units")
    if isinstance(telemetry, Telemetry):
        if spacecraft is not None:
            check_model_names(telemetry, spacecraft)
        return validate_telemetry(telemetry, check_units=check_units)
    if not _is_path(telemetry):
        raise InputError(f"{arg(name)}: give a telemetry file path or a Telemetry, not "
                         f"{type(telemetry).__name__}")
    return read_telemetry(telemetry, check_units=check_units, spacecraft=spacecraft)


def _model_pulses(log: PulseLog, spacecraft: Spacecraft | None) -> PulseLog:
    """``log`` when its thrusters are ``spacecraft``'s (or no model is given), else an
    InputError naming both."""
    if spacecraft is not None and tuple(log.thruster_names) != spacecraft.thruster_names:
        have = ", ".join(spacecraft.thruster_names) or "none"
        raise InputError(f"its thrusters ({', '.join(log.thruster_names)}) are not those of the "
                         f"spacecraft model {spacecraft.name!r} ({have})", path=log.source)
    return log


def one_pulse_log(pulses: PulsesArg, name: str = "pulses", *,
                  spacecraft: Spacecraft | None = None) -> PulseLog:
    """One pulse-log argument, a :class:`~cassini_bayes.telemetry.PulseLog` or a CSV path,
    read or checked with the file rules (thrusters of ``spacecraft``; Cassini's without one)."""
    from cassini_bayes.telemetry import read_pulses, validate_pulses

    if isinstance(pulses, PulseLog):
        return validate_pulses(_model_pulses(pulses, spacecraft))
    if not _is_path(pulses):
        raise InputError(f"{arg(name)}: give a pulse-log file path or a PulseLog, not "
                         f"{type(pulses).__name__}")
    return read_pulses(pulses, spacecraft=spacecraft)


def pulse_inputs(pulses: PulseLogsArg | None, name: str = "pulses",
                 spacecraft: Spacecraft | None = None
                 ) -> tuple[list[PulseLog], list[dict], list[Path]]:
    """``(pulse logs, config records, input paths)`` of a pulse-log argument: a
    :class:`~cassini_bayes.telemetry.PulseLog` or a CSV path, or a list of them (thrusters of
    ``spacecraft``; Cassini's without one)."""
    from cassini_bayes.rundir import file_record
    from cassini_bayes.telemetry import read_pulses

    logs, records, paths = [], [], []
    for x in _items(pulses, name):
        if _is_path(x):
            logs.append(read_pulses(x, spacecraft=spacecraft))
            records.append(file_record(x))
            paths.append(Path(x))
        elif isinstance(x, PulseLog):
            record, files = _record(x.source)
            logs.append(_model_pulses(x, spacecraft))
            records.append(record)
            paths += files
        else:
            raise InputError(f"{arg(name)}: {type(x).__name__} is not a pulse-log file or "
                             "PulseLog")
    return logs, records, paths


_S = TypeVar("_S", bound=str)


def choice(name: str, value: _S, choices: Sequence[str]) -> _S:
    """``value`` when it is one of ``choices``, else an InputError naming the argument."""
    if value not in choices:
        raise InputError(f"{arg(name, value, cli_quote=True)}: choose "
                         + " or ".join(repr(c) for c in choices))
    return value


def _finite_within(value: Any, lo: float | None, hi: float | None) -> bool:
    return bool(np.isfinite(value) and (lo is None or value >= lo) and (hi is None or value <= hi))


def number(name: str, value: Any, *, lo: float | None = None, hi: float | None = None,
           integer: bool = False, where: str | None = None) -> float | int:
    """``value`` when it is a real number (an integer with ``integer``) in ``[lo, hi]``, else
    an InputError naming the argument (``where``: its name as spelled, default
    :func:`~cassini_bayes.errors.arg`'s)."""
    kind = numbers.Integral if integer else numbers.Real   # NumPy scalars included
    ok = (not isinstance(value, bool) and isinstance(value, kind)
          and _finite_within(value, lo, hi))
    if not ok:
        want = "an integer" if integer else "a number"
        rng = (f" in {lo:g} .. {hi:g}" if lo is not None and hi is not None else
               f" of at least {lo:g}" if lo is not None else
               f" of at most {hi:g}" if hi is not None else "")
        raise InputError(f"{where or arg(name)}: use {want}{rng}, got {value!r}")
    return int(value) if integer else float(value)


def check_seed(seed: int) -> int:
    """``seed`` when an integer in ``0 .. 2**63 - 1``, else an InputError."""
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= SEED_MAX:
        raise InputError(f"{arg('seed', seed)}: use an integer in 0 .. {SEED_MAX}")
    return seed


def sampler_settings(chains: int, warmup: int, draws: int, target_accept: float,
                     progress: bool = False) -> SamplerSettings:
    """:class:`~cassini_bayes.inference.runner.SamplerSettings` from the fit functions'
    arguments, checked against the ranges the command line accepts; warns (once) when the
    chains must run vectorised because JAX started before the fit could ask for devices."""
    from cassini_bayes._devices import warn_if_vectorised
    from cassini_bayes.inference.runner import SamplerSettings

    for name, value, lo, hi in (("chains", chains, 1, MAX_CHAINS),
                                ("warmup", warmup, 10, MAX_DRAWS),
                                ("draws", draws, 10, MAX_DRAWS)):
        if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
            raise InputError(f"{arg(name, value)}: use an integer in {lo} .. {hi}")
    target_accept = number("target_accept", target_accept, lo=0.5, hi=0.999)
    warn_if_vectorised(chains)
    return SamplerSettings(chains=chains, warmup=warmup, draws=draws,
                           target_accept=target_accept, progress=as_flag(progress, "progress"))
