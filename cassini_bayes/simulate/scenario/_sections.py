"""The settings sections of a scenario: ``[run]``, ``[initial]``, ``[rwa_controller]``,
``[rcs_controller]``, ``[noise]`` and ``[flex_mode]``, one reader each."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from cassini_bayes._toml import TomlTable
from cassini_bayes.errors import InputError
from cassini_bayes.simulate.controllers import COMMAND_RESOLUTION_S, MIN_PULSE_S, thruster_sets
from cassini_bayes.simulate.scenario._truth import wheel_index
from cassini_bayes.simulate.scenario._types import (MAX_SAMPLES, MAX_STEPS, FlexMode, Noise,
                                                    RcsControl, RwaControl)
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import OMEGA_ABS_MAX, WHEEL_RPM_MAX
from cassini_bayes.units import RPM_TO_RAD_S


class RunSettings(NamedTuple):
    """``[run]``: duration, integration step and telemetry period (s), controller."""

    duration_s: float
    dt_s: float
    sample_period_s: float
    control: str
    section: TomlTable


class Initial(NamedTuple):
    """``[initial]``: wheels on (k,), attitude quaternion (scalar last), body rates (rad/s),
    wheel rates (rad/s, k)."""

    wheels_on: list[bool]
    q: np.ndarray
    rates_rad_s: np.ndarray
    wheel_rad_s: np.ndarray
    section: TomlTable


def read_seed(top: TomlTable) -> int:
    """The top-level ``seed``: an integer in 0 .. 2**63 − 1 (as ``--seed``), 0 when absent."""
    seed = top.table.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**63:
        raise top.err("seed", f"must be an integer in 0 .. 2**63 - 1 (as --seed), got {seed!r}")
    return seed


def read_run(top: TomlTable) -> RunSettings:
    """``[run]``: the step and the sample period divide the run; it fits the size limits."""
    run = top.sub("run", {"duration_s", "dt_s", "sample_period_s", "control"}, required=True)
    duration = run.num("duration_s", positive=True)
    dt = run.num("dt_s", positive=True)
    period = run.num("sample_period_s", positive=True)
    control = run.string("control")
    if control not in ("rwa", "rcs"):
        raise run.err("control", f"must be \"rwa\" or \"rcs\", got {control!r}")
    if duration / dt > MAX_STEPS:
        raise run.err("duration_s", f"= {duration} s is {duration / dt:.3g} integration steps of "
                                    f"dt_s = {dt} s, more than the limit {MAX_STEPS:.0e} "
                                    "(~1.2 GB); "
                                    "split the run into shorter scenarios (docs/limits.md)")
    if period > duration:
        raise run.err("sample_period_s", f"= {period} s is longer than the run "
                                         f"(duration_s = {duration} s)")
    if duration / period + 1 > MAX_SAMPLES:
        raise run.err("sample_period_s", f"= {period} s gives {duration / period + 1:.6g} samples "
                                         f"over {duration} s, more than the limit {MAX_SAMPLES}; "
                                         "sample less often or shorten the run (docs/limits.md)")
    if abs(period / dt - round(period / dt)) > 1e-9 or round(period / dt) < 1:
        raise run.err("sample_period_s", f"= {period} must be a whole number of steps dt_s = {dt}")
    if abs(duration / period - round(duration / period)) > 1e-9:
        raise run.err("duration_s", f"= {duration} must be a whole number of sample periods")
    if abs(period / 0.1 - round(period / 0.1)) > 1e-9:
        raise run.err("sample_period_s", "must be a multiple of 0.1 s (the on-time telemetry "
                                         "resolution)")
    return RunSettings(duration, dt, period, control, run)


def read_initial(top: TomlTable, truth: Spacecraft) -> Initial:
    """``[initial]``: which wheels are on (required), attitude, body and wheel rates."""
    section = top.sub("initial", {"wheels_on", "q", "rates_rad_s", "wheel_rpm"}, required=True)
    on_names = section.table.get("wheels_on")
    if on_names is None:
        raise InputError("missing required key 'initial.wheels_on'", path=section.src)
    if not isinstance(on_names, list):
        raise section.err("wheels_on", "must be a list of wheel names")
    on = [False] * len(truth.wheels)
    for name in on_names:
        on[wheel_index(truth, name, "initial.wheels_on", section.src)] = True
    q0 = section.vec("q", 4, default=[0.0, 0.0, 0.0, 1.0], unit=True)
    rates = section.vec("rates_rad_s", default=np.zeros(3), hi=OMEGA_ABS_MAX)
    rpm = section.sub("wheel_rpm",
                      set(truth.wheel_names) | {n.lower() for n in truth.wheel_names})
    wheel_rates = np.zeros(len(truth.wheels))
    for name in rpm.table:
        j = wheel_index(truth, name, f"initial.wheel_rpm.{name}", section.src)
        if not on[j]:
            raise rpm.err(name, "gives a rate for a wheel that is not in 'initial.wheels_on'")
        wheel_rates[j] = rpm.num(name, hi=WHEEL_RPM_MAX) * RPM_TO_RAD_S
    return Initial(on, q0, rates, wheel_rates, section)


def read_rwa_controller(top: TomlTable, truth: Spacecraft, prior: Spacecraft,
                        control: str, initial: Initial) -> RwaControl:
    """``[rwa_controller]``: gains and the axes the controller believes (the prior model's
    unless given, as another wheel's name or a unit vector); under RWA control at least three
    wheels on whose believed axes span 3-D."""
    section = top.sub("rwa_controller", {"bandwidth_rad_s", "damping", "believed_axis"})
    believed = prior.wheel_axes.copy()
    axes = section.sub("believed_axis", set(truth.wheel_names))
    for name, value in axes.table.items():
        key = f"rwa_controller.believed_axis.{name}"
        j = wheel_index(truth, name, key, section.src)
        if isinstance(value, str):
            believed[j] = prior.wheel_axes[wheel_index(prior, value, key, section.src)]
        else:
            believed[j] = axes.vec(name, unit=True)
    rwa = RwaControl(section.num("bandwidth_rad_s", 0.1, positive=True),
                     section.num("damping", 0.7, positive=True),
                     tuple(tuple(float(x) for x in a) for a in believed))
    if control == "rwa" and sum(initial.wheels_on) < 3:
        raise initial.section.err("wheels_on", "needs at least three wheels under RWA control")
    if control == "rwa":
        if np.linalg.matrix_rank(believed[np.array(initial.wheels_on)], tol=1e-3) < 3:
            raise InputError("the believed axes of the wheels on do not span 3-D; check "
                             "'rwa_controller.believed_axis'", path=section.src)
    return rwa


def check_rcs_control(run: RunSettings, truth: Spacecraft, prior: Spacecraft) -> None:
    """Under RCS control the truth model has thrusters, and the prior model's turn it about each
    body axis both ways (:func:`~cassini_bayes.simulate.controllers.thruster_sets`)."""
    if run.control != "rcs":
        return
    if not truth.thrusters:
        raise run.section.err("control", f"= \"rcs\" needs thrusters; the truth model "
                                         f"{truth.name!r} has none: fly it with control = \"rwa\"")
    try:
        thruster_sets(prior)
    except InputError as e:
        raise InputError(f"'run.control' = \"rcs\": {e}", path=run.section.src) from None


def read_rcs_controller(top: TomlTable) -> RcsControl:
    """``[rcs_controller]``: dead-bands (mrad in the file), gains, pulse limits on the 1/8 s
    command grid."""
    section = top.sub("rcs_controller", {"deadband_mrad", "rate_gain_s", "width_gain_s_per_mrad",
                                         "max_pulse_s", "min_off_s", "wheel_rate_gain_per_s"})
    deadband_mrad = section.vec("deadband_mrad", default=[2.0, 2.0, 2.0])
    if np.any(deadband_mrad <= 0):
        raise section.err("deadband_mrad", "must be positive (mrad)")
    max_pulse = section.num("max_pulse_s", 0.75, positive=True)
    if max_pulse < MIN_PULSE_S or abs(max_pulse / COMMAND_RESOLUTION_S
                                      - round(max_pulse / COMMAND_RESOLUTION_S)) > 1e-9:
        raise section.err("max_pulse_s", "must be a multiple of 0.125 s, at least 0.125 s")
    return RcsControl(tuple(deadband_mrad * 1e-3), section.num("rate_gain_s", 10.0, nonneg=True),
                      section.num("width_gain_s_per_mrad", 0.125, nonneg=True) * 1e3, max_pulse,
                      section.num("min_off_s", 0.5, nonneg=True),
                      section.num("wheel_rate_gain_per_s", 0.5, positive=True))


def read_noise(top: TomlTable, sample_period_s: float) -> Noise:
    """``[noise]``: sensor noise; time-tag jitter at most a twentieth of the sample period, so
    time tags stay increasing."""
    section = top.sub("noise", {"gyro_rad_s", "star_tracker_rad", "tach_quantum_rpm",
                                "tach_noise_rpm", "gyro_bias_rad_s", "gyro_scale_factor",
                                "time_tag_jitter_s"})
    gyro_scale = section.vec("gyro_scale_factor", default=[0.0, 0.0, 0.0])
    if np.any(np.abs(gyro_scale) >= 0.1):
        raise section.err("gyro_scale_factor", "is a small fractional error (|s| < 0.1)")
    jitter = section.num("time_tag_jitter_s", 0.0, nonneg=True)
    if jitter > sample_period_s / 20.0:
        raise section.err("time_tag_jitter_s", f"= {jitter} s must be at most sample_period_s / "
                                               f"20 = {sample_period_s / 20.0} s (time tags must "
                                               "stay increasing)")
    return Noise(section.num("gyro_rad_s", 0.0, nonneg=True),
                 section.num("star_tracker_rad", 0.0, nonneg=True),
                 section.num("tach_quantum_rpm", 0.0, nonneg=True),
                 section.num("tach_noise_rpm", 0.0, nonneg=True),
                 tuple(float(x) for x in section.vec("gyro_bias_rad_s",
                                                     default=[0.0, 0.0, 0.0])),
                 tuple(float(x) for x in gyro_scale), jitter)


def read_flex_mode(top: TomlTable, inertia: np.ndarray, dt_s: float) -> FlexMode | None:
    """The optional ``[flex_mode]`` section, checked against the truth inertia and the step."""
    if not top.has("flex_mode"):
        return None
    section = top.sub("flex_mode", {"freq_hz", "damping", "coupling"})
    freq_hz = section.num("freq_hz", positive=True)
    zeta = section.num("damping", nonneg=True)
    if zeta >= 1.0:
        raise section.err("damping", f"= {zeta} must be below 1 (a fraction of critical damping)")
    if 2.0 * np.pi * freq_hz * dt_s > 0.5:
        raise section.err("freq_hz", f"= {freq_hz} Hz is too fast for run.dt_s = {dt_s} s (need "
                                     "2π f dt <= 0.5); shorten dt_s")
    delta = section.vec("coupling")
    if not np.any(delta):
        raise section.err("coupling", "must not be zero (drop [flex_mode] to switch the mode off)")
    share = float(delta @ np.linalg.solve(inertia, delta))
    if share >= 0.5:
        raise section.err("coupling", f"is too large for the truth inertia (δᵀ I⁻¹ δ = "
                                      f"{share:.3g}; must be below 0.5)")
    return FlexMode(freq_hz, zeta, tuple(float(x) for x in delta))
