"""Nuisance parameters of the robust models: sensor and actuator errors the papers leave out.

Every effect is small, so it enters the momentum model to first order, and linearly:

* **gyro bias** ``b`` (rad/s, per axis, per file) and **gyro scale-factor error** ``s`` (per
  axis): the gyro measures ``ω_meas = (1 + s) ω + b + noise``, so
  ``ω = (ω_meas − b)/(1 + s) ≈ ω_meas − b − s ∘ ω_meas`` and the body momentum
  ``I ω ≈ I ω_meas − I* b − I* diag(ω_meas) s``, with ``I*`` the mode of the inertia (the
  neglected ``(I − I*)(b + s ∘ ω)`` is second order: posterior relative error × 1e-4);
* **wheel spin-inertia scale** ``c`` (one common fraction): ``J_k → (1 + c) J_k``, so the wheel
  momentum ``H_w → (1 + c) H_w``;
* **wheel spin-axis tilts** ``a_k = (a_k1, a_k2)`` (rad): ``g_k → g_k + a_k1 u_k1 + a_k2 u_k2``
  with ``u_k1, u_k2`` an orthonormal pair perpendicular to ``g_k`` (a rotation about ``g_k``
  itself changes nothing), so ``H_w → H_w + Σ_k J_k ρ_k (a_k1 u_k1 + a_k2 u_k2)``;
* **body-fixed external torque** ``T_B`` (N m, per file; beside the inertial ``T_N`` of the
  idealised model): the inertial momentum gains ``∫ A(q_s)ᵀ ds T_B``, so the body residual gains
  ``−A(q_t) C_t T_B`` with ``C_t = ∫_{t_0}^{t} A(q_s)ᵀ ds`` (trapezoidal). Prior sd as ``T_N``
  (Feldman & Lee App. A: 15 µN m per axis); over a short slew the two are nearly the same
  torque, and the priors share it out.

What the data cannot separate stays prior-dominated by construction: scaling ``I``, ``H_0`` and
``T_N`` by ``(1 + c)`` together with the wheel inertias leaves every momentum balance unchanged
(Psiaki 2005, WMAP), and so does scaling ``I`` by ``1/(1 − σ)`` against a common gyro scale factor
``σ``; in the linearised model these are exact null directions of the likelihood, so ``c`` and the
common part of ``s`` keep their priors and the overall scale of ``I`` widens by their prior sd
(about 0.5 % with the default knowledge) instead of drifting. The priors (zero-mean Normal, one sd
each) come from the spacecraft model's :class:`~cassini_bayes.spacecraft.Knowledge`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from cassini_bayes.spacecraft import Spacecraft, wheel_tilt_basis

__all__ = ["EFFECTS", "NuisanceLayout", "nuisance_layout", "tilt_basis", "robust_columns"]

# Effect name → the posterior site holding its parameters.
EFFECTS = {"gyro_bias": "gyro_bias", "gyro_scale": "gyro_scale",
           "wheel_inertia": "wheel_scale", "wheel_axes": "wheel_tilt",
           "body_torque": "T_body"}
BODY_TORQUE_PRIOR_SD_NM = 15e-6  # N m per axis, as the inertial T_N (Feldman & Lee App. A)


class NuisanceLayout(NamedTuple):
    """Order and prior of the robust nuisance vector ``ν`` (appended to the model's θ).

    ``ν = (b_0 (3), …, b_{F−1} (3), s (3), c (1), a_0 (2), …, a_{K−1} (2), T_B,0 (3), …)``.

    Attributes
    ----------
    n_files : F; ``wheels`` the K wheel names (active in any file) that get tilts.
    sd : (R,) prior standard deviations (rad/s, 1, 1, rad, N m), R = 6F + 4 + 2K.
    slices : effect name (:data:`EFFECTS`) → slice of ``ν``.
    tilt_u : (K, 2, 3) the unit vectors ``u_k1, u_k2`` perpendicular to each spin axis.
    """

    n_files: int
    wheels: tuple[str, ...]
    sd: np.ndarray
    slices: dict
    tilt_u: np.ndarray

    @property
    def size(self) -> int:
        return int(self.sd.size)


def tilt_basis(axis) -> np.ndarray:
    """(2, 3) orthonormal pair perpendicular to the unit vector ``axis`` (the simulator's too)."""
    return wheel_tilt_basis(axis)


def nuisance_layout(spacecraft: Spacecraft, n_files: int, wheels) -> NuisanceLayout:
    """The layout and prior of ``ν`` for ``n_files`` files and the named active ``wheels``."""
    k = spacecraft.knowledge
    wheels = tuple(wheels)
    nk = len(wheels)
    sd = np.concatenate([np.full(3 * n_files, k.gyro_bias_sd_rad_s),
                         np.full(3, k.gyro_scale_factor_sd),
                         [k.wheel_inertia_sd_frac],
                         np.full(2 * nk, np.deg2rad(k.wheel_axis_sd_deg)),
                         np.full(3 * n_files, BODY_TORQUE_PRIOR_SD_NM)])
    b = 3 * n_files
    e = b + 4 + 2 * nk
    slices = {"gyro_bias": slice(0, b), "gyro_scale": slice(b, b + 3),
              "wheel_inertia": slice(b + 3, b + 4), "wheel_axes": slice(b + 4, e),
              "body_torque": slice(e, e + 3 * n_files)}
    tilt_u = (np.stack([tilt_basis(spacecraft.wheel(w).axis) for w in wheels]) if nk
              else np.zeros((0, 2, 3)))
    return NuisanceLayout(n_files, wheels, sd, slices, tilt_u)


def robust_columns(layout: NuisanceLayout, f: int, inertia: np.ndarray, omega: np.ndarray,
                   h_wheels: np.ndarray, wheel_h: dict, a: np.ndarray,
                   t: np.ndarray) -> np.ndarray:
    """(n, 3, R) body-axis columns of ``ν`` in the residual ``e_t`` of file ``f`` (module doc).

    Parameters
    ----------
    inertia : (3, 3) kg m², the linearisation point ``I*``.
    omega : (n, 3) measured body rates, rad/s.
    h_wheels : (n, 3) wheel momentum in body axes from the model's ``J_k`` and ``g_k``, N m s.
    wheel_h : wheel name → (n,) ``J_k ρ_k`` (N m s) of the file's active wheels.
    a : (n, 3, 3) the DCMs ``A(q_t)``; ``t`` (n,) sample times, s.
    """
    n = omega.shape[0]
    cols = np.zeros((n, 3, layout.size))
    sl = layout.slices
    cols[:, :, 3 * f:3 * f + 3] = -inertia                                  # I* b
    cols[:, :, sl["gyro_scale"]] = -inertia[None] * omega[:, None, :]       # I* diag(ω) s
    cols[:, :, sl["wheel_inertia"].start] = h_wheels                        # c H_w
    a0 = sl["wheel_axes"].start
    for k, name in enumerate(layout.wheels):
        if name in wheel_h:
            for j in range(2):
                cols[:, :, a0 + 2 * k + j] = wheel_h[name][:, None] * layout.tilt_u[k, j]
    at = np.swapaxes(a, -1, -2)
    steps = 0.5 * (at[1:] + at[:-1]) * np.diff(t)[:, None, None]
    c_t = np.concatenate([np.zeros((1, 3, 3)), np.cumsum(steps, 0)])   # ∫ A(q_s)ᵀ ds
    t0 = sl["body_torque"].start + 3 * f
    cols[:, :, t0:t0 + 3] = -np.einsum("nij,njk->nik", a, c_t)         # −A(q_t) C_t T_B
    return cols
