"""The commanded and reported events of a scenario: ``[[slew]]``, ``[[wheel_ramp]]``,
``[[deadband]]``, ``[[pulse]]``, ``[[window]]`` and ``[leak]``, one reader each; every time lies
within the run."""

from __future__ import annotations

import numpy as np

from cassini_bayes._toml import TomlTable
from cassini_bayes.errors import InputError
from cassini_bayes.simulate.controllers import COMMAND_RESOLUTION_S, MIN_PULSE_S
from cassini_bayes.simulate.scenario._sections import Initial, RunSettings
from cassini_bayes.simulate.scenario._truth import wheel_index
from cassini_bayes.simulate.scenario._types import (DeadbandChange, Leak, PulseCommand, Slew,
                                                    WheelRamp, Window)
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import OMEGA_ABS_MAX, WHEEL_RPM_MAX
from cassini_bayes.units import RPM_TO_RAD_S


def _check_time(entry: TomlTable, key: str, t_s: float, duration_s: float) -> None:
    if not 0.0 <= t_s <= duration_s:
        raise entry.err(key, f"= {t_s} s lies outside the run [0, {duration_s}] s")


def _on_command_grid(t_s: float) -> bool:
    return abs(t_s / COMMAND_RESOLUTION_S - round(t_s / COMMAND_RESOLUTION_S)) <= 1e-9


def thruster_index(entry: TomlTable, key: str, truth: Spacecraft) -> int:
    """Index of the thruster ``entry[key]`` names among the truth model's (case-insensitive)."""
    name = entry.string(key)
    names = [n.upper() for n in truth.thruster_names]
    if name.upper() not in names:
        have = ", ".join(truth.thruster_names) or "none"
        raise entry.err(key, f"must be a thruster of the truth model {truth.name!r} ({have}), "
                             f"got {name!r}")
    return names.index(name.upper())


def read_slews(top: TomlTable, run: RunSettings) -> list[Slew]:
    """``[[slew]]``: one at a time, within the run, under RWA control."""
    duration = run.duration_s
    slews: list[Slew] = []
    for entry in top.items("slew", {"t_start_s", "axis", "angle_deg", "rate_mrad_s",
                                    "accel_mrad_s2"}):
        t0 = entry.num("t_start_s")
        _check_time(entry, "t_start_s", t0, duration)
        slew = Slew(t0, tuple(entry.vec("axis", unit=True)), np.deg2rad(entry.num("angle_deg")),
                    entry.num("rate_mrad_s", positive=True, hi=OMEGA_ABS_MAX * 1e3) * 1e-3,
                    entry.num("accel_mrad_s2", positive=True) * 1e-3)
        if slew.t_end_s > duration:
            raise entry.err("t_start_s", f"slew ends at {slew.t_end_s:.1f} s, after the run "
                                         f"({duration} s)")
        if slews and t0 < slews[-1].t_end_s:
            raise entry.err("t_start_s", f"= {t0} s starts before the previous slew ends "
                                         f"({slews[-1].t_end_s:.1f} s); slews run one at a time")
        slews.append(slew)
    if slews and run.control != "rwa":
        raise InputError("[[slew]] needs 'run.control = \"rwa\"'", path=top.src)
    return slews


def read_wheel_ramps(top: TomlTable, run: RunSettings, truth: Spacecraft,
                     initial: Initial) -> list[WheelRamp]:
    """``[[wheel_ramp]]``: wheel biasing of a wheel that is on, under RCS control."""
    ramps = []
    for entry in top.items("wheel_ramp", {"wheel", "t_start_s", "target_rpm", "torque_nm"}):
        j = wheel_index(truth, entry.string("wheel"), entry.where + "wheel", top.src)
        if not initial.wheels_on[j]:
            raise entry.err("wheel", "is not in 'initial.wheels_on'")
        t0 = entry.num("t_start_s")
        _check_time(entry, "t_start_s", t0, run.duration_s)
        ramps.append(WheelRamp(j, t0,
                               entry.num("target_rpm", hi=WHEEL_RPM_MAX) * RPM_TO_RAD_S,
                               entry.num("torque_nm", positive=True, hi=10.0)))
    if ramps and run.control != "rcs":
        raise InputError("[[wheel_ramp]] needs 'run.control = \"rcs\"' (under RWA control the "
                         "attitude controller drives the wheels)", path=top.src)
    return ramps


def read_deadbands(top: TomlTable, run: RunSettings) -> list[DeadbandChange]:
    """``[[deadband]]``: RCS dead-band changes (mrad in the file), in time order."""
    changes = []
    for entry in top.items("deadband", {"t_s", "deadband_mrad"}):
        t0 = entry.num("t_s")
        _check_time(entry, "t_s", t0, run.duration_s)
        deadband_mrad = entry.vec("deadband_mrad")
        if np.any(deadband_mrad <= 0):
            raise entry.err("deadband_mrad", "must be positive (mrad)")
        changes.append(DeadbandChange(t0, tuple(deadband_mrad * 1e-3)))
    return sorted(changes, key=lambda c: c.t_s)


def read_pulses(top: TomlTable, run: RunSettings, truth: Spacecraft) -> list[PulseCommand]:
    """``[[pulse]]``: open-loop pulses on the 1/8 s command grid, at least the minimum pulse;
    a run with thrusters firing steps at the command resolution."""
    pulses = []
    for entry in top.items("pulse", {"t_on_s", "thruster", "width_s"}):
        k = thruster_index(entry, "thruster", truth)
        t0 = entry.num("t_on_s")
        _check_time(entry, "t_on_s", t0, run.duration_s)
        width = entry.num("width_s", positive=True)
        for key, value in (("t_on_s", t0), ("width_s", width)):
            if not _on_command_grid(value):
                raise entry.err(key, f"= {value} is not on the 1/8 s command grid")
        if width < MIN_PULSE_S:
            raise entry.err("width_s", f"= {width} s is below the 125 ms minimum pulse")
        pulses.append(PulseCommand(t0, k, width))
    if (run.control == "rcs" or pulses) and abs(run.dt_s - COMMAND_RESOLUTION_S) > 1e-12:
        raise run.section.err("dt_s", "must be 0.125 s when thrusters fire (the 1/8 s command "
                                      "resolution)")
    return pulses


def read_windows(top: TomlTable, run: RunSettings) -> list[Window]:
    """``[[window]]``: named quiet windows ``t0_s < t1_s`` within the run."""
    windows = []
    for entry in top.items("window", {"name", "t0_s", "t1_s"}):
        t0, t1 = entry.num("t0_s"), entry.num("t1_s")
        _check_time(entry, "t0_s", t0, run.duration_s)
        _check_time(entry, "t1_s", t1, run.duration_s)
        if t1 <= t0:
            raise entry.err("t1_s", f"= {t1} must be after t0_s = {t0}")
        windows.append(Window(entry.string("name"), t0, t1))
    return windows


def read_leak(top: TomlTable, run: RunSettings, truth: Spacecraft) -> Leak | None:
    """The optional ``[leak]`` section (all three keys required)."""
    if not top.has("leak"):
        return None
    section = top.sub("leak", {"thruster", "fraction", "t_start_s"})
    k = thruster_index(section, "thruster", truth)
    fraction = section.num("fraction", positive=True)
    if fraction > 1.0:
        raise section.err("fraction", f"= {fraction} must be at most 1 (a fraction of the thrust)")
    t0 = section.num("t_start_s")
    _check_time(section, "t_start_s", t0, run.duration_s)
    return Leak(k, fraction, t0)
