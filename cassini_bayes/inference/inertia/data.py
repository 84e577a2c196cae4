"""Data preparation of the inertia model: per-file arrays, noise levels and the prepared
:class:`InertiaProblem` (:func:`prepare_inertia`; the numerical steps are in
:mod:`cassini_bayes.inference.inertia.gls`).
"""

from __future__ import annotations

import warnings
from typing import NamedTuple, Sequence

import jax
import numpy as np

from cassini_bayes.errors import InputError, UnidentifiableError
from cassini_bayes.frames import dcm, quat_conjugate, quat_continuous, quat_multiply, quat_to_rotvec
from cassini_bayes.inference.inertia.gls import (
    full_prior,
    gls,
    information_ratio,
    set_robust_columns,
    sufficient_statistics,
    whitening,
)
from cassini_bayes.inference.inertia.likelihood import SYM_INDEX
from cassini_bayes.inference.inertia.prior import InertiaPrior, inertia_prior
from cassini_bayes.inference.noise import ATTITUDE_FLOOR, RATE_FLOORS, floored, white_noise_sd
from cassini_bayes.inference.nuisance import NuisanceLayout, nuisance_layout
from cassini_bayes.inference.sensitivity import Sensitivity, linear_sensitivity
from cassini_bayes.names import INERTIA_NAMES
from cassini_bayes.physics.momentum import regressor, wheel_momentum_body
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import Telemetry

__all__ = ["MIN_RATE_SNR", "noise_levels", "InertiaProblem", "prepare_inertia"]

MIN_RATE_SNR = 3.0            # rms body rate / its noise level below which a file is "still"


@jax.jit
def _file_arrays(q, omega, rates, axes, inertias):
    """One compiled pass over a file: DCMs, wheel momentum, regressor, attitude increments."""
    q = quat_continuous(q)
    a = dcm(q)
    h_w = wheel_momentum_body(rates, axes, inertias)
    inc = quat_to_rotvec(quat_multiply(q[1:], quat_conjugate(q[:-1])))
    return a, h_w, regressor(omega), inc, q


def _noise_from_arrays(omega, rates, inc) -> np.ndarray:
    return floored([white_noise_sd(omega), white_noise_sd(rates),
                    white_noise_sd(inc, differenced=True)], (*RATE_FLOORS, ATTITUDE_FLOOR))


def noise_levels(tel: Telemetry, spacecraft: Spacecraft) -> np.ndarray:
    """Robust white-noise levels ``(σ_ω rad/s, σ_ρ rad/s, σ_θ rad)`` of one telemetry file.

    For white noise of sd ``σ`` on a smooth signal, second differences have sd ``√6 σ``; the
    median absolute deviation ignores the few samples where the slew profile itself bends. The
    attitude uses second differences of the body-frame rotation increments
    ``rotvec(q_{t+1} q_t⁻¹)``. Each level is floored (1e-9 rad/s, 1e-7 rad/s, 1e-9 rad). On
    slews sampled slowly the wheel-rate level also picks up the wheels' own acceleration changes;
    it is only the centre of a wide prior.
    """
    rates, axes, js = _wheel_arrays(tel, spacecraft)
    inc = _file_arrays(np.asarray(tel.q, float), np.asarray(tel.omega, float), rates, axes,
                       js)[3]
    return _noise_from_arrays(np.asarray(tel.omega, float), rates, np.asarray(inc))


class InertiaData(NamedTuple):
    """The arrays of :func:`~cassini_bayes.inference.inertia.model.inertia_model` (a pytree: the
    sampler traces it, so problems of the same shapes share one compiled program). ``F`` files,
    ``P`` parameters ``[π (6), (H_0, T_N) per file, ν]``.

    Attributes
    ----------
    fmat : (F, P, P) per-file information ``Σ_t Cᵀ B̂_t⁻¹ C`` at the empirical-Bayes noise.
    gvec : (F, P) per-file score ``Σ_t Cᵀ B̂_t⁻¹ e_t`` at ``theta_star``.
    q_star : (F,) per-file ``Σ_t e_tᵀ B̂_t⁻¹ e_t`` at ``theta_star``.
    n_obs : (F,) scalar observations per file (3 per sample).
    theta_star : (P,) the linearisation point (the GLS mode).
    centre, tril : (P,), (P, P) the sampler's whitening ``θ = centre + tril z``.
    pi_mean, pi_sd : (6,) the prior of ``π`` (kg m²).
    file_sd : (6,) the prior sd of each file's ``H_0`` (N m s) and ``T_N`` (N m) per axis
        (:attr:`~cassini_bayes.inference.inertia.prior.InertiaPrior.file_sd`).
    log_noise : (F, 3) log empirical-Bayes noise levels (rad/s, rad/s, rad).
    nu_sd, nu_weights : the robust nuisance's prior sds (R,) and the wheel block's weights of the
        common scale; ``None`` in the idealised model.
    """

    fmat: object
    gvec: object
    q_star: object
    n_obs: object
    theta_star: object
    centre: object
    tril: object
    pi_mean: object
    pi_sd: object
    file_sd: object
    log_noise: object
    nu_sd: object = None
    nu_weights: object = None


class InertiaProblem(NamedTuple):
    """Everything the inertia model needs, prepared once from the data (SI units).

    ``data`` holds the arrays of :func:`inertia_model` (per-file sufficient statistics, so two
    problems with the same shapes reuse one compiled sampler); the other fields describe the data
    for the run directory and the report.

    Attributes
    ----------
    data : :class:`InertiaData`, the arrays of :func:`inertia_model`.
    torque : whether ``T_N`` is a parameter (selects the model function).
    prior : the stated prior of ``π``.
    t : (N,) sample times, s; ``file_idx`` (N,) int.
    omega : (N, 3) rad/s; ``h_wheels`` (N, 3) N m s body; ``q`` (N, 4) sign-continuous.
    sources : the telemetry file names, one per file.
    noise_hat : (F, 3) data noise levels σ̂ (rad/s, rad/s, rad), second-difference estimate.
    noise_eb : (F, 3) empirical-Bayes noise levels σ* (same units) fixing ``B̂_t``.
    residual_data : per-sample arrays (structure of arrays) for :func:`momentum_residuals`.
    laplace_mean, laplace_sd : Laplace approximation of the posterior of ``π`` (kg m²); robust:
        ``π = (1 + c) π̃`` with the wheel scale ``c`` at its prior (nuisance.py), to first order.
    information_ratio : (6,) eigenvalues of ``D F D`` (data information of π with H_0/T_N
        profiled, ``D`` the prior sd): < 1 means that direction is prior-dominated.
    weak_directions : human-readable list of prior-dominated parameter combinations.
    robust : whether the robust nuisance parameters ``ν`` are in the model.
    layout : :class:`~cassini_bayes.inference.nuisance.NuisanceLayout` of ``ν`` (always built).
    sensitivity : :class:`~cassini_bayes.inference.sensitivity.Sensitivity` of ``π`` to every
        effect, linearised at the mode.
    robust_cols : (N, 3, R) body columns of ``ν`` (robust only), to correct the residuals.
    """

    data: InertiaData
    torque: bool
    prior: InertiaPrior
    t: np.ndarray
    file_idx: np.ndarray
    omega: np.ndarray
    h_wheels: np.ndarray
    q: np.ndarray
    sources: tuple[str, ...]
    noise_hat: np.ndarray
    noise_eb: np.ndarray
    laplace_mean: np.ndarray
    laplace_sd: np.ndarray
    information_ratio: np.ndarray
    weak_directions: tuple[str, ...]
    residual_data: dict
    robust: bool = False
    layout: object = None
    sensitivity: Sensitivity | None = None
    robust_cols: np.ndarray | None = None


def _wheel_arrays(tel: Telemetry, spacecraft: Spacecraft):
    """Rates (n, k) rad/s (NaN→0), axes (k, 3), inertias (k,) of the telemetry's active wheels."""
    names = tel.active_wheels()
    if not names:
        raise InputError("no wheel has any rate; an RWA slew needs the wheel rates (rpm) of "
                         f"{' '.join(n.lower() for n in spacecraft.wheel_names)}",
                         path=tel.source)
    cols, axes, js = [], [], []
    for name in names:
        w = spacecraft.wheel(name)
        cols.append(np.nan_to_num(np.asarray(tel.wheel_rate(name), float)))
        axes.append(w.axis)
        js.append(w.inertia)
    return np.stack(cols, 1), np.stack(axes), np.asarray(js)


class Setup(NamedTuple):
    """The layout of the full parameter vector ``[π (6), (H_0 (3), T_N (3)) per file, ν (R)]``
    (every effect; the model uses the subset ``active``), shared by the steps of
    :func:`prepare_inertia`."""

    prior: InertiaPrior
    layout: NuisanceLayout
    p_base: int              # 6 + 6 F: π and (H_0, T_N) per file
    p_full: int              # p_base + R
    active: np.ndarray       # indices of the model's parameters in the full vector
    fit_map: np.ndarray      # (p_full, p_full): the columns the likelihood sees, cols @ fit_map
    w_index: np.ndarray      # indices of the wheel-scale block in the full vector


def problem_setup(telemetries: Sequence[Telemetry], spacecraft: Spacecraft, *, torque: bool,
           robust: bool, wheel_errors: str) -> Setup:
    """The :class:`Setup` of a problem."""
    n_files = len(telemetries)
    wheels_any = []
    for tel in telemetries:
        for name in tel.active_wheels():
            if spacecraft.wheel(name).name not in wheels_any:
                wheels_any.append(spacecraft.wheel(name).name)
    layout = nuisance_layout(spacecraft, n_files, wheels_any, wheel_errors=wheel_errors,
                             torque_rate=torque)
    p_base = 6 + 6 * n_files
    p_full = p_base + layout.size
    active = list(range(6))
    for f in range(n_files):
        active += list(range(6 + 6 * f, 6 + 6 * f + (6 if torque else 3)))
    if robust:
        active += list(range(p_base, p_full))
    # The common wheel spin-inertia scale c = ωᵀ w (w the wheel-scale block of θ) is not in the
    # likelihood: the data see only the momentum balance normalised by (1 + c), i.e. π/(1 + c),
    # H_0/(1 + c), T_N/(1 + c) and the relative scales δ = P w, P = 1 − 1 ωᵀ (module docstring),
    # so the fitted columns are cols @ fit_map with the wheel block projected by P (common model:
    # P = 0, the column dropped); the model maps π = (1 + c) π̃. (Keeping ``c H_w`` as a linear
    # column with a fixed noise covariance would let the fit shrink the noise term along the
    # unidentified scale and drag c many prior sd low.) The sensitivity keeps the full columns.
    w_index = p_base + np.arange(layout.size)[layout.wheel_block]
    n_d = layout.n_scales                  # the per-wheel d_k; the shared c_s is seen as zero
    fit_map = np.eye(p_full)
    fit_map[np.ix_(w_index, w_index)] = 0.0
    d_index = w_index[:n_d]
    fit_map[np.ix_(d_index, d_index)] = np.eye(n_d) - np.full((n_d, n_d), 1.0 / n_d)
    return Setup(inertia_prior(spacecraft), layout, p_base, p_full, np.asarray(active), fit_map,
                 w_index)


def file_data(f: int, tel: Telemetry, spacecraft: Spacecraft, p_full: int) -> dict:
    """The arrays of file ``f``: times, DCMs, wheel momentum, body rates, the columns of every
    effect in ``e_t = cols_t θ − y_t`` (body axes; the robust block is filled by
    :func:`~cassini_bayes.inference.inertia.gls.set_robust_columns`), the wheel noise matrix and
    the data noise levels ``σ̂``."""
    if tel.n < 10:
        raise InputError(f"only {tel.n} samples; an inertia fit needs a slew of many samples",
                         path=tel.source)
    rates, axes, js = _wheel_arrays(tel, spacecraft)
    q_in = np.asarray(tel.q, float)
    w = np.asarray(tel.omega, float)
    a, h_w, reg, inc, q_cont = (np.asarray(x) for x in _file_arrays(q_in, w, rates, axes, js))
    t = np.asarray(tel.t, float)
    dt = t - t[0]
    cols = np.zeros((tel.n, 3, p_full))  # e_t = cols_t θ − y_t (body axes)
    cols[:, :, :6] = reg
    j0 = 6 + 6 * f
    cols[:, :, j0:j0 + 3] = -a
    cols[:, :, j0 + 3:j0 + 6] = -a * dt[:, None, None]
    names = [spacecraft.wheel(n).name for n in tel.active_wheels()]
    return dict(t=t, dt=dt, a=a, h_w=h_w, w=w, cols=cols, y=-h_w,
                wheel_h={n: rates[:, k] * js[k] for k, n in enumerate(names)},
                wcov=np.einsum("k,ki,kj->ij", js**2, axes, axes),
                s_hat=_noise_from_arrays(w, rates, inc),
                q=q_cont)


def _check_excitation(files: list[dict], telemetries: Sequence[Telemetry]) -> None:
    """Excitation: the body rates must rise above their own noise (errors in variables: a
    regressor made of noise carries no information even though least squares would use it)."""
    snr = np.array([np.sqrt(np.mean(np.sum(fd["w"]**2, -1)) / (3 * fd["s_hat"][0]**2))
                    for fd in files])
    if snr.max() < MIN_RATE_SNR:
        src = ", ".join(t.source for t in telemetries)
        raise UnidentifiableError(
            f"{src}: the slews do not excite the inertia: the body rates are at their noise level "
            f"(rms/noise {snr.max():.2g} < {MIN_RATE_SNR:g}), so none of "
            f"{', '.join(INERTIA_NAMES)} is identified; give telemetry of RWA slews")
    for f in np.flatnonzero(snr < MIN_RATE_SNR):
        warnings.warn(f"{telemetries[f].source}: body rates at their noise level (rms/noise "
                      f"{snr[f]:.2g}); this file adds no information on the inertia", stacklevel=3)


def _sensitivity(info_full, full_prec, full_sd, setup: Setup, n_files: int):
    """The linearised sensitivity of ``π`` to every effect
    (:func:`~cassini_bayes.inference.sensitivity.linear_sensitivity`)."""
    groups = {"external_torque": np.concatenate([np.arange(9 + 6 * f, 12 + 6 * f)
                                                 for f in range(n_files)])}
    for name, sl in setup.layout.slices.items():
        groups[name] = setup.p_base + np.arange(setup.p_full - setup.p_base)[sl]
    return linear_sensitivity(info_full, full_prec, full_sd, setup.active, groups)


def _residual_data(files: list[dict]) -> dict:
    """Per-sample arrays of all files (structure of arrays) for
    :func:`~cassini_bayes.inference.inertia.likelihood.momentum_residuals`."""
    n_files = len(files)
    onehot = np.concatenate([np.full(fd["t"].size, f) for f, fd in enumerate(files)])
    onehot = (onehot[None, :] == np.arange(n_files)[:, None]).astype(float)
    # device_put, not jnp.asarray: that compiles a one-operation program per shape (every
    # process; docs/performance.md)
    return jax.device_put(dict(
        omega_t=np.concatenate([fd["w"] for fd in files]).T,
        h_wheels_t=np.concatenate([fd["h_w"] for fd in files]).T,
        a_t=np.ascontiguousarray(np.moveaxis(np.concatenate([fd["a"] for fd in files]), 0, -1)),
        dt=np.concatenate([fd["dt"] for fd in files]),
        onehot=onehot,
        wheel_cov_t=np.concatenate(
            [np.broadcast_to([fd["wcov"][i, j] for i, j in SYM_INDEX], (fd["t"].size, 6))
             for fd in files]).T.copy()))


def prepare_inertia(telemetries: Sequence[Telemetry], spacecraft: Spacecraft, *,
                    torque: bool = True, robust: bool = False, wheel_errors: str = "per_wheel",
                    max_iter: int = 20) -> InertiaProblem:
    """Prepare the inertia problem: arrays, noise covariance, sufficient statistics, checks.

    Steps (all NumPy, O(N) once):

    1. per file: DCMs, wheel momentum, the regressor, the data noise levels ``σ̂``, and the
       columns of every effect the model may carry (``H_0``, ``T_N``, the robust nuisance
       parameters ``ν`` of :mod:`cassini_bayes.inference.nuisance`);
    2. iterated generalised least squares with empirical-Bayes noise levels: alternate the GLS
       posterior mode of ``θ = (π, H_0,f, T_N,f[, ν])`` (prior included) and a Fisher-scoring step
       of ``log σ_f`` (3 per file, prior ``N(log σ̂, 1)``) on the Gaussian likelihood with
       covariance ``B_t(σ, I, h_t)``, until the steps are < 1e-6 (the robust columns, linear in
       ``ν`` around the current mode ``I*``, are rebuilt each step);
    3. per file, the sufficient statistics of the quadratic form
       ``Q_f(θ) = Σ_t e_tᵀ B̂_t⁻¹ e_t`` around the mode ``θ*``: ``F_f``, ``g_f``, ``Q_f(θ*)``;
    4. the Laplace approximation (mode, covariance) that centres and whitens the sampler's
       coordinates, the identifiability check, and the linearised sensitivity of ``π`` to every
       effect (:func:`cassini_bayes.inference.sensitivity.linear_sensitivity`).

    ``robust`` adds the nuisance parameters ``ν`` (gyro bias per file, gyro scale factor, wheel
    spin-inertia scales per wheel and shared, wheel spin-axis tilts, body-fixed torque and, with
    ``torque``, the inertial torque's rate) with priors from ``spacecraft.knowledge``;
    ``wheel_errors`` (``"per_wheel"`` or ``"common"``) picks the wheel spin-inertia model
    (:func:`~cassini_bayes.inference.nuisance.nuisance_layout`).

    Raises
    ------
    UnidentifiableError
        The slews carry no information about any inertia entry (no rotation, or rotation too small
        against the noise): the data are less informative than the prior in every direction.
    InputError
        A telemetry file has too few samples or no wheel rates.
    """
    _check_wheels_run(telemetries)
    n_files = len(telemetries)
    setup = problem_setup(telemetries, spacecraft, torque=torque, robust=robust,
                   wheel_errors=wheel_errors)
    files = [file_data(f, tel, spacecraft, setup.p_full) for f, tel in enumerate(telemetries)]
    set_robust_columns(files, setup, setup.prior.mean)
    _check_excitation(files, telemetries)
    full_sd, full_prec, full_mean = full_prior(setup, n_files)
    theta_full, log_s, log_s_hat = gls(files, setup, full_prec, full_mean, robust=robust,
                                       max_iter=max_iter)
    theta = theta_full[setup.active]
    set_robust_columns(files, setup, theta[:6])  # the linearisation point I* at the mode
    info_full, fmat, gvec, q_star, n_obs = sufficient_statistics(files, setup, theta_full, log_s)
    active, fit_map = setup.active, setup.fit_map
    info = (fit_map.T @ info_full @ fit_map)[np.ix_(active, active)]
    prior_prec = full_prec[active]
    ratio, weak = information_ratio(info, prior_prec, setup.prior, telemetries)
    centre, tril, cov, c_sd = whitening(info, prior_prec, theta, setup, robust=robust)
    sens = _sensitivity(info_full, full_prec, full_sd, setup, n_files)

    data = InertiaData(fmat=fmat, gvec=gvec, q_star=q_star, n_obs=n_obs, theta_star=theta,
                       centre=centre, tril=tril, pi_mean=setup.prior.mean, pi_sd=setup.prior.sd,
                       file_sd=setup.prior.file_sd, log_noise=log_s,
                       nu_sd=setup.layout.sd if robust else None,
                       nu_weights=setup.layout.scale_weights if robust else None)
    data = jax.device_put(jax.tree.map(np.asarray, data))
    return InertiaProblem(
        data=data, torque=torque, prior=setup.prior,
        t=np.concatenate([fd["t"] for fd in files]),
        file_idx=np.concatenate([np.full(fd["t"].size, f) for f, fd in enumerate(files)]),
        omega=np.concatenate([fd["w"] for fd in files]),
        h_wheels=np.concatenate([fd["h_w"] for fd in files]),
        q=np.concatenate([fd["q"] for fd in files]), sources=tuple(t.source for t in telemetries),
        noise_hat=np.exp(log_s_hat), noise_eb=np.exp(log_s), laplace_mean=theta[:6],
        laplace_sd=np.sqrt(np.diag(cov)[:6] + (theta[:6] * c_sd)**2),
        information_ratio=ratio, weak_directions=weak,
        residual_data=_residual_data(files), robust=robust, layout=setup.layout,
        sensitivity=sens,
        robust_cols=(np.concatenate([fd["cols"][:, :, setup.p_base:] for fd in files])
                     if robust else None))


def _check_wheels_run(telemetries: Sequence[Telemetry]) -> None:
    """Raise :class:`InputError` without telemetry, or for a file in which no wheel runs: the
    inertia is calibrated from the momentum the wheels exchange with the body (Feldman & Lee
    Eq 3)."""
    if not telemetries:
        raise InputError("no telemetry given; pass at least one slew file")
    for tel in telemetries:
        if not tel.active_wheels():
            raise InputError("no wheel runs (every wheel column is empty): the inertia is "
                             "calibrated from the momentum the wheels exchange with the body; "
                             "give reaction-wheel slew telemetry with the wheel rates",
                             path=tel.source)
