"""Limits of a calibration plan: a TOML file, loaded and checked (docs/planning.md).

Schema (SI inside; the file's units are in the key names)::

    name = "..."                    description = "..."
    [limits]
    duration_s = 5400.0             # the whole calibration, first sample to last (required)
    quiet_s = 300.0                 # rest before the first slew, between slews, after the last
    max_body_rate_mrad_s = 3.0      # largest body rate |ω| (required)
    max_axis_rate_mrad_s = [3, 3, 0.3]   # optional: largest rate about each body axis
    max_body_accel_mrad_s2 = 0.03   # optional: largest commanded body acceleration
    max_slew_deg = 90.0             # optional: largest angle of one slew
    max_wheel_rpm = 2000.0          # largest wheel speed (required)
    max_wheel_torque_nm = 0.2       # largest wheel motor torque (required)
    max_wheel_momentum_nms = 34.0   # largest momentum of one wheel, J |ρ| (optional)
    min_pulse_s = 0.125             # shortest thruster pulse (thrust plans; default 0.125 s)
    max_pulse_s = 0.75              # longest thruster pulse (thrust plans; default 0.75 s)
    thrusters = ["Z1", "Z2", ...]   # thrusters a thrust plan may fire (default all)
    [run]       dt_s, sample_period_s        (the telemetry the calibration will use)
    [initial]   wheels_on, q, wheel_rpm      (the spacecraft when the plan starts)
    [noise]     as a scenario's              (the sensors the calibration will use)
    [rwa_controller]  as a scenario's
    [rcs_controller]  as a scenario's (thrust plans: the dead-band controller of a biasing event)

``[run]``, ``[initial]``, ``[noise]`` and ``[rwa_controller]`` have a scenario's keys
(:mod:`cassini_bayes.simulate.scenario`): a plan is written as a scenario made of them, the
spacecraft model as truth and prior, and the planned ``[[slew]]`` list. Every impossible or
inconsistent value is one :class:`~cassini_bayes.errors.InputError` line naming the key: a
limit that is not positive, a duration shorter than one slew, wheel limits below the wheel
speeds the plan starts from.
"""

from __future__ import annotations

import copy
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from cassini_bayes._paths import EXPERIMENTS_DIR, input_path
from cassini_bayes._toml import TomlTable, read_toml
from cassini_bayes.errors import InputError
from cassini_bayes.simulate.controllers import MIN_PULSE_S
from cassini_bayes.simulate.scenario import Scenario, scenario_from_dict
from cassini_bayes.spacecraft import Spacecraft

__all__ = [
    "ACCEL_TORQUE_SHARE",
    "LIMITS_DIR",
    "Limits",
    "accel_bound",
    "base_scenario_dict",
    "limits_from_dict",
    "limits_path",
    "load_limits",
    "torque_per_accel",
]

LIMITS_DIR = EXPERIMENTS_DIR / "limits"
ACCEL_TORQUE_SHARE = 0.5
"""Share of the wheel torque limit a planned slew's acceleration may use; the rest is left to the
controller's gyroscopic and feedback torques (checked on the simulated telemetry)."""
_TOP = {"name", "description", "limits", "run", "initial", "noise", "rwa_controller",
        "rcs_controller"}
_LIMIT_KEYS = {"duration_s", "quiet_s", "max_body_rate_mrad_s", "max_axis_rate_mrad_s",
               "max_body_accel_mrad_s2", "max_slew_deg", "max_wheel_rpm",
               "max_wheel_torque_nm", "max_wheel_momentum_nms", "min_pulse_s", "max_pulse_s",
               "thrusters"}
MAX_PULSE_S = 0.75
"""Default longest pulse of a thrust plan (s): Cassini's biasing events' (Feldman & Lee §V)."""
_REQUIRED = ("duration_s", "max_body_rate_mrad_s", "max_wheel_rpm", "max_wheel_torque_nm")


@dataclass(frozen=True)
class Limits:
    """Checked limits of a plan (SI).

    duration_s, quiet_s : s. rate_max_rad_s : largest |ω|; axis_rate_max_rad_s (3,) per body
    axis (inf: none). accel_max_rad_s2 : largest commanded acceleration (inf: only the wheel
    torque bounds it). slew_max_rad : largest angle of one slew (inf: none).
    wheel_rate_max_rad_s, wheel_torque_max_nm, wheel_momentum_max_nms : per wheel (momentum inf:
    none). min_pulse_s, max_pulse_s : shortest and longest thruster pulse, s.
    sections : the file's scenario sections (``run``, ``initial``, ``noise``,
    ``rwa_controller``, ``rcs_controller``), as read. name, source : the file's name and path.
    thrusters : the thrusters a thrust plan may fire (``None``: all).
    """

    name: str
    description: str
    source: str
    duration_s: float
    quiet_s: float
    rate_max_rad_s: float
    axis_rate_max_rad_s: tuple[float, float, float]
    accel_max_rad_s2: float
    slew_max_rad: float
    wheel_rate_max_rad_s: float
    wheel_torque_max_nm: float
    wheel_momentum_max_nms: float
    min_pulse_s: float
    sections: dict
    max_pulse_s: float = MAX_PULSE_S
    thrusters: tuple[str, ...] | None = None

    def to_dict(self) -> dict:
        """The limits as a file would state them (``[limits]`` keys, the file's units)."""
        out = {"duration_s": self.duration_s, "quiet_s": self.quiet_s,
               "max_body_rate_mrad_s": self.rate_max_rad_s * 1e3,
               "max_wheel_rpm": self.wheel_rate_max_rad_s * 30.0 / np.pi,
               "max_wheel_torque_nm": self.wheel_torque_max_nm,
               "min_pulse_s": self.min_pulse_s, "max_pulse_s": self.max_pulse_s}
        if self.thrusters is not None:
            out["thrusters"] = list(self.thrusters)
        if np.all(np.isfinite(self.axis_rate_max_rad_s)):
            out["max_axis_rate_mrad_s"] = [x * 1e3 for x in self.axis_rate_max_rad_s]
        if np.isfinite(self.accel_max_rad_s2):
            out["max_body_accel_mrad_s2"] = self.accel_max_rad_s2 * 1e3
        if np.isfinite(self.slew_max_rad):
            out["max_slew_deg"] = float(np.rad2deg(self.slew_max_rad))
        if np.isfinite(self.wheel_momentum_max_nms):
            out["max_wheel_momentum_nms"] = self.wheel_momentum_max_nms
        return out


def limits_path(name: str | os.PathLike) -> Path:
    """A limits file: a path, or the bare name of one shipped under ``experiments/limits/``."""
    return input_path(name, "limits", LIMITS_DIR)


def base_scenario_dict(limits: Limits, spacecraft_path: str) -> dict[str, Any]:
    """A scenario dict without slews: the limits file's sections, ``control = "rwa"``, the
    duration, and the spacecraft model as truth and prior (what a plan is flown on)."""
    s = copy.deepcopy(limits.sections)
    run = s.setdefault("run", {})
    run.update(duration_s=limits.duration_s, control="rwa")
    s["truth"] = {"model": spacecraft_path}
    s["prior"] = {"model": spacecraft_path}
    s["name"] = limits.name
    s["description"] = limits.description
    return s


def torque_per_accel(sc: Spacecraft, wheels_on) -> np.ndarray:
    """(k_on, 3) wheel motor torque per unit body acceleration, N m per rad/s²: the RWA
    controller's allocation (the pseudo-inverse of the wheels' axes) of ``I α``."""
    g = np.stack([sc.wheel(n).axis for n in wheels_on])
    return np.linalg.pinv(g.T) @ np.asarray(sc.inertia, float)


def accel_bound(limits: Limits, sc: Spacecraft, wheels_on) -> float:
    """Largest slew acceleration (rad/s²) about the worst direction (sampled): the cap, and the
    torque share :data:`ACCEL_TORQUE_SHARE` of the wheels' torque limit."""
    dirs = np.concatenate([np.eye(3), -np.eye(3), _fibonacci(200)])
    need = np.abs(torque_per_accel(sc, wheels_on) @ dirs.T).max(0)
    return min(limits.accel_max_rad_s2,
               ACCEL_TORQUE_SHARE * limits.wheel_torque_max_nm / float(need.max()))


def _fibonacci(n: int) -> np.ndarray:
    """``n`` unit vectors spread evenly over the sphere."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = np.pi * (1.0 + 5.0 ** 0.5) * i
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], -1)


def limits_from_dict(d: dict[str, Any], spacecraft_path: str,
                     src: str = "<limits>", *, slews: bool = True) -> tuple[Limits, Scenario]:
    """Check a limits dict against the spacecraft of the model file ``spacecraft_path``; returns
    the limits and the base scenario (:func:`base_scenario_dict`, loaded: its own keys are
    checked as a scenario's). ``slews``: the plan is made of slews (a duration shorter than one
    slew is refused); ``False`` for a thrust plan's biasing event."""
    if not isinstance(d, dict):
        raise InputError("a limits file is a TOML table", path=src)
    top = TomlTable(d, "", src, _TOP)
    if not top.has("limits"):
        raise InputError("missing table [limits] (duration_s, max_body_rate_mrad_s, "
                         "max_wheel_rpm, max_wheel_torque_nm, ...)", path=src)
    t = top.sub("limits", _LIMIT_KEYS)
    for key in _REQUIRED:
        t.num(key, positive=True)
    axis_rate = np.full(3, np.inf)
    if t.has("max_axis_rate_mrad_s"):
        v = t.vec("max_axis_rate_mrad_s")
        if np.any(v <= 0):
            raise t.err("max_axis_rate_mrad_s", f"= {list(v)} must be positive (mrad/s about X, "
                                                "Y, Z)")
        axis_rate = v * 1e-3
    min_pulse = t.num("min_pulse_s", MIN_PULSE_S, positive=True)
    if min_pulse < MIN_PULSE_S - 1e-12:
        raise t.err("min_pulse_s", f"= {min_pulse} s is below the {MIN_PULSE_S} s command grid "
                                   "of the thrusters")
    max_pulse = t.num("max_pulse_s", MAX_PULSE_S, positive=True)
    if max_pulse < min_pulse:
        raise t.err("max_pulse_s", f"= {max_pulse} s is below 'limits.min_pulse_s' = {min_pulse} "
                                   "s")
    sections = {k: copy.deepcopy(d[k]) for k in ("run", "initial", "noise", "rwa_controller",
                                                 "rcs_controller") if k in d}
    for k in ("run", "initial"):
        if k not in sections:
            raise InputError(f"missing table [{k}] (the telemetry's dt_s and sample_period_s; "
                             "the wheels on and their speeds when the plan starts)", path=src)
    if not isinstance(sections["run"], dict) or set(sections["run"]) - {"dt_s",
                                                                       "sample_period_s"}:
        raise InputError("[run] of a limits file takes dt_s and sample_period_s only (the "
                         "duration is 'limits.duration_s')", path=src)
    lim = Limits(
        name=str(d.get("name", Path(src).stem)), description=str(d.get("description", "")),
        source=src, duration_s=t.num("duration_s", positive=True),
        quiet_s=t.num("quiet_s", 0.0, nonneg=True),
        rate_max_rad_s=t.num("max_body_rate_mrad_s", positive=True) * 1e-3,
        axis_rate_max_rad_s=tuple(float(x) for x in axis_rate),
        accel_max_rad_s2=_optional(t, "max_body_accel_mrad_s2") * 1e-3,
        slew_max_rad=np.deg2rad(_optional(t, "max_slew_deg")),
        wheel_rate_max_rad_s=t.num("max_wheel_rpm", positive=True) * np.pi / 30.0,
        wheel_torque_max_nm=t.num("max_wheel_torque_nm", positive=True),
        wheel_momentum_max_nms=_optional(t, "max_wheel_momentum_nms"),
        min_pulse_s=min_pulse, sections=sections, max_pulse_s=max_pulse,
        thrusters=_thrusters(t))
    base = scenario_from_dict(base_scenario_dict(lim, spacecraft_path), src)
    _check_consistency(lim, base, src, slews)
    if lim.thrusters is not None:
        unknown = [n for n in lim.thrusters if n not in base.prior.thruster_names]
        if unknown:
            raise t.err("thrusters", f"names {', '.join(unknown)}, not thrusters of the "
                                     f"spacecraft model ({', '.join(base.prior.thruster_names)})")
    return lim, base


def _thrusters(t: TomlTable) -> tuple[str, ...] | None:
    """``thrusters``: a non-empty list of names, or ``None`` (all may fire)."""
    if not t.has("thrusters"):
        return None
    v = t.table["thrusters"]
    if not isinstance(v, list) or not v or not all(isinstance(x, str) and x for x in v):
        raise t.err("thrusters", f"= {v!r}: give a non-empty list of thruster names")
    return tuple(v)


def _optional(t: TomlTable, key: str) -> float:
    """An optional positive limit; infinite (no limit) when the key is absent."""
    return t.num(key, positive=True) if t.has(key) else np.inf


def _check_consistency(lim: Limits, base: Scenario, src: str, slews: bool = True) -> None:
    """Limits that contradict each other or the state the plan starts from (one line each)."""
    sc = base.prior
    on = [n for n, o in zip(base.wheel_names, base.wheels_on) if o]
    rho0 = np.abs(np.asarray(base.wheel0_rad_s))
    for name, rate, j in zip(base.wheel_names, rho0, sc.wheel_inertias):
        rpm = rate * 30.0 / np.pi
        if rate > lim.wheel_rate_max_rad_s:
            raise InputError(f"'limits.max_wheel_rpm' = {lim.wheel_rate_max_rad_s * 30 / np.pi:g}"
                             f" is below {name}'s speed when the plan starts ({rpm:g} rpm, "
                             f"'initial.wheel_rpm'); raise the limit or bias the wheel first",
                             path=src)
        if j * rate > lim.wheel_momentum_max_nms:
            raise InputError(f"'limits.max_wheel_momentum_nms' = {lim.wheel_momentum_max_nms:g} "
                             f"is below {name}'s momentum when the plan starts "
                             f"({j * rate:.4g} N m s at {rpm:g} rpm)", path=src)
    accel = accel_bound(lim, sc, on)
    rate = min(lim.rate_max_rad_s, float(np.min(lim.axis_rate_max_rad_s)))
    one_slew = 2.0 * rate / accel
    need = 2.0 * lim.quiet_s + (one_slew if slews else 0.0)
    if lim.duration_s <= need:
        if not slews:
            raise InputError(f"'limits.duration_s' = {lim.duration_s:g} s leaves no time between "
                             f"the {lim.quiet_s:g} s quiet at the start and at the end "
                             "('limits.quiet_s')", path=src)
        raise InputError(f"'limits.duration_s' = {lim.duration_s:g} s is shorter than one slew: "
                         f"{lim.quiet_s:g} s quiet before and after plus {one_slew:.0f} s to "
                         f"reach {rate * 1e3:g} mrad/s and stop at {accel * 1e3:.3g} mrad/s²; "
                         f"give at least {need:.0f} s", path=src)
    if lim.duration_s < 2.0 * base.sample_period_s:
        raise InputError(f"'limits.duration_s' = {lim.duration_s:g} s holds fewer than two "
                         "telemetry samples", path=src)


def load_limits(path: str | os.PathLike, spacecraft_path: str, *,
                slews: bool = True) -> tuple[Limits, Scenario]:
    """Load a limits TOML (a path, or the stem of a file under ``experiments/limits/``) for the
    spacecraft of the model file ``spacecraft_path`` (written into the plan's scenario);
    ``slews`` as :func:`limits_from_dict`."""
    p = limits_path(path)
    return limits_from_dict(read_toml(p, "limits", "experiments/limits/"), spacecraft_path,
                            str(p), slews=slews)
