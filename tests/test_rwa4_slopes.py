"""The RWA method's window slopes (:func:`cassini_bayes.inference.rwa4.likelihood.slopes`): in a
quiet window the wheels absorb the external torque, so the inertial momentum's slope against
time is that torque (Euler ``dH/dt = T``; Feldman & Lee Eq 2 with the wheels' momentum).

Noise-free simulated telemetry of the ESPA bus's RWA calibration (its first slew pair only, so
the simulation is short): at the truth the slopes vanish with no torque, equal the inertial
torque with one (the failing case: a slope row that ignored the torque), and the slope rows of
the nuisance columns cancel every torque effect.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from cassini_bayes.frames import quat_continuous
from cassini_bayes.inference.nuisance import nuisance_layout
from cassini_bayes.inference.rwa4.window_means import (no_nuisance, nuisance_means,
                                                        window_means)
from cassini_bayes.inference.rwa4.likelihood import (DATA_KEYS, balance, loglik, nuisance_cols,
                                                      rows, slopes)
from cassini_bayes.names import INERTIA_NAMES
from cassini_bayes.simulate.scenario._types import Noise

WHEEL = "RW2"
PAIR = ((0.0, 195.0), (255.0, 445.0))   # the scenario's quiet periods around its first slew


def _fly(**torques):
    """Noise-free telemetry of the shortened scenario with the given torques and gyro bias (all
    others 0), the window arrays with slopes, the nuisance columns and the truth ``(u, π)``."""
    from cassini_bayes.simulate import load_scenario, simulate

    s = load_scenario("wheel_axis_espa_bus")
    zero = (0.0, 0.0, 0.0)
    s = dataclasses.replace(s, duration_s=450.0, slews=s.slews[:1],
                            noise=Noise(gyro_bias_rad_s=torques.get("gyro_bias", 0.0)),
                            external_torque_inertial_nm=torques.get("inertial", zero),
                            external_torque_body_nm=torques.get("body", zero),
                            external_torque_inertial_rate_nm_s=torques.get("rate", zero))
    tel = simulate(jax.random.key(0), s).telemetry
    sc = s.prior
    t = np.asarray(tel.t, float)
    names = list(tel.wheel_names)
    k_u = names.index(WHEEL)
    known = [k for k in range(len(names)) if k != k_u]
    axes = np.stack([sc.wheel(n).axis for n in names])
    js = np.array([sc.wheel(n).inertia for n in names])
    masks = [tuple((t >= w[0]) & (t <= w[1]) for w in PAIR)]
    q = np.asarray(quat_continuous(np.asarray(tel.q, float)))
    omega, rates = np.asarray(tel.omega, float), np.asarray(tel.wheel_rates, float)
    data = window_means(q, omega, rates, axes, js, k_u, known, masks, t)
    data["rcs"] = window_means(q, omega, rates, axes, js, k_u, known, masks)   # no times
    layout = nuisance_layout(sc, 1, [names[k] for k in known], scaled=names,
                             inertial_torque=True, torque_rate=True)
    nuis = nuisance_means(layout, q, omega, rates, axes, js, known, names, masks, t,
                           slopes=True)
    i_star = np.asarray(sc.inertia, float)
    data["pi_star"] = i_star[[0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2]]     # the model file's π
    truth = s.truth.to_dict()["inertia"]
    pi = jnp.asarray([truth[n] for n in INERTIA_NAMES])
    u = jnp.asarray(s.truth.wheel(WHEEL).axis)
    h_scale = float(js[k_u] * np.abs(np.nanmean(rates[:, k_u]))) / (PAIR[0][1] - PAIR[0][0])
    return data, nuis, layout, u, pi, h_scale


@pytest.fixture(scope="module")
def still():
    return _fly()


def _slopes(data, u, pi):
    return np.asarray(slopes(u, pi, m_pi_s=data["m_pi_s"], r_u_s=data["r_u_s"],
                             k_h_s=data["k_h_s"], j4=data["j4"]))


def test_slopes_vanish_at_the_truth_without_torque(still):
    """No torque, no noise: each window's slope is 0 to 1e-9 of the solved wheel's momentum
    spread over a window (measured 6e-16: the simulator's integration error)."""
    data, _, _, u, pi, h_scale = still
    s = _slopes(data, u, pi)
    assert s.shape == (2, 3)
    assert np.abs(s).max() < 1e-9 * h_scale, (s, h_scale)


def test_slopes_measure_the_inertial_torque():
    """With an inertial torque the slopes at the truth are that torque (1e-9 relative, measured
    7e-12; a slope row that ignored it would fail by 100 %), and the inertial-torque nuisance
    column's slope cancels it."""
    torque = np.array([5e-5, -3e-5, 2e-5])
    data, nuis, layout, u, pi, _ = _fly(inertial=tuple(torque))
    s = _slopes(data, u, pi)
    np.testing.assert_allclose(s, np.tile(torque, (2, 1)), rtol=0, atol=1e-9 * 5e-5)
    nu = np.zeros(layout.size)
    nu[layout.slices["inertial_torque"]] = torque
    res = s + np.asarray(nuis["nu_cols_s"]) @ nu
    assert np.abs(res).max() < 1e-9 * 5e-5, res


def test_slope_columns_cancel_body_torque_and_drift():
    """A body-fixed torque and an inertial torque rate: the slope rows' nuisance columns (the
    slopes of ``−A(q_t) ∫ A(q_s)ᵀ ds`` and ``−A(q_t)(t − t₀)²/2``) cancel them to 1e-6 of the
    torque (trapezoid rule against the simulator's integration; measured 1.2e-9), while the slopes
    alone are the torque's size."""
    body, rate = np.array([-4e-5, 6e-5, 3e-5]), np.array([2e-8, -1e-8, 3e-8])
    data, nuis, layout, u, pi, _ = _fly(body=tuple(body), rate=tuple(rate))
    s = _slopes(data, u, pi)
    assert np.abs(s).max() > 2e-5
    nu = np.zeros(layout.size)
    nu[layout.slices["body_torque"]] = body
    nu[layout.slices["torque_rate"]] = rate
    res = s + np.asarray(nuis["nu_cols_s"]) @ nu
    assert np.abs(res).max() < 1e-6 * np.abs(s).max(), (s, res)


def test_gyro_bias_column_is_taken_at_the_sampled_inertia():
    """A gyro bias ``b`` adds ``I b`` to the measured momentum with the true inertia ``I``: the
    pair row's bias columns at the true ``π`` cancel it (to 1e-6 of its size). Columns at the
    model file's tensor ``I*`` (a few per cent off the truth here) leave ``(I − I*) b``, which
    a fit could only absorb in a bias of the wrong size."""
    b = np.array([3e-6, -2e-6, 4e-6])
    data, nuis, layout, u, pi, _ = _fly(gyro_bias=tuple(b))
    nu = np.zeros(layout.size)
    nu[layout.slices["gyro_bias"]] = b

    def residual(at):
        d = balance(u, pi, m_pi=data["m_pi"], r_u=data["r_u"], k_h=data["k_h"], j4=data["j4"])
        cols = nuisance_cols(u, at, r_u=data["r_u"], j4=data["j4"], nu_cols=nuis["nu_cols"],
                             nu_pi=nuis["nu_pi"], nu_wheel=nuis["nu_wheel"])
        return np.asarray(d), np.asarray(d + cols @ nu)

    size, res = residual(pi)
    assert np.abs(size).max() > 1e-6 and np.abs(res).max() < 1e-6 * np.abs(size).max(), res
    _, res_star = residual(jnp.asarray(data["pi_star"]))
    assert np.abs(res_star).max() > 1e-3 * np.abs(size).max(), res_star


def test_rows_join_pairs_and_slopes(still):
    """The likelihood's rows: 3 per pair then 3 per window's slope, the white-noise covariance
    block diagonal (mean and slope weights are orthogonal), one shared set of nuisance columns;
    the RCS method (no times given) has no slope rows."""
    data, nuis, _, u, pi, _ = still
    kw = dict(data, **nuis)
    log_sigma = jnp.log(jnp.asarray([5e-6, 0.05, 3e-5]))
    d, cov, cols = rows(u, pi, log_sigma, **{k: kw[k] for k in DATA_KEYS})
    d, cov, cols = np.asarray(d), np.asarray(cov), np.asarray(cols)
    assert d.shape == (9,) and cov.shape == (9, 9) and cols.shape == (9, nuis["nu_sd"].size)
    assert np.all(cov[:3, 3:] == 0) and np.all(cov[3:6, 6:] == 0)
    assert np.isfinite(float(loglik(u, pi, log_sigma, u_ref=u, pi_ref=pi,
                                    **{k: kw[k] for k in DATA_KEYS})))
    assert data["rcs"]["m_pi_s"].shape == (0, 3, 6) and data["rcs"]["t_aa_s"].shape[0] == 0


def test_normaliser_does_not_move_with_the_inertia_or_the_axis(still):
    """The rows are computed from the measured rates, so their noise already moves with ``π``
    and ``u``; the likelihood's normaliser (its white-noise determinant) must not move with them
    as well (:func:`~cassini_bayes.inference.rwa4.likelihood.loglik`): with no nuisance columns,
    ``loglik + ½ dᵀ C⁻¹ d`` is the same at ``π`` and ``1.1 π`` and a tilted axis (to 1e-9),
    while the determinant at the sampled values moves (by more than 0.3 at ``1.1 π``)."""
    data, _, _, u, pi, _ = still
    kw = dict(data, **no_nuisance(1, 2))
    log_sigma = jnp.log(jnp.asarray([5e-6, 0.05, 3e-5]))
    keys = {k: kw[k] for k in DATA_KEYS}
    tilted = u + jnp.asarray([0.0, 0.02, -0.01])
    tilted = tilted / jnp.linalg.norm(tilted)

    def normaliser(u_, pi_):
        d, cov, _ = (np.asarray(x) for x in rows(u_, pi_, log_sigma, **keys))
        ll = float(loglik(u_, pi_, log_sigma, u_ref=u, pi_ref=pi, **keys))
        return ll + 0.5 * d @ np.linalg.solve(cov, d), np.linalg.slogdet(cov)[1]

    (n0, det0), (n1, det1), (n2, _) = (normaliser(u, pi), normaliser(u, 1.1 * pi),
                                       normaliser(tilted, pi))
    assert abs(n1 - n0) < 1e-9 * abs(n0) and abs(n2 - n0) < 1e-9 * abs(n0), (n0, n1, n2)
    assert abs(det1 - det0) > 0.3, (det0, det1)
