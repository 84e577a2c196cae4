"""Data preparation of the RWA4 model: the windows' means of the momentum balance and the robust
effects' columns (:mod:`~cassini_bayes.inference.rwa4.window_means`), noise levels, the chart
and its Laplace whitening (:func:`prepare_rwa4`).
"""

from __future__ import annotations

from typing import NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.errors import InputError, arg
from cassini_bayes.estimators.rwa4 import fit_axis_rcs, fit_axis_rwa
from cassini_bayes.frames import quat_conjugate, quat_continuous, quat_multiply, quat_to_rotvec
from cassini_bayes.inference.inertia import (InertiaGaussian, cholesky_params_from_pi,
                                             inertia_prior, is_physical, pi_from_cholesky_params)
from cassini_bayes.inference.laplace import laplace
from cassini_bayes.inference.noise import (ATTITUDE_FLOOR, RATE_FLOORS, floored, rate_noise_levels,
                                           white_noise_sd)
from cassini_bayes.inference.nuisance import NuisanceLayout, nuisance_layout
from cassini_bayes.inference.rwa4.model import LOG_DENSITY, PHYSICAL
from cassini_bayes.inference.rwa4.prior import PRIORS, margin_scale
from cassini_bayes.inference.rwa4.window_means import (no_nuisance, nuisance_means,
                                                       window_means)
from cassini_bayes.inference.rwa4.windows import (MIN_SPIN_CHANGE_RPM, WHEEL, Window,
                                                  check_windows, wheel_name, detect_windows)
from cassini_bayes.names import AXIS_METHODS
from cassini_bayes.physics.momentum import inertia_matrix
from cassini_bayes.spacecraft import Spacecraft, WheelCone
from cassini_bayes.telemetry import RPM_TO_RAD_S, Telemetry

__all__ = ["METHODS", "MAX_SD_DIRECTION_DEG", "Rwa4Data", "Rwa4Problem", "check_cone_prior",
           "prepare_rwa4"]

METHODS = AXIS_METHODS
MAX_SD_DIRECTION_DEG = 20.0  # a wider Laplace direction sd: the data do not determine the axis
N_COORDS = 8                     # sampler coordinates: 2 direction + 6 inertia (either chart)


class Rwa4Data(NamedTuple):
    """The arrays of :func:`~cassini_bayes.inference.rwa4.model.rwa4_model` (a pytree: problems
    of the same shapes share one compiled sampler). ``G`` window pairs, ``R`` nuisance columns.

    Attributes
    ----------
    m_pi, r_u, k_h, n_w, t_aa, j4, known_cov : the window means of :func:`loglik` (its
        docstring): per window (2G), ``A(q)ᵀ`` times the inertia regressor, times the solved
        wheel's rate (rad/s), and times the known wheels' momentum (N m s); the sample counts;
        the attitude products; the solved wheel's spin inertia (kg m²); ``Σ J² g gᵀ`` of the
        known wheels.
    m_pi_s, r_u_s, k_h_s, n_s, t_aa_s : the same per window's least-squares slope against time
        (S = 2G windows, RWA method; S = 0, RCS), ``n_s = 1/Σ w²`` of the slope weights ``w``.
    nu_cols, nu_cols_s, nu_pi, nu_pi_s, nu_sd, nu_wheel : the robust model's nuisance columns
        of the pairs (G, 3, R) and of the slopes (S, 3, R), the gyro columns per inertia entry
        (G, 3, R, 6) and (S, 3, R, 6), prior sds (R,) and solved-wheel marks (R,)
        (:func:`~cassini_bayes.inference.rwa4.window_means.nuisance_means`; ``R = 0`` in the
        idealised model).
    u0, basis : the gnomonic chart's centre (3,) and tangent basis (2, 3).
    pi_mean, pi_chol : the inertia prior's mean (6,) kg m² and Cholesky factor (6, 6).
    log_noise_hat : (3,) log noise levels (rad/s, rad/s, rad).
    margin_scale : the physical-inertia factor's scale (:func:`margin_scale`).
    cone_weight, cone_axis, cone_angle, cone_sd : the articulation-cone prior (weight 0 or 1;
        the cone's unit axis; rad).
    lp_centre, lp_tril : the RWA chart's log-Cholesky inertia coordinates.
    rcs_apex, rcs_pi, rcs_centre, rcs_scale, rcs_walls : the RCS chart
        (:func:`_rcs_chart`; ``None`` in the RWA chart).
    centre, tril : the sampler's whitening ``θ = centre + tril w`` (``None`` until the Laplace
        step has run).
    """

    m_pi: object
    r_u: object
    k_h: object
    n_w: object
    t_aa: object
    j4: object
    known_cov: object
    m_pi_s: object
    r_u_s: object
    k_h_s: object
    n_s: object
    t_aa_s: object
    nu_cols: object
    nu_cols_s: object
    nu_pi: object
    nu_pi_s: object
    nu_sd: object
    nu_wheel: object
    u0: object
    basis: object
    pi_mean: object
    pi_chol: object
    log_noise_hat: object
    margin_scale: object
    cone_weight: object
    cone_axis: object
    cone_angle: object
    cone_sd: object
    lp_centre: object
    lp_tril: object
    rcs_apex: object = None
    rcs_pi: object = None
    rcs_centre: object = None
    rcs_scale: object = None
    rcs_walls: object = None
    centre: object = None
    tril: object = None


class Rwa4Problem(NamedTuple):
    """Everything the RWA4 model needs, prepared once (SI units).

    Attributes
    ----------
    data : :class:`Rwa4Data`, the arrays of :func:`rwa4_model`.
    method : ``"rcs"`` or ``"rwa"``; prior : ``"uniform"`` or ``"cone"``.
    cone : the solved wheel's articulation cone from the spacecraft model (``None``: the model
        gives none; the ``cone`` prior and the articulation-cone check then do not apply).
    pairs : the ``(Time A, Time B)`` windows (s) used, one pair per group.
    inertia : the Gaussian inertia prior (mean (6,), cov (6, 6), kg m²).
    inertia_source : ``"spacecraft"`` or ``"posterior"``.
    baseline : the least-squares axis (Brown Eq 1 or Eq 3 at the prior-mean inertia), (3,).
    sd_direction_deg : the Laplace approximation's largest angular sd of the axis, deg.
    spin_change_rpm : change of the wheel's mean rate from A to B, per pair.
    noise_hat : (3,) σ̂ (rad/s, rad/s, rad).
    source : the telemetry file.
    wheel : the wheel solved for.
    chart : ``"rcs"`` (balance coordinates) or ``"rwa"`` (direct), module docstring.
    layout : the nuisance layout of the robust model's effects (built for either model).
    nuisance : their columns (:func:`~cassini_bayes.inference.rwa4.window_means.nuisance_means`;
        in ``data`` only when ``robust``).
    robust : whether the likelihood integrates the effects out.
    """

    data: Rwa4Data
    method: str
    prior: str
    cone: WheelCone | None
    pairs: tuple[tuple[Window, Window], ...]
    inertia: InertiaGaussian
    inertia_source: str
    baseline: np.ndarray
    sd_direction_deg: float
    spin_change_rpm: np.ndarray
    noise_hat: np.ndarray
    source: str
    wheel: str
    chart: str
    layout: NuisanceLayout
    nuisance: dict
    robust: bool


def _attitude_noise(q: np.ndarray) -> float:
    """White-noise level (rad) of the attitude ``q`` (n, 4) (:func:`~cassini_bayes.inference.
    noise.white_noise_sd` of its body-frame increments)."""
    if q.shape[0] < 4:
        return 0.0
    qc = np.asarray(quat_continuous(q))
    inc = np.asarray(quat_to_rotvec(quat_multiply(qc[1:], quat_conjugate(qc[:-1]))))
    return white_noise_sd(inc, differenced=True)


def tangent_basis(u: np.ndarray) -> np.ndarray:
    """(2, 3) orthonormal basis of the plane perpendicular to the unit vector ``u``."""
    e = np.eye(3)[int(np.argmin(np.abs(u)))]
    e1 = np.cross(u, e)
    e1 /= np.linalg.norm(e1)
    return np.stack([e1, np.cross(u, e1)])


def _noise_levels(tel: Telemetry, q: np.ndarray, windows) -> np.ndarray:
    """σ̂ (3,): gyro (rad/s), wheel rate (rad/s), attitude (rad), medians over the windows
    (quiet: the robust white-noise estimate is cleanest there)."""
    t = np.asarray(tel.t, float)
    levels = np.array([rate_noise_levels(tel.slice(*w))[:2] for w in windows], float)
    s_q = np.median([_attitude_noise(q[(t >= w[0]) & (t <= w[1])]) for w in windows])
    return floored([*np.median(levels, axis=0), s_q], (*RATE_FLOORS, ATTITUDE_FLOOR))


def _balance_map(data: dict, pi_mean: np.ndarray, pi_chol: np.ndarray):
    """The RCS method's linearising change of inertia coordinates (module docstring).

    With ``π = μ + L ξ`` the pair's balance is ``J₄ R (z + u4)`` with ``R = ΔR_u`` and
    ``z = a + K ξ``, ``a = R⁻¹(M μ + Δk)/J₄``, ``K = R⁻¹ M L/J₄`` (``M = Δm_π``). Returns ``a``
    (3,) and ``Q⁻¹`` (6, 6) with ``ξ = Q⁻¹ [z − a; w]``, the rows of ``Q`` being ``K`` and an
    orthonormal basis ``w`` of the prior-whitened inertia directions the balance does not see;
    ``None`` when ``R`` or ``K`` is singular (no spin change or no drift).
    """
    j4 = float(data["j4"])
    r = np.asarray(data["r_u"][1] - data["r_u"][0])
    m = np.asarray(data["m_pi"][1] - data["m_pi"][0])
    dk = np.asarray(data["k_h"][1] - data["k_h"][0])
    if np.linalg.cond(r) > 1e8:
        return None
    a = np.linalg.solve(r, m @ pi_mean + dk) / j4
    k = np.linalg.solve(r, m @ pi_chol) / j4
    _, s, vt = np.linalg.svd(k)
    if not s[-1] > 1e-8 * s[0]:
        return None
    return a, np.linalg.inv(np.concatenate([k, vt[3:]], 0))


def _second_moment(pi) -> np.ndarray:
    """``½ tr(I) 1 − I`` (3, 3) kg m² of ``π`` (6,), linear in ``π``; positive definite exactly
    for physical tensors (:func:`~cassini_bayes.inference.rwa4.prior._physical_margin`)."""
    i_m = np.asarray(inertia_matrix(jnp.asarray(pi, float)))
    return 0.5 * np.trace(i_m) * np.eye(3) - i_m


def _rcs_chart(a: np.ndarray, q_inv: np.ndarray, u0: np.ndarray, basis: np.ndarray,
               pi_mean: np.ndarray, pi_chol: np.ndarray) -> dict | None:
    """The RCS chart's arrays (module docstring, "Sampler coordinates"), from the balance map
    ``z = a + K ξ`` (:func:`_balance_map`), the axis chart ``u0``/``basis`` and the prior.

    ``π`` is a positive multiple of ``ξ − ξ_a`` (``ξ_a = −L⁻¹μ``, zero inertia), i.e. of
    ``[z − z_a; w − w_a]``: with ``z − z_a = t ζ(s)``, ``ζ(s) = −(u0 + Eᵀs)/√(1 + |s|²)``, and
    ``w − w_a = t ω/√(1 + |s|²)``, ``π = (t/√(1 + |s|²)) P [1; s; ω]``, so the physical region
    of ``x = (s, ω)`` is one convex set ``A(x) = ½ tr(P [1; x]) 1 − P [1; x] ≻ 0``, whatever
    ``|z|``. Returns ``rcs_apex`` (``z_a``, 3), ``rcs_pi`` (``P``, 6 × 6), ``rcs_centre``
    (``c``, ``x`` at the prior mean), ``rcs_scale`` (``C``, the Cholesky factor of the prior
    covariance of ``x`` there) and ``rcs_walls`` (``W_k = L_c⁻¹ A_lin(C e_k) L_c⁻ᵀ``, 5 × 3 × 3,
    ``A(c) = L_c L_cᵀ``). ``None`` when ``|z_a| ≥ ½ |a|``: the ray from ``z_a`` must meet the
    sphere ``|z| ≈ 1`` once.
    """
    q = np.linalg.inv(q_inv)
    xi_apex = -np.linalg.solve(pi_chol, pi_mean)
    z_apex, w_apex = a + q[:3] @ xi_apex, q[3:] @ xi_apex
    if not np.linalg.norm(z_apex) < 0.5 * np.linalg.norm(a):
        return None
    to_pi = pi_chol @ q_inv
    p_mat = to_pi @ np.block([[-u0[:, None], -basis.T, np.zeros((3, 3))],
                              [np.zeros((3, 3)), np.eye(3)]])

    def x_of_xi(xi):
        z, w = a + q[:3] @ xi, q[3:] @ xi
        t = jnp.linalg.norm(z - z_apex)
        zeta = (z - z_apex) / t
        s = (basis @ -zeta) / (u0 @ -zeta)
        return jnp.concatenate([s, (w - w_apex) * jnp.sqrt(1.0 + jnp.sum(s**2)) / t])

    centre = np.asarray(x_of_xi(jnp.zeros(6)))
    jac = np.asarray(jax.jacfwd(x_of_xi)(jnp.zeros(6)))
    scale = np.linalg.cholesky(jac @ jac.T)
    a_lin = np.stack([_second_moment(p_mat[:, 1:] @ scale[:, k]) for k in range(5)])
    l_c = np.linalg.cholesky(_second_moment(p_mat @ np.concatenate([[1.0], centre])))
    walls = np.linalg.solve(l_c, np.linalg.solve(l_c, a_lin).transpose(0, 2, 1))
    return dict(rcs_apex=z_apex, rcs_pi=p_mat, rcs_centre=centre, rcs_scale=scale,
                rcs_walls=0.5 * (walls + walls.transpose(0, 2, 1)))


def _inertia_prior(inertia: InertiaGaussian | None, spacecraft: Spacecraft):
    """The Gaussian inertia prior (default the spacecraft model's knowledge), its source
    (``"spacecraft"`` or ``"posterior"``), mean (6,) kg m² and Cholesky factor (6, 6)."""
    if inertia is None:
        ip = inertia_prior(spacecraft)
        inertia, i_src = InertiaGaussian(ip.mean, np.diag(ip.sd**2)), "spacecraft"
    else:
        i_src = "posterior"
    i_mean = np.asarray(inertia.mean, float)
    if not is_physical(i_mean):
        raise InputError("the inertia prior mean is not a physical inertia tensor")
    i_chol = np.linalg.cholesky(np.asarray(inertia.cov, float))
    return inertia, i_src, i_mean, i_chol


def _chart(kw: dict, method: str, data: dict, inertia: InertiaGaussian, i_mean: np.ndarray,
           i_chol: np.ndarray) -> tuple[str, np.ndarray]:
    """Add the chart's arrays to ``kw``; the chart (``"rcs"`` when the RCS balance map and its
    chart exist, :func:`_balance_map`, :func:`_rcs_chart`; else ``"rwa"``) and the sampler's
    starting point (module docstring)."""
    theta0 = np.zeros(N_COORDS)
    chart = "rwa"
    lp_c = cholesky_params_from_pi(i_mean)
    jac = np.asarray(jax.jacfwd(pi_from_cholesky_params)(jnp.asarray(lp_c)))
    cov_lp = np.linalg.solve(jac, np.linalg.solve(jac, np.asarray(inertia.cov)).T)
    kw["lp_centre"] = jnp.asarray(lp_c)
    kw["lp_tril"] = jnp.asarray(np.linalg.cholesky(0.5 * (cov_lp + cov_lp.T)))
    bal = _balance_map(data, i_mean, i_chol) if method == "rcs" else None
    arrays = None if bal is None else _rcs_chart(*bal, np.asarray(kw["u0"]),
                                                 np.asarray(kw["basis"]), i_mean, i_chol)
    if arrays is not None:
        chart = "rcs"
        kw.update({k: jnp.asarray(v) for k, v in arrays.items()})
        # θ = 0: δ = 0 and |z| = 1, the data's values; x at the prior mean (its direction)
    return chart, theta0


def _sd_direction_deg(chart: str, centre, tril, kw: Rwa4Data) -> float:
    """The Laplace approximation's largest angular sd (deg) of the axis: its gnomonic chart
    coordinates ``v`` are linearised in ``θ`` at the mode (``v = θ[:2]`` in the RWA chart)."""
    def v_of(theta):
        u = PHYSICAL[chart](theta, kw)[0]
        return (kw.basis @ u) / (kw.u0 @ u)

    jac = np.asarray(jax.jacfwd(v_of)(jnp.asarray(centre))) @ np.asarray(tril)
    return float(np.degrees(np.sqrt(np.linalg.eigvalsh(jac @ jac.T)[-1])))


def check_cone_prior(spacecraft: Spacecraft, wheel: str, prior: str) -> WheelCone | None:
    """The wheel's articulation cone from the model (``None``: none); a one-line InputError when
    ``prior`` is ``"cone"`` and the model gives the wheel none."""
    cone = spacecraft.wheel(wheel).cone
    if prior == "cone" and cone is None:
        raise InputError(f"{arg('prior', 'cone', cli_quote=True)}: the spacecraft model "
                         f"{spacecraft.name!r} gives no articulation cone for {wheel}; add "
                         "'cone_axis' and 'cone_deg' to its [[wheel]] entry "
                         "(docs/model_file.md) or use the uniform prior")
    return cone


def prepare_rwa4(tel: Telemetry, spacecraft: Spacecraft, *, method: str = "rcs",
                 pairs: Sequence[tuple[Window, Window]] | None = None, prior: str = "uniform",
                 inertia: InertiaGaussian | None = None, wheel: str = WHEEL,
                 robust: bool = True, wheel_errors: str = "per_wheel") -> Rwa4Problem:
    """Prepare the spin-axis problem of ``wheel`` from one telemetry file and its window pairs.

    Parameters
    ----------
    tel : telemetry with the wheel running (and, for the RWA method, the known wheels).
    spacecraft : wheel axes/inertias (the solved wheel's axis in the model is ignored) and the
        inertia prior.
    method : ``"rcs"`` (Brown Eq 1) or ``"rwa"`` (Brown Eq 3).
    pairs : ``[(A, B), …]`` windows in s; detected (:func:`detect_windows`) when ``None``.
    prior : ``"uniform"`` or ``"cone"`` (the wheel's articulation cone, which the spacecraft
        model's ``[[wheel]]`` entry must give: ``cone_axis``, ``cone_deg``).
    inertia : Gaussian inertia prior; default the spacecraft model's knowledge requirements.
    wheel : the wheel whose axis is solved for (default RWA4; Brown's flight test: RWA1).
    robust : integrate out the nuisance effects of the module docstring ("Robust model"), with
        the priors of the spacecraft model's ``Knowledge``; ``False``: Brown's idealised model.
    wheel_errors : the robust model's wheel spin-inertia errors: ``"per_wheel"`` (default; the
        solved wheel has its own scale too) or ``"common"`` (one scale for every wheel).

    Raises
    ------
    InputError
        Unknown method/prior/wheel, the cone prior for a wheel without a cone, no rates of the
        wheel, windows outside the data or
        overlapping, thrusters firing inside a window, no spin change (RCS), data that cannot
        determine the axis.
    """
    _check_options(method, prior)
    wheel = wheel_name(tel, wheel)
    cone = check_cone_prior(spacecraft, wheel, prior)
    pairs = (detect_windows(tel, method, wheel=wheel, spacecraft=spacecraft) if pairs is None
             else [tuple(p) for p in pairs])
    pairs = check_windows(tel, pairs, method)

    t = np.asarray(tel.t, float)
    names = tel.wheel_names
    k_u = names.index(wheel)
    rates = np.asarray(tel.wheel_rates, float)
    axes = np.stack([spacecraft.wheel(n).axis for n in names])
    js = np.array([spacecraft.wheel(n).inertia for n in names])
    active = tel.active_mask()
    known = [k for k in range(len(names)) if k != k_u and active[k]]
    masks = [((t >= a[0]) & (t <= a[1]), (t >= b[0]) & (t <= b[1])) for a, b in pairs]
    spin = _spin_changes(rates[:, k_u], masks, method, wheel, tel.source)

    inertia, i_src, i_mean, i_chol = _inertia_prior(inertia, spacecraft)

    q = np.asarray(quat_continuous(np.asarray(tel.q, float)))
    omega = np.asarray(tel.omega, float)
    i_pred = np.asarray(inertia_matrix(i_mean))
    u_ls = _least_squares_axis(method, q, omega, rates, axes, js, i_pred, masks, k_u)

    noise = _noise_levels(tel, q, [w for p in pairs for w in p])
    slopes = method == "rwa"      # quiet windows: the wheels absorb the external torque
    data = window_means(q, omega, rates, axes, js, k_u, known, masks, t if slopes else None)
    layout = nuisance_layout(spacecraft, 1, [names[k] for k in known],
                             wheel_errors=wheel_errors, scaled=[names[k] for k in known] + [wheel],
                             inertial_torque=True, torque_rate=True)
    nuisance = nuisance_means(layout, q, omega, rates, axes, js, known, names, masks, t, slopes)
    data.update(nuisance if robust else no_nuisance(len(pairs), data["n_s"].shape[0]))
    kw = dict(data, u0=jnp.asarray(u_ls), basis=jnp.asarray(tangent_basis(u_ls)),
              pi_mean=jnp.asarray(i_mean), pi_chol=jnp.asarray(i_chol),
              log_noise_hat=jnp.asarray(np.log(noise)),
              margin_scale=margin_scale(i_mean), **_cone_arrays(prior, cone))
    chart, theta0 = _chart(kw, method, data, inertia, i_mean, i_chol)
    kw, sd_dir = _laplace_centred(chart, theta0, Rwa4Data(**kw), wheel, tel.source)
    return Rwa4Problem(
        data=kw, method=method, prior=prior, cone=cone, pairs=tuple(pairs), inertia=inertia,
        inertia_source=i_src, baseline=u_ls, sd_direction_deg=sd_dir, spin_change_rpm=spin,
        noise_hat=noise, source=tel.source, wheel=wheel, chart=chart, layout=layout,
        nuisance=nuisance, robust=robust)


def _spin_changes(rho: np.ndarray, masks, method: str, wheel: str, source: str) -> np.ndarray:
    """The solved wheel's spin change (rpm) from Time A to Time B of each pair, from its rates
    ``rho`` (rad/s); the RCS method needs the first pair's to be at least
    ``MIN_SPIN_CHANGE_RPM`` (Brown Eq 1 divides by it)."""
    rho = np.nan_to_num(rho)
    spin = np.array([(rho[mb].mean() - rho[ma].mean()) / RPM_TO_RAD_S for ma, mb in masks])
    if method == "rcs" and abs(spin[0]) < MIN_SPIN_CHANGE_RPM:
        raise InputError(f"{wheel} changes by {spin[0]:.3g} rpm between Time A and Time B "
                         f"(< {MIN_SPIN_CHANGE_RPM:g} rpm): no spin change to calibrate from",
                         path=source)
    return spin


def _cone_arrays(prior: str, cone) -> dict:
    """The cone prior's entries of the model's data: its axis, angle and sd (rad), weighted 1
    with the cone prior and 0 (placeholders) without."""
    return dict(cone_weight=jnp.asarray(1.0 if prior == "cone" else 0.0),
                cone_axis=jnp.asarray(np.eye(3)[2] if cone is None else cone.axis),
                cone_angle=jnp.asarray(np.radians(0.0 if cone is None else cone.angle_deg)),
                cone_sd=jnp.asarray(np.radians(1.0 if cone is None else cone.sd_deg)))


def _check_options(method: str, prior: str) -> None:
    """Raise :class:`InputError` unless ``method`` and ``prior`` are known."""
    if method not in METHODS:
        raise InputError(f"{arg('method', method, cli_quote=True)}: choose one of "
                         f"{', '.join(METHODS)}")
    if prior not in PRIORS:
        raise InputError(f"{arg('prior', prior, cli_quote=True)}: choose one of "
                         f"{', '.join(PRIORS)}")


def _least_squares_axis(method: str, q, omega, rates, axes, js, i_pred, masks,
                        k_u: int) -> np.ndarray:
    """The least-squares axis, also the chart's centre: Brown Eq 1 (RCS), or Brown Eq 3 (RWA)
    with the body term C I ω kept at the prior-mean inertia ``i_pred`` (Eq 3 drops it for
    perfectly quiescent windows; it moves the axis by a few thousandths of a degree)."""
    if method == "rcs":
        fit = fit_axis_rcs(q, omega, rates, axes, js, i_pred, masks[0][0], masks[0][1],
                           unknown=k_u)
    else:
        fit = fit_axis_rwa(q, omega, rates, axes, js, masks, unknown=k_u, inertia=i_pred)
    return np.asarray(fit.axis, float)


def _laplace_centred(chart: str, theta0, kw: Rwa4Data, wheel: str, source):
    """``kw`` with the Laplace approximation's mode and Cholesky factor in the chart, and the
    axis direction's Laplace sd (deg); :class:`InputError` when the data leave the axis wider
    than :data:`MAX_SD_DIRECTION_DEG` (no excitation between the windows)."""
    centre, tril = laplace(LOG_DENSITY[chart], theta0, data=kw)
    sd_dir = _sd_direction_deg(chart, centre, tril, kw)
    if not sd_dir < MAX_SD_DIRECTION_DEG:
        raise InputError(f"the data determine the {wheel} axis only to ±{sd_dir:.3g}° "
                         f"(Laplace sd > {MAX_SD_DIRECTION_DEG:g}°): no excitation between the "
                         "windows; choose windows across a spin change (RCS) or a slew (RWA)",
                         path=source)
    return kw._replace(centre=jnp.asarray(centre), tril=jnp.asarray(tril)), sd_dir
