"""The robust nuisance's columns in the thrust model's predicted left side of Feldman & Lee
Eq 17, one event at a time (the effects and their signs: :mod:`cassini_bayes.inference.thrust`,
"Robust model")."""

from __future__ import annotations

import numpy as np

from cassini_bayes.frames import skew
from cassini_bayes.inference.nuisance import NuisanceLayout, wheel_scale_columns
from cassini_bayes.physics.quadrature import cumulative_trapezoid
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import Telemetry

__all__ = ["wheel_momentum", "nuisance_columns"]


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
                     inertia: np.ndarray, h: np.ndarray, per_wheel: dict) -> np.ndarray:
    """(n, 3, R) columns of ``ν`` in the predicted left side of event ``e``: sample times ``t``
    (n,) s, measured rates ``omega`` (n, 3) rad/s, the linearisation inertia (3, 3) kg m² and
    the wheels' momentum ``h``, ``per_wheel`` of :func:`wheel_momentum`."""
    n = t.shape[0]
    cols = np.zeros((n, 3, layout.size))
    sl = layout.slices
    dt = (t - t[0])[:, None]
    c_t = cumulative_trapezoid(h, t)
    b0 = sl["gyro_bias"].start + 3 * e
    cols[:, :, b0:b0 + 3] = -np.asarray(skew(c_t))                        # ∫ b × H_w dt
    cols[:, :, sl["gyro_scale"]] = inertia[None] * omega[:, None, :]      # I diag(ω) s
    cols[:, :, layout.wheel_block] = -wheel_scale_columns(layout, h, per_wheel)  # −J_k ρ_k g_k
    a0 = sl["wheel_axes"].start
    for k, name in enumerate(layout.wheels):
        if name in per_wheel:
            for j in range(2):
                cols[:, :, a0 + 2 * k + j] = -per_wheel[name][:, None] * layout.tilt_u[k, j]
    wheel = np.r_[np.arange(layout.size)[layout.wheel_block], np.arange(a0, sl["wheel_axes"].stop)]
    cols[:, :, wheel] = _with_gyroscopic(cols[:, :, wheel], omega, t)
    t0 = sl["body_torque"].start + 3 * e
    cols[:, :, t0:t0 + 3] = dt[:, :, None] * np.eye(3)[None]              # T_e (t − t_0)
    if "torque_rate" in sl:
        r0 = sl["torque_rate"].start + 3 * e
        cols[:, :, r0:r0 + 3] = 0.5 * dt[:, :, None]**2 * np.eye(3)[None]  # ½ Ṫ_e (t − t_0)²
    return cols


def _with_gyroscopic(momentum: np.ndarray, omega: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(n, 3, W) wheel-momentum columns ``δH`` plus their gyroscopic impulse ``∫ ω × δH dt``
    (Feldman & Lee Eq 15, the cumulative trapezoid of
    :func:`~cassini_bayes.physics.impulse.gyroscopic_impulse`): a wheel's momentum enters the
    left side of Eq 17 through ``H`` and through ``ΔG``, so an error in it does both."""
    f = np.einsum("nij,njw->niw", np.asarray(skew(omega)), momentum)     # ω × δH
    return momentum + cumulative_trapezoid(f, t)
