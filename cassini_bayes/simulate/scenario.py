"""Simulation scenarios: TOML files under ``experiments/scenarios/``, loaded and validated.

A scenario names its truth (a spacecraft model file plus overrides), the prior model the
calibration starts from, the run (duration, integration step, telemetry period, controller), the
commanded events (slews, wheel biasing ramps, dead-band changes, open-loop pulses), the sensor
noise and the seed. Unknown keys, missing required values and impossible values are
:class:`~cassini_bayes.errors.InputError` with one line naming the key. Schema::

    name = "..."                 description = "..."          seed = 0
    [run]       duration_s, dt_s, sample_period_s, control = "rwa" | "rcs"
    [truth]     model = "models/…toml" (required); optional overrides:
                inertia = {Ixx = …, …}, thrust_n = 0.75 | [one per thruster], tau_delay_s,
                tau_rise_s,
                tau_fall_s (``tau_delay_s = 0`` and ``tau_rise_s = tau_fall_s`` is a first-order
                valve), rwa4_axis = [x, y, z] (unit), external_torque_inertial_nm = [3],
                external_torque_body_nm = [3], external_torque_inertial_rate_nm_s = [3],
                wheel_inertia_scale = 1.0 (true spin inertias = scale × the model file's),
                wheel_inertia_errors = [e_1, …, e_K] (each wheel's own fractional error, in the
                model file's wheel order), wheel_inertia_error_sd = σ (each wheel's error drawn
                ~ N(0, σ²) independently from the scenario's seed, added to the fixed ones):
                true J_k = scale × (1 + e_k) × the model file's,
                wheel_axis_tilt_deg = {RWA1 = [a1, a2], …} (true axes tilted along
                ``spacecraft.wheel_tilt_basis``; the prior model keeps the nominal ones),
                center_of_mass_offset_m = [3] (true centre of mass minus the model file's, m:
                the thrusters' true torques, Feldman & Lee Eq 16)
    [prior]     model = "…" (required)
    [initial]   wheels_on = ["RWA1", …] (required), q = [q1, q2, q3, q4], rates_rad_s = [3],
                wheel_rpm = {RWA1 = …}
    [rwa_controller]  bandwidth_rad_s, damping, believed_axis = {RWA4 = "RWA1" | [x, y, z]}
    [rcs_controller]  deadband_mrad = [3], rate_gain_s, width_gain_s_per_mrad, max_pulse_s,
                      min_off_s, wheel_rate_gain_per_s
    [[slew]]         t_start_s, axis = [3] (unit), angle_deg, rate_mrad_s, accel_mrad_s2
    [[wheel_ramp]]   wheel, t_start_s, target_rpm, torque_nm
    [[deadband]]     t_s, deadband_mrad = [3]
    [[pulse]]        t_on_s, thruster = a thruster of the truth model ("Z1"…"Y4"), width_s
    [noise]     gyro_rad_s, star_tracker_rad, tach_quantum_rpm, tach_noise_rpm,
                gyro_bias_rad_s = [3], gyro_scale_factor = [3]  (ω_meas = (1 + s) ω + b + noise),
                time_tag_jitter_s (sd of each sample's time-tag error, ≤ sample_period_s / 20)
    [flex_mode] freq_hz, damping, coupling = [3] (kg^½ m): one flexible or slosh mode
                (:class:`FlexMode`; off when the section is absent)
    [[window]]  name, t0_s, t1_s      (quiet windows reported in truth.json)
    [leak]      thruster (of the truth model), fraction (0 < f ≤ 1 of the true thrust),
                t_start_s: from ``t_start_s`` on, a constant torque ``f F_k Q[:, k]`` (a stuck-open valve leaking
                ``f`` of thruster ``k``'s thrust, Lee §3.2; off when the section is absent)

Thrusters: RCS control (``control = "rcs"``) flies any model whose thrusters can turn it about
each body axis both ways (the sets of :func:`~cassini_bayes.simulate.controllers.thruster_sets`,
from the prior model's geometry); open-loop ``[[pulse]]`` and ``[leak]`` take any thruster of the
truth model; a model without thrusters flies RWA slews only. Wheels: any number;
the RWA controller allocates torque with the pseudo-inverse of the believed axes, and the truth
model's optional ``max_speed_rpm`` / ``max_torque_nm`` limit each wheel.

Bounds (docs/limits.md): a run has at most :data:`MAX_STEPS` integration steps and
:data:`MAX_SAMPLES` telemetry samples; every number is at most :data:`NUMBER_ABS_MAX` in
magnitude; wheel rates at most ``WHEEL_RPM_MAX``, body and slew rates at most ``OMEGA_ABS_MAX``
(the telemetry bounds of :mod:`cassini_bayes.telemetry`), thrust and pulse time constants within
the spacecraft-model ranges of :mod:`cassini_bayes.spacecraft`; ``seed`` in 0 .. 2**63 − 1.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from cassini_bayes._paths import DATA_DIR, SCENARIOS_DIR, input_path
from cassini_bayes._toml import is_numbers, read_toml
from cassini_bayes.errors import InputError
from cassini_bayes.spacecraft import (LENGTH_MAX, TAU_MAX, THRUST_MAX, Spacecraft,
                                      check_physical_inertia, load_spacecraft, tilted_axis)
from cassini_bayes.simulate.controllers import (COMMAND_RESOLUTION_S, MIN_PULSE_S, slew_duration,
                                                thruster_sets)
from cassini_bayes.telemetry import MAX_ROWS, OMEGA_ABS_MAX, WHEEL_RPM_MAX
from cassini_bayes.units import RPM_TO_RAD_S

__all__ = ["Slew", "WheelRamp", "DeadbandChange", "PulseCommand", "Noise", "FlexMode", "Window",
           "RwaControl", "RcsControl", "Leak", "Scenario", "load_scenario", "scenario_from_dict",
           "scenario_path", "check_size", "MAX_STEPS", "MAX_SAMPLES"]

_UNIT_TOL = 1e-6
MAX_STEPS = 2_000_000
"""Most integration steps ``duration_s / dt_s`` of one scenario: ``simulate``'s memory grows with
the steps (per-step cost: docs/limits.md); 2e6 steps are 69 h at the 1/8 s thruster step."""
MAX_SAMPLES = MAX_ROWS
"""Most telemetry samples ``duration_s / sample_period_s + 1`` of one scenario: the telemetry file
row limit :data:`cassini_bayes.telemetry.MAX_ROWS`, so every simulated file can be read back."""
NUMBER_ABS_MAX = 1e10
"""Largest magnitude of any number in a scenario file (keeps every product far from overflow)."""
_WHEEL_ERROR_STREAM = 1   # the random stream of the wheel spin-inertia error draws


@dataclass(frozen=True)
class Slew:
    """Eigen-axis slew about a body ``axis`` (unit) by ``angle_rad``; trapezoidal rate profile."""

    t_start_s: float
    axis: tuple[float, float, float]
    angle_rad: float
    rate_rad_s: float
    accel_rad_s2: float

    @property
    def t_end_s(self) -> float:
        return self.t_start_s + slew_duration(self.angle_rad, self.rate_rad_s, self.accel_rad_s2)


@dataclass(frozen=True)
class WheelRamp:
    """Bias wheel ``wheel`` (index) towards ``target_rad_s`` with motor torque ≤ ``torque_nm``."""

    wheel: int
    t_start_s: float
    target_rad_s: float
    torque_nm: float


@dataclass(frozen=True)
class DeadbandChange:
    """From ``t_s`` on, RCS dead-bands ``deadband_rad`` (3,) about X, Y, Z."""

    t_s: float
    deadband_rad: tuple[float, float, float]


@dataclass(frozen=True)
class PulseCommand:
    """Open-loop thruster pulse: ``thruster`` index into the truth model's thrusters, command
    time and width (s)."""

    t_on_s: float
    thruster: int
    width_s: float


@dataclass(frozen=True)
class Noise:
    """Sensor noise (1σ unless said otherwise).

    gyro_rad_s : white noise on each body-rate sample, rad/s.
    star_tracker_rad : attitude noise per axis, a small rotation, rad.
    tach_quantum_rpm : wheel-rate quantization step, rpm (0 = none).
    tach_noise_rpm : white noise on wheel rates before quantization, rpm.
    gyro_bias_rad_s : constant gyro bias per body axis, rad/s (0 = none).
    gyro_scale_factor : gyro scale-factor error per body axis, fraction (0 = none).
    time_tag_jitter_s : sd of the white error of each sample's recorded time, s (0 = none).
    """

    gyro_rad_s: float = 0.0
    star_tracker_rad: float = 0.0
    tach_quantum_rpm: float = 0.0
    tach_noise_rpm: float = 0.0
    gyro_bias_rad_s: tuple[float, float, float] = (0.0, 0.0, 0.0)
    gyro_scale_factor: tuple[float, float, float] = (0.0, 0.0, 0.0)
    time_tag_jitter_s: float = 0.0


@dataclass(frozen=True)
class FlexMode:
    """One flexible-appendage or propellant-slosh mode in hybrid coordinates.

    Modal coordinate ``η`` (unit modal mass, kg^½ m), body rate ``ω``, wheels ``H_w``::

        H = I ω + H_w + δ η̇                       (total body-axis momentum)
        η̈ + 2 ζ Ω η̇ + Ω² η + δ · ω̇ = 0            (the mode, cantilevered on the body)

    ``I`` is the whole spacecraft's inertia with the appendage or propellant frozen (what the
    calibrations estimate: ``η̇ = 0`` gives Feldman & Lee Eq 3); ``I − δ δᵀ`` must stay positive
    definite. For a spring-mass (or pendulum) slosh mass ``m`` at ``r`` from the centre of mass
    moving along the unit ``e``, ``δ = √m r × e``; for a cantilevered boom, ``δ`` is its modal
    momentum coefficient. Cassini's magnetometer boom: 0.7 Hz, ζ 0.2-1 %; the RPWS antennas:
    0.13 Hz, ζ 0.2 % (Feldman & Lee §II). Held free (no body rotation) the body-coupled mode rings
    at ``Ω / √(1 − δᵀ I⁻¹ δ)``.

    freq_hz : ``Ω / 2π``, the cantilevered frequency, Hz.
    damping : ``ζ``, fraction of critical.
    coupling : ``δ`` (3,), body axes, kg^½ m.
    """

    freq_hz: float
    damping: float
    coupling: tuple[float, float, float]


@dataclass(frozen=True)
class Window:
    """A named quiet window ``[t0_s, t1_s]`` reported with the truth."""

    name: str
    t0_s: float
    t1_s: float


@dataclass(frozen=True)
class Leak:
    """A leaking thruster: index into the truth model's thrusters, fraction of its true thrust,
    onset (s)."""

    thruster: int
    fraction: float
    t_start_s: float


@dataclass(frozen=True)
class RwaControl:
    """RWA PD controller: bandwidth (rad/s), damping ratio, believed wheel axes (k, 3)."""

    bandwidth_rad_s: float = 0.1
    damping: float = 0.7
    believed_axes: tuple[tuple[float, float, float], ...] = ()


@dataclass(frozen=True)
class RcsControl:
    """RCS dead-band controller settings (SI)."""

    deadband_rad: tuple[float, float, float] = (2e-3, 2e-3, 2e-3)
    rate_gain_s: float = 10.0
    width_gain_s_per_rad: float = 125.0
    max_pulse_s: float = 0.75
    min_off_s: float = 0.5
    wheel_rate_gain_per_s: float = 0.5


@dataclass(frozen=True)
class Scenario:
    """A validated scenario (SI units). See the module docstring for the file schema."""

    name: str
    description: str
    source: str
    seed: int
    duration_s: float
    dt_s: float
    sample_period_s: float
    control: str
    truth: Spacecraft
    thrust_n: tuple[float, ...]
    prior: Spacecraft
    wheels_on: tuple[bool, ...]
    q0: tuple[float, float, float, float]
    rates0_rad_s: tuple[float, float, float]
    wheel0_rad_s: tuple[float, ...]
    rwa: RwaControl
    rcs: RcsControl
    external_torque_inertial_nm: tuple[float, float, float] = (0.0, 0.0, 0.0)
    external_torque_body_nm: tuple[float, float, float] = (0.0, 0.0, 0.0)
    external_torque_inertial_rate_nm_s: tuple[float, float, float] = (0.0, 0.0, 0.0)
    wheel_inertia_scale: float = 1.0
    wheel_inertia_errors: tuple[float, ...] = ()
    slews: tuple[Slew, ...] = ()
    wheel_ramps: tuple[WheelRamp, ...] = ()
    deadbands: tuple[DeadbandChange, ...] = ()
    pulses: tuple[PulseCommand, ...] = ()
    noise: Noise = field(default_factory=Noise)
    flex: FlexMode | None = None
    windows: tuple[Window, ...] = ()
    leak: Leak | None = None
    truth_model_path: str = ""
    prior_model_path: str = ""

    @property
    def n_steps(self) -> int:
        return int(round(self.duration_s / self.dt_s))

    @property
    def steps_per_sample(self) -> int:
        return int(round(self.sample_period_s / self.dt_s))

    @property
    def n_samples(self) -> int:
        return self.n_steps // self.steps_per_sample + 1

    @property
    def uses_thrusters(self) -> bool:
        return self.control == "rcs" or bool(self.pulses)

    @property
    def wheel_names(self) -> tuple[str, ...]:
        return self.truth.wheel_names


def check_size(s: Scenario) -> None:
    """Raise unless the run fits :data:`MAX_STEPS` steps and :data:`MAX_SAMPLES` samples (for
    scenarios built or changed in code, past :func:`scenario_from_dict`'s checks)."""
    if s.n_steps > MAX_STEPS or s.n_samples > MAX_SAMPLES:
        raise InputError(f"'run.duration_s' = {s.duration_s} s is {s.n_steps} steps and "
                         f"{s.n_samples} samples, more than the limits {MAX_STEPS} steps and "
                         f"{MAX_SAMPLES} samples; split the run (docs/limits.md)", path=s.source)


def scenario_path(name: str | os.PathLike, what: str = "scenario") -> Path:
    """Path of a scenario (or campaign): a file, or the bare name of one shipped under
    ``experiments/scenarios/`` (:func:`cassini_bayes._paths.input_path`, the rule of every file
    argument)."""
    return input_path(name, what, SCENARIOS_DIR)


class _Reader:
    """Typed, key-checked access to a TOML table; every error names ``src`` and the key."""

    def __init__(self, table: Any, where: str, src: str, allowed: set[str]):
        if not isinstance(table, dict):
            raise InputError(f"'{where.rstrip('.')}' must be a table", path=src)
        self.t, self.where, self.src = table, where, src
        for key in table:
            if key not in allowed:
                raise InputError(f"unknown key '{where}{key}'; allowed: "
                                 f"{', '.join(sorted(allowed))}", path=src)

    def err(self, key: str, msg: str) -> InputError:
        return InputError(f"'{self.where}{key}' {msg}", path=self.src)

    def has(self, key: str) -> bool:
        return key in self.t

    def num(self, key: str, default=None, *, positive=False, nonneg=False,
            hi: float | None = None) -> float:
        if key not in self.t:
            if default is None:
                raise InputError(f"missing required key '{self.where}{key}'", path=self.src)
            return float(default)
        v = self.t[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
            raise self.err(key, f"must be a finite number, got {v!r}")
        if abs(v) > (NUMBER_ABS_MAX if hi is None else hi):
            raise self.err(key, f"= {v:g} is beyond the physical limit "
                                f"{NUMBER_ABS_MAX if hi is None else hi:g} in magnitude; check "
                                "the value and its unit (docs/limits.md)")
        if positive and v <= 0:
            raise self.err(key, f"must be positive, got {v}")
        if nonneg and v < 0:
            raise self.err(key, f"must not be negative, got {v}")
        return float(v)

    def vec(self, key: str, n: int = 3, default=None, *, unit=False, nonneg=False,
            hi: float | None = None) -> np.ndarray:
        if key not in self.t:
            if default is None:
                raise InputError(f"missing required key '{self.where}{key}'", path=self.src)
            return np.asarray(default, float)
        v = self.t[key]
        if not is_numbers(v):
            raise self.err(key, f"must be a list of {n} numbers, got {v!r}")
        a = np.asarray(v, float)
        if a.shape != (n,) or not np.all(np.isfinite(a)):
            raise self.err(key, f"must be a list of {n} finite numbers, got {v!r}")
        if np.any(np.abs(a) > (NUMBER_ABS_MAX if hi is None else hi)):
            raise self.err(key, f"has an entry beyond the physical limit "
                                f"{NUMBER_ABS_MAX if hi is None else hi:g} in magnitude, got "
                                f"{v!r}; check the values and their unit (docs/limits.md)")
        if unit and abs(np.linalg.norm(a) - 1.0) > _UNIT_TOL:
            raise self.err(key, f"must be a unit vector (|v| = {np.linalg.norm(a):.6f}); "
                                "normalise it")
        if nonneg and np.any(a < 0):
            raise self.err(key, f"must not have negative entries, got {v!r}")
        return a

    def str_(self, key: str, default=None) -> str:
        if key not in self.t:
            if default is None:
                raise InputError(f"missing required key '{self.where}{key}'", path=self.src)
            return default
        v = self.t[key]
        if not isinstance(v, str):
            raise self.err(key, f"must be a string, got {v!r}")
        return v

    def sub(self, key: str, allowed: set[str], required=False) -> "_Reader":
        if key not in self.t:
            if required:
                raise InputError(f"missing required section [{self.where}{key}]", path=self.src)
            return _Reader({}, f"{self.where}{key}.", self.src, allowed)
        return _Reader(self.t[key], f"{self.where}{key}.", self.src, allowed)

    def items(self, key: str, allowed: set[str]) -> list["_Reader"]:
        v = self.t.get(key, [])
        if not isinstance(v, list):
            raise self.err(key, "must be an array of tables ([[...]])")
        return [_Reader(x, f"{self.where}{key}[{i}].", self.src, allowed) for i, x in enumerate(v)]


def _model(name: str, key: str, src: str) -> tuple[Spacecraft, str]:
    """The spacecraft of ``[truth]``/``[prior]`` ``model``: a path (relative to the working
    directory, else to the shipped data, so ``models/NAME.toml`` works from anywhere) or the name
    of a shipped model."""
    p = Path(name)
    if not p.is_absolute() and not p.exists() and (DATA_DIR / p).exists():
        p = DATA_DIR / p
    try:
        return load_spacecraft(p), str(p)
    except InputError as e:
        raise InputError(f"'{key}': {e}", path=src) from None


def _wheel_index(sc: Spacecraft, name: str, key: str, src: str) -> int:
    names = [n.upper() for n in sc.wheel_names]
    if str(name).upper() not in names:
        raise InputError(f"'{key}' names no wheel of the model: {name!r} (have "
                         f"{', '.join(names)})", path=src)
    return names.index(str(name).upper())


def _check_time(r: _Reader, key: str, t: float, duration: float) -> None:
    if not 0.0 <= t <= duration:
        raise r.err(key, f"= {t} s lies outside the run [0, {duration}] s")


def _wheel_inertia_errors(tr: _Reader, k: int, seed: int) -> np.ndarray | None:
    """Each wheel's fractional spin-inertia error (k,): ``[truth] wheel_inertia_errors`` plus
    independent ``N(0, wheel_inertia_error_sd²)`` draws from the scenario's seed (its own stream,
    so the sensor noise is untouched); ``None`` when neither key is given."""
    if not (tr.has("wheel_inertia_errors") or tr.has("wheel_inertia_error_sd")):
        return None
    err = tr.vec("wheel_inertia_errors", k, default=np.zeros(k))
    sd = tr.num("wheel_inertia_error_sd", 0.0, nonneg=True)
    err = err + sd * np.random.default_rng([seed, _WHEEL_ERROR_STREAM]).standard_normal(k)
    if np.any(np.abs(err) >= 0.1):
        raise tr.err("wheel_inertia_errors", f"= {np.round(err, 4).tolist()}: each wheel's error "
                     "is a small fraction (|e| < 0.1; with wheel_inertia_error_sd, the drawn one)")
    return err


def _flex_mode(top: _Reader, inertia: np.ndarray, dt: float, src: str) -> FlexMode | None:
    """The optional ``[flex_mode]`` section, checked against the truth inertia and the step."""
    if not top.has("flex_mode"):
        return None
    fm = top.sub("flex_mode", {"freq_hz", "damping", "coupling"})
    f = fm.num("freq_hz", positive=True)
    zeta = fm.num("damping", nonneg=True)
    if zeta >= 1.0:
        raise fm.err("damping", f"= {zeta} must be below 1 (a fraction of critical damping)")
    if 2.0 * np.pi * f * dt > 0.5:
        raise fm.err("freq_hz", f"= {f} Hz is too fast for run.dt_s = {dt} s (need 2π f dt <= "
                                "0.5); shorten dt_s")
    delta = fm.vec("coupling")
    if not np.any(delta):
        raise fm.err("coupling", "must not be zero (drop [flex_mode] to switch the mode off)")
    share = float(delta @ np.linalg.solve(inertia, delta))
    if share >= 0.5:
        raise fm.err("coupling", f"is too large for the truth inertia (δᵀ I⁻¹ δ = {share:.3g}; "
                                 "must be below 0.5)")
    return FlexMode(f, zeta, tuple(float(x) for x in delta))


def _thruster_index(r: "_Reader", key: str, truth: Spacecraft) -> int:
    """Index of the thruster ``r[key]`` names among the truth model's (case-insensitive)."""
    name = r.str_(key)
    names = [n.upper() for n in truth.thruster_names]
    if name.upper() not in names:
        have = ", ".join(truth.thruster_names) or "none"
        raise r.err(key, f"must be a thruster of the truth model {truth.name!r} ({have}), got "
                         f"{name!r}")
    return names.index(name.upper())


def _leak(top: _Reader, duration: float, dt: float, truth: Spacecraft) -> Leak | None:
    """The optional ``[leak]`` section (all three keys required)."""
    if not top.has("leak"):
        return None
    lk = top.sub("leak", {"thruster", "fraction", "t_start_s"})
    k = _thruster_index(lk, "thruster", truth)
    f = lk.num("fraction", positive=True)
    if f > 1.0:
        raise lk.err("fraction", f"= {f} must be at most 1 (a fraction of the thrust)")
    t0 = lk.num("t_start_s")
    _check_time(lk, "t_start_s", t0, duration)
    return Leak(k, f, t0)


def scenario_from_dict(d: dict[str, Any], src: str = "<scenario>") -> Scenario:
    """Build and validate a :class:`Scenario` from the TOML schema (as a dict)."""
    top = _Reader(d, "", src, {"name", "description", "seed", "run", "truth", "prior", "initial",
                               "rwa_controller", "rcs_controller", "slew", "wheel_ramp",
                               "deadband", "pulse", "noise", "window", "flex_mode", "leak"})
    seed = top.t.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**63:
        raise top.err("seed", f"must be an integer in 0 .. 2**63 - 1 (as --seed), got {seed!r}")
    run = top.sub("run", {"duration_s", "dt_s", "sample_period_s", "control"}, required=True)
    duration = run.num("duration_s", positive=True)
    dt = run.num("dt_s", positive=True)
    period = run.num("sample_period_s", positive=True)
    control = run.str_("control")
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

    tr = top.sub("truth", {"model", "inertia", "thrust_n", "tau_delay_s", "tau_rise_s",
                           "tau_fall_s", "rwa4_axis", "external_torque_inertial_nm",
                           "external_torque_body_nm", "external_torque_inertial_rate_nm_s",
                           "wheel_inertia_scale", "wheel_axis_tilt_deg", "wheel_inertia_errors",
                           "wheel_inertia_error_sd", "center_of_mass_offset_m"},
                    required=True)
    truth, truth_path = _model(tr.str_("model"), "truth.model", src)
    ti = tr.sub("inertia", {"Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz"})
    i0 = truth.inertia
    xx, yy, zz = (ti.num(k, i0[j, j], positive=True) for j, k in enumerate(("Ixx", "Iyy", "Izz")))
    xy, xz, yz = ti.num("Ixy", i0[0, 1]), ti.num("Ixz", i0[0, 2]), ti.num("Iyz", i0[1, 2])
    inertia = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    check_physical_inertia(inertia, "[truth.inertia]", src)
    truth = truth.with_inertia(inertia)
    m = len(truth.thrusters)
    if tr.has("thrust_n"):
        if not m:
            raise tr.err("thrust_n", f"gives a thrust, but the truth model {truth.name!r} has no "
                                     "thrusters")
        v = tr.t["thrust_n"]
        thrust = (np.full(m, tr.num("thrust_n", positive=True, hi=THRUST_MAX))
                  if not isinstance(v, list) else tr.vec("thrust_n", m, nonneg=True, hi=THRUST_MAX))
        if np.any(thrust <= 0):
            raise tr.err("thrust_n", "must be positive (N)")
    else:
        thrust = truth.thrust_per_thruster
    pulse = truth.pulse
    # a valve may open at once (first-order valve: tau_delay_s = 0, tau_rise_s = tau_fall_s)
    pulse = replace(pulse, **{k: tr.num(f"{k}_s", getattr(pulse, k), positive=k != "tau_delay",
                                        nonneg=True, hi=TAU_MAX)
                              for k in ("tau_delay", "tau_rise", "tau_fall")})
    truth = replace(truth, pulse=pulse, thrust=float(np.mean(thrust)) if m else truth.thrust)
    if tr.has("rwa4_axis"):
        axis = tr.vec("rwa4_axis", unit=True)
        _wheel_index(truth, "RWA4", "truth.rwa4_axis", src)
        truth = truth.with_wheel_axis("RWA4", axis / np.linalg.norm(axis))
    # Real-world errors: true wheels differing from the model file (the prior model keeps its own).
    j_scale = tr.num("wheel_inertia_scale", 1.0, positive=True)
    if abs(j_scale - 1.0) >= 0.5:
        raise tr.err("wheel_inertia_scale", f"= {j_scale} must be close to 1 (a fractional error)")
    j_err = _wheel_inertia_errors(tr, len(truth.wheels), seed)
    tilts = tr.sub("wheel_axis_tilt_deg", set(truth.wheel_names))
    wheels = []
    for w, e in zip(truth.wheels, j_err if j_err is not None else np.zeros(len(truth.wheels))):
        axis = w.axis
        if w.name in tilts.t:
            a = tilts.vec(w.name, 2)
            if np.any(np.abs(a) > 10.0):
                raise tilts.err(w.name, "tilts are small angles in degrees (|a| <= 10)")
            axis = tilted_axis(axis, np.deg2rad(a))
        wheels.append(replace(w, axis=axis, inertia=w.inertia * j_scale * (1.0 + e)))
    truth = replace(truth, wheels=tuple(wheels))
    if tr.has("center_of_mass_offset_m"):
        if not m:
            raise tr.err("center_of_mass_offset_m", f"moves the centre of mass the thrusters "
                                                    f"turn about, but the truth model "
                                                    f"{truth.name!r} has no thrusters")
        truth = replace(truth, com_m=truth.com_m + tr.vec("center_of_mass_offset_m",
                                                          hi=LENGTH_MAX))
    ext_n = tr.vec("external_torque_inertial_nm", default=np.zeros(3))
    ext_b = tr.vec("external_torque_body_nm", default=np.zeros(3))
    ext_rate = tr.vec("external_torque_inertial_rate_nm_s", default=np.zeros(3))

    pr = top.sub("prior", {"model"}, required=True)
    prior, prior_path = _model(pr.str_("model"), "prior.model", src)
    if prior.wheel_names != truth.wheel_names:
        raise InputError("'prior.model' must have the same wheels as 'truth.model'", path=src)
    if prior.thruster_names != truth.thruster_names:
        raise InputError("'prior.model' must have the same thrusters as 'truth.model'", path=src)

    k = len(truth.wheels)
    ini = top.sub("initial", {"wheels_on", "q", "rates_rad_s", "wheel_rpm"}, required=True)
    on_names = ini.t.get("wheels_on")
    if on_names is None:
        raise InputError("missing required key 'initial.wheels_on'", path=src)
    if not isinstance(on_names, list):
        raise ini.err("wheels_on", "must be a list of wheel names")
    on = [False] * k
    for n in on_names:
        on[_wheel_index(truth, n, "initial.wheels_on", src)] = True
    q0 = ini.vec("q", 4, default=[0.0, 0.0, 0.0, 1.0], unit=True)
    w0 = ini.vec("rates_rad_s", default=np.zeros(3), hi=OMEGA_ABS_MAX)
    rpm = ini.sub("wheel_rpm", set(truth.wheel_names) | {n.lower() for n in truth.wheel_names})
    rho0 = np.zeros(k)
    for name in rpm.t:
        j = _wheel_index(truth, name, f"initial.wheel_rpm.{name}", src)
        if not on[j]:
            raise rpm.err(name, "gives a rate for a wheel that is not in 'initial.wheels_on'")
        rho0[j] = rpm.num(name, hi=WHEEL_RPM_MAX) * RPM_TO_RAD_S

    rc = top.sub("rwa_controller", {"bandwidth_rad_s", "damping", "believed_axis"})
    believed = prior.wheel_axes.copy()
    ba = rc.sub("believed_axis", set(truth.wheel_names))
    for name, v in ba.t.items():
        j = _wheel_index(truth, name, f"rwa_controller.believed_axis.{name}", src)
        if isinstance(v, str):
            believed[j] = prior.wheel_axes[_wheel_index(prior, v,
                                                        f"rwa_controller.believed_axis.{name}",
                                                        src)]
        else:
            believed[j] = ba.vec(name, unit=True)
    rwa = RwaControl(rc.num("bandwidth_rad_s", 0.1, positive=True),
                     rc.num("damping", 0.7, positive=True),
                     tuple(tuple(float(x) for x in a) for a in believed))
    if control == "rwa" and sum(on) < 3:
        raise ini.err("wheels_on", "needs at least three wheels under RWA control")
    if control == "rwa":
        g = believed[np.array(on)]
        if np.linalg.matrix_rank(g, tol=1e-3) < 3:
            raise InputError("the believed axes of the wheels on do not span 3-D; check "
                             "'rwa_controller.believed_axis'", path=src)

    cc = top.sub("rcs_controller", {"deadband_mrad", "rate_gain_s", "width_gain_s_per_mrad",
                                    "max_pulse_s", "min_off_s", "wheel_rate_gain_per_s"})
    db = cc.vec("deadband_mrad", default=[2.0, 2.0, 2.0])
    if np.any(db <= 0):
        raise cc.err("deadband_mrad", "must be positive (mrad)")
    max_pulse = cc.num("max_pulse_s", 0.75, positive=True)
    if max_pulse < MIN_PULSE_S or abs(max_pulse / COMMAND_RESOLUTION_S
                                      - round(max_pulse / COMMAND_RESOLUTION_S)) > 1e-9:
        raise cc.err("max_pulse_s", "must be a multiple of 0.125 s, at least 0.125 s")
    rcs = RcsControl(tuple(db * 1e-3), cc.num("rate_gain_s", 10.0, nonneg=True),
                     cc.num("width_gain_s_per_mrad", 0.125, nonneg=True) * 1e3, max_pulse,
                     cc.num("min_off_s", 0.5, nonneg=True),
                     cc.num("wheel_rate_gain_per_s", 0.5, positive=True))

    slews = []
    for r in top.items("slew", {"t_start_s", "axis", "angle_deg", "rate_mrad_s",
                                "accel_mrad_s2"}):
        t0 = r.num("t_start_s")
        _check_time(r, "t_start_s", t0, duration)
        s = Slew(t0, tuple(r.vec("axis", unit=True)), np.deg2rad(r.num("angle_deg")),
                 r.num("rate_mrad_s", positive=True, hi=OMEGA_ABS_MAX * 1e3) * 1e-3,
                 r.num("accel_mrad_s2", positive=True) * 1e-3)
        if s.t_end_s > duration:
            raise r.err("t_start_s", f"slew ends at {s.t_end_s:.1f} s, after the run "
                                     f"({duration} s)")
        if slews and t0 < slews[-1].t_end_s:
            raise r.err("t_start_s", f"= {t0} s starts before the previous slew ends "
                                     f"({slews[-1].t_end_s:.1f} s); slews run one at a time")
        slews.append(s)
    if slews and control != "rwa":
        raise InputError("[[slew]] needs 'run.control = \"rwa\"'", path=src)
    if control == "rcs":
        if not truth.thrusters:
            raise run.err("control", f"= \"rcs\" needs thrusters; the truth model "
                                     f"{truth.name!r} has none: fly it with control = \"rwa\"")
        try:
            thruster_sets(prior)
        except InputError as e:
            raise InputError(f"'run.control' = \"rcs\": {e}", path=src) from None

    ramps = []
    for r in top.items("wheel_ramp", {"wheel", "t_start_s", "target_rpm", "torque_nm"}):
        j = _wheel_index(truth, r.str_("wheel"), r.where + "wheel", src)
        if not on[j]:
            raise r.err("wheel", "is not in 'initial.wheels_on'")
        t0 = r.num("t_start_s")
        _check_time(r, "t_start_s", t0, duration)
        ramps.append(WheelRamp(j, t0, r.num("target_rpm", hi=WHEEL_RPM_MAX) * RPM_TO_RAD_S,
                               r.num("torque_nm", positive=True, hi=10.0)))
    if ramps and control != "rcs":
        raise InputError("[[wheel_ramp]] needs 'run.control = \"rcs\"' (under RWA control the "
                         "attitude controller drives the wheels)", path=src)
    deadbands = []
    for r in top.items("deadband", {"t_s", "deadband_mrad"}):
        t0 = r.num("t_s")
        _check_time(r, "t_s", t0, duration)
        v = r.vec("deadband_mrad")
        if np.any(v <= 0):
            raise r.err("deadband_mrad", "must be positive (mrad)")
        deadbands.append(DeadbandChange(t0, tuple(v * 1e-3)))
    pulses = []
    for r in top.items("pulse", {"t_on_s", "thruster", "width_s"}):
        k = _thruster_index(r, "thruster", truth)
        t0 = r.num("t_on_s")
        _check_time(r, "t_on_s", t0, duration)
        w = r.num("width_s", positive=True)
        for key, val in (("t_on_s", t0), ("width_s", w)):
            if abs(val / COMMAND_RESOLUTION_S - round(val / COMMAND_RESOLUTION_S)) > 1e-9:
                raise r.err(key, f"= {val} is not on the 1/8 s command grid")
        if w < MIN_PULSE_S:
            raise r.err("width_s", f"= {w} s is below the 125 ms minimum pulse")
        pulses.append(PulseCommand(t0, k, w))
    if (control == "rcs" or pulses) and abs(dt - COMMAND_RESOLUTION_S) > 1e-12:
        raise run.err("dt_s", "must be 0.125 s when thrusters fire (the 1/8 s command "
                              "resolution)")

    nz = top.sub("noise", {"gyro_rad_s", "star_tracker_rad", "tach_quantum_rpm",
                           "tach_noise_rpm", "gyro_bias_rad_s", "gyro_scale_factor",
                           "time_tag_jitter_s"})
    gyro_scale = nz.vec("gyro_scale_factor", default=[0.0, 0.0, 0.0])
    if np.any(np.abs(gyro_scale) >= 0.1):
        raise nz.err("gyro_scale_factor", "is a small fractional error (|s| < 0.1)")
    jitter = nz.num("time_tag_jitter_s", 0.0, nonneg=True)
    if jitter > period / 20.0:
        raise nz.err("time_tag_jitter_s", f"= {jitter} s must be at most sample_period_s / 20 = "
                                          f"{period / 20.0} s (time tags must stay increasing)")
    noise = Noise(nz.num("gyro_rad_s", 0.0, nonneg=True),
                  nz.num("star_tracker_rad", 0.0, nonneg=True),
                  nz.num("tach_quantum_rpm", 0.0, nonneg=True),
                  nz.num("tach_noise_rpm", 0.0, nonneg=True),
                  tuple(float(x) for x in nz.vec("gyro_bias_rad_s", default=[0.0, 0.0, 0.0])),
                  tuple(float(x) for x in gyro_scale), jitter)
    flex = _flex_mode(top, truth.inertia, dt, src)
    windows = []
    for r in top.items("window", {"name", "t0_s", "t1_s"}):
        t0, t1 = r.num("t0_s"), r.num("t1_s")
        _check_time(r, "t0_s", t0, duration)
        _check_time(r, "t1_s", t1, duration)
        if t1 <= t0:
            raise r.err("t1_s", f"= {t1} must be after t0_s = {t0}")
        windows.append(Window(r.str_("name"), t0, t1))
    leak = _leak(top, duration, dt, truth)

    return Scenario(
        name=top.str_("name", Path(src).stem), description=top.str_("description", ""),
        source=src, seed=seed, duration_s=duration, dt_s=dt, sample_period_s=period,
        control=control, truth=truth, thrust_n=tuple(float(x) for x in thrust), prior=prior,
        wheels_on=tuple(on), q0=tuple(q0 / np.linalg.norm(q0)), rates0_rad_s=tuple(w0),
        wheel0_rad_s=tuple(rho0), rwa=rwa, rcs=rcs,
        external_torque_inertial_nm=tuple(ext_n), external_torque_body_nm=tuple(ext_b),
        external_torque_inertial_rate_nm_s=tuple(ext_rate),
        wheel_inertia_scale=j_scale,
        wheel_inertia_errors=() if j_err is None else tuple(float(x) for x in j_err),
        slews=tuple(slews), wheel_ramps=tuple(ramps),
        deadbands=tuple(sorted(deadbands, key=lambda c: c.t_s)),
        pulses=tuple(pulses), noise=noise, flex=flex, windows=tuple(windows),
        leak=leak,
        truth_model_path=truth_path, prior_model_path=prior_path,
    )


def load_scenario(path: str | os.PathLike) -> Scenario:
    """Load a scenario TOML (a path, or the stem of a file under ``experiments/scenarios/``)."""
    p = scenario_path(path)
    d = read_toml(p, "scenario", "experiments/scenarios/")
    if "campaign" in d:
        raise InputError("a thruster-health campaign file, not a scenario: simulate it with "
                         "'cassini-bayes simulate-health FILE --out DIR'", path=str(p))
    return scenario_from_dict(d, str(p))
