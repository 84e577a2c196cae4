"""Spacecraft model objects, loaded and validated from the TOML files under ``models/``.

A model file (docs/design.md §4.3) holds the *predicted* mass properties and the hardware geometry a
calibration needs. Required sections: ``[inertia]``, at least one ``[[wheel]]``, ``[thrusters]``.
Optional sections: ``[mass]``, ``[pulse]`` (thruster time constants, their manufacturer
ranges and ``tau_log_sd_min``, the smallest log sd of the thrust fit's rise and fall priors),
``[thrust]`` (predicted force), ``[gyro]`` and ``[wheel_knowledge]`` (the knowledge of the
sensors and wheels, the priors of the robust models' nuisance parameters; :class:`Knowledge`).
Unknown keys are errors, so a typo never goes unnoticed.

Units: kg m² for inertias, m for lengths, s for time constants, N for thrust. Wheel axes are unit
vectors in body axes (the columns of Feldman & Lee's ``T``, App. A).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from cassini_bayes._paths import model_path
from cassini_bayes._toml import is_numbers, read_toml
from cassini_bayes.errors import InputError, as_path

__all__ = ["Wheel", "Thrusters", "PulseConstants", "Knowledge", "Spacecraft", "wheel_tilt_basis",
           "tilted_axis", "load_spacecraft",
           "spacecraft_from_dict", "CASSINI_WHEEL_AXES"]

# Feldman & Lee (2006) App. A: RWA → body matrix T; its columns are the spin axes of RWA1-3.
_S2, _S3, _S6 = np.sqrt(2.0), np.sqrt(3.0), np.sqrt(6.0)
CASSINI_T = np.array(
    [[0.0, -1.0 / _S2, 1.0 / _S2], [_S2 / _S3, -1.0 / _S6, -1.0 / _S6], [1 / _S3, 1 / _S3, 1 / _S3]]
)
CASSINI_WHEEL_AXES = CASSINI_T.T.copy()  # rows: RWA1, RWA2, RWA3 spin axes (body)

_UNIT_TOL = 1e-6


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
class Wheel:
    """A reaction wheel: ``axis`` unit vector in body axes, ``inertia`` kg m² about it.

    ``inertia_sd_frac``: this wheel's spin-inertia knowledge (one sd, a fraction), overriding
    ``[wheel_knowledge] inertia_sd_frac`` for it; ``None`` when the file does not give one.
    """

    name: str
    axis: np.ndarray
    inertia: float
    inertia_sd_frac: float | None = None


@dataclass(frozen=True)
class Thrusters:
    """Thruster geometry of Feldman & Lee Eq 16 (m) and the centre of mass ``com`` (m)."""

    Lx: float = 1.234
    Ly: float = 1.580
    Lzy: float = 2.880
    Lzz: float = 3.019
    com: np.ndarray = field(default_factory=lambda: np.zeros(3))


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
    thrust : predicted steady thrust per thruster, N.
    mass : spacecraft mass, kg (NaN when not given).
    """

    name: str
    inertia: np.ndarray
    moi_uncertainty: float
    poi_uncertainty: float
    wheels: tuple[Wheel, ...]
    thrusters: Thrusters
    pulse: PulseConstants = field(default_factory=PulseConstants)
    thrust: float = 0.75
    mass: float = float("nan")
    description: str = ""
    source: str = ""
    knowledge: Knowledge = field(default_factory=Knowledge)

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

    def wheel(self, name: str) -> Wheel:
        for w in self.wheels:
            if w.name.upper() == name.upper():
                return w
        raise InputError(f"spacecraft model {self.name!r} has no wheel {name!r}; "
                         f"it has {', '.join(self.wheel_names)}")

    def with_inertia(self, inertia) -> "Spacecraft":
        return replace(self, inertia=np.asarray(inertia, float))

    def with_wheel_axis(self, name: str, axis) -> "Spacecraft":
        axis = np.asarray(axis, float)
        wheels = tuple(replace(w, axis=axis) if w.name.upper() == name.upper() else w
                       for w in self.wheels)
        return replace(self, wheels=wheels)

    def to_dict(self) -> dict[str, Any]:
        """The TOML schema as a plain dict (for ``config.toml`` and ``truth.json``)."""
        i = self.inertia
        return {
            "name": self.name,
            "description": self.description,
            "source": self.source,
            "inertia": {"Ixx": float(i[0, 0]), "Iyy": float(i[1, 1]), "Izz": float(i[2, 2]),
                        "Ixy": float(i[0, 1]), "Ixz": float(i[0, 2]), "Iyz": float(i[1, 2]),
                        "moi_uncertainty": self.moi_uncertainty,
                        "poi_uncertainty": self.poi_uncertainty},
            "wheel": [{"name": w.name, "axis": [float(x) for x in w.axis],
                       "inertia": float(w.inertia),
                       **({} if w.inertia_sd_frac is None
                          else {"inertia_sd_frac": w.inertia_sd_frac})} for w in self.wheels],
            "thrusters": {"Lx": self.thrusters.Lx, "Ly": self.thrusters.Ly,
                          "Lzy": self.thrusters.Lzy, "Lzz": self.thrusters.Lzz,
                          "com": [float(x) for x in self.thrusters.com]},
            "pulse": {k: (list(v) if isinstance(v, tuple) else v)
                      for k, v in self.pulse.__dict__.items()},
            "thrust": {"F": self.thrust},
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


_TOP_KEYS = {"name", "description", "source", "inertia", "wheel", "thrusters", "pulse", "thrust",
             "mass", "gyro", "wheel_knowledge", "telemetry_knowledge", "torque_knowledge"}
_GYRO_KEYS = {"bias_sd_rad_s": "gyro_bias_sd_rad_s", "scale_factor_sd": "gyro_scale_factor_sd"}
_WHEEL_KNOWLEDGE_KEYS = {"inertia_sd_frac": "wheel_inertia_sd_frac",
                         "common_inertia_sd_frac": "wheel_common_inertia_sd_frac",
                         "axis_sd_deg": "wheel_axis_sd_deg"}
_TELEMETRY_KNOWLEDGE_KEYS = {"time_tag_sd_s": "time_tag_sd_s"}
_TORQUE_KNOWLEDGE_KEYS = {"sd_nm": "torque_sd_nm", "rate_sd_nm_per_h": "torque_rate_sd_nm_per_h"}
_INERTIA_KEYS = {"Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz", "moi_uncertainty", "poi_uncertainty"}
_WHEEL_KEYS = {"name", "axis", "inertia", "inertia_sd_frac"}
_THRUSTER_KEYS = {"Lx", "Ly", "Lzy", "Lzz", "com"}
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
MASS_MAX = 1e7
"""Largest mass, kg (Cassini 5.7 t fuelled; the ISS 4.2e5 kg)."""


def _check_keys(table: dict, allowed: set[str], where: str, src: str) -> None:
    for key in table:
        if key not in allowed:
            raise InputError(f"unknown key '{where}{key}'; allowed: {', '.join(sorted(allowed))}",
                             path=src)


def _table(d: dict, key: str, src: str, *, required: bool = False) -> dict:
    """The sub-table ``[key]`` ({} when absent and optional); anything else is an error."""
    if key not in d:
        if required:
            raise InputError(f"missing required section [{key}]", path=src)
        return {}
    v = d[key]
    if not isinstance(v, dict):
        raise InputError(f"'{key}' must be a table [{key}], got {v!r}; write it as a [{key}] "
                         "section", path=src)
    return v


def _string(d: dict, key: str, where: str, src: str, default: str | None = None) -> str:
    if key not in d:
        if default is None:
            raise InputError(f"missing required key '{where}{key}'", path=src)
        return default
    v = d[key]
    if not isinstance(v, str):
        raise InputError(f"'{where}{key}' must be a string (in quotes), got {v!r}", path=src)
    return v


def _number(table: dict, key: str, where: str, src: str, default=None,
            lo: float | None = None, hi: float | None = None, unit: str = "",
            open_lo: bool = True) -> float:
    """A finite number, optionally in ``(lo, hi]`` (``[lo, hi]`` with ``open_lo=False``)."""
    if key not in table:
        if default is None:
            raise InputError(f"missing required key '{where}{key}'", path=src)
        return float(default)
    v = table[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
        raise InputError(f"'{where}{key}' must be a finite number, got {v!r}", path=src)
    v = float(v)
    below = lo is not None and (v <= lo if open_lo else v < lo)
    if below or (hi is not None and v > hi):
        rng = f"{'(' if open_lo else '['}{lo:g}, {hi:g}]" if hi is not None else f"> {lo:g}"
        sign = " (it must be positive)" if lo == 0 and v <= 0 else ""
        raise InputError(f"'{where}{key}' = {v:g} {unit} is outside the physical range {rng} "
                         f"{unit}{sign}; check the value and its unit (docs/limits.md)", path=src)
    return v


def _vector(value, key: str, src: str, bound: float = LENGTH_MAX) -> np.ndarray:
    """A list of 3 finite numbers, each of magnitude ≤ ``bound``."""
    if not is_numbers(value) or len(value) != 3:
        raise InputError(f"'{key}' must be a list of 3 numbers, got {value!r}", path=src)
    v = np.asarray(value, float)
    if not np.all(np.isfinite(v)) or np.any(np.abs(v) > bound):
        raise InputError(f"'{key}' must be 3 finite numbers of magnitude <= {bound:g}, got "
                         f"{value!r}", path=src)
    return v


def _pair(table: dict, key: str, where: str, src: str, default: tuple[float, float],
          hi: float) -> tuple[float, float]:
    """``[low, high]`` with ``0 < low < high ≤ hi``."""
    v = table.get(key, list(default))
    ok = is_numbers(v) and len(v) == 2
    if not ok or not (0 < v[0] < v[1] <= hi):
        raise InputError(f"'{where}{key}' must be [low, high] with 0 < low < high <= {hi:g} (s), "
                         f"got {v!r}", path=src)
    return float(v[0]), float(v[1])


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
    _check_keys(d, _TOP_KEYS, "", src)
    ti = _table(d, "inertia", src, required=True)
    _check_keys(ti, _INERTIA_KEYS, "inertia.", src)
    xx, yy, zz = (_number(ti, k, "inertia.", src, lo=0.0, hi=INERTIA_MAX, unit="kg m^2")
                  for k in ("Ixx", "Iyy", "Izz"))
    xy, xz, yz = (_number(ti, k, "inertia.", src, lo=-INERTIA_MAX, hi=INERTIA_MAX,
                          unit="kg m^2", open_lo=False) for k in ("Ixy", "Ixz", "Iyz"))
    inertia = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    check_physical_inertia(inertia, "[inertia]", src)
    moi = _number(ti, "moi_uncertainty", "inertia.", src, 0.10)
    poi = _number(ti, "poi_uncertainty", "inertia.", src, 75.0, lo=0.0, hi=INERTIA_MAX,
                  unit="kg m^2")
    if not 0 < moi < 1:
        raise InputError(f"'inertia.moi_uncertainty' is a fraction in (0, 1), got {moi}", path=src)

    wheels_raw = d.get("wheel", [])
    if not isinstance(wheels_raw, list) or not all(isinstance(w, dict) for w in wheels_raw):
        raise InputError("'wheel' must be an array of tables, one [[wheel]] section per wheel",
                         path=src)
    if not wheels_raw:
        raise InputError("at least one [[wheel]] is required", path=src)
    wheels = []
    for i, w in enumerate(wheels_raw):
        where = f"wheel[{i}]."
        _check_keys(w, _WHEEL_KEYS, where, src)
        name = _string(w, "name", where, src)
        if "axis" not in w:
            raise InputError(f"missing required key '{where}axis'", path=src)
        axis = _vector(w["axis"], where + "axis", src)
        if abs(np.linalg.norm(axis) - 1) > _UNIT_TOL:
            raise InputError(f"'{where}axis' must be a unit vector (|axis| = "
                             f"{np.linalg.norm(axis):.6f}); normalise it", path=src)
        j = _number(w, "inertia", where, src, lo=WHEEL_INERTIA_RANGE[0],
                    hi=WHEEL_INERTIA_RANGE[1], unit="kg m^2", open_lo=False)
        sd = None
        if "inertia_sd_frac" in w:
            sd = _number(w, "inertia_sd_frac", where, src)
            if not 0 <= sd < 0.5:
                raise InputError(f"'{where}inertia_sd_frac' is a fraction in [0, 0.5) (0.005 = "
                                 f"0.5 %), got {sd}", path=src)
        wheels.append(Wheel(name.upper(), axis / np.linalg.norm(axis), j, sd))
    names = [w.name for w in wheels]
    if len(set(names)) != len(names):
        raise InputError(f"wheel names must be unique, got {names}", path=src)

    tt = _table(d, "thrusters", src, required=True)
    _check_keys(tt, _THRUSTER_KEYS, "thrusters.", src)
    thr = Thrusters(*(_number(tt, k, "thrusters.", src, lo=0.0, hi=LENGTH_MAX, unit="m")
                      for k in ("Lx", "Ly", "Lzy", "Lzz")),
                    com=_vector(tt.get("com", [0.0, 0.0, 0.0]), "thrusters.com", src))

    tp = _table(d, "pulse", src)
    _check_keys(tp, _PULSE_KEYS, "pulse.", src)
    base = PulseConstants()
    kw = {}
    for k in ("tau_delay", "tau_rise", "tau_fall"):
        kw[k] = _number(tp, k, "pulse.", src, getattr(base, k), lo=0.0, hi=TAU_MAX, unit="s")
        rk = k + "_range"
        kw[rk] = _pair(tp, rk, "pulse.", src, getattr(base, rk), TAU_MAX)
    kw["tau_log_sd_min"] = _number(tp, "tau_log_sd_min", "pulse.", src, base.tau_log_sd_min,
                                   lo=0.0, hi=TAU_LOG_SD_MAX)
    thrust_t = _table(d, "thrust", src)
    _check_keys(thrust_t, {"F"}, "thrust.", src)
    thrust = _number(thrust_t, "F", "thrust.", src, 0.75, lo=0.0, hi=THRUST_MAX, unit="N")
    mass_t = _table(d, "mass", src)
    _check_keys(mass_t, {"kg"}, "mass.", src)
    mass = (_number(mass_t, "kg", "mass.", src, lo=0.0, hi=MASS_MAX, unit="kg") if mass_t
            else float("nan"))
    return Spacecraft(
        name=_string(d, "name", "", src, Path(src).stem), inertia=inertia, moi_uncertainty=moi,
        poi_uncertainty=poi, wheels=tuple(wheels), thrusters=thr, pulse=PulseConstants(**kw),
        thrust=thrust, mass=mass, description=_string(d, "description", "", src, ""),
        source=_string(d, "source", "", src, ""), knowledge=_knowledge(d, src),
    )


def _knowledge(d: dict[str, Any], src: str) -> Knowledge:
    """The optional ``[gyro]``, ``[wheel_knowledge]`` and ``[telemetry_knowledge]`` sections (one
    sd each, ≥ 0)."""
    base = Knowledge()
    kw = {}
    for section, keys in (("gyro", _GYRO_KEYS), ("wheel_knowledge", _WHEEL_KNOWLEDGE_KEYS),
                          ("telemetry_knowledge", _TELEMETRY_KNOWLEDGE_KEYS),
                          ("torque_knowledge", _TORQUE_KNOWLEDGE_KEYS)):
        table = _table(d, section, src)
        _check_keys(table, set(keys), f"{section}.", src)
        for key, attr in keys.items():
            v = _number(table, key, f"{section}.", src, getattr(base, attr))
            if v < 0:
                raise InputError(f"'{section}.{key}' is a standard deviation and must be >= 0, "
                                 f"got {v}", path=src)
            kw[attr] = v
    for key in ("inertia_sd_frac", "common_inertia_sd_frac"):
        if kw[_WHEEL_KNOWLEDGE_KEYS[key]] >= 0.5:
            raise InputError(f"'wheel_knowledge.{key}' is a fraction (0.005 = 0.5 %), got "
                             f"{kw[_WHEEL_KNOWLEDGE_KEYS[key]]}", path=src)
    for key in ("sd_nm", "rate_sd_nm_per_h"):
        if kw[_TORQUE_KNOWLEDGE_KEYS[key]] > 1e-2:
            raise InputError(f"'torque_knowledge.{key}' is a small external torque in N m "
                             f"(<= 0.01; Cassini's is ~1.5e-5), got "
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


def load_spacecraft(path: str | Path) -> Spacecraft:
    """Load a spacecraft model TOML (a path, or the stem of a file shipped under ``models/``)."""
    if as_path(path, "a spacecraft model .toml file or a shipped model's name").is_dir():
        raise InputError("is a directory, expected a spacecraft model .toml file", path=str(path))
    p = model_path(str(path))
    d = read_toml(p, "spacecraft model", "models/")
    return spacecraft_from_dict(d, str(p))
