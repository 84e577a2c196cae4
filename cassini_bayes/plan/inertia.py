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
from cassini_bayes.inference.inertia.data import Setup, _setup
from cassini_bayes.inference.inertia.gls import full_prior
from cassini_bayes.inference.noise import ATTITUDE_FLOOR, RATE_FLOORS
from cassini_bayes.physics.momentum import inertia_matrix, regressor
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
    setup = _setup([stub], spacecraft, torque=True, robust=True, wheel_errors="per_wheel")
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
    steps = 0.5 * (at[1:] + at[:-1]) * jnp.diff(t)[:, None, None]
    c_t = jnp.concatenate([jnp.zeros((1, 3, 3)), jnp.cumsum(steps, 0)])  # ∫ A(q_s)ᵀ ds
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
    fit_map = setup.fit_map
    active = setup.active
    info = (fit_map.T @ info_full @ fit_map)[np.ix_(active, active)]
    cov = jnp.linalg.inv(info + jnp.diag(model.prior_prec))
    w_act = np.searchsorted(active, setup.w_index)
    weights = setup.layout.scale_weights
    c_var = weights @ cov[np.ix_(w_act, w_act)] @ weights
    var = jnp.diag(cov)[:6]
    return PredictedInertia(jnp.sqrt(var + jnp.asarray(pi) ** 2 * c_var), jnp.sqrt(var),
                            jnp.sqrt(c_var))


def predict(model: InertiaModel, arrays, pi, h0, tn, sigma) -> PredictedInertia:
    """Predicted posterior of ``π`` from noise-free simulated telemetry ``arrays``
    (:class:`~cassini_bayes.simulate.run.SimArrays`: ``t``, ``q``, ``omega``, ``wheel_rates``);
    other arguments as :func:`information`."""
    info = information(model, arrays.t, arrays.q, arrays.omega, arrays.wheel_rates,
                       jnp.asarray(pi), jnp.asarray(h0), jnp.asarray(tn), jnp.asarray(sigma))
    return posterior_sd(model, info, pi)
