"""Nuisance parameters of the robust models: sensor and actuator errors the papers leave out.

Every effect is small, so it enters the momentum model to first order, and linearly:

* **gyro bias** ``b`` (rad/s, per axis, per file) and **gyro scale-factor error** ``s`` (per
  axis): the gyro measures ``ω_meas = (1 + s) ω + b + noise``, so
  ``ω = (ω_meas − b)/(1 + s) ≈ ω_meas − b − s ∘ ω_meas`` and the body momentum
  ``I ω ≈ I ω_meas − I* b − I* diag(ω_meas) s``, with ``I*`` the mode of the inertia (the
  neglected ``(I − I*)(b + s ∘ ω)`` is second order: posterior relative error × 1e-4);
* **wheel spin-inertia scales** ``c_k`` (one fraction per wheel, ``wheel_errors="per_wheel"``,
  the default): ``J_k → (1 + c_k) J_k``, so ``H_w → H_w + Σ_k c_k J_k ρ_k g_k`` — column ``k`` is
  wheel ``k``'s own momentum in body axes. The wheels sit on a cone, not along the body axes, so
  the *differences* between the ``c_k`` tilt the wheel momentum and leak into the products of
  inertia (and into a solved wheel's axis); a single common scale cannot absorb them. With
  ``wheel_errors="common"`` (the earlier model, kept for comparison) one ``c`` scales every
  wheel: ``H_w → (1 + c) H_w``, one column ``H_w`` (the sum of the per-wheel columns);
* **wheel spin-axis tilts** ``a_k = (a_k1, a_k2)`` (rad): ``g_k → g_k + a_k1 u_k1 + a_k2 u_k2``
  with ``u_k1, u_k2`` an orthonormal pair perpendicular to ``g_k`` (a rotation about ``g_k``
  itself changes nothing), so ``H_w → H_w + Σ_k J_k ρ_k (a_k1 u_k1 + a_k2 u_k2)``;
* **body-fixed external torque** ``T_B`` (N m, per file; beside the inertial ``T_N`` of the
  idealised model): the inertial momentum gains ``∫ A(q_s)ᵀ ds T_B``, so the body residual gains
  ``−A(q_t) C_t T_B`` with ``C_t = ∫_{t_0}^{t} A(q_s)ᵀ ds`` (trapezoidal). Prior sd as ``T_N``
  (Feldman & Lee App. A: 15 µN m per axis); over a short slew the two are nearly the same
  torque, and the priors share it out.

What the data cannot separate stays prior-dominated by construction: scaling ``I``, ``H_0`` and
``T_N`` by ``(1 + c)`` together with every wheel inertia leaves every momentum balance unchanged
(Psiaki 2005, WMAP), and so does scaling ``I`` by ``1/(1 − σ)`` against a common gyro scale factor
``σ``; in the linearised model these are exact null directions of the likelihood, so the common
wheel scale ``c = mean_k c_k`` (:data:`NuisanceLayout.scale_weights`) and the common part of ``s``
keep their priors and the overall scale of ``I`` widens by their prior sd instead of drifting.
The differences ``c_k − c`` are learned from slews about several axes. With independent per-wheel
priors of sd ``σ_J`` the common part has prior sd ``σ_J/√K`` (K wheels): 0.29 % for three wheels
at 0.5 %, against 0.5 % in the common-scale model. The priors (zero-mean Normal, one sd each)
come from the spacecraft model's :class:`~cassini_bayes.spacecraft.Knowledge` and, per wheel,
its ``[[wheel]] inertia_sd_frac`` (:func:`wheel_inertia_sd`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from cassini_bayes.errors import InputError
from cassini_bayes.spacecraft import Spacecraft, wheel_tilt_basis

__all__ = ["EFFECTS", "WHEEL_ERRORS", "NuisanceLayout", "nuisance_layout", "tilt_basis",
           "wheel_inertia_sd", "wheel_scale_columns", "robust_columns"]

# Effect name → the posterior site holding its parameters.
EFFECTS = {"gyro_bias": "gyro_bias", "gyro_scale": "gyro_scale",
           "wheel_inertia": "wheel_scale", "wheel_axes": "wheel_tilt",
           "body_torque": "T_body"}
BODY_TORQUE_PRIOR_SD_NM = 15e-6  # N m per axis, as the inertial T_N (Feldman & Lee App. A)
# Models of the wheel spin-inertia error: one scale per wheel (default) or one common scale.
WHEEL_ERRORS = ("per_wheel", "common")


class NuisanceLayout(NamedTuple):
    """Order and prior of the robust nuisance vector ``ν`` (appended to the model's θ).

    ``ν = (b_0 (3), …, b_{F−1} (3), s (3), c_0 … c_{S−1} (S), a_0 (2), …, a_{K−1} (2),
    T_B,0 (3), …)``; ``S`` = the number of scaled wheels (per wheel) or 1 (common).

    Attributes
    ----------
    n_files : F; ``wheels`` the K wheel names (active in any file) that get tilts.
    sd : (R,) prior standard deviations (rad/s, 1, 1, rad, N m), R = 6F + 3 + S + 2K.
    slices : effect name (:data:`EFFECTS`) → slice of ``ν``.
    tilt_u : (K, 2, 3) the unit vectors ``u_k1, u_k2`` perpendicular to each spin axis.
    wheel_errors : ``"per_wheel"`` or ``"common"`` (:data:`WHEEL_ERRORS`).
    scale_wheels : the S wheels with their own scale (per wheel; ``()`` for common).
    scale_axes : (S, 3) their spin axes (body); common: (0, 3).
    """

    n_files: int
    wheels: tuple[str, ...]
    sd: np.ndarray
    slices: dict
    tilt_u: np.ndarray
    wheel_errors: str = "per_wheel"
    scale_wheels: tuple[str, ...] = ()
    scale_axes: np.ndarray = np.zeros((0, 3))

    @property
    def size(self) -> int:
        return int(self.sd.size)

    @property
    def n_scales(self) -> int:
        """S, the number of wheel spin-inertia scale parameters."""
        sl = self.slices["wheel_inertia"]
        return sl.stop - sl.start

    @property
    def scale_weights(self) -> np.ndarray:
        """(S,) weights ``ω`` of the common scale ``c = Σ_k ω_k c_k`` (equal, summing to 1): the
        direction the data cannot see (module docstring); ``c_k − c`` they can."""
        return np.full(self.n_scales, 1.0 / max(self.n_scales, 1))


def tilt_basis(axis) -> np.ndarray:
    """(2, 3) orthonormal pair perpendicular to the unit vector ``axis`` (the simulator's too)."""
    return wheel_tilt_basis(axis)


def wheel_inertia_sd(spacecraft: Spacecraft, name: str) -> float:
    """Prior sd (a fraction) of wheel ``name``'s spin-inertia scale: its ``[[wheel]]
    inertia_sd_frac`` when the model file gives one, else ``[wheel_knowledge] inertia_sd_frac``."""
    w = spacecraft.wheel(name)
    return (spacecraft.knowledge.wheel_inertia_sd_frac if w.inertia_sd_frac is None
            else w.inertia_sd_frac)


def nuisance_layout(spacecraft: Spacecraft, n_files: int, wheels, *,
                    wheel_errors: str = "per_wheel", scaled=None) -> NuisanceLayout:
    """The layout and prior of ``ν`` for ``n_files`` files and the named active ``wheels``.

    ``wheel_errors`` (:data:`WHEEL_ERRORS`): one spin-inertia scale per wheel of ``scaled``
    (default ``wheels``; the RWA4 model adds the solved wheel, which gets no tilt), prior sd
    :func:`wheel_inertia_sd` each, or one common scale with the ``[wheel_knowledge]`` sd.
    """
    if wheel_errors not in WHEEL_ERRORS:
        raise InputError(f"wheel errors {wheel_errors!r}: choose one of "
                         f"{', '.join(WHEEL_ERRORS)}")
    k = spacecraft.knowledge
    wheels = tuple(wheels)
    nk = len(wheels)
    if wheel_errors == "per_wheel":
        scaled = wheels if scaled is None else tuple(scaled)
        scale_sd = np.array([wheel_inertia_sd(spacecraft, w) for w in scaled], float)
        scale_axes = (np.stack([spacecraft.wheel(w).axis for w in scaled]) if scaled
                      else np.zeros((0, 3)))
    else:
        scaled, scale_sd, scale_axes = (), np.array([k.wheel_inertia_sd_frac]), np.zeros((0, 3))
    ns = scale_sd.size
    sd = np.concatenate([np.full(3 * n_files, k.gyro_bias_sd_rad_s),
                         np.full(3, k.gyro_scale_factor_sd),
                         scale_sd,
                         np.full(2 * nk, np.deg2rad(k.wheel_axis_sd_deg)),
                         np.full(3 * n_files, BODY_TORQUE_PRIOR_SD_NM)])
    b = 3 * n_files
    e = b + 3 + ns + 2 * nk
    slices = {"gyro_bias": slice(0, b), "gyro_scale": slice(b, b + 3),
              "wheel_inertia": slice(b + 3, b + 3 + ns), "wheel_axes": slice(b + 3 + ns, e),
              "body_torque": slice(e, e + 3 * n_files)}
    tilt_u = (np.stack([tilt_basis(spacecraft.wheel(w).axis) for w in wheels]) if nk
              else np.zeros((0, 2, 3)))
    return NuisanceLayout(n_files, wheels, sd, slices, tilt_u, wheel_errors, tuple(scaled),
                          scale_axes)


def wheel_scale_columns(layout: NuisanceLayout, h_wheels: np.ndarray,
                        wheel_h: dict) -> np.ndarray:
    """(n, 3, S) body-axis columns of the wheel spin-inertia scales: per wheel ``J_k ρ_k g_k``
    (zero for a wheel not in ``wheel_h``), common ``H_w`` = ``h_wheels`` (n, 3) N m s."""
    if layout.wheel_errors == "common":
        return np.asarray(h_wheels, float)[:, :, None]
    cols = np.zeros(np.shape(h_wheels) + (layout.n_scales,))
    for k, name in enumerate(layout.scale_wheels):
        if name in wheel_h:
            cols[:, :, k] = wheel_h[name][:, None] * layout.scale_axes[k]
    return cols


def robust_columns(layout: NuisanceLayout, f: int, inertia: np.ndarray, omega: np.ndarray,
                   h_wheels: np.ndarray, wheel_h: dict, a: np.ndarray,
                   t: np.ndarray) -> np.ndarray:
    """(n, 3, R) body-axis columns of ``ν`` in the residual ``e_t`` of file ``f`` (module doc).

    Parameters
    ----------
    inertia : (3, 3) kg m², the linearisation point ``I*``.
    omega : (n, 3) measured body rates, rad/s.
    h_wheels : (n, 3) wheel momentum in body axes from the model's ``J_k`` and ``g_k``, N m s
        (the sum of the per-wheel scale columns).
    wheel_h : wheel name → (n,) ``J_k ρ_k`` (N m s) of the file's active wheels.
    a : (n, 3, 3) the DCMs ``A(q_t)``; ``t`` (n,) sample times, s.
    """
    n = omega.shape[0]
    cols = np.zeros((n, 3, layout.size))
    sl = layout.slices
    cols[:, :, 3 * f:3 * f + 3] = -inertia                                  # I* b
    cols[:, :, sl["gyro_scale"]] = -inertia[None] * omega[:, None, :]       # I* diag(ω) s
    cols[:, :, sl["wheel_inertia"]] = wheel_scale_columns(layout, h_wheels, wheel_h)  # c_k J_k ρ_k
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
