"""Spacecraft model objects, loaded and validated from the TOML files under ``models/``.

A model file (docs/model_file.md) describes any spacecraft: the *predicted* mass properties and
the hardware geometry a calibration needs. Required: ``[inertia]`` and at least one ``[[wheel]]``.
Thrusters are ``[[thruster]]`` entries (name, position, direction, optional ``F`` and ``branch``)
or Cassini's ``[thrusters]`` shorthand (the lever arms of Feldman & Lee Eq 16, expanded to its
eight entries); a spacecraft without thrusters has neither, nor ``[thrust]`` or ``[pulse]``.
Optional sections: ``[mass]``, ``[center_of_mass]``, ``[pulse]`` (thruster time constants, their
manufacturer ranges and ``tau_log_sd_min``, the smallest log sd of the thrust fit's rise and fall
priors), ``[thrust]`` (predicted force), ``[gyro]`` and ``[wheel_knowledge]`` (the knowledge of
the sensors and wheels, the priors of the robust models' nuisance parameters; :class:`Knowledge`).
Unknown keys are errors, so a typo never goes unnoticed.

Units: kg m² for inertias, m for lengths, s for time constants, N for thrust, rpm and N m for the
optional wheel limits. Wheel axes and thrust directions are unit vectors in body axes.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Sequence

import numpy as np
from numpy.typing import ArrayLike

from cassini_bayes._paths import model_path
from cassini_bayes._toml import UNIT_TOL, TomlTable, read_toml
from cassini_bayes.errors import InputError, as_path
from cassini_bayes.names import THRUSTER_NAMES
from cassini_bayes.units import RPM_TO_RAD_S

__all__ = ["Wheel", "WheelCone", "Thruster", "PulseConstants", "Knowledge", "Spacecraft", "wheel_tilt_basis",
           "WHEEL_SPEED_NOMINAL_RPM",
           "tilted_axis", "load_spacecraft", "eq16_thrusters", "moment_matrix",
           "eq16_moment_matrix",
           "spacecraft_from_dict", "CASSINI_WHEEL_AXES"]

# Feldman & Lee (2006) App. A: RWA → body matrix T; its columns are the spin axes of RWA1-3.
_S2, _S3, _S6 = np.sqrt(2.0), np.sqrt(3.0), np.sqrt(6.0)
CASSINI_T = np.array(
    [[0.0, -1.0 / _S2, 1.0 / _S2], [_S2 / _S3, -1.0 / _S6, -1.0 / _S6], [1 / _S3, 1 / _S3, 1 / _S3]]
)
CASSINI_WHEEL_AXES = CASSINI_T.T.copy()  # rows: RWA1, RWA2, RWA3 spin axes (body)

# Feldman & Lee (2006) Eq 16: Z1..Z4 at [±Lx, ±Ly, Lzz], Y1..Y4 at [±Lx, ±Ly, Lzy]; the Z-facing
# thrusters push along −Z, Y1, Y2 along −Y and Y3, Y4 along +Y (the directions for which r × F
# reproduces every entry of Eq 16's moment matrix, so that Y2 with Y4 turns about +Z).
_EQ16_SIGNS_XY = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]] * 2, dtype=float)
_EQ16_DIRECTIONS = np.array([[0, 0, -1]] * 4 + [[0, -1, 0], [0, -1, 0], [0, 1, 0], [0, 1, 0]],
                            dtype=float)

COM_SD_DEFAULT_FRAC = 0.01
"""Default ``[center_of_mass] sd_m``: this fraction of the largest thruster position's length
(Cassini: 3.6 cm of its 3.6 m arm), the centre of mass's knowledge scaled to the spacecraft."""
WHEEL_SPEED_NOMINAL_RPM = 2000.0
"""A wheel's top speed where its ``[[wheel]]`` entry gives no ``max_speed_rpm``, rpm, for
:attr:`Spacecraft.momentum_capacity_nms` (Cassini's RWAs: 34 N m s at 0.16 kg m², Brown §I).
A speed, not a size: wheels of any spacecraft run to 10³–10⁴ rpm, so the capacity scales with
the wheels' spin inertia."""


def wheel_tilt_basis(axis) -> np.ndarray:
    """(2, 3) orthonormal pair ``u_1, u_2`` perpendicular to the unit spin ``axis``.

    The two small-angle tilt directions of a wheel axis (a rotation about the axis itself changes
    nothing): ``u_1 = axis × e / |axis × e|`` with ``e`` the body axis least aligned with ``axis``,
    ``u_2 = axis × u_1``. Shared by the simulator (true axes) and the robust models (nuisance).
    """
    g = np.asarray(axis, float) / np.linalg.norm(axis)
    e = np.zeros(3)
    e[np.argmin(np.abs(g))] = 1.0
    u1 = np.cross(g, e)
    u1 /= np.linalg.norm(u1)
    return np.stack([u1, np.cross(g, u1)])


def tilted_axis(axis, tilt_rad) -> np.ndarray:
    """The unit ``axis`` tilted by ``tilt_rad = (a_1, a_2)`` rad along :func:`wheel_tilt_basis`."""
    g = np.asarray(axis, float) + np.asarray(tilt_rad, float) @ wheel_tilt_basis(axis)
    return g / np.linalg.norm(g)


@dataclass(frozen=True)
class WheelCone:
    """The cone a wheel's spin axis lies on at any articulation angle: ``angle_deg`` from the
    unit ``axis`` (body axes), known to ``sd_deg`` (1 sd, the mechanical cant tolerance).
    Cassini's RWA4: 54.7356° from +Z (Brown §I)."""

    axis: np.ndarray
    angle_deg: float
    sd_deg: float = 1.0


@dataclass(frozen=True)
class Wheel:
    """A reaction wheel: ``axis`` unit vector in body axes, ``inertia`` kg m² about it.

    ``inertia_sd_frac``: this wheel's spin-inertia knowledge (one sd, a fraction), overriding
    ``[wheel_knowledge] inertia_sd_frac`` for it; ``None`` when the file does not give one.
    ``max_speed_rpm``, ``max_torque_nm``: the simulator's limits on its rate and motor torque
    (``inf`` when the file gives none). ``articulated``: its axis can be moved in flight (Cassini's
    RWA4, Brown §I), so the input checks take the model's axis as unknown. ``cone``: the
    articulation cone its axis lies on (the wheel-axis fit's ``cone`` prior and its adequacy
    check; ``None``: none known). ``reference``, ``reference_tol_deg``: the wheel whose axis
    this one must match and how closely (Cassini's RWA4 replacing RWA1 within ±2°, Brown §I),
    reported by the wheel-axis fit; ``None`` when the file gives none.
    """

    name: str
    axis: np.ndarray
    inertia: float
    inertia_sd_frac: float | None = None
    max_speed_rpm: float = float("inf")
    max_torque_nm: float = float("inf")
    articulated: bool = False
    cone: WheelCone | None = None
    reference: str | None = None
    reference_tol_deg: float | None = None


@dataclass(frozen=True)
class Thruster:
    """A thruster: ``position`` (3,) m in body axes from the predicted centre of mass,
    ``direction`` (3,) the unit vector of its force on the spacecraft; ``thrust_n`` its nominal
    steady thrust (N; ``None``: the model's ``[thrust] F``) and ``branch`` its redundancy branch
    (``""`` when none is named)."""

    name: str
    position: np.ndarray
    direction: np.ndarray
    thrust_n: float | None = None
    branch: str = ""


def eq16_thrusters(lx_m: float, ly_m: float, lzy_m: float, lzz_m: float) -> tuple[Thruster, ...]:
    """Cassini's eight thrusters ``Z1 … Y4`` from the lever arms of Feldman & Lee Eq 16 (m):
    ``Z1..Z4`` at ``[±Lx, ±Ly, Lzz]`` pushing along −Z, ``Y1..Y4`` at ``[±Lx, ±Ly, Lzy]``
    pushing along −Y (``Y1, Y2``) and +Y (``Y3, Y4``); branch A."""
    z = np.array([lzz_m] * 4 + [lzy_m] * 4, float)
    pos = np.stack([_EQ16_SIGNS_XY[:, 0] * lx_m, _EQ16_SIGNS_XY[:, 1] * ly_m, z], -1)
    return tuple(Thruster(n, pos[k], _EQ16_DIRECTIONS[k].copy(), None, "A")
                 for k, n in enumerate(THRUSTER_NAMES))


def moment_matrix(thrusters: Sequence[Thruster], com_m=(0.0, 0.0, 0.0)) -> np.ndarray:
    """(3, m) torque per newton of each thruster, N m / N: column ``s`` is ``(r_s − e) × d_s``
    with ``e`` the centre of mass (m) in the frame of the positions (Feldman & Lee Eq 16)."""
    if not thrusters:
        return np.zeros((3, 0))
    pos = np.stack([s.position for s in thrusters])
    dirs = np.stack([s.direction for s in thrusters])
    # Feldman & Lee Eq 16: Q = [(r_s - e) x d_s]_s
    return np.cross(pos - np.asarray(com_m, float)[None, :], dirs).T


def eq16_moment_matrix(lx_m: float, ly_m: float, lzy_m: float, lzz_m: float,
                       com_m=(0.0, 0.0, 0.0)) -> np.ndarray:
    """(3, 8) moment matrix of Feldman & Lee Eq 16 from its lever arms and centre of mass (m)."""
    return moment_matrix(eq16_thrusters(lx_m, ly_m, lzy_m, lzz_m), com_m)


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
    ``[telemetry_knowledge]`` (``time_tag_sd_s``) and ``[torque_knowledge]`` (``sd_nm``,
    ``rate_sd_nm_per_h``). The defaults are conservative engineering values, not numbers from
    the papers: a gyro bias of 5e-7 rad/s (0.1 deg/h) per axis, a gyro
    scale-factor error of 5e-4 (500 ppm) per axis, a spin-inertia error of 0.5 % per wheel (each
    wheel independently; a ``[[wheel]]`` table's ``inertia_sd_frac`` overrides it for that
    wheel) plus 0.5 % shared by every wheel (one calibration method, test stand and temperature;
    the data cannot tell it from the overall scale of the inertia, so the moments' uncertainty
    rests on it; 0 removes it), a wheel spin-axis misalignment of 0.2 deg per tilt component
    (Brown §III.A finds the re-articulated RWA4 0.53 deg from its nominal axis; the fixed wheels are known better) and a white time-tag error
    of 10 ms per telemetry sample (the papers give no figure; 1 % of Cassini's 1 s sample period).
    External torques (the robust models' body-fixed and inertial torques): 15 µN m per axis, the
    Feldman & Lee App. A bound for March 2000 taken as one sd, and a rate of change of 15 µN m
    per hour (solar and RTG torques change as the slews turn the sun line). Where the torques the
    calibration windows cannot measure may be larger (another epoch, outgassing, a leak), say so
    here: the RWA4 axis's cone rests on this prior (``docs/robust/open_world.md``).
    """

    gyro_bias_sd_rad_s: float = 5e-7
    gyro_scale_factor_sd: float = 5e-4
    wheel_inertia_sd_frac: float = 0.005
    wheel_axis_sd_deg: float = 0.2
    time_tag_sd_s: float = 0.01
    wheel_common_inertia_sd_frac: float = 0.005
    torque_sd_nm: float = 15e-6
    torque_rate_sd_nm_per_h: float = 15e-6


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
                                               "reference_tol_deg": w.reference_tol_deg})}
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
            "telemetry_knowledge": {"time_tag_sd_s": self.knowledge.time_tag_sd_s},
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


_TOP_KEYS = {"name", "description", "source", "inertia", "wheel", "thrusters", "thruster",
             "center_of_mass", "pulse", "thrust", "mass", "gyro", "wheel_knowledge",
             "telemetry_knowledge", "torque_knowledge"}
_GYRO_KEYS = {"bias_sd_rad_s": "gyro_bias_sd_rad_s", "scale_factor_sd": "gyro_scale_factor_sd"}
_WHEEL_KNOWLEDGE_KEYS = {"inertia_sd_frac": "wheel_inertia_sd_frac",
                         "common_inertia_sd_frac": "wheel_common_inertia_sd_frac",
                         "axis_sd_deg": "wheel_axis_sd_deg"}
_TELEMETRY_KNOWLEDGE_KEYS = {"time_tag_sd_s": "time_tag_sd_s"}
_TORQUE_KNOWLEDGE_KEYS = {"sd_nm": "torque_sd_nm", "rate_sd_nm_per_h": "torque_rate_sd_nm_per_h"}
_INERTIA_KEYS = {"Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz", "moi_uncertainty", "poi_uncertainty"}
_WHEEL_KEYS = {"name", "axis", "inertia", "inertia_sd_frac", "max_speed_rpm", "max_torque_nm",
               "articulated", "cone_axis", "cone_deg", "cone_sd_deg", "reference",
               "reference_tol_deg"}
_EQ16_KEYS = {"Lx", "Ly", "Lzy", "Lzz", "com"}
_THRUSTER_ENTRY_KEYS = {"name", "position", "direction", "F", "branch"}
_COM_KEYS = {"offset_m", "sd_m"}
_NAME_PATTERN = re.compile(r"[A-Za-z][A-Za-z0-9_]*\Z")
_RESERVED_COLUMNS = {"t", "q1", "q2", "q3", "q4", "wx", "wy", "wz"}
_PULSE_KEYS = set(PulseConstants.__dataclass_fields__)


# Physical ranges of the model-file numbers (docs/limits.md): wide margins around any spacecraft,
# tight enough that nothing downstream can overflow (products of inertia, rate and time stay
# far below 1e308).
INERTIA_MAX = 1e9
"""Largest moment or product of inertia, kg m² (the ISS is ~1e8; Cassini ~9e3)."""
INERTIA_MIN = 1e-4
"""Smallest principal moment, kg m² (a 1U CubeSat is ~2e-3)."""
WHEEL_INERTIA_RANGE = (1e-6, 100.0)
"""Wheel spin inertia, kg m² (Cassini's RWAs 0.16; the ISS's CMG rotors ~7)."""
LENGTH_MAX = 100.0
"""Largest thruster lever arm or centre-of-mass offset, m (Cassini's lever arms are 1.2-3.0 m)."""
THRUST_MAX = 1e3
"""Largest steady thrust per thruster, N (Cassini's 0.75 N RCS, its main engine 445 N)."""
TAU_MAX = 10.0
"""Largest pulse time constant or range end, s (Cassini's are tens of ms)."""
TAU_LOG_SD_MAX = 2.0
"""Largest ``pulse.tau_log_sd_min`` (a factor e^±4 at ±2σ; wider says nothing)."""
POI_DEFAULT_FRAC = 0.01
"""Default ``inertia.poi_uncertainty``: this fraction of the largest predicted moment, kg m²
(Cassini's files state ±75 kg m², 0.85 % of its 8800 kg m²)."""
MASS_MAX = 1e7
"""Largest mass, kg (Cassini 5.7 t fuelled; the ISS 4.2e5 kg)."""
WHEEL_SPEED_MAX_RPM = 1e5
"""Largest ``wheel.max_speed_rpm`` (CubeSat wheels run to ~1e4 rpm, Cassini's to ~2000)."""
WHEEL_TORQUE_MAX_NM = 100.0
"""Largest ``wheel.max_torque_nm`` (CubeSat wheels give ~1e-3 N m, large CMGs ~1e2)."""
TORQUE_HOLD_MIN_S = 60.0
"""``[torque_knowledge] sd_nm`` (and ``rate_sd_nm_per_h``) are at most the wheels' momentum
capacity over this time, N m: a torque that would fill the wheels within a minute is no
disturbance of a wheel-controlled spacecraft, but a unit error (µN m written as N m)."""


def check_physical_inertia(inertia: np.ndarray, what: str, src: str) -> None:
    """Raise unless ``inertia`` is a finite, symmetric positive definite tensor within
    :data:`INERTIA_MAX` that obeys the triangle inequalities."""
    if not np.all(np.isfinite(inertia)) or np.max(np.abs(inertia)) > INERTIA_MAX:
        raise InputError(f"{what} has an entry outside +-{INERTIA_MAX:g} kg m^2 (or not finite); "
                         "inertias are in kg m^2 (docs/limits.md)", path=src)
    eig = np.linalg.eigvalsh(inertia)
    if eig[0] <= 0:
        raise InputError(f"{what} is not positive definite (eigenvalues {np.round(eig, 3)} kg m^2);"
                         " check the signs and magnitudes of the entries", path=src)
    if eig[0] < INERTIA_MIN:
        raise InputError(f"{what} has a principal moment {eig[0]:.3g} kg m^2 below "
                         f"{INERTIA_MIN:g} kg m^2; inertias are in kg m^2 (docs/limits.md)",
                         path=src)
    if eig[0] + eig[1] < eig[2] * (1 - 1e-12):
        raise InputError(f"{what} violates the triangle inequality (principal moments "
                         f"{np.round(eig, 3)} kg m^2): no rigid body has it", path=src)


def spacecraft_from_dict(d: dict[str, Any], src: str = "<spacecraft>") -> Spacecraft:
    """Build and validate a :class:`Spacecraft` from the TOML schema (as a dict).

    Every key is checked for type, finiteness and physical range (the ranges are the module
    constants above, documented in docs/limits.md); any failure is one :class:`InputError` line
    naming ``src`` and the key.
    """
    top = TomlTable(d, "", src, _TOP_KEYS)
    inertia_t = top.sub("inertia", _INERTIA_KEYS, required=True)
    xx, yy, zz = (inertia_t.in_range(k, lo=0.0, hi=INERTIA_MAX, unit="kg m^2")
                  for k in ("Ixx", "Iyy", "Izz"))
    xy, xz, yz = (inertia_t.in_range(k, lo=-INERTIA_MAX, hi=INERTIA_MAX, unit="kg m^2",
                                     open_lo=False) for k in ("Ixy", "Ixz", "Iyz"))
    inertia = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    check_physical_inertia(inertia, "[inertia]", src)
    moi = inertia_t.num("moi_uncertainty", 0.10)
    poi = inertia_t.in_range("poi_uncertainty", POI_DEFAULT_FRAC * max(xx, yy, zz), lo=0.0,
                             hi=INERTIA_MAX, unit="kg m^2")
    if not 0 < moi < 1:
        raise InputError(f"'inertia.moi_uncertainty' is a fraction in (0, 1), got {moi}", path=src)

    wheels = _wheels(top)
    thrusters, eq16, com = _thrusters(top)
    com_t = top.sub("center_of_mass", _COM_KEYS)
    if com_t.has("offset_m"):
        if eq16 is not None:
            raise InputError("give the centre of mass once: '[thrusters] com' (Eq 16 shorthand) "
                             "or 'center_of_mass.offset_m', not both", path=src)
        com = com_t.vec("offset_m", hi=LENGTH_MAX)
    com_sd = com_t.in_range("sd_m", _default_com_sd(thrusters), lo=0.0, hi=LENGTH_MAX, unit="m",
                            open_lo=False)

    if not thrusters:
        for key in ("pulse", "thrust"):
            if key in d:
                raise InputError(f"[{key}] describes thrusters, but the model has none (no "
                                 "[[thruster]] entries); remove it or add the thrusters",
                                 path=src)
    pulse_t = top.sub("pulse", _PULSE_KEYS)
    base = PulseConstants()
    kw = {}
    for k in ("tau_delay", "tau_rise", "tau_fall"):
        kw[k] = pulse_t.in_range(k, getattr(base, k), lo=0.0, hi=TAU_MAX, unit="s")
        rk = k + "_range"
        kw[rk] = pulse_t.interval(rk, getattr(base, rk), TAU_MAX)
    kw["tau_log_sd_min"] = pulse_t.in_range("tau_log_sd_min", base.tau_log_sd_min, lo=0.0,
                                            hi=TAU_LOG_SD_MAX)
    thrust = _nominal_thrust(top.sub("thrust", {"F"}), thrusters, eq16)
    mass_t = top.sub("mass", {"kg"})
    mass = (mass_t.in_range("kg", lo=0.0, hi=MASS_MAX, unit="kg") if mass_t.table
            else float("nan"))
    return Spacecraft(
        name=top.string("name", Path(src).stem), inertia=inertia, moi_uncertainty=moi,
        poi_uncertainty=poi, wheels=wheels, thrusters=thrusters, pulse=PulseConstants(**kw),
        thrust=thrust, mass=mass, description=top.string("description", ""),
        source=top.string("source", ""),
        knowledge=_knowledge(top, _capacity_nms(wheels)),
        com_m=com, com_sd_m=com_sd, eq16=eq16,
    )


def _column_name(name: str, where: str, what: str, src: str) -> str:
    """``name`` when it can name a telemetry column (a letter, then letters, digits or ``_``;
    not a required column), else an InputError naming the entry."""
    if not _NAME_PATTERN.match(name) or name.lower() in _RESERVED_COLUMNS:
        raise InputError(f"'{where}name' = {name!r}: a {what} name becomes a telemetry column, so "
                         "it must start with a letter and hold only letters, digits and '_', "
                         f"and not be one of {' '.join(sorted(_RESERVED_COLUMNS))}", path=src)
    return name


def _unique(names: Sequence[str], what: str, src: str) -> None:
    """Raise naming the first name given twice (case-insensitive: column headers are)."""
    seen: dict[str, int] = {}
    for i, n in enumerate(names):
        if n.upper() in seen:
            raise InputError(f"two {what}s are named {n!r} ({what}[{seen[n.upper()]}] and "
                             f"{what}[{i}]); each {what} needs its own name", path=src)
        seen[n.upper()] = i


def _unit(table: TomlTable, key: str, label: str) -> np.ndarray:
    """``table[key]``, a unit 3-vector (within :data:`~cassini_bayes._toml.UNIT_TOL`),
    normalised; else an InputError naming the key and ``label``."""
    v = table.vec(key, hi=LENGTH_MAX)
    name = table.where + key
    norm = float(np.linalg.norm(v))
    if norm == 0:
        raise InputError(f"'{name}' of {label} is zero; it must be a unit vector", path=table.src)
    if abs(norm - 1) > UNIT_TOL:
        raise InputError(f"'{name}' of {label} must be a unit vector (|v| = {norm:.6f}); "
                         "normalise it", path=table.src)
    return v / norm


def _wheels(top: TomlTable) -> tuple[Wheel, ...]:
    """The ``[[wheel]]`` entries, checked (unique names, unit axes, limits)."""
    src = top.src
    entries = top.items("wheel", _WHEEL_KEYS, per="wheel")
    if not entries:
        raise InputError("at least one [[wheel]] is required", path=src)
    wheels = []
    for w in entries:
        name = _column_name(w.string("name"), w.where, "wheel", src).upper()
        axis = _unit(w, "axis", f"wheel {name}")
        j = w.in_range("inertia", lo=WHEEL_INERTIA_RANGE[0], hi=WHEEL_INERTIA_RANGE[1],
                       unit="kg m^2", open_lo=False)
        sd = None
        if w.has("inertia_sd_frac"):
            sd = w.num("inertia_sd_frac")
            if not 0 <= sd < 0.5:
                raise w.err("inertia_sd_frac", f"is a fraction in [0, 0.5) (0.005 = 0.5 %), got "
                                               f"{sd}")
        speed = w.in_range("max_speed_rpm", np.inf, lo=0.0, hi=WHEEL_SPEED_MAX_RPM, unit="rpm")
        torque = w.in_range("max_torque_nm", np.inf, lo=0.0, hi=WHEEL_TORQUE_MAX_NM, unit="N m")
        articulated = w.flag("articulated", False)
        wheels.append(Wheel(name, axis, j, sd, speed, torque, articulated, _cone(w, name),
                            *_reference(w, name)))
    _unique([w.name for w in wheels], "wheel", src)
    names = {w.name for w in wheels}
    for i, w in enumerate(wheels):
        if w.reference is not None and (w.reference not in names or w.reference == w.name):
            raise InputError(f"'wheel[{i}].reference' = {w.reference!r} must name another wheel "
                             f"of the model ({', '.join(sorted(names - {w.name}))})", path=src)
    return tuple(wheels)


def _cone(w: TomlTable, name: str) -> WheelCone | None:
    """The wheel's articulation cone (``cone_axis``, ``cone_deg``, optional ``cone_sd_deg``), or
    ``None`` when the entry gives none; the axis and the angle come together."""
    where = w.where
    given = [k for k in ("cone_axis", "cone_deg", "cone_sd_deg") if w.has(k)]
    if not given:
        return None
    if not w.has("cone_axis") or not w.has("cone_deg"):
        missing = "cone_axis" if not w.has("cone_axis") else "cone_deg"
        raise InputError(f"'{where}{given[0]}' needs '{where}{missing}' too (wheel {name}: the "
                         "articulation cone is an axis and an angle from it)", path=w.src)
    axis = _unit(w, "cone_axis", f"wheel {name}")
    angle = w.in_range("cone_deg", lo=0.0, hi=180.0, unit="deg")
    sd = w.in_range("cone_sd_deg", 1.0, lo=0.0, hi=30.0, unit="deg")
    return WheelCone(axis, angle, sd)


def _reference(w: TomlTable, name: str) -> tuple[str | None, float | None]:
    """The wheel's reference wheel and tolerance (deg), or ``(None, None)``; both or neither."""
    where = w.where
    if not w.has("reference") and not w.has("reference_tol_deg"):
        return None, None
    if not w.has("reference") or not w.has("reference_tol_deg"):
        missing = "reference" if not w.has("reference") else "reference_tol_deg"
        raise InputError(f"wheel {name}: '{where}reference' and '{where}reference_tol_deg' come "
                         f"together; add '{where}{missing}'", path=w.src)
    ref = w.string("reference").upper()
    return ref, w.in_range("reference_tol_deg", lo=0.0, hi=180.0, unit="deg")


def _thrusters(top: TomlTable
               ) -> tuple[tuple[Thruster, ...], tuple[float, float, float, float] | None,
                          np.ndarray]:
    """``(thrusters, Eq 16 lever arms or None, centre of mass (3,) m)`` from ``[[thruster]]``
    entries or Cassini's ``[thrusters]`` shorthand (none: a spacecraft without thrusters)."""
    if top.has("thrusters") and top.has("thruster"):
        raise InputError("give the thrusters once: [[thruster]] entries or the [thrusters] "
                         "shorthand of Feldman & Lee Eq 16, not both", path=top.src)
    if top.has("thrusters"):
        eq16_t = top.sub("thrusters", _EQ16_KEYS)
        arms = tuple(eq16_t.in_range(k, lo=0.0, hi=LENGTH_MAX, unit="m")
                     for k in ("Lx", "Ly", "Lzy", "Lzz"))
        com = eq16_t.vec("com", default=[0.0, 0.0, 0.0], hi=LENGTH_MAX)
        return eq16_thrusters(*arms), arms, com
    out = []
    for x in top.items("thruster", _THRUSTER_ENTRY_KEYS, per="thruster"):
        name = _column_name(x.string("name"), x.where, "thruster", x.src)
        for key in ("position", "direction"):
            if not x.has(key):
                raise InputError(f"missing required key '{x.where}{key}' (thruster {name})",
                                 path=x.src)
        pos = x.vec("position", hi=LENGTH_MAX)
        direction = _unit(x, "direction", f"thruster {name}")
        f = x.in_range("F", lo=0.0, hi=THRUST_MAX, unit="N") if x.has("F") else None
        out.append(Thruster(name, pos, direction, f, x.string("branch", "")))
    _unique([s.name for s in out], "thruster", top.src)
    return tuple(out), None, np.zeros(3)


def _nominal_thrust(thrust_t: TomlTable, thrusters: Sequence[Thruster], eq16) -> float:
    """The model's nominal thrust per thruster, N: ``[thrust] F``; without it Cassini's 0.75 N for
    the Eq 16 shorthand, the mean of the per-thruster ``F`` for ``[[thruster]]`` entries (each
    must then have one); NaN without thrusters."""
    if not thrusters:
        return float("nan")
    if thrust_t.has("F") or eq16 is not None:
        return thrust_t.in_range("F", 0.75, lo=0.0, hi=THRUST_MAX, unit="N")
    missing = [s.name for s in thrusters if s.thrust_n is None]
    if missing:
        raise InputError(f"thruster {missing[0]} has no thrust: give 'F' (N) in its [[thruster]] "
                         "entry or the model's [thrust] F", path=thrust_t.src)
    return float(np.mean([s.thrust_n for s in thrusters]))


def _knowledge(top: TomlTable, capacity_nms: float) -> Knowledge:
    """The optional ``[gyro]``, ``[wheel_knowledge]``, ``[telemetry_knowledge]`` and
    ``[torque_knowledge]`` sections (one sd each, ≥ 0); the torques at most the wheels'
    momentum ``capacity_nms`` over :data:`TORQUE_HOLD_MIN_S`."""
    src = top.src
    base = Knowledge()
    kw = {}
    for section, keys in (("gyro", _GYRO_KEYS), ("wheel_knowledge", _WHEEL_KNOWLEDGE_KEYS),
                          ("telemetry_knowledge", _TELEMETRY_KNOWLEDGE_KEYS),
                          ("torque_knowledge", _TORQUE_KNOWLEDGE_KEYS)):
        table = top.sub(section, set(keys))
        for key, attr in keys.items():
            v = table.num(key, getattr(base, attr))
            if v < 0:
                raise InputError(f"'{section}.{key}' is a standard deviation and must be >= 0, "
                                 f"got {v}", path=src)
            kw[attr] = v
    for key in ("inertia_sd_frac", "common_inertia_sd_frac"):
        if kw[_WHEEL_KNOWLEDGE_KEYS[key]] >= 0.5:
            raise InputError(f"'wheel_knowledge.{key}' is a fraction (0.005 = 0.5 %), got "
                             f"{kw[_WHEEL_KNOWLEDGE_KEYS[key]]}", path=src)
    hold = capacity_nms / TORQUE_HOLD_MIN_S
    given = top.sub("torque_knowledge", set(_TORQUE_KNOWLEDGE_KEYS))
    for key in ("sd_nm", "rate_sd_nm_per_h"):
        if given.has(key) and kw[_TORQUE_KNOWLEDGE_KEYS[key]] > hold:
            raise InputError(f"'torque_knowledge.{key}' is a small external torque in N m "
                             f"(at most {hold:.3g}, what fills the wheels' {capacity_nms:.3g} "
                             f"N m s in a minute; Cassini's is ~1.5e-5), got "
                             f"{kw[_TORQUE_KNOWLEDGE_KEYS[key]]}", path=src)
    if kw["wheel_axis_sd_deg"] > 10:
        raise InputError("'wheel_knowledge.axis_sd_deg' is a small misalignment in degrees "
                         f"(<= 10), got {kw['wheel_axis_sd_deg']}", path=src)
    if kw["gyro_bias_sd_rad_s"] > 1e-2:
        raise InputError("'gyro.bias_sd_rad_s' is a small gyro bias in rad/s (<= 0.01), got "
                         f"{kw['gyro_bias_sd_rad_s']}", path=src)
    if kw["gyro_scale_factor_sd"] >= 0.1:
        raise InputError("'gyro.scale_factor_sd' is a small fraction (< 0.1), got "
                         f"{kw['gyro_scale_factor_sd']}", path=src)
    if kw["time_tag_sd_s"] > 1.0:
        raise InputError("'telemetry_knowledge.time_tag_sd_s' is a time-tag error in seconds "
                         f"(<= 1), got {kw['time_tag_sd_s']}", path=src)
    return Knowledge(**kw)


def load_spacecraft(path: str | os.PathLike) -> Spacecraft:
    """Load a spacecraft model TOML (a path, or the stem of a file shipped under ``models/``)."""
    if as_path(path, "a spacecraft model .toml file or a shipped model's name").is_dir():
        raise InputError("is a directory, expected a spacecraft model .toml file", path=str(path))
    p = model_path(str(path))
    d = read_toml(p, "spacecraft model", "models/")
    return spacecraft_from_dict(d, str(p))
