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
  (``[torque_knowledge] sd_nm``; default the Feldman & Lee App. A bound, 15 µN m per axis); over
  a short slew the two are nearly the same torque, and the priors share it out.

* **a shared wheel spin-inertia error** ``c_s`` (per wheel, the default, when the model file's
  ``[wheel_knowledge] common_inertia_sd_frac`` is above zero): every wheel's scale is
  ``c_k = c_s + d_k``, the shared part from one calibration method, one test stand, one
  temperature, the individual ``d_k`` from each wheel's own calibration. Its column is the sum of
  the per-wheel columns (``H_w``);
* **inertial torque** ``T_I`` (N m, per file; the RWA4 model, whose balance has no ``T_N``): the
  inertial momentum gains ``T_I (t − t_0)``, so the body residual gains ``−A(q_t) (t − t_0) T_I``;
* **inertial torque rate** ``Ṫ`` (N m/s, per file; the inertia model, beside its constant
  ``T_N``): ``−A(q_t) ½ (t − t_0)² Ṫ``. Solar and RTG torques change as the slews turn the sun
  line in body axes; the prior lets the App. A bound (15 µN m) change by its whole size within
  an hour (``[torque_knowledge] rate_sd_nm_per_h``). Without it a torque that drifts within the run
  leaks into the products of inertia (``docs/robust/open_world.md``).
* **a flexible or slosh mode** (the thrust model, where the events show one): the momentum
  ``M y(t)`` it holds, linear in the six entries of ``M = δ δᵀ`` (kg m²) at the mode's frequency
  and damping (:mod:`cassini_bayes.inference.thrust.flex`, :func:`with_flex_mode`).

What the data cannot separate stays prior-dominated by construction: scaling ``I``, ``H_0`` and
``T_N`` by ``(1 + c)`` together with every wheel inertia leaves every momentum balance unchanged
(Psiaki 2005, WMAP), and so does scaling ``I`` by ``1/(1 − σ)`` against a common gyro scale factor
``σ``; in the linearised model these are exact null directions of the likelihood, so the common
wheel scale ``c = c_s + mean_k d_k`` (:data:`NuisanceLayout.scale_weights`) and the common part
of ``s`` keep their priors and the overall scale of ``I`` widens by their prior sd instead of
drifting (the thrust fit takes the common wheel scale out of ``ν`` and scales its draws,
:func:`without_common_scale`). The differences ``c_k − c`` are learned from slews about
several axes. With independent per-wheel priors of sd ``σ_J`` alone the common part would
have prior sd ``σ_J/√K`` (K wheels): 0.29 % for three wheels at 0.5 %, a claim that the
wheels' errors average out which no data can check; the shared term makes it
``√(σ_s² + σ_J²/K)`` (0.58 % at the defaults). The priors (zero-mean Normal, one sd each)
come from the spacecraft model's :class:`~cassini_bayes.spacecraft.Knowledge` and, per wheel,
its ``[[wheel]] inertia_sd_frac`` (:func:`wheel_inertia_sd`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from cassini_bayes.errors import InputError
from cassini_bayes.names import EFFECTS, WHEEL_ERRORS
from cassini_bayes.physics.quadrature import cumulative_trapezoid
from cassini_bayes.spacecraft import Spacecraft, wheel_tilt_basis

__all__ = ["EFFECTS", "WHEEL_ERRORS", "NuisanceLayout", "nuisance_layout", "with_flex_mode",
           "with_time_tag_steps", "with_clock_errors",
           "tilt_basis",
           "wheel_inertia_sd", "wheel_scale_columns", "without_common_scale", "robust_columns",
           "split_nuisance",
           "site_prior_sd", "prior_wheel_errors"]

_TORQUE_EFFECTS = ("body_torque", "inertial_torque", "torque_rate")


_UNDRAWN = ("time_tag_steps", "clock")


class NuisanceLayout(NamedTuple):
    """Order and prior of the robust nuisance vector ``ν`` (appended to the model's θ).

    ``ν = (b_0 (3), …, b_{F−1} (3), s (3), c_0 … c_{S−1} (S), [c_s (1)], a_0 (2), …, a_{K−1} (2),
    T_B,0 (3), …, [T_I,0 (3), …], [Ṫ_0 (3), …], [M (6)], [δ (P)], [clock (2F)])``; ``S`` = the
    number of scaled wheels (per wheel) or 1 (common); the bracketed effects only where the
    layout has them.

    Attributes
    ----------
    n_files : F; ``wheels`` the K wheel names (active in any file) that get tilts.
    sd : (R,) prior standard deviations (rad/s, 1, 1, 1, rad, N m, N m, N m/s, kg m², s; the
        clock's s and s per sample).
    slices : effect name (:data:`EFFECTS`; ``time_tag_steps``, ``clock``: no site) → slice of
        ``ν``, for the effects the layout has.
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
        """S, the number of wheel spin-inertia scale parameters (without the shared one)."""
        sl = self.slices["wheel_inertia"]
        return sl.stop - sl.start

    @property
    def has_common(self) -> bool:
        """Whether the per-wheel scales share a common term ``c_s`` (:func:`nuisance_layout`)."""
        return "wheel_inertia_common" in self.slices

    @property
    def wheel_block(self) -> slice:
        """The contiguous slice of every wheel-scale parameter: ``c_0 … c_{S−1}`` and ``c_s``."""
        sl = self.slices["wheel_inertia"]
        return slice(sl.start, sl.stop + int(self.has_common))

    @property
    def scale_weights(self) -> np.ndarray:
        """Weights ``ω`` over :attr:`wheel_block` of the common scale ``c = Σ ω_k w_k`` (the
        mean of the per-wheel parameters plus the shared one): the direction the data cannot see
        (module docstring); ``c_k − c`` they can."""
        return np.r_[np.full(self.n_scales, 1.0 / max(self.n_scales, 1)),
                     np.ones(int(self.has_common))]

    @property
    def common_scale_weights(self) -> np.ndarray:
        """Weights ``ω`` over :attr:`wheel_block` of the common scale as the prior splits it,
        ``u = Σ ω_j w_j``, so that every wheel's ``c_k = u + e_k`` with deviations ``e_k``
        independent of ``u`` a priori: the per-wheel parameters' precision-weighted mean plus the
        shared one (the common model: its one scale). Equal to :attr:`scale_weights` where the
        wheels' knowledge is equal."""
        if self.wheel_errors == "common":
            return np.ones(1)
        prec = np.asarray(self.sd, float)[self.slices["wheel_inertia"]] ** -2.0
        return np.r_[prec / max(float(prec.sum()), 1e-300), np.ones(int(self.has_common))]

    @property
    def common_scale_sd(self) -> float:
        """Prior sd (a fraction) of the common scale ``u`` (:attr:`common_scale_weights`):
        ``√(σ_s² + 1/Σ_k σ_k⁻²)`` per wheel."""
        w = self.common_scale_weights
        return float(np.sqrt(np.sum((w * np.asarray(self.sd, float)[self.wheel_block])**2)))

    @property
    def sites(self) -> tuple[str, ...]:
        """The effects drawn as posterior sites: all but the time-tag steps, one per tagged
        sample, and the clock's errors, which are integrated out only
        (:func:`with_time_tag_steps`, :func:`with_clock_errors`)."""
        return tuple(e for e in self.slices if e not in _UNDRAWN)

    @property
    def torque_effects(self) -> tuple[str, ...]:
        """The torque effects the layout has, in order (they follow the tilts)."""
        return tuple(e for e in _TORQUE_EFFECTS if e in self.slices)

    def wheel_scales(self, nu: np.ndarray) -> np.ndarray:
        """Each wheel's total spin-inertia scale ``c_k = d_k [+ c_s]`` from ``ν`` (..., R):
        (..., S) per wheel, (...) common."""
        nu = np.asarray(nu)
        scale = nu[..., self.slices["wheel_inertia"]]
        if self.has_common:
            scale = scale + nu[..., self.slices["wheel_inertia_common"]]
        return scale if self.wheel_errors == "per_wheel" else scale[..., 0]


def tilt_basis(axis) -> np.ndarray:
    """(2, 3) orthonormal pair perpendicular to the unit vector ``axis`` (the simulator's too)."""
    return wheel_tilt_basis(axis)


def wheel_inertia_sd(spacecraft: Spacecraft, name: str) -> float:
    """Prior sd (a fraction) of wheel ``name``'s spin-inertia scale: its ``[[wheel]]
    inertia_sd_frac`` when the model file gives one, else ``[wheel_knowledge] inertia_sd_frac``."""
    w = spacecraft.wheel(name)
    return (spacecraft.knowledge.wheel_inertia_sd_frac if w.inertia_sd_frac is None
            else w.inertia_sd_frac)


def prior_wheel_errors(spacecraft: Spacecraft, key) -> np.ndarray:
    """One draw of every wheel's spin-inertia error ``c_k = c_s + d_k`` (model-file wheel order)
    from the per-wheel robust model's prior: the closed-world campaigns' truth."""
    import jax

    k_s, k_d = jax.random.split(key)
    sd = np.array([wheel_inertia_sd(spacecraft, w.name) for w in spacecraft.wheels])
    shared = spacecraft.knowledge.wheel_common_inertia_sd_frac * float(jax.random.normal(k_s))
    return shared + sd * np.asarray(jax.random.normal(k_d, (sd.size,)))


def nuisance_layout(spacecraft: Spacecraft, n_files: int, wheels, *,
                    wheel_errors: str = "per_wheel", scaled=None,
                    inertial_torque: bool = False, torque_rate: bool = False) -> NuisanceLayout:
    """The layout and prior of ``ν`` for ``n_files`` files and the named active ``wheels``.

    ``wheel_errors`` (:data:`WHEEL_ERRORS`): one spin-inertia scale per wheel of ``scaled``
    (default ``wheels``; the RWA4 model adds the solved wheel, which gets no tilt), prior sd
    :func:`wheel_inertia_sd` each, plus the shared ``c_s`` when ``[wheel_knowledge]
    common_inertia_sd_frac`` > 0; or one common scale with the ``[wheel_knowledge]`` sd.
    ``inertial_torque`` and ``torque_rate`` add those per-file effects (module docstring).
    """
    if wheel_errors not in WHEEL_ERRORS:
        raise InputError(f"wheel errors {wheel_errors!r}: choose one of "
                         f"{', '.join(WHEEL_ERRORS)}")
    k = spacecraft.knowledge
    wheels = tuple(wheels)
    nk = len(wheels)
    common_sd = np.zeros(0)
    if wheel_errors == "per_wheel":
        scaled = wheels if scaled is None else tuple(scaled)
        scale_sd = np.array([wheel_inertia_sd(spacecraft, w) for w in scaled], float)
        scale_axes = (np.stack([spacecraft.wheel(w).axis for w in scaled]) if scaled
                      else np.zeros((0, 3)))
        if k.wheel_common_inertia_sd_frac > 0 and scaled:
            common_sd = np.array([k.wheel_common_inertia_sd_frac])
    else:
        scaled, scale_sd, scale_axes = (), np.array([k.wheel_inertia_sd_frac]), np.zeros((0, 3))
    blocks = [("gyro_bias", np.full(3 * n_files, k.gyro_bias_sd_rad_s)),
              ("gyro_scale", np.full(3, k.gyro_scale_factor_sd)),
              ("wheel_inertia", scale_sd),
              ("wheel_inertia_common", common_sd),
              ("wheel_axes", np.full(2 * nk, np.deg2rad(k.wheel_axis_sd_deg))),
              ("body_torque", np.full(3 * n_files, k.torque_sd_nm)),
              ("inertial_torque", np.full(3 * n_files if inertial_torque else 0,
                                          k.torque_sd_nm)),
              ("torque_rate", np.full(3 * n_files if torque_rate else 0,
                                      k.torque_rate_sd_nm_per_h / 3600.0))]
    slices, start = {}, 0
    for name, block in blocks:
        if block.size or name in ("wheel_inertia", "wheel_axes"):
            slices[name] = slice(start, start + block.size)
        start += block.size
    sd = np.concatenate([block for _, block in blocks])
    tilt_u = (np.stack([tilt_basis(spacecraft.wheel(w).axis) for w in wheels]) if nk
              else np.zeros((0, 2, 3)))
    return NuisanceLayout(n_files, wheels, sd, slices, tilt_u, wheel_errors, tuple(scaled),
                          scale_axes)


def with_flex_mode(layout: NuisanceLayout, sd_kg_m2: float) -> NuisanceLayout:
    """``layout`` with the six entries of a flexible mode's ``M = δ δᵀ`` appended, prior sd
    ``sd_kg_m2`` each."""
    r = layout.size
    return layout._replace(sd=np.r_[layout.sd, np.full(6, float(sd_kg_m2))],
                           slices={**layout.slices, "flex_mode": slice(r, r + 6)})


def with_time_tag_steps(layout: NuisanceLayout, n_steps: int,
                        time_tag_sd_s: float) -> NuisanceLayout:
    """``layout`` with ``n_steps`` time-tag errors appended, prior sd ``time_tag_sd_s`` each
    (the thrust model's time-tag walk, :mod:`cassini_bayes.inference.thrust.time_tags`)."""
    if n_steps == 0:
        return layout
    r = layout.size
    return layout._replace(sd=np.r_[layout.sd, np.full(n_steps, float(time_tag_sd_s))],
                           slices={**layout.slices, "time_tag_steps": slice(r, r + n_steps)})


def with_clock_errors(layout: NuisanceLayout, sd: np.ndarray) -> NuisanceLayout:
    """``layout`` with each event's regular-clock offset (s) and period error (s per sample)
    appended, prior sds ``sd`` (2E,) in that order (the thrust model's grid,
    :mod:`cassini_bayes.inference.thrust.clock`)."""
    r = layout.size
    sd = np.asarray(sd, float)
    return layout._replace(sd=np.r_[layout.sd, sd],
                           slices={**layout.slices, "clock": slice(r, r + sd.size)})


def split_nuisance(nu, layout: NuisanceLayout) -> dict:
    """The robust nuisance vectors ``ν`` (..., R) as named posterior sites: ``gyro_bias``
    (..., F, 3) rad/s, ``gyro_scale`` (..., 3), ``wheel_scale`` (..., S) each wheel's total
    scale ``c_k`` per wheel or (...) common, ``wheel_scale_common`` (...) the shared ``c_s``,
    ``wheel_tilt`` (..., K, 2) rad, ``T_body``/``T_inertial`` (..., F, 3) N m, ``T_N_rate``
    (..., F, 3) N m/s, ``flex_inertia`` (..., 6) kg m² (a flexible mode's ``δ δᵀ``)."""
    nu = np.asarray(nu)
    lead, sl = nu.shape[:-1], layout.slices
    out = {EFFECTS["gyro_bias"]: nu[..., sl["gyro_bias"]].reshape(lead + (layout.n_files, 3)),
           EFFECTS["gyro_scale"]: nu[..., sl["gyro_scale"]],
           EFFECTS["wheel_inertia"]: layout.wheel_scales(nu),
           EFFECTS["wheel_axes"]: nu[..., sl["wheel_axes"]].reshape(lead + (-1, 2))}
    if layout.has_common:
        out[EFFECTS["wheel_inertia_common"]] = nu[..., sl["wheel_inertia_common"]][..., 0]
    for effect in layout.torque_effects:
        out[EFFECTS[effect]] = nu[..., sl[effect]].reshape(lead + (layout.n_files, 3))
    if "flex_mode" in sl:
        out[EFFECTS["flex_mode"]] = nu[..., sl["flex_mode"]]
    return out


def site_prior_sd(layout: NuisanceLayout) -> dict[str, np.ndarray]:
    """Posterior site of :func:`split_nuisance` → flat prior sd (zero-mean Normal) of its
    elements; a wheel's total scale ``c_k = d_k + c_s`` has the marginal ``√(σ_k² + σ_s²)``."""
    sd = np.asarray(layout.sd)
    out = {EFFECTS[e]: sd[layout.slices[e]] for e in layout.sites}
    if layout.has_common:
        site = EFFECTS["wheel_inertia"]
        out[site] = np.sqrt(out[site]**2 + sd[layout.slices["wheel_inertia_common"]]**2)
    return out


def wheel_scale_columns(layout: NuisanceLayout, h_wheels: np.ndarray,
                        wheel_h: dict) -> np.ndarray:
    """(n, 3, W) body-axis columns of every wheel-scale parameter (:attr:`NuisanceLayout.
    wheel_block`): per wheel ``J_k ρ_k g_k`` (zero for a wheel not in ``wheel_h``) and, with a
    shared part, their sum for ``c_s``; common: ``H_w`` = ``h_wheels`` (n, 3) N m s."""
    if layout.wheel_errors == "common":
        return np.asarray(h_wheels, float)[:, :, None]
    cols = np.zeros(np.shape(h_wheels) + (layout.n_scales + int(layout.has_common),))
    for k, name in enumerate(layout.scale_wheels):
        if name in wheel_h:
            cols[:, :, k] = wheel_h[name][:, None] * layout.scale_axes[k]
    if layout.has_common:
        cols[:, :, -1] = cols[:, :, :-1].sum(-1)                      # c_s: every wheel's
    return cols


def without_common_scale(cols: np.ndarray, layout: NuisanceLayout) -> np.ndarray:
    """``cols`` (..., R) with the common scale taken out of the wheel block: each wheel-scale
    column ``W_j − C ω_j`` (``C`` the column of a unit common scale: every per-wheel column's sum,
    or the common model's one; ``ω`` :attr:`NuisanceLayout.common_scale_weights`). ``ν`` then
    holds the deviations ``e_k = c_k − u`` alone, and the likelihood sees the wheels at the model
    file's common scale (``u = 0``); for a model whose balance is homogeneous in the inertia, the
    thrust and the wheels (Feldman & Lee Eq 17, the inertia sampled) ``u`` keeps its prior, and
    the fit scales what it reports by ``1 + u``."""
    out = np.array(cols, float, copy=True)
    block = out[..., layout.wheel_block]
    unit = np.r_[np.ones(layout.n_scales if layout.wheel_errors == "per_wheel" else 1),
                 np.zeros(int(layout.has_common))]
    out[..., layout.wheel_block] = block - (block @ unit)[..., None] * layout.common_scale_weights
    return out


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
    cols[:, :, layout.wheel_block] = wheel_scale_columns(layout, h_wheels, wheel_h)  # J_k ρ_k g_k
    a0 = sl["wheel_axes"].start
    for k, name in enumerate(layout.wheels):
        if name in wheel_h:
            for j in range(2):
                cols[:, :, a0 + 2 * k + j] = wheel_h[name][:, None] * layout.tilt_u[k, j]
    at = np.swapaxes(a, -1, -2)
    c_t = cumulative_trapezoid(at, t)                                  # ∫ A(q_s)ᵀ ds
    t0 = sl["body_torque"].start + 3 * f
    cols[:, :, t0:t0 + 3] = -np.einsum("nij,njk->nik", a, c_t)         # −A(q_t) C_t T_B
    dt = (t - t[0])[:, None, None]
    for effect, power in (("inertial_torque", 1), ("torque_rate", 2)):
        if effect in sl:
            j = sl[effect].start + 3 * f                   # −A(q_t) (t − t_0)^p / p! T
            cols[:, :, j:j + 3] = -a * dt**power / power
    return cols
