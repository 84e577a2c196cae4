"""The robust nuisance's columns in the thrust model's predicted left side of Feldman & Lee
Eq 17, one event at a time (the effects and their signs: :mod:`cassini_bayes.inference.thrust`,
"Robust model")."""

from __future__ import annotations

import jax
import numpy as np

from cassini_bayes.estimators.leak import interval_means
from cassini_bayes.frames import skew
from cassini_bayes.inference.nuisance import (NuisanceLayout, wheel_scale_columns,
                                              without_common_scale)
from cassini_bayes.inference.thrust.likelihood import PulseLayout, jump_area
from cassini_bayes.physics.quadrature import cumulative_trapezoid
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import Telemetry

__all__ = ["wheel_momentum", "nuisance_columns", "rotation_errors", "events_nuisance_columns"]


def wheel_momentum(tel: Telemetry, spacecraft: Spacecraft):
    """Body wheel momentum (n, 3) N m s, the wheel noise matrix Σ J² g gᵀ (3, 3) and each active
    wheel's ``J_k ρ_k`` (n,) N m s."""
    h = np.zeros((tel.n, 3))
    wcov = np.zeros((3, 3))
    per_wheel = {}
    for name in tel.active_wheels():
        w = spacecraft.wheel(name)
        rate = np.nan_to_num(np.asarray(tel.wheel_rate(name), float))
        per_wheel[name] = w.inertia * rate
        h += w.inertia * rate[:, None] * w.axis[None, :]
        wcov += w.inertia**2 * np.outer(w.axis, w.axis)
    return h, wcov, per_wheel


def nuisance_columns(layout: NuisanceLayout, e: int, t: np.ndarray, omega: np.ndarray,
                     inertia: np.ndarray, h: np.ndarray, per_wheel: dict,
                     d_theta: np.ndarray | None = None) -> np.ndarray:
    """(n, 3, R) columns of ``ν`` in the predicted left side of event ``e``: sample times ``t``
    (n,) s, measured rates ``omega`` (n, 3) rad/s, the linearisation inertia (3, 3) kg m² and
    the wheels' momentum ``h``, ``per_wheel`` of :func:`wheel_momentum`. ``d_theta`` (3, n)
    rad: the trapezoid's rotation error per interval across the pulses' rate steps
    (:func:`rotation_errors`), through which a wheel error also moves the left side."""
    n = t.shape[0]
    cols = np.zeros((n, 3, layout.size))
    sl = layout.slices
    dt = (t - t[0])[:, None]
    b0 = sl["gyro_bias"].start + 3 * e
    unit = np.broadcast_to(np.eye(3)[None], (n, 3, 3))                    # δω = b: e_a
    cols[:, :, b0:b0 + 3] = _rate_error_columns(unit, omega, t, inertia, h, d_theta)
    scale = omega[:, :, None] * np.eye(3)[None]                           # δω = s ∘ ω: ω_a e_a
    cols[:, :, sl["gyro_scale"]] = (np.einsum("ij,nja->nia", inertia, scale)
                                    + _rate_error_columns(scale, omega, t, inertia, h, d_theta))
    cols[:, :, layout.wheel_block] = -wheel_scale_columns(layout, h, per_wheel)  # −J_k ρ_k g_k
    a0 = sl["wheel_axes"].start
    for k, name in enumerate(layout.wheels):
        if name in per_wheel:
            for j in range(2):
                cols[:, :, a0 + 2 * k + j] = -per_wheel[name][:, None] * layout.tilt_u[k, j]
    wheel = np.r_[np.arange(layout.size)[layout.wheel_block], np.arange(a0, sl["wheel_axes"].stop)]
    cols[:, :, wheel] = _with_gyroscopic(cols[:, :, wheel], omega, t, d_theta)
    t0 = sl["body_torque"].start + 3 * e
    cols[:, :, t0:t0 + 3] = dt[:, :, None] * np.eye(3)[None]              # T_e (t − t_0)
    if "torque_rate" in sl:
        r0 = sl["torque_rate"].start + 3 * e
        cols[:, :, r0:r0 + 3] = 0.5 * dt[:, :, None]**2 * np.eye(3)[None]  # ½ Ṫ_e (t − t_0)²
    return cols


def _rate_error_columns(d_omega: np.ndarray, omega: np.ndarray, t: np.ndarray,
                        inertia: np.ndarray, h: np.ndarray, d_theta: np.ndarray | None
                        ) -> np.ndarray:
    """(n, 3, A) what a gyro error ``ω = ω_meas − δω`` (``d_omega`` (n, 3, A), one error per
    column) moves in the left side's ``ΔG`` (Feldman & Lee Eq 15):
    ``∫ (δω × (I ω + H_w) + ω × I δω) dt`` and, given ``d_theta``, the rate-step correction's
    ``Σ (δθ × I δω_m + δω_m × I δθ)``; the ``I δω`` of Eq 17 is the caller's (a bias's is a
    constant, which the event's offset takes)."""
    i_dw = np.einsum("ij,nja->nia", inertia, d_omega)
    total = omega @ inertia.T + h
    f = np.cross(d_omega, total[:, :, None], axis=1) + np.cross(omega[:, :, None], i_dw, axis=1)
    out = cumulative_trapezoid(f, t)
    if d_theta is not None:
        out = out + _rate_step_change(d_theta, inertia, d_omega=d_omega)
    return out


def _with_gyroscopic(momentum: np.ndarray, omega: np.ndarray, t: np.ndarray,
                     d_theta: np.ndarray | None = None) -> np.ndarray:
    """(n, 3, W) wheel-momentum columns ``δH`` plus their gyroscopic impulse ``∫ ω × δH dt``
    (Feldman & Lee Eq 15, the cumulative trapezoid of
    :func:`~cassini_bayes.physics.impulse.gyroscopic_impulse`) and, given ``d_theta`` (3, n),
    that trapezoid's correction across the rate steps, ``Σ δθ × δH_m``
    (:func:`~cassini_bayes.physics.impulse.rate_step_correction`, linear in the intervals' mean
    momentum ``H_m``): a wheel's momentum enters the left side of Eq 17 through ``H`` and
    through ``ΔG``, so an error in it does both."""
    f = np.einsum("nij,njw->niw", np.asarray(skew(omega)), momentum)     # ω × δH
    out = momentum + cumulative_trapezoid(f, t)
    if d_theta is not None:
        out += _rate_step_change(d_theta, None, d_h=momentum)
    return out


def _rate_step_change(d_theta, inertia, d_omega=None, d_h=None) -> np.ndarray:
    """(n, 3, A) the change of :func:`~cassini_bayes.physics.impulse.rate_step_correction`
    (``Σ δθ × (I ω_m + H_m) + ω_m × I δθ``) when the rates move by ``d_omega`` or the wheel
    momentum by ``d_h`` (n, 3, A) per column, at the rotation errors ``d_theta`` (3, n)."""
    d_theta = np.asarray(d_theta)
    if d_h is not None:
        step = np.cross(d_theta[:, :, None], _mid(d_h), axis=0)
    else:
        mid = _mid(d_omega)
        step = (np.cross(d_theta[:, :, None], np.einsum("ij,jna->ina", inertia, mid), axis=0)
                + np.cross(mid, (inertia @ d_theta)[:, :, None], axis=0))
    return np.cumsum(step, 1).transpose(1, 0, 2)


def _mid(x: np.ndarray) -> np.ndarray:
    """(3, n, A): :func:`interval_means` of each column of ``x`` (n, 3, A)."""
    return np.moveaxis(interval_means(np.moveaxis(x, -1, 0)), 0, -1)


def rotation_errors(layouts: PulseLayout, q_f, tau, inertia) -> np.ndarray:
    """(E, 3, n) rad: every event's ``δθ = I⁻¹ Q (F ⊙ ε)`` per interval, the trapezoid's error
    of the thrusters' rotation across the pulses' rate steps
    (:func:`~cassini_bayes.physics.impulse.rate_step_correction`) at the torques ``q_f`` (3, M)
    N m, the time constants ``tau`` (3,) s and the inertia (3, 3) kg m²."""
    area = jax.vmap(jump_area, in_axes=(0, None, None, None, None))(layouts, q_f, *tau)
    return np.einsum("ij,ejn->ein", np.linalg.inv(inertia), np.asarray(area))


def events_nuisance_columns(tels: list[Telemetry], spacecraft: Spacecraft,
                            layout: NuisanceLayout | None, inertia: np.ndarray,
                            d_theta: np.ndarray, scale_free: bool) -> np.ndarray:
    """(E, R, 3, n) every event's :func:`nuisance_columns` (zero on padding; R = 0 without a
    ``layout``, the idealised model), ``d_theta`` (E, 3, n) of :func:`rotation_errors` on the
    padded samples, the wheels' common scale taken out where ``scale_free``
    (:func:`~cassini_bayes.inference.nuisance.without_common_scale`)."""
    n_max = np.shape(d_theta)[-1]
    out = np.zeros((len(tels), n_max, 3, 0 if layout is None else layout.size))
    if layout is None:
        return np.ascontiguousarray(out.transpose(0, 3, 2, 1))
    for e, tel in enumerate(tels):
        h, _, per_wheel = wheel_momentum(tel, spacecraft)
        cols = nuisance_columns(layout, e, np.asarray(tel.t, float), np.asarray(tel.omega, float),
                                inertia, h, per_wheel, d_theta[e, :, :tel.n])
        out[e, :tel.n] = without_common_scale(cols, layout) if scale_free else cols
    return np.ascontiguousarray(out.transpose(0, 3, 2, 1))
