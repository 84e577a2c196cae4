"""The ``[truth]`` and ``[prior]`` sections of a scenario: the true spacecraft (a model file plus
overrides) and the prior model the calibration starts from."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import NamedTuple

import numpy as np

from cassini_bayes._paths import DATA_DIR
from cassini_bayes._toml import TomlTable
from cassini_bayes.errors import InputError
from cassini_bayes.spacecraft import (LENGTH_MAX, TAU_MAX, THRUST_MAX, PulseConstants,
                                      Spacecraft, check_physical_inertia, load_spacecraft,
                                      tilted_axis)

TRUTH_KEYS = {"model", "inertia", "thrust_n", "tau_delay_s", "tau_rise_s", "tau_fall_s",
              "rwa4_axis", "external_torque_inertial_nm", "external_torque_body_nm",
              "external_torque_inertial_rate_nm_s", "wheel_inertia_scale", "wheel_axis_tilt_deg",
              "wheel_inertia_errors", "wheel_inertia_error_sd", "center_of_mass_offset_m"}
_INERTIA_KEYS = {"Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz"}
_WHEEL_ERROR_STREAM = 1   # the random stream of the wheel spin-inertia error draws


class Truth(NamedTuple):
    """The ``[truth]`` section read: the true spacecraft and what it does not hold itself.

    spacecraft : the true model (inertia, pulse, thrust mean, wheels, centre of mass overridden).
    model_path : the model file it came from.
    thrust_n : each thruster's true thrust, N (m,).
    external_torque_inertial_nm, external_torque_body_nm : constant disturbance torques, N m (3,).
    external_torque_inertial_rate_nm_s : the inertial torque's rate of change, N m/s (3,).
    wheel_inertia_scale : true spin inertias over the model file's, all wheels.
    wheel_inertia_errors : each wheel's fractional error (k,), ``None`` when not given.
    """

    spacecraft: Spacecraft
    model_path: str
    thrust_n: np.ndarray
    external_torque_inertial_nm: np.ndarray
    external_torque_body_nm: np.ndarray
    external_torque_inertial_rate_nm_s: np.ndarray
    wheel_inertia_scale: float
    wheel_inertia_errors: np.ndarray | None


def model_file(name: str, key: str, src: str) -> tuple[Spacecraft, str]:
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


def wheel_index(sc: Spacecraft, name: str, key: str, src: str) -> int:
    """Index of the wheel ``name`` among the model's (case-insensitive), else an error naming
    ``key``."""
    names = [n.upper() for n in sc.wheel_names]
    if str(name).upper() not in names:
        raise InputError(f"'{key}' names no wheel of the model: {name!r} (have "
                         f"{', '.join(names)})", path=src)
    return names.index(str(name).upper())


def read_truth(top: TomlTable, seed: int) -> Truth:
    """``[truth]``: the model file, then its overrides (inertia, thrust, pulse time constants,
    wheel axes and inertias, centre of mass) and the disturbance torques."""
    section = top.sub("truth", TRUTH_KEYS, required=True)
    truth, path = model_file(section.string("model"), "truth.model", section.src)
    truth = truth.with_inertia(_inertia(section, truth.inertia))
    thrust = _thrust(section, truth)
    truth = replace(truth, pulse=_pulse(section, truth),
                    thrust=float(np.mean(thrust)) if truth.thrusters else truth.thrust)
    if section.has("rwa4_axis"):
        axis = section.vec("rwa4_axis", unit=True)
        wheel_index(truth, "RWA4", "truth.rwa4_axis", section.src)
        truth = truth.with_wheel_axis("RWA4", axis / np.linalg.norm(axis))
    # Real-world errors: true wheels differing from the model file (the prior model keeps its own).
    scale = section.num("wheel_inertia_scale", 1.0, positive=True)
    if abs(scale - 1.0) >= 0.5:
        raise section.err("wheel_inertia_scale", f"= {scale} must be close to 1 (a fractional "
                                                 "error)")
    errors = _wheel_inertia_errors(section, len(truth.wheels), seed)
    truth = _true_wheels(section, truth, scale, errors)
    if section.has("center_of_mass_offset_m"):
        if not truth.thrusters:
            raise section.err("center_of_mass_offset_m", f"moves the centre of mass the "
                                                         f"thrusters turn about, but the truth "
                                                         f"model {truth.name!r} has no thrusters")
        truth = replace(truth, com_m=truth.com_m + section.vec("center_of_mass_offset_m",
                                                               hi=LENGTH_MAX))
    return Truth(truth, path, thrust,
                 section.vec("external_torque_inertial_nm", default=np.zeros(3)),
                 section.vec("external_torque_body_nm", default=np.zeros(3)),
                 section.vec("external_torque_inertial_rate_nm_s", default=np.zeros(3)),
                 scale, errors)


def _inertia(section: TomlTable, model_inertia: np.ndarray) -> np.ndarray:
    """``[truth.inertia]``: the model file's inertia (kg m²) with the given entries replaced."""
    table = section.sub("inertia", _INERTIA_KEYS)
    i0 = model_inertia
    xx, yy, zz = (table.num(k, i0[j, j], positive=True)
                  for j, k in enumerate(("Ixx", "Iyy", "Izz")))
    xy, xz, yz = table.num("Ixy", i0[0, 1]), table.num("Ixz", i0[0, 2]), table.num("Iyz", i0[1, 2])
    inertia = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    check_physical_inertia(inertia, "[truth.inertia]", section.src)
    return inertia


def _thrust(section: TomlTable, truth: Spacecraft) -> np.ndarray:
    """``thrust_n``: one thrust for all thrusters or a list of one each (N); else the model's."""
    m = len(truth.thrusters)
    if not section.has("thrust_n"):
        return truth.thrust_per_thruster
    if not m:
        raise section.err("thrust_n", f"gives a thrust, but the truth model {truth.name!r} has "
                                      "no thrusters")
    if isinstance(section.table["thrust_n"], list):
        thrust = section.vec("thrust_n", m, nonneg=True, hi=THRUST_MAX)
    else:
        thrust = np.full(m, section.num("thrust_n", positive=True, hi=THRUST_MAX))
    if np.any(thrust <= 0):
        raise section.err("thrust_n", "must be positive (N)")
    return thrust


def _pulse(section: TomlTable, truth: Spacecraft) -> PulseConstants:
    """``tau_delay_s``, ``tau_rise_s``, ``tau_fall_s`` over the model's pulse time constants; a
    valve may open at once (first-order valve: tau_delay_s = 0, tau_rise_s = tau_fall_s)."""
    pulse = truth.pulse
    return replace(pulse, **{k: section.num(f"{k}_s", getattr(pulse, k),
                                            positive=k != "tau_delay", nonneg=True, hi=TAU_MAX)
                             for k in ("tau_delay", "tau_rise", "tau_fall")})


def _wheel_inertia_errors(section: TomlTable, k: int, seed: int) -> np.ndarray | None:
    """Each wheel's fractional spin-inertia error (k,): ``[truth] wheel_inertia_errors`` plus
    independent ``N(0, wheel_inertia_error_sd²)`` draws from the scenario's seed (its own stream,
    so the sensor noise is untouched); ``None`` when neither key is given."""
    if not (section.has("wheel_inertia_errors") or section.has("wheel_inertia_error_sd")):
        return None
    err = section.vec("wheel_inertia_errors", k, default=np.zeros(k))
    sd = section.num("wheel_inertia_error_sd", 0.0, nonneg=True)
    err = err + sd * np.random.default_rng([seed, _WHEEL_ERROR_STREAM]).standard_normal(k)
    if np.any(np.abs(err) >= 0.1):
        raise section.err("wheel_inertia_errors", f"= {np.round(err, 4).tolist()}: each wheel's "
                          "error is a small fraction (|e| < 0.1; with wheel_inertia_error_sd, the "
                          "drawn one)")
    return err


def _true_wheels(section: TomlTable, truth: Spacecraft, scale: float,
                 errors: np.ndarray | None) -> Spacecraft:
    """The true wheels: axes tilted by ``wheel_axis_tilt_deg`` (along
    ``spacecraft.wheel_tilt_basis``), spin inertias ``scale × (1 + e_k)`` × the model file's."""
    tilts = section.sub("wheel_axis_tilt_deg", set(truth.wheel_names))
    wheels = []
    for wheel, error in zip(truth.wheels,
                            errors if errors is not None else np.zeros(len(truth.wheels))):
        axis = wheel.axis
        if wheel.name in tilts.table:
            tilt_deg = tilts.vec(wheel.name, 2)
            if np.any(np.abs(tilt_deg) > 10.0):
                raise tilts.err(wheel.name, "tilts are small angles in degrees (|a| <= 10)")
            axis = tilted_axis(axis, np.deg2rad(tilt_deg))
        wheels.append(replace(wheel, axis=axis, inertia=wheel.inertia * scale * (1.0 + error)))
    return replace(truth, wheels=tuple(wheels))


def read_prior(top: TomlTable, truth: Spacecraft) -> tuple[Spacecraft, str]:
    """``[prior]``: the model the calibration starts from (the truth's wheels and thrusters)."""
    section = top.sub("prior", {"model"}, required=True)
    prior, path = model_file(section.string("model"), "prior.model", section.src)
    if prior.wheel_names != truth.wheel_names:
        raise InputError("'prior.model' must have the same wheels as 'truth.model'",
                         path=section.src)
    if prior.thruster_names != truth.thruster_names:
        raise InputError("'prior.model' must have the same thrusters as 'truth.model'",
                         path=section.src)
    return prior, path
