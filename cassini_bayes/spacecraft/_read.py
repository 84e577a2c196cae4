"""Read and validate a spacecraft model file (docs/model_file.md) into a :class:`Spacecraft`.

Every key is checked for type, finiteness and physical range (the ranges below, documented in
docs/limits.md); unknown keys are errors, so a typo never goes unnoticed.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from cassini_bayes._paths import model_path
from cassini_bayes._toml import UNIT_TOL, TomlTable, read_toml
from cassini_bayes.errors import InputError, as_path
from cassini_bayes.spacecraft._geometry import (
    QUIET_WHEEL_TOL_RPM,
    Thruster,
    Wheel,
    WheelCone,
    eq16_thrusters,
)
from cassini_bayes.spacecraft._model import (
    Knowledge,
    PulseConstants,
    Spacecraft,
    _capacity_nms,
    _default_com_sd,
)

_TOP_KEYS = {"name", "description", "source", "inertia", "wheel", "thrusters", "thruster",
             "center_of_mass", "pulse", "thrust", "mass", "gyro", "wheel_knowledge",
             "telemetry_knowledge", "torque_knowledge", "flex_knowledge"}
_GYRO_KEYS = {"bias_sd_rad_s": "gyro_bias_sd_rad_s", "scale_factor_sd": "gyro_scale_factor_sd"}
_WHEEL_KNOWLEDGE_KEYS = {"inertia_sd_frac": "wheel_inertia_sd_frac",
                         "common_inertia_sd_frac": "wheel_common_inertia_sd_frac",
                         "axis_sd_deg": "wheel_axis_sd_deg"}
_TELEMETRY_KNOWLEDGE_KEYS = {"time_tag_sd_s": "time_tag_sd_s"}
_FLAGS = {"telemetry_knowledge": {"regular_clock"}}
_TORQUE_KNOWLEDGE_KEYS = {"sd_nm": "torque_sd_nm", "rate_sd_nm_per_h": "torque_rate_sd_nm_per_h"}
_INERTIA_KEYS = {"Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz", "moi_uncertainty", "poi_uncertainty"}
_WHEEL_KEYS = {"name", "axis", "inertia", "inertia_sd_frac", "max_speed_rpm", "max_torque_nm",
               "articulated", "cone_axis", "cone_deg", "cone_sd_deg", "reference",
               "reference_tol_deg", "quiet_tol_rpm"}
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
FLEX_FREQ_MAX_HZ = 50.0
"""Highest ``[flex_knowledge] freq_hz`` (structural modes a pulse of milliseconds can ring)."""
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
        quiet = w.in_range("quiet_tol_rpm", QUIET_WHEEL_TOL_RPM, lo=0.0, hi=WHEEL_SPEED_MAX_RPM,
                           unit="rpm")
        wheels.append(Wheel(name, axis, j, sd, speed, torque, articulated, _cone(w, name),
                            *_reference(w, name), quiet_tol_rpm=quiet))
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
        table = top.sub(section, set(keys) | _FLAGS.get(section, set()))
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
    kw["regular_clock"] = top.sub("telemetry_knowledge", set(_TELEMETRY_KNOWLEDGE_KEYS)
                                  | _FLAGS["telemetry_knowledge"]).flag("regular_clock", False)
    return Knowledge(**kw, **_flex_knowledge(top, src))


def _flex_knowledge(top: TomlTable, src: str) -> dict:
    """The optional ``[flex_knowledge]`` section: ``share_sd`` (a fraction, 0-1), ``freq_hz``
    and ``damping`` (``[low, high]``, at most :data:`FLEX_FREQ_MAX_HZ` and 0.5)."""
    base = Knowledge()
    table = top.sub("flex_knowledge", {"share_sd", "freq_hz", "damping"})
    share = table.num("share_sd", base.flex_share_sd)
    if not 0.0 <= share < 1.0:
        raise InputError("'flex_knowledge.share_sd' is a fraction of the inertia (0.01 = 1 %), "
                         f"got {share}", path=src)
    return {"flex_share_sd": share,
            "flex_freq_hz": table.interval("freq_hz", base.flex_freq_hz, FLEX_FREQ_MAX_HZ, "Hz"),
            "flex_damping": table.interval("damping", base.flex_damping, 0.5, "of critical")}


def load_spacecraft(path: str | os.PathLike) -> Spacecraft:
    """Load a spacecraft model TOML (a path, or the stem of a file shipped under ``models/``)."""
    if as_path(path, "a spacecraft model .toml file or a shipped model's name").is_dir():
        raise InputError("is a directory, expected a spacecraft model .toml file", path=str(path))
    p = model_path(str(path))
    d = read_toml(p, "spacecraft model", "models/")
    return spacecraft_from_dict(d, str(p))
