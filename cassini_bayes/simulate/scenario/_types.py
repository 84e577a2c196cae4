"""The validated scenario (SI units) and the bounds of one run; the file schema is in
:mod:`cassini_bayes.simulate.scenario`."""

from __future__ import annotations

from dataclasses import dataclass, field

from cassini_bayes.errors import InputError
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.simulate.controllers import slew_duration
from cassini_bayes.telemetry import MAX_ROWS

__all__ = ["Slew", "WheelRamp", "DeadbandChange", "PulseCommand", "Noise", "FlexMode", "Window",
           "RwaControl", "RcsControl", "Leak", "Scenario", "check_size", "MAX_STEPS",
           "MAX_SAMPLES", "NUMBER_ABS_MAX"]

MAX_STEPS = 2_000_000
"""Most integration steps ``duration_s / dt_s`` of one scenario: ``simulate``'s memory grows with
the steps (per-step cost: docs/limits.md); 2e6 steps are 69 h at the 1/8 s thruster step."""
MAX_SAMPLES = MAX_ROWS
"""Most telemetry samples ``duration_s / sample_period_s + 1`` of one scenario: the telemetry file
row limit :data:`cassini_bayes.telemetry.MAX_ROWS`, so every simulated file can be read back."""
NUMBER_ABS_MAX = 1e10
"""Largest magnitude of any number in a scenario file (keeps every product far from overflow)."""


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
