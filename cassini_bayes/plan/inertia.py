"""Predicted posterior of the robust inertia model for a planned manoeuvre (pure JAX).

The robust inertia model (:mod:`cassini_bayes.inference.inertia`) is linear-Gaussian in its
parameters ``θ = [π (6), H_0 (3), T_N (3), ν (R)]``: per sample the body residual is
``e_t = C_t θ − y_t`` (Feldman & Lee 2006 Eq 3 with the nuisance columns of
:mod:`cassini_bayes.inference.nuisance`) with covariance

    B_t = σ_ω² I I + σ_ρ² Σ_k J_k² g_k g_kᵀ + σ_θ² [h_t×][h_t×]ᵀ,     h_t = A(q_t) H_N,t.

Its Laplace approximation is therefore exact: the posterior precision is the Fisher information
``Σ_t C_tᵀ B_t⁻¹ C_t`` of the columns the likelihood sees (the fit's ``fit_map``: the wheels'
common spin-inertia scale ``c`` projected out, Psiaki 2005) plus the prior precision, and
``π = (1 + c) π̃`` adds ``π² var(c)`` to the moments and products (``prepare_inertia``'s
``laplace_sd``). On data simulated without noise the information is its expectation, and the
posterior sd it gives is the one a fit of noisy data of that manoeuvre should report.

Here the columns are written in JAX, so the predicted sd is a differentiable function of the
telemetry (body rates, attitude, wheel rates) and hence, through the simulator, of the
manoeuvre. The layout, priors and ``fit_map`` are the fit's own (``inference.inertia.data``), and
a test checks that on the same telemetry, linearisation point and noise levels the prediction
equals the fit's Laplace sd to rounding.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.frames import dcm
from cassini_bayes.inference.inertia.data import Setup, problem_setup
from cassini_bayes.inference.inertia.gls import full_prior
from cassini_bayes.inference.noise import ATTITUDE_FLOOR, RATE_FLOORS
from cassini_bayes.names import INERTIA_NAMES
from cassini_bayes.physics.momentum import inertia_matrix, regressor
from cassini_bayes.physics.quadrature import cumulative_trapezoid
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import Telemetry

__all__ = [
    "InertiaModel",
    "PredictedInertia",
    "inertia_model",
    "information",
    "noise_sigmas",
    "posterior_sd",
    "predict",
]

RPM_TO_RAD_S = 2.0 * np.pi / 60.0


class InertiaModel(NamedTuple):
    """The constants of the robust inertia fit of one telemetry file (NumPy, static under jit).

    setup : the fit's parameter layout (``inference.inertia.data.Setup``).
    wheels : indices (model order) of the wheels the fit sees as active.
    axes, j : (k, 3) spin axes and (k,) spin inertias (kg m²) of every wheel of the model the
        fit is given (the prior model: what the fit believes).
    prior_prec : (P,) prior precision of the model's parameters (``setup.active``).
    """

    setup: Setup
    wheels: tuple[int, ...]
    axes: np.ndarray
    j: np.ndarray
    prior_prec: np.ndarray


def inertia_model(spacecraft: Spacecraft, wheels_on) -> InertiaModel:
    """The robust (per-wheel, with torque and torque rate) inertia fit's constants for one file
    of ``spacecraft`` (the model the fit is given) with the named ``wheels_on`` active."""
    names = [w.name for w in spacecraft.wheels]
    on = {spacecraft.wheel(n).name for n in wheels_on}
    idx = tuple(i for i, n in enumerate(names) if n in on)
    rates = np.zeros((2, len(names)))
    rates[:, list(idx)] = 1000.0
    # a stand-in file whose active wheels are ``wheels_on``: the layout reads only those
    stub = Telemetry(t=np.array([0.0, 1.0]), q=np.tile([0.0, 0.0, 0.0, 1.0], (2, 1)),
                     omega=np.zeros((2, 3)), wheel_rates=rates, wheel_names=tuple(names),
                     on_times=None, source="<plan>")
    setup = problem_setup([stub], spacecraft, torque=True, robust=True, wheel_errors="per_wheel")
    _, full_prec, _ = full_prior(setup, 1)
    return InertiaModel(setup, idx, np.asarray(spacecraft.wheel_axes, float),
                        np.asarray(spacecraft.wheel_inertias, float), full_prec[setup.active])


def noise_sigmas(gyro_rad_s: float, tach_noise_rpm: float, tach_quantum_rpm: float,
                 star_tracker_rad: float) -> np.ndarray:
    """The model's white-noise levels ``(σ_ω rad/s, σ_ρ rad/s, σ_θ rad)`` of a scenario's
    sensors: the tachometer's white noise and its quantisation (a uniform error of variance
    ``q²/12``) add; each level floored as the fit floors its estimate."""
    s_rho = np.hypot(tach_noise_rpm, tach_quantum_rpm / np.sqrt(12.0)) * RPM_TO_RAD_S
    return np.maximum([gyro_rad_s, s_rho, star_tracker_rad], [*RATE_FLOORS, ATTITUDE_FLOOR])


def _columns(model: InertiaModel, t, a, omega, wheel_h, inertia):
    """(n, 3, P_full) body columns of ``θ`` (``data.file_data`` and ``nuisance.robust_columns``
    in JAX): ``wheel_h`` (n, k) the momentum ``J_k ρ_k`` of every model wheel (N m s)."""
    layout = model.setup.layout
    n = t.shape[0]
    dt = t - t[0]
    cols = [regressor(omega), -a, -a * dt[:, None, None],               # π, H_0, T_N
            jnp.broadcast_to(-inertia, (n, 3, 3)),                        # gyro bias: I* b
            -inertia[None] * omega[:, None, :]]                           # gyro scale: I* ω s
    per = [wheel_h[:, k][:, None] * model.axes[k][None] for k in model.wheels]  # J_k ρ_k g_k
    cols += [p[:, :, None] for p in per]
    if layout.has_common:
        cols.append(sum(per)[:, :, None])                                 # shared scale c_s
    for kk, k in enumerate(model.wheels):                                 # axis tilts
        for m in range(2):
            cols.append((wheel_h[:, k][:, None] * layout.tilt_u[kk, m][None])[:, :, None])
    at = jnp.swapaxes(a, -1, -2)
    c_t = cumulative_trapezoid(at, t)                                     # ∫ A(q_s)ᵀ ds
    cols.append(-jnp.einsum("nij,njk->nik", a, c_t))                      # body torque T_B
    cols.append(-a * (0.5 * dt**2)[:, None, None])                        # torque rate Ṫ_N
    out = jnp.concatenate(cols, -1)
    assert out.shape[-1] == model.setup.p_full, (out.shape, model.setup.p_full)
    return out


def information(model: InertiaModel, t, q, omega, wheel_rates, pi, h0, tn, sigma):
    """Fisher information (P_full, P_full) of the full vector ``θ`` from one file (JAX).

    Parameters
    ----------
    t : (n,) s; ``q`` (n, 4) attitude (scalar last); ``omega`` (n, 3) rad/s body rates;
        ``wheel_rates`` (n, k) rad/s of every model wheel (anything for the idle ones).
    pi : (6,) kg m², the linearisation point ``I*`` (the robust columns and ``B_t``).
    h0, tn : (3,) inertial momentum (N m s) and torque (N m) that give ``h_t`` in ``B_t``.
    sigma : (3,) ``(σ_ω rad/s, σ_ρ rad/s, σ_θ rad)``.
    """
    inertia = inertia_matrix(jnp.asarray(pi))
    a = dcm(q)
    on = np.zeros(model.j.size)
    on[list(model.wheels)] = 1.0
    wheel_h = jnp.where(on[None] > 0, jnp.nan_to_num(wheel_rates), 0.0) * model.j[None]
    cols = _columns(model, t, a, omega, wheel_h, inertia)
    h_n = h0[None, :] + (t - t[0])[:, None] * tn[None, :]
    h = jnp.einsum("nij,nj->ni", a, h_n)
    kmat = jnp.sum(h * h, -1)[:, None, None] * jnp.eye(3)[None] - h[:, :, None] * h[:, None, :]
    wcov = np.einsum("k,ki,kj->ij", (model.j * on) ** 2, model.axes, model.axes)
    b = (sigma[0] ** 2 * inertia @ inertia + sigma[1] ** 2 * wcov)[None] + sigma[2] ** 2 * kmat
    wc = jnp.linalg.solve(b, cols)
    return jnp.einsum("nip,niq->pq", cols, wc)


class PredictedInertia(NamedTuple):
    """Predicted posterior of ``π`` (kg m²): ``sd`` (6,) as a fit reports it; ``sd_data`` (6,)
    the part the manoeuvre controls (``π̃ = π/(1 + c)``, the wheels' common spin-inertia scale
    ``c`` held at its value); ``c_sd`` the sd of ``c`` (a fraction, its prior's)."""

    sd: jax.Array
    sd_data: jax.Array
    c_sd: jax.Array


def posterior_sd(model: InertiaModel, info_full, pi) -> PredictedInertia:
    """Laplace sd of ``π`` from the full information (``gls.whitening``'s formula, in JAX)."""
    setup = model.setup
    active = setup.active
    cov = posterior_cov(model, info_full)
    w_act = np.searchsorted(active, setup.w_index)
    weights = setup.layout.scale_weights
    c_var = weights @ cov[np.ix_(w_act, w_act)] @ weights
    var = jnp.diag(cov)[:6]
    return PredictedInertia(jnp.sqrt(var + jnp.asarray(pi) ** 2 * c_var), jnp.sqrt(var),
                            jnp.sqrt(c_var))


AXES = ("x", "y", "z")


def _site_names(model: InertiaModel) -> list[tuple[str, str]]:
    """``(site, label)`` per entry of :func:`site_values`, in order (one file)."""
    lay = model.setup.layout
    out = [(n, n) for n in INERTIA_NAMES]
    out += [("H0", f"H0_{a}") for a in AXES] + [("T_N", f"T_N_{a}") for a in AXES]
    sl = lay.slices
    if "gyro_bias" in sl:
        out += [("gyro_bias", f"gyro_bias_{a}") for a in AXES]
    if "gyro_scale" in sl:
        out += [("gyro_scale", f"gyro_scale_{a}") for a in AXES]
    if "wheel_inertia" in sl:
        names = lay.scale_wheels or ("all",)
        out += [("wheel_scale", f"wheel_scale_{w}") for w in names]
    if lay.has_common:
        out.append(("wheel_scale_common", "wheel_scale_common"))
    if "wheel_axes" in sl:
        out += [("wheel_tilt", f"wheel_tilt_{w}_{m + 1}") for w in lay.wheels for m in range(2)]
    for eff, site in (("body_torque", "T_body"), ("inertial_torque", "T_inertial"),
                      ("torque_rate", "T_N_rate")):
        if eff in sl:
            out += [(site, f"{site}_{a}") for a in AXES]
    return out


def site_values(model: InertiaModel, theta):
    """The robust fit's posterior sites (``inference.inertia.model``'s deterministics, one file)
    from its active parameter vector ``θ`` (the fit's coordinates: ``π̃``, ``H̃_0``, ``T̃_N``, ``ν``
    with the wheel block of ``fit_map``), flattened in the order of :func:`site_labels`.

    The physical values are ``(1 + c)`` times what the likelihood sees for ``π``, ``H_0``,
    ``T_N`` and the torques, ``c = ωᵀ w`` the wheels' common spin-inertia scale; the per-wheel
    scales are ``d_k = m + (1 + c)(d̃_k − m) [+ c_s]``, ``m`` their mean (the model's mapping).
    """
    setup = model.setup
    lay = setup.layout
    full = jnp.zeros(setup.p_full).at[np.asarray(setup.active)].set(theta)
    pi_t, h0, tn, nu = full[:6], full[6:9], full[9:12], full[12:]
    sl = lay.slices
    one = 1.0
    parts = []
    if "wheel_inertia" in sl:
        w = nu[lay.wheel_block]
        c = jnp.asarray(lay.scale_weights) @ w
        one = 1.0 + c
    parts += [one * pi_t, one * h0, one * tn]
    for eff in ("gyro_bias", "gyro_scale"):
        if eff in sl:
            parts.append(nu[sl[eff]])
    if "wheel_inertia" in sl:
        d = nu[sl["wheel_inertia"]]
        m = jnp.mean(d)
        common = nu[sl["wheel_inertia_common"]] if lay.has_common else 0.0
        parts.append(m + one * (d - m) + common)
        if lay.has_common:
            parts.append(common)
    if "wheel_axes" in sl:
        parts.append(nu[sl["wheel_axes"]])
    for eff in ("body_torque", "inertial_torque", "torque_rate"):
        if eff in sl:
            parts.append(one * nu[sl[eff]])
    return jnp.concatenate([jnp.atleast_1d(p) for p in parts])


def site_labels(model: InertiaModel) -> tuple[str, ...]:
    """Labels of :func:`site_values`' entries (``Ixx``, ``H0_x``, ``wheel_tilt_RWA1_2``, …)."""
    return tuple(label for _, label in _site_names(model))


def posterior_cov(model: InertiaModel, info_full) -> jax.Array:
    """Laplace covariance of the active parameters (the fit's coordinates, ``fit_map``)."""
    setup = model.setup
    active = setup.active
    info = (setup.fit_map.T @ info_full @ setup.fit_map)[np.ix_(active, active)]
    return jnp.linalg.inv(info + jnp.diag(model.prior_prec))


def site_sd(model: InertiaModel, cov, point):
    """(predicted sd, prior sd) of every site of :func:`site_values` by the delta method at the
    active parameter vector ``point`` (the truth): ``J Σ Jᵀ``, ``J = ∂sites/∂θ``."""
    jac = jax.jacfwd(lambda th: site_values(model, th))(jnp.asarray(point, float))
    post = jnp.sqrt(jnp.einsum("ip,pq,iq->i", jac, cov, jac))
    prior = jnp.sqrt(jnp.einsum("ip,p,ip->i", jac, 1.0 / jnp.asarray(model.prior_prec), jac))
    return post, prior


def predict(model: InertiaModel, arrays, pi, h0, tn, sigma) -> PredictedInertia:
    """Predicted posterior of ``π`` from noise-free simulated telemetry ``arrays``
    (:class:`~cassini_bayes.simulate.run.SimArrays`: ``t``, ``q``, ``omega``, ``wheel_rates``);
    other arguments as :func:`information`."""
    info = information(model, arrays.t, arrays.q, arrays.omega, arrays.wheel_rates,
                       jnp.asarray(pi), jnp.asarray(h0), jnp.asarray(tn), jnp.asarray(sigma))
    return posterior_sd(model, info, pi)


def predict_sites(model: InertiaModel, arrays, pi, h0, tn, sigma):
    """``(inertia, labels, sd, prior_sd)``: :func:`predict`'s :class:`PredictedInertia`, and
    the predicted posterior sd and the prior sd of every site of the robust fit
    (:func:`site_values`: inertia, momentum, torques and every nuisance parameter, SI),
    linearised at the truth ``π``, ``H_0 = h0``, ``T_N = tn``, nuisances zero; arguments as
    :func:`information`."""
    info = information(model, arrays.t, arrays.q, arrays.omega, arrays.wheel_rates,
                       jnp.asarray(pi), jnp.asarray(h0), jnp.asarray(tn), jnp.asarray(sigma))
    point = np.zeros(model.setup.p_full)
    point[:6], point[6:9], point[9:12] = np.asarray(pi), np.asarray(h0), np.asarray(tn)
    sd, prior = site_sd(model, posterior_cov(model, info), point[model.setup.active])
    return posterior_sd(model, info, pi), site_labels(model), sd, prior


def fitted_site_sd(model: InertiaModel, posterior) -> np.ndarray:
    """Posterior sd of every site of a robust fit of one file (``posterior[name]``: draws of
    shape (chain, draw, ...), e.g. an ArviZ posterior group) in the order of
    :func:`site_labels`: what :func:`predict_sites` predicts."""
    cols = []
    for name in dict.fromkeys(site for site, _ in _site_names(model)):
        v = np.asarray(posterior[name].values if hasattr(posterior[name], "values")
                       else posterior[name])
        cols.append(v.reshape(v.shape[0] * v.shape[1], -1))
    d = np.concatenate(cols, 1)
    if d.shape[1] != len(_site_names(model)):
        raise ValueError(f"the posterior has {d.shape[1]} site entries, the model "
                         f"{len(_site_names(model))}: not a robust fit of one file")
    return d.std(0)
