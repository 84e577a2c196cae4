"""The spacecraft model types: pulse constants, sensor and wheel knowledge, the spacecraft.

Units: kg m² for inertias, m for lengths, s for time constants, N for thrust; rpm only in the
wheel limits a model file states.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Sequence

import numpy as np
from numpy.typing import ArrayLike

from cassini_bayes.errors import InputError
from cassini_bayes.names import THRUSTER_NAMES
from cassini_bayes.spacecraft._geometry import (
    _EQ16_DIRECTIONS,
    QUIET_WHEEL_TOL_RPM,
    _EQ16_SIGNS_XY,
    Thruster,
    Wheel,
    eq16_thrusters,
    moment_matrix,
)
from cassini_bayes.units import RPM_TO_RAD_S

COM_SD_DEFAULT_FRAC = 0.01
"""Default ``[center_of_mass] sd_m``: this fraction of the largest thruster position's length
(Cassini: 3.6 cm of its 3.6 m arm), the centre of mass's knowledge scaled to the spacecraft."""
WHEEL_SPEED_NOMINAL_RPM = 2000.0
"""A wheel's top speed where its ``[[wheel]]`` entry gives no ``max_speed_rpm``, rpm, for
:attr:`Spacecraft.momentum_capacity_nms` (Cassini's RWAs: 34 N m s at 0.16 kg m², Brown §I).
A speed, not a size: wheels of any spacecraft run to 10³–10⁴ rpm, so the capacity scales with
the wheels' spin inertia."""



@dataclass(frozen=True)
class PulseConstants:
    """Thruster pulse time constants (s) and their manufacturer test ranges (Feldman & Lee §V)."""

    tau_delay: float = 0.005
    tau_rise: float = 0.020
    tau_fall: float = 0.065
    tau_delay_range: tuple[float, float] = (0.003, 0.007)
    tau_rise_range: tuple[float, float] = (0.015, 0.025)
    tau_fall_range: tuple[float, float] = (0.040, 0.090)
    # Smallest log sd of the rise and fall priors (cassini_bayes.inference.thrust.tau_prior):
    # 0.45 keeps a first-order valve (rise = fall, 38-54 ms) inside the rise prior's ±2σ.
    tau_log_sd_min: float = 0.45


@dataclass(frozen=True)
class Knowledge:
    """How well the gyro and the wheels are known: one standard deviation each.

    The priors of the robust models' nuisance parameters (``cassini_bayes.inference.nuisance``).
    From the optional model-file sections ``[gyro]`` (``bias_sd_rad_s``, ``scale_factor_sd``),
    ``[wheel_knowledge]`` (``inertia_sd_frac``, ``common_inertia_sd_frac``, ``axis_sd_deg``),
    ``[telemetry_knowledge]`` (``time_tag_sd_s``, ``regular_clock``) and ``[torque_knowledge]``
    (``sd_nm``, ``rate_sd_nm_per_h``). The defaults are conservative engineering values, not
    numbers from the papers: a gyro bias of 5e-7 rad/s (0.1 deg/h) per axis, a gyro
    scale-factor error of 5e-4 (500 ppm) per axis, a spin-inertia error of 0.5 % per wheel (each
    wheel independently; a ``[[wheel]]`` table's ``inertia_sd_frac`` overrides it for that
    wheel) plus 0.5 % shared by every wheel (one calibration method, test stand and temperature;
    the data cannot tell it from the overall scale of the inertia, so the moments' uncertainty
    rests on it; 0 removes it), a wheel spin-axis misalignment of 0.2 deg per tilt component
    (Brown §III.A finds the re-articulated RWA4 0.53 deg from its nominal axis; the fixed wheels
    are known better) and a white time-tag error of 10 ms per telemetry sample (the papers give
    no figure; 1 % of Cassini's 1 s sample period). ``regular_clock``: the telemetry is sampled
    on a regular clock and only its labels carry that error, which the thrust fit then puts on
    their grid (:mod:`cassini_bayes.inference.thrust.clock`); off by default.
    External torques (the robust models' body-fixed and inertial torques): 15 µN m per axis, the
    Feldman & Lee App. A bound for March 2000 taken as one sd, and a rate of change of 15 µN m
    per hour (solar and RTG torques change as the slews turn the sun line). Where the torques the
    calibration windows cannot measure may be larger (another epoch, outgassing, a leak), say so
    here: the RWA4 axis's cone rests on this prior (``docs/robust/open_world.md``).
    A flexible appendage or slosh mode (``[flex_knowledge]``: ``share_sd``, ``freq_hz``,
    ``damping``): the thrust fit searches the given frequency (Hz) and damping-ratio ranges for
    one (Feldman & Lee §II: Cassini's booms ring at 0.13 and 0.7 Hz, damped 0.2-1 %) and gives
    each entry of its ``δ δᵀ`` a prior sd of ``share_sd`` × the mean principal moment (1 %).
    """

    gyro_bias_sd_rad_s: float = 5e-7
    gyro_scale_factor_sd: float = 5e-4
    wheel_inertia_sd_frac: float = 0.005
    wheel_axis_sd_deg: float = 0.2
    time_tag_sd_s: float = 0.01
    wheel_common_inertia_sd_frac: float = 0.005
    torque_sd_nm: float = 15e-6
    torque_rate_sd_nm_per_h: float = 15e-6
    flex_share_sd: float = 0.01
    flex_freq_hz: tuple[float, float] = (0.05, 1.0)
    flex_damping: tuple[float, float] = (0.002, 0.05)
    regular_clock: bool = False


@dataclass(frozen=True)
class Spacecraft:
    """A spacecraft model: predicted inertia with its knowledge requirements, wheels, thrusters.

    Attributes
    ----------
    inertia : (3, 3) predicted inertia tensor about the centre of mass, body axes, kg m².
    moi_uncertainty : fractional knowledge requirement on the moments (0.10 = ±10 %).
    poi_uncertainty : knowledge requirement on the products, kg m².
    wheels : the reaction wheels, in file order.
    thrusters : the thrusters, in file order (empty for a spacecraft without thrusters).
    thrust : predicted steady thrust per thruster, N (NaN without thrusters).
    mass : spacecraft mass, kg (NaN when not given).
    com_m : (3,) centre of mass relative to the origin of the thruster positions, m (Feldman &
        Lee Eq 16's ``[eX, eY, eZ]``; zero when the positions are from the centre of mass).
    com_sd_m : knowledge of the centre of mass, one sd per axis, m.
    eq16 : ``(Lx, Ly, Lzy, Lzz)`` m when the thrusters came from Cassini's ``[thrusters]``
        shorthand (written back in that form), else ``None``.
    """

    name: str
    inertia: np.ndarray
    moi_uncertainty: float
    poi_uncertainty: float
    wheels: tuple[Wheel, ...]
    thrusters: tuple[Thruster, ...] = ()
    pulse: PulseConstants = field(default_factory=PulseConstants)
    thrust: float = 0.75
    mass: float = float("nan")
    description: str = ""
    source: str = ""
    knowledge: Knowledge = field(default_factory=Knowledge)
    com_m: np.ndarray = field(default_factory=lambda: np.zeros(3))
    com_sd_m: float = 0.0
    eq16: tuple[float, float, float, float] | None = None

    @property
    def wheel_axes(self) -> np.ndarray:
        """(k, 3) unit spin axes, body axes."""
        return np.stack([w.axis for w in self.wheels])

    @property
    def wheel_inertias(self) -> np.ndarray:
        """(k,) spin inertias, kg m²."""
        return np.array([w.inertia for w in self.wheels])

    @property
    def wheel_names(self) -> tuple[str, ...]:
        return tuple(w.name for w in self.wheels)

    @property
    def momentum_capacity_nms(self) -> float:
        """The most angular momentum the wheels can hold together, N m s: ``Σ_k J_k ρ_max,k``
        with ``ρ_max,k`` each wheel's ``max_speed_rpm`` (:data:`WHEEL_SPEED_NOMINAL_RPM` where
        the model file gives none). The spacecraft's own momentum scale."""
        return _capacity_nms(self.wheels)

    @property
    def articulated_wheels(self) -> tuple[str, ...]:
        """Names of the wheels whose axis can move in flight (``articulated = true``)."""
        return tuple(w.name for w in self.wheels if w.articulated)

    @property
    def thruster_names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.thrusters)

    @property
    def moment_matrix(self) -> np.ndarray:
        """(3, m) torque per newton of each thruster, N m / N: column ``s`` is
        ``(r_s − e) × d_s`` (Feldman & Lee Eq 16), ``e`` = :attr:`com_m`."""
        return moment_matrix(self.thrusters, self.com_m)

    @property
    def thrust_per_thruster(self) -> np.ndarray:
        """(m,) nominal steady thrust of each thruster, N: its own ``F`` or the model's."""
        return np.array([self.thrust if s.thrust_n is None else s.thrust_n
                         for s in self.thrusters], float)

    @property
    def eq16_layout(self) -> bool:
        """Whether the thrusters are Cassini's eight in the layout of Feldman & Lee Eq 16 (the
        names ``Z1 … Y4`` in order, its directions and position signs, one height per group):
        what the thrust fit, the leak monitor and the health fit assume."""
        if self.thruster_names != THRUSTER_NAMES:
            return False
        pos = np.stack([s.position for s in self.thrusters])
        dirs = np.stack([s.direction for s in self.thrusters])
        return bool(np.array_equal(dirs, _EQ16_DIRECTIONS)
                    and np.array_equal(np.sign(pos[:, :2]), _EQ16_SIGNS_XY)
                    and np.all(np.abs(pos[:, :2]) == np.abs(pos[:1, :2]))
                    and np.all(pos[:4, 2] == pos[0, 2]) and np.all(pos[4:, 2] == pos[4, 2]))

    def require_thrusters(self, what: str, *, eq16: bool = False) -> None:
        """Raise :class:`InputError` unless the model has thrusters (``eq16``: Cassini's eight
        in the layout of Eq 16, :attr:`eq16_layout`), naming ``what`` needs them."""
        if not self.thrusters:
            raise InputError(f"{what} needs thrusters, but the spacecraft model {self.name!r} has "
                             "none; give a model with [[thruster]] entries")
        if eq16 and not self.eq16_layout:
            raise InputError(f"{what} supports Cassini's eight thrusters in the layout of "
                             f"Feldman & Lee Eq 16 (Z1..Y4) only; the spacecraft model "
                             f"{self.name!r} has {', '.join(self.thruster_names)}")

    def wheel(self, name: str) -> Wheel:
        for w in self.wheels:
            if w.name.upper() == name.upper():
                return w
        raise InputError(f"spacecraft model {self.name!r} has no wheel {name!r}; "
                         f"it has {', '.join(self.wheel_names)}")

    def thruster(self, name: str) -> Thruster:
        for s in self.thrusters:
            if s.name.upper() == name.upper():
                return s
        have = ", ".join(self.thruster_names) or "no thrusters"
        raise InputError(f"spacecraft model {self.name!r} has no thruster {name!r}; it has "
                         f"{have}")

    def with_inertia(self, inertia: ArrayLike) -> Spacecraft:
        """This model with the inertia tensor ``inertia`` (3, 3), kg m²."""
        return replace(self, inertia=np.asarray(inertia, float))

    def with_wheel_axis(self, name: str, axis: ArrayLike) -> Spacecraft:
        axis = np.asarray(axis, float)
        wheels = tuple(replace(w, axis=axis) if w.name.upper() == name.upper() else w
                       for w in self.wheels)
        return replace(self, wheels=wheels)

    def _thrusters_dict(self) -> dict[str, Any]:
        """The thrusters as the model file writes them: Cassini's ``[thrusters]`` shorthand
        when they are its expansion, else ``[[thruster]]`` entries and ``[center_of_mass]``."""
        com = [float(x) for x in self.com_m]
        out: dict[str, Any] = {}
        shorthand = (self.eq16 is not None
                     and all(a.name == b.name and np.array_equal(a.position, b.position)
                             and np.array_equal(a.direction, b.direction)
                             and a.thrust_n is None and a.branch == b.branch
                             for a, b in zip(self.thrusters, eq16_thrusters(*self.eq16)))
                     and len(self.thrusters) == 8)
        if shorthand:
            lx, ly, lzy, lzz = self.eq16
            out["thrusters"] = {"Lx": lx, "Ly": ly, "Lzy": lzy, "Lzz": lzz, "com": com}
            if self.com_sd_m != _default_com_sd(self.thrusters):
                out["center_of_mass"] = {"sd_m": self.com_sd_m}
            return out
        if self.thrusters:
            out["thruster"] = [{"name": s.name, "position": [float(x) for x in s.position],
                                "direction": [float(x) for x in s.direction],
                                **({} if s.thrust_n is None else {"F": s.thrust_n}),
                                **({"branch": s.branch} if s.branch else {})}
                               for s in self.thrusters]
            out["center_of_mass"] = {"offset_m": com, "sd_m": self.com_sd_m}
        return out

    def to_dict(self) -> dict[str, Any]:
        """The TOML schema as a plain dict (for ``config.toml`` and ``truth.json``)."""
        i = self.inertia
        wheel_extra = lambda w: {  # noqa: E731 - the optional keys a wheel has
            **({} if w.inertia_sd_frac is None else {"inertia_sd_frac": w.inertia_sd_frac}),
            **({} if np.isinf(w.max_speed_rpm) else {"max_speed_rpm": w.max_speed_rpm}),
            **({} if np.isinf(w.max_torque_nm) else {"max_torque_nm": w.max_torque_nm}),
            **({"articulated": True} if w.articulated else {}),
            **({} if w.cone is None else {"cone_axis": [float(x) for x in w.cone.axis],
                                          "cone_deg": w.cone.angle_deg,
                                          "cone_sd_deg": w.cone.sd_deg}),
            **({} if w.reference is None else {"reference": w.reference,
                                               "reference_tol_deg": w.reference_tol_deg}),
            **({} if w.quiet_tol_rpm == QUIET_WHEEL_TOL_RPM
               else {"quiet_tol_rpm": w.quiet_tol_rpm})}
        thrusters = self._thrusters_dict()
        return {
            "name": self.name,
            "description": self.description,
            "source": self.source,
            "inertia": {"Ixx": float(i[0, 0]), "Iyy": float(i[1, 1]), "Izz": float(i[2, 2]),
                        "Ixy": float(i[0, 1]), "Ixz": float(i[0, 2]), "Iyz": float(i[1, 2]),
                        "moi_uncertainty": self.moi_uncertainty,
                        "poi_uncertainty": self.poi_uncertainty},
            "wheel": [{"name": w.name, "axis": [float(x) for x in w.axis],
                       "inertia": float(w.inertia), **wheel_extra(w)} for w in self.wheels],
            **thrusters,
            **({"pulse": {k: (list(v) if isinstance(v, tuple) else v)
                          for k, v in self.pulse.__dict__.items()},
                "thrust": {"F": self.thrust}} if self.thrusters else {}),
            **({"mass": {"kg": self.mass}} if np.isfinite(self.mass) else {}),
            "gyro": {"bias_sd_rad_s": self.knowledge.gyro_bias_sd_rad_s,
                     "scale_factor_sd": self.knowledge.gyro_scale_factor_sd},
            "wheel_knowledge": {"inertia_sd_frac": self.knowledge.wheel_inertia_sd_frac,
                                "common_inertia_sd_frac":
                                    self.knowledge.wheel_common_inertia_sd_frac,
                                "axis_sd_deg": self.knowledge.wheel_axis_sd_deg},
            "telemetry_knowledge": {"time_tag_sd_s": self.knowledge.time_tag_sd_s,
                                    "regular_clock": self.knowledge.regular_clock},
            "torque_knowledge": {"sd_nm": self.knowledge.torque_sd_nm,
                                 "rate_sd_nm_per_h": self.knowledge.torque_rate_sd_nm_per_h},
        }


def _capacity_nms(wheels: Sequence[Wheel]) -> float:
    """:attr:`Spacecraft.momentum_capacity_nms` of ``wheels``, N m s."""
    return float(sum(w.inertia * (w.max_speed_rpm if np.isfinite(w.max_speed_rpm)
                                  else WHEEL_SPEED_NOMINAL_RPM) for w in wheels)
                 * RPM_TO_RAD_S)


def _default_com_sd(thrusters: Sequence[Thruster]) -> float:
    """:data:`COM_SD_DEFAULT_FRAC` of the largest thruster position's length, m (0 without)."""
    if not thrusters:
        return 0.0
    return COM_SD_DEFAULT_FRAC * float(max(np.linalg.norm(s.position) for s in thrusters))

