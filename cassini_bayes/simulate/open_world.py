"""Open-world truths: errors drawn independently of the robust fits' error model.

The robust models (:mod:`cassini_bayes.inference.nuisance`) give every error they know a
zero-mean Normal prior whose sd is the spacecraft model's :class:`~cassini_bayes.spacecraft.
Knowledge`. A campaign that draws the truth's errors from those same Normals checks the sampler,
not the model. :func:`draw_open_world` draws them instead

* from other families — uniform on ``±a``, Student-t with 3 degrees of freedom, Laplace — each
  scaled to an sd ``widen`` (default 1.5) times the prior's, independently per wheel and per axis
  (:data:`LAWS`);
* together with effects no fit models: a flexible mode of random frequency, damping and
  coupling; time-tag errors that are uniform, not Normal, plus occasional stale samples (a packet
  that repeats its neighbour's data: a ±1 sample slip); and a slowly drifting inertial torque,
  drawn uniform (the inertia and RWA4 fits now model a torque rate with a Normal prior; the
  thrust fit does not);
* and, with ``draw_inertia`` (thrust and RWA4 fits, which take the inertia from the model file's
  knowledge), a true inertia uniform on the model file's ``±moi_uncertainty`` moments and
  ``±poi_uncertainty`` products about its prediction;
* and, with ``draw_thrusters`` (per-thruster thrust fits), each thruster's thrust, the valve
  time constants and the centre of mass's offset.

Everything drawn is in :attr:`OpenWorld.record` (JSON-ready, ``truth.json`` style). The errors the
simulator knows go into the scenario dict's ``[truth]``, ``[noise]`` and ``[flex_mode]`` keys
(:mod:`cassini_bayes.simulate.scenario`); the time tags are applied to the simulated telemetry by
:func:`apply_time_tags`. Pure NumPy: the layer imports no sampler.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from cassini_bayes._toml import read_toml
from cassini_bayes.errors import InputError
from cassini_bayes.simulate.scenario import scenario_from_dict, scenario_path
from cassini_bayes.spacecraft import check_physical_inertia
from cassini_bayes.telemetry import Telemetry

__all__ = ["LAWS", "WIDEN", "EFFECTS_OFF", "OpenWorld", "draw_law", "draw_open_world",
           "without", "apply_time_tags", "base_scenario", "inertia_from_knowledge"]

LAWS = ("uniform", "student_t3", "laplace")
"""The non-Normal families, each parametrised by its sd: uniform on ``±√3 sd``, Student-t(3)
scaled by ``sd / √3`` (the t(3) variance is 3), Laplace with scale ``sd / √2``."""
WIDEN = 1.5
"""Default ratio of a drawn error's sd to the fit's prior sd."""
SLIP_PROB = 0.002
"""Chance that a telemetry sample is stale: it repeats its previous or next sample's data."""
THRUST_SPREAD = 0.05
"""Half-width of the true thrusts' uniform spread about their nominal, a fraction."""
FLEX_FREQ_HZ = (0.1, 1.0)        # Cassini's RPWS antennas 0.13 Hz, magnetometer boom 0.7 Hz
FLEX_DAMPING = (0.002, 0.01)     # ζ 0.2-1 % (Feldman & Lee §II)
FLEX_SHARE = (1e-3, 7e-3)        # δᵀ I⁻¹ δ; Cassini's |δ|² 5-40 kg m² (the `_real` scenarios 14)
_MAX_PHASE = 0.45                # 2π f dt below the scenario's 0.5 limit
# Which effects each law draws (a fixed assignment: every effect has a non-Normal family).
EFFECT_LAWS = {"gyro_bias_rad_s": "student_t3", "gyro_scale_factor": "laplace",
               "wheel_inertia_errors": "uniform", "wheel_axis_tilt_deg": "student_t3",
               "external_torque_body_nm": "laplace", "external_torque_inertial_nm": "laplace",
               "time_tag_error_s": "uniform"}


@dataclass(frozen=True)
class OpenWorld:
    """One open-world truth.

    scenario : the TOML-style scenario dict with the drawn truth (``scenario_from_dict`` reads it).
    record : everything drawn, JSON-ready: per effect its law, sd and values.
    time_tag_error_s : (n,) error added to each telemetry sample's time, s.
    slip : (n,) int in {-1, 0, +1}: sample ``i`` carries the data of sample ``i + slip[i]``.
    """

    scenario: dict
    record: dict
    time_tag_error_s: np.ndarray
    slip: np.ndarray


def draw_law(rng: np.random.Generator, law: str, sd: float, size) -> np.ndarray:
    """``size`` independent zero-mean draws of ``law`` (:data:`LAWS`) with standard deviation
    ``sd``."""
    if law == "uniform":
        return rng.uniform(-math.sqrt(3.0) * sd, math.sqrt(3.0) * sd, size)
    if law == "student_t3":
        return sd / math.sqrt(3.0) * rng.standard_t(3, size)
    if law == "laplace":
        return rng.laplace(0.0, sd / math.sqrt(2.0), size)
    raise InputError(f"unknown law {law!r}; use one of {', '.join(LAWS)}")


def base_scenario(base: dict | str | Path) -> dict:
    """A scenario dict: ``base`` itself (copied) or the TOML file it names (a path, or a stem
    under ``experiments/scenarios/``)."""
    if isinstance(base, dict):
        return copy.deepcopy(base)
    return read_toml(scenario_path(str(base)), "scenario", "experiments/scenarios/")


def _effect(rng, name: str, sd: float, size, record: dict) -> np.ndarray:
    law = EFFECT_LAWS[name]
    x = draw_law(rng, law, sd, size)
    record[name] = {"law": law, "sd": sd, "values": x.tolist()}
    return x


def inertia_from_knowledge(rng: np.random.Generator, prior) -> tuple[np.ndarray, np.ndarray]:
    """A true inertia ``(Ixx … Iyz)`` kg m² uniform on the prior model's knowledge box about its
    prediction, redrawn until physical (the triangle inequalities of the principal moments);
    returns it and the box's half-widths."""
    i0 = np.asarray(prior.inertia, float)
    centre = np.array([i0[0, 0], i0[1, 1], i0[2, 2], i0[0, 1], i0[0, 2], i0[1, 2]])
    half = np.concatenate([prior.moi_uncertainty * centre[:3], np.full(3, prior.poi_uncertainty)])
    for _ in range(100):
        v = centre + rng.uniform(-half, half)
        m = np.array([[v[0], v[3], v[4]], [v[3], v[1], v[5]], [v[4], v[5], v[2]]])
        try:
            check_physical_inertia(m, "the drawn inertia", "<open world>")
        except InputError:
            continue
        return v, half
    raise InputError("no physical inertia in 100 draws from the model file's knowledge box")


def _inertia(rng, prior, record: dict) -> dict[str, float]:
    """True inertia from the prior model's knowledge box (:func:`inertia_from_knowledge`)."""
    v, half = inertia_from_knowledge(rng, prior)
    i0 = np.asarray(prior.inertia, float)
    centre = np.array([i0[0, 0], i0[1, 1], i0[2, 2], i0[0, 1], i0[0, 2], i0[1, 2]])
    record["inertia"] = {"law": "uniform", "half_width": half.tolist(),
                         "prediction": centre.tolist(), "values": v.tolist()}
    return dict(zip(("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz"), v.tolist()))


def _thrusters(rng, prior, widen: float, record: dict) -> dict[str, Any]:
    """The thrusters' truth: each steady thrust uniform on ±:data:`THRUST_SPREAD` of its
    nominal (a new set's acceptance-test spread; the fit's log-thrust prior is far wider), each
    valve time constant uniform on the model file's test range, and the centre of mass off the
    model file's by a Laplace draw per axis of sd ``widen`` × ``[center_of_mass] sd_m``."""
    if not prior.thrusters:
        raise InputError(f"the model {prior.name!r} has no thrusters to draw")
    f0 = prior.thrust_per_thruster
    f = f0 * (1.0 + rng.uniform(-THRUST_SPREAD, THRUST_SPREAD, f0.size))
    taus = {k: float(rng.uniform(*getattr(prior.pulse, f"{k}_range")))
            for k in ("tau_delay", "tau_rise", "tau_fall")}
    com = draw_law(rng, "laplace", widen * prior.com_sd_m, 3)
    record["thrusters"] = {"law": f"uniform ±{THRUST_SPREAD:g} of nominal",
                           "names": [t.name for t in prior.thrusters], "values": f.tolist(),
                           "tau_law": "uniform on the model file's range", **taus,
                           "center_of_mass_offset_m": {"law": "laplace",
                                                       "sd": widen * prior.com_sd_m,
                                                       "values": com.tolist()}}
    return {"thrust_n": f.tolist(), "center_of_mass_offset_m": com.tolist(),
            **{f"{k}_s": v for k, v in taus.items()}}


def _flex(rng, inertia: np.ndarray, dt_s: float, record: dict) -> dict:
    """A flexible mode: log-uniform frequency and damping, an isotropic coupling direction with
    the share of the inertia it carries, ``δᵀ I⁻¹ δ``, uniform on :data:`FLEX_SHARE`: relative
    to the spacecraft (an appendage's share of its inertia, not kg m²)."""
    f_hi = min(FLEX_FREQ_HZ[1], _MAX_PHASE / (2.0 * math.pi * dt_s))
    f = float(np.exp(rng.uniform(math.log(FLEX_FREQ_HZ[0]), math.log(f_hi))))
    zeta = float(np.exp(rng.uniform(*np.log(FLEX_DAMPING))))
    u = rng.standard_normal(3)
    share = rng.uniform(*FLEX_SHARE)
    delta = u * math.sqrt(share / float(u @ np.linalg.solve(inertia, u)))
    out = {"freq_hz": f, "damping": zeta, "coupling": delta.tolist()}
    record["flex_mode"] = {"law": "log-uniform freq and damping, isotropic coupling",
                           "freq_range_hz": [FLEX_FREQ_HZ[0], f_hi], **out}
    return out


def draw_open_world(base: dict | str | Path, rng: np.random.Generator | int, *,
                    widen: float = WIDEN, draw_inertia: bool = False,
                    solved_wheel: str | None = None, torque_sd_nm: float | None = None,
                    slip_prob: float = SLIP_PROB, draw_thrusters: bool = False) -> OpenWorld:
    """Draw an open-world truth for the scenario ``base`` (see the module docstring).

    base : scenario dict (as read from TOML) or a scenario name/path; its own sensor-error,
        wheel-error, torque, flexible-mode and time-tag keys are replaced.
    rng : NumPy Generator, or an int seed for ``np.random.default_rng``.
    widen : each error's sd over its prior sd (the prior model's ``Knowledge``).
    draw_inertia : draw the true inertia from the prior model's knowledge box (thrust, RWA4).
    solved_wheel : a wheel whose axis the fit solves for (RWA4): not drawn; it keeps the
        scenario's own true axis (its ``wheel_axis_tilt_deg`` entry, or Cassini's ``rwa4_axis``),
        the offset from the model file that the calibration is there to find.
    torque_sd_nm : scale of the external torques per axis, N m (drawn ``widen`` × wider; default
        the prior model's ``[torque_knowledge] sd_nm``, the robust fits' prior sd); the inertial
        torque also drifts, by up to this much over the run (unmodelled).
    slip_prob : chance per sample of a stale sample (±1 sample slip).
    draw_thrusters : also draw the thrusters' truth (:func:`_thrusters`: each thruster's thrust,
        the valve time constants and the centre of mass), for per-thruster thrust fits. Drawn
        after every other effect, so the other draws do not depend on it.
    """
    rng = np.random.default_rng(rng) if not isinstance(rng, np.random.Generator) else rng
    d = base_scenario(base)
    nominal = scenario_from_dict(d, src=str(d.get("name", "<scenario>")))
    prior, kn = nominal.prior, nominal.prior.knowledge
    torque_sd_nm = kn.torque_sd_nm if torque_sd_nm is None else torque_sd_nm
    truth = d.setdefault("truth", {})
    noise = d.setdefault("noise", {})
    for k in ("wheel_inertia_scale", "wheel_inertia_error_sd",
              "external_torque_inertial_rate_nm_s"):
        truth.pop(k, None)
    rec: dict[str, Any] = {"widen": widen, "scenario": nominal.name}
    noise["gyro_bias_rad_s"] = _effect(rng, "gyro_bias_rad_s", widen * kn.gyro_bias_sd_rad_s, 3,
                                       rec).tolist()
    noise["gyro_scale_factor"] = _effect(rng, "gyro_scale_factor",
                                         widen * kn.gyro_scale_factor_sd, 3, rec).tolist()
    known = {w.name: w.inertia_sd_frac for w in prior.wheels if w.inertia_sd_frac is not None}
    names = nominal.truth.wheel_names          # the order of [truth] wheel_inertia_errors
    sd_j = widen * np.array([known.get(w, kn.wheel_inertia_sd_frac) for w in names])
    e = _effect(rng, "wheel_inertia_errors", 1.0, len(names), rec) * sd_j
    rec["wheel_inertia_errors"].update(sd=sd_j.tolist(), values=e.tolist(), wheels=list(names))
    truth["wheel_inertia_errors"] = e.tolist()
    tilted = [w for w in d["initial"]["wheels_on"] if str(w).upper() != str(solved_wheel).upper()]
    tilt = _effect(rng, "wheel_axis_tilt_deg", widen * kn.wheel_axis_sd_deg, (len(tilted), 2), rec)
    rec["wheel_axis_tilt_deg"]["wheels"] = tilted
    own = {w: v for w, v in truth.get("wheel_axis_tilt_deg", {}).items()
           if str(w).upper() == str(solved_wheel).upper()}
    truth["wheel_axis_tilt_deg"] = {w: tilt[i].tolist() for i, w in enumerate(tilted)} | own
    truth["external_torque_body_nm"] = _effect(rng, "external_torque_body_nm",
                                               widen * torque_sd_nm, 3, rec).tolist()
    truth["external_torque_inertial_nm"] = _effect(rng, "external_torque_inertial_nm",
                                                   widen * torque_sd_nm, 3, rec).tolist()
    drift = rng.uniform(-1.0, 1.0, 3) * torque_sd_nm / nominal.duration_s
    truth["external_torque_inertial_rate_nm_s"] = drift.tolist()
    rec["external_torque_inertial_rate_nm_s"] = {
        "law": "uniform", "half_width": torque_sd_nm / nominal.duration_s, "values": drift.tolist()}
    if draw_inertia:
        truth["inertia"] = _inertia(rng, prior, rec)
    inertia = np.asarray(scenario_from_dict(d, src=nominal.source).truth.inertia, float)
    d["flex_mode"] = _flex(rng, inertia, nominal.dt_s, rec)
    noise.pop("time_tag_jitter_s", None)      # the simulator's is Normal: applied afterwards
    n = nominal.n_samples
    tt = _effect(rng, "time_tag_error_s", widen * kn.time_tag_sd_s, n, rec)
    rec["time_tag_error_s"]["values"] = None  # n values: summarised, kept in OpenWorld
    rec["time_tag_error_s"]["max_abs"] = float(np.max(np.abs(tt)))
    stale = rng.random(n) < slip_prob
    slip = np.where(stale, rng.choice([-1, 1], n), 0)
    slip[0] = max(slip[0], 0)
    slip[-1] = min(slip[-1], 0)
    rec["slips"] = {"prob": slip_prob, "index": np.flatnonzero(slip).tolist(),
                    "shift": slip[slip != 0].tolist()}
    if draw_thrusters:
        truth.update(_thrusters(rng, prior, widen, rec))
    return OpenWorld(d, rec, tt, slip)


EFFECTS_OFF = ("flex", "drift", "time_tags", "slips", "wheels", "tilts", "gyro", "torques")
"""Effects :func:`without` can switch off (to find which one an interval misses by)."""


def without(ow: OpenWorld, effects) -> OpenWorld:
    """``ow`` with ``effects`` (names from :data:`EFFECTS_OFF`) switched off, every other draw
    unchanged; the record lists them under ``"off"``."""
    bad = sorted(set(effects) - set(EFFECTS_OFF))
    if bad:
        raise InputError(f"unknown effect(s) {', '.join(bad)}; use {', '.join(EFFECTS_OFF)}")
    d = copy.deepcopy(ow.scenario)
    truth, noise = d["truth"], d["noise"]
    tt, slip = ow.time_tag_error_s, ow.slip
    for e in effects:
        if e == "flex":
            d.pop("flex_mode", None)
        elif e == "drift":
            truth["external_torque_inertial_rate_nm_s"] = [0.0, 0.0, 0.0]
        elif e == "time_tags":
            tt = np.zeros_like(tt)
        elif e == "slips":
            slip = np.zeros_like(slip)
        elif e == "wheels":
            truth["wheel_inertia_errors"] = [0.0] * len(truth["wheel_inertia_errors"])
        elif e == "tilts":         # the drawn tilts; a solved wheel keeps its own axis
            drawn = set(ow.record["wheel_axis_tilt_deg"]["wheels"])
            truth["wheel_axis_tilt_deg"] = {w: v for w, v in truth["wheel_axis_tilt_deg"].items()
                                            if w not in drawn}
        elif e == "gyro":
            noise["gyro_bias_rad_s"] = noise["gyro_scale_factor"] = [0.0, 0.0, 0.0]
        else:
            truth["external_torque_body_nm"] = [0.0, 0.0, 0.0]
            truth["external_torque_inertial_nm"] = [0.0, 0.0, 0.0]
    return OpenWorld(d, ow.record | {"off": sorted(set(effects))}, tt, slip)


def apply_time_tags(tel: Telemetry, ow: OpenWorld) -> Telemetry:
    """``tel`` with the open world's time-tag errors added to its times and its stale samples
    repeating their neighbours' data (attitude, rates, wheel rates, on-time counters)."""
    n = tel.n
    if ow.time_tag_error_s.shape != (n,):
        raise InputError(f"the telemetry has {n} samples, the open-world draw "
                         f"{ow.time_tag_error_s.shape[0]}: draw it for this scenario",
                         path=tel.source)
    src = np.arange(n) + ow.slip
    t = tel.t + ow.time_tag_error_s
    if np.any(np.diff(t) <= 0.0):
        raise InputError("time-tag errors reorder the samples: use a smaller widen",
                         path=tel.source)
    return replace(tel, t=t, q=tel.q[src], omega=tel.omega[src],
                   wheel_rates=tel.wheel_rates[src],
                   on_times=None if tel.on_times is None else tel.on_times[src])
