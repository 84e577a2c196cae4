"""The physics of each budget line, as functions of posterior draws (for
:func:`cassini_bayes.analysis.propagation.propagate`).

Every line takes ``d``: parameter → (n,) draws (``Ixx … Iyz`` kg m², ``F`` N, ``tau_delay``,
``tau_rise``, ``tau_fall`` s) or (n, 3) (``u4``, the RWA4 spin axis, body axes), each draw read as
a possible *truth*, and the calibration's point estimate (the posterior mean, what an operator
would upload) as what the spacecraft *believes*. The line is the error that belief makes if the
truth is the draw; its spread over the draws is the posterior uncertainty of the error.

Lines:

* :func:`inertia_worst_moment_pct` — the inertia calibration (Feldman & Lee 2006 Eq 12, worst of
  the three moments), against its ±1 %;
* :func:`thrust_error_pct` — the thrust calibration, against its ±10 %;
* :func:`tau_thrust_error_pct` — thrust adjusted for pulse dynamics (Feldman & Lee §V, ``F/R``)
  with the estimated time constants when the true ones are the draws;
* :func:`thrust_mass_property_pct` — the least-squares thrust (Feldman & Lee Eq 23) computed with
  the estimated inertia when the truth is the draw, through its sensitivity to the inertia;
* :func:`axis_error_deg` — the RWA4 spin axis (Brown 2012), against 3° (RCS) / 1° (RWA);
* :func:`rcs_mass_property_deg` — Brown's extra RCS-method error from mass-property knowledge
  (Eq 1 over a short drift, ``û ∝ Î I⁻¹ u``), against its 1.5°;
* :func:`rwa_control_error_mrad` — the part of the reaction-wheel attitude control error (Lee
  Table 2) due to inertia and RWA4-axis knowledge, per body axis.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from cassini_bayes.names import INERTIA_NAMES, TAU_NAMES

__all__ = [
    "inertia_of",
    "inertia_worst_moment_pct",
    "thrust_error_pct",
    "tau_thrust_error_pct",
    "thrust_mass_property_pct",
    "axis_error_deg",
    "rcs_mass_property_deg",
    "Maneuver",
    "rwa_control_error_mrad",
]

_MOMENTS = INERTIA_NAMES[:3]


def inertia_of(values) -> np.ndarray:
    """(..., 3, 3) tensor from (..., 6) entries ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)``, kg m²."""
    v = np.asarray(values, float)
    xx, yy, zz, xy, xz, yz = np.moveaxis(v, -1, 0)
    return np.stack([np.stack([xx, xy, xz], -1), np.stack([xy, yy, yz], -1),
                     np.stack([xz, yz, zz], -1)], -2)


def _stack(d, names) -> np.ndarray:
    return np.stack([np.asarray(d[k], float) for k in names], -1)


def inertia_worst_moment_pct(d, estimate) -> np.ndarray:
    """Worst error of the estimated moments, ``max_k 100 |Î_k − I_k| / I_k`` (%; Feldman & Lee
    Eq 12 with the truth as reference); ``estimate`` (6,) kg m², ``d`` holds ``Ixx Iyy Izz``."""
    truth = _stack(d, _MOMENTS)
    est = np.asarray(estimate, float)[:3]
    return np.max(100.0 * np.abs(est - truth) / truth, axis=-1)


def thrust_error_pct(d, estimate_n: float) -> np.ndarray:
    """``100 |F̂ − F| / F`` (%), ``F`` the draws of the thrust (N)."""
    f = np.asarray(d["F"], float)
    return 100.0 * np.abs(float(estimate_n) - f) / f


def tau_thrust_error_pct(d, tau_estimate_s, widths_s, counts=None) -> np.ndarray:
    """Error (%) of the thrust adjusted for pulse dynamics with the estimated time constants.

    The actual impulse of a pulse mix is ``F R(τ) Σ Δ`` (Feldman & Lee §V); the adjusted estimate
    divides by ``R(τ̂)``, so its relative error is ``R(τ)/R(τ̂) − 1``. ``tau_estimate_s`` (3,)
    ``(delay, rise, fall)`` s; ``widths_s``/``counts`` the commanded pulse mix.
    """
    from cassini_bayes.physics.pulse import mix_ratio

    w = np.atleast_1d(np.asarray(widths_s, float))
    c = np.ones_like(w) if counts is None else np.asarray(counts, float)
    tau = _stack(d, TAU_NAMES)
    n = tau.shape[0]
    wn, cn = np.broadcast_to(w, (n, w.size)), np.broadcast_to(c, (n, w.size))
    r_true = np.asarray(mix_ratio(wn, cn, tau[:, :1], tau[:, 1:2], tau[:, 2:3]))
    te = np.asarray(tau_estimate_s, float)
    r_est = float(mix_ratio(w, c, te[0], te[1], te[2]))
    return 100.0 * np.abs(r_true / r_est - 1.0)


def thrust_mass_property_pct(d, inertia_estimate, sensitivity_pct) -> np.ndarray:
    """``|s · (Î − I)|`` (%): the thrust error from inertia knowledge.

    The least-squares thrust (Feldman & Lee Eqs 19-23) is linear in the inertia it assumes (the
    body momentum ``I ω``), so its error is the sensitivity ``sensitivity_pct`` (6,) — % of the
    thrust per kg m² of each entry ``Ixx … Iyz`` — times the difference between the estimate
    ``inertia_estimate`` (6,) and the true entries (the draws).
    """
    diff = np.asarray(inertia_estimate, float) - _stack(d, INERTIA_NAMES)
    return np.abs(diff @ np.asarray(sensitivity_pct, float))


def _unit(v) -> np.ndarray:
    v = np.asarray(v, float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def axis_error_deg(d, axis_estimate) -> np.ndarray:
    """Angle (deg) between the estimated RWA4 axis and the draws ``d["u4"]`` (n, 3)."""
    u, e = _unit(d["u4"]), _unit(axis_estimate)
    cross = np.linalg.norm(np.cross(u, e), axis=-1)
    return np.degrees(np.arctan2(cross, u @ e))


def rcs_mass_property_deg(d, inertia_estimate, axis=None) -> np.ndarray:
    """Brown (2012) §III.B: extra RCS-method axis error (deg) when the calibration uses the
    estimated inertia ``inertia_estimate`` (6,) kg m² and the truth is the draw (``Ixx … Iyz``);
    the true axis is ``d["u4"]`` when the draws carry it, else the fixed ``axis`` (3,)."""
    from cassini_bayes._devices import setup_jax
    from cassini_bayes.analysis.mass_property import rcs_axis_error_rad

    setup_jax()   # imported here: a report of another kind needs no JAX
    i_true = inertia_of(_stack(d, INERTIA_NAMES))
    u = _unit(d["u4"]) if "u4" in d else np.broadcast_to(_unit(axis), (i_true.shape[0], 3))
    err = rcs_axis_error_rad(i_true, inertia_of(inertia_estimate), u)
    return np.degrees(np.asarray(err))


class Maneuver(NamedTuple):
    """The turn the reaction-wheel control error is evaluated on (Lee Table 2's control line).

    Attributes
    ----------
    rate_rad_s : (3,) commanded body rate, rad/s.
    accel_rad_s2 : (3,) commanded body acceleration, rad/s².
    wheel_momentum_nms : (3,) total wheel momentum in body axes, N m s.
    bandwidth_rad_s : natural frequency ``ω_n`` of the PD attitude loop, rad/s.
    wheel_axes : (3, 3) believed spin axes (rows) of the three wheels in use, RWA4 last.
    """

    rate_rad_s: np.ndarray
    accel_rad_s2: np.ndarray
    wheel_momentum_nms: np.ndarray
    bandwidth_rad_s: float
    wheel_axes: np.ndarray


def rwa_control_error_mrad(d, inertia_estimate, axis_estimate, maneuver: Maneuver) -> np.ndarray:
    """(n, 3) attitude error (mrad, body X Y Z) of the wheel controller from knowledge errors.

    The controller of Feldman & Lee (2006) §III commands ``T_c = Î ω̇_d + ω × (Î ω + H)`` with the
    believed inertia ``Î`` and maps it to wheel torques with the believed axes ``Â``; the true
    spacecraft has ``I`` and RWA4 along ``u4``. The torque left over,
    ``ΔT = (Î − I) α + ω × ((Î − I) ω) + (u4 − û4) τ4`` (``τ4`` the torque commanded on RWA4),
    is rejected by the PD loop; quasi-statically the attitude error is ``I⁻¹ ΔT / ω_n²``.
    Draws without ``u4`` have the believed axis; without inertia entries, ``Î``.
    """
    est = np.asarray(inertia_estimate, float)
    i_hat = inertia_of(est)
    n = len(next(iter(d.values())))
    i_true = (inertia_of(_stack(d, INERTIA_NAMES)) if INERTIA_NAMES[0] in d
              else np.broadcast_to(i_hat, (n, 3, 3)))
    w = np.asarray(maneuver.rate_rad_s, float)
    a = np.asarray(maneuver.accel_rad_s2, float)
    h = np.asarray(maneuver.wheel_momentum_nms, float)
    axes = np.array(maneuver.wheel_axes, float)  # a copy: the believed RWA4 axis goes in
    axes[-1] = _unit(axis_estimate)
    t_c = i_hat @ a + np.cross(w, i_hat @ w + h)              # Feldman & Lee §III
    tau4 = np.linalg.solve(axes.T, t_c)[-1]
    u4 = _unit(d["u4"]) if "u4" in d else np.broadcast_to(axes[-1], (n, 3))
    di = i_hat[None] - i_true
    dt = di @ a + np.cross(w, di @ w) + (u4 - axes[-1]) * tau4
    theta = np.linalg.solve(i_true, dt[..., None])[..., 0] / maneuver.bandwidth_rad_s ** 2
    return 1e3 * theta
