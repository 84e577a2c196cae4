"""Tier (a): the impulse model of Feldman & Lee Eqs 14-23."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from cassini_bayes.physics.impulse import (angular_impulse, impulse_from_on_times,
                                           impulse_from_pulses, impulse_lhs, impulse_lhs_basis,
                                           system_xy, system_xyz, system_z, system_zz,
                                           system_zzz)
from cassini_bayes.physics.pulse import pulse_impulse
from cassini_bayes.spacecraft import CASSINI_WHEEL_AXES
from cassini_bayes.spacecraft import eq16_moment_matrix as moment_matrix
from kinematics import rotvec_to_quat_np, slew_segments, wheels_for_conserved_momentum

LX, LY, LZY, LZZ = 1.234, 1.580, 2.880, 3.019
I_TRUE = np.array([[7375.02, -136.58, 6.23], [-136.58, 6061.58, 180.26], [6.23, 180.26, 3829.7]])
_lhs = jax.jit(impulse_lhs)
_pulses = jax.jit(impulse_from_pulses)


def test_moment_matrix_is_eq16_entry_by_entry():
    ex, ey, ez = 0.011, -0.023, 0.037
    q = np.asarray(moment_matrix(LX, LY, LZY, LZZ, (ex, ey, ez)))
    # Feldman & Lee Eq 16 as printed (Z rows: the Z thrusters' arms use Lzz - eZ only in
    # products with zero direction components, so they do not appear)
    printed = np.array([
        [-(LY - ey), -(LY - ey), LY + ey, LY + ey, LZY - ez, LZY - ez, -(LZY - ez), -(LZY - ez)],
        [LX - ex, -(LX + ex), -(LX + ex), LX - ex, 0, 0, 0, 0],
        [0, 0, 0, 0, -(LX - ex), LX + ex, -LX - ex, LX - ex]])
    np.testing.assert_allclose(q, printed, atol=1e-15)


@pytest.mark.parametrize("dt", [4.0])
def test_lhs_vanishes_without_thrust_at_second_order(dt):
    """No thruster fires: V(t) = 0 up to the trapezoid's O(Δt²) error in ΔG."""
    errs = []
    for step in (dt, dt / 2):
        q0 = rotvec_to_quat_np(np.array([0.2, 0.1, -0.3]))
        t, q, w = slew_segments(q0, [((1, 1, 0), 0.8, 200.0), ((0, 0, 1), -0.6, 240.0)], step, 40.)
        _, h = wheels_for_conserved_momentum(t, q, w, I_TRUE, [20.0, -15.0, 30.0],
                                             CASSINI_WHEEL_AXES, [0.161, 0.160, 0.161])
        v = np.asarray(_lhs(t, w, I_TRUE, h))
        errs.append(np.max(np.abs(v)))
    assert errs[0] < 1e-2  # N m s, against wheel momenta of tens of N m s
    assert 3.5 < errs[0] / errs[1] < 4.5  # second order


def test_lhs_basis_is_exact_in_the_inertia():
    """``V`` is linear in ``I`` (Feldman & Lee Eq 17: ``I Δω`` and ``ΔG``): its basis gives
    :func:`impulse_lhs` for any inertia to rounding (1e-12 relative of the largest term)."""
    from cassini_bayes.physics.momentum import inertia_vector

    q0 = rotvec_to_quat_np(np.array([0.2, 0.1, -0.3]))
    t, q, w = slew_segments(q0, [((1, 1, 0), 0.8, 200.0), ((0, 0, 1), -0.6, 240.0)], 4.0, 40.)
    _, h = wheels_for_conserved_momentum(t, q, w, I_TRUE, [20.0, -15.0, 30.0],
                                         CASSINI_WHEEL_AXES, [0.161, 0.160, 0.161])
    basis = np.asarray(impulse_lhs_basis(t, w, h))
    for inertia in (I_TRUE, 1.1 * I_TRUE + np.diag([50.0, -20.0, 10.0])):
        got = basis[0] + np.tensordot(np.asarray(inertia_vector(inertia)), basis[1:], 1)
        scale = np.max(np.abs(np.asarray(_lhs(t, w, np.zeros((3, 3)), h))))
        np.testing.assert_allclose(got, np.asarray(_lhs(t, w, inertia, h)), rtol=0,
                                   atol=1e-12 * scale)


def test_on_time_impulse_counts_from_first_row():
    on = np.array([[1.0] * 8, [1.5] * 8, [2.0] * 8])
    j = np.asarray(impulse_from_on_times(on, 0.75))
    np.testing.assert_allclose(j[:, 0], [0.0, 0.375, 0.75])
    f = np.arange(1, 9) * 0.1
    np.testing.assert_allclose(np.asarray(impulse_from_on_times(on, f))[2], f)


def test_pulse_log_impulse_matches_closed_form_after_the_pulses():
    t = np.linspace(0.0, 10.0, 101)
    t_on = np.array([1.0, 2.0, 2.0, 5.0])
    thr = np.array([0, 5, 7, 0])
    width = np.array([0.125, 0.25, 0.25, 0.5])
    taus = (0.005, 0.020, 0.065)
    j = np.asarray(_pulses(t, t_on, thr, width, *taus))
    expect = np.zeros(8)
    for k, wdt in zip(thr, width):
        expect[k] += float(pulse_impulse(wdt, *taus))
    np.testing.assert_allclose(j[-1], expect, rtol=1e-12)
    np.testing.assert_array_equal(j[0], 0.0)
    assert np.all(np.diff(j, axis=0) >= 0)  # impulse only accumulates


def test_pulse_impulse_is_vmappable_and_differentiable_in_tau():
    t = jnp.linspace(0.0, 20.0, 51)
    t_on, thr, width = jnp.array([1.0, 3.0]), jnp.array([4, 4]), jnp.array([0.125, 0.125])

    def total(tf):
        return impulse_from_pulses(t, t_on, thr, width, 0.005, 0.02, tf)[-1, 4]

    tfs = jnp.array([0.04, 0.065, 0.09])
    batch = jax.vmap(total)(tfs)
    np.testing.assert_allclose(batch, [2 * float(pulse_impulse(0.125, 0.005, 0.02, x))
                                       for x in tfs], rtol=1e-12)
    g = float(jax.grad(total)(0.065))
    assert np.isclose(g, (float(total(0.065 + 1e-6)) - float(total(0.065 - 1e-6))) / 2e-6,
                      rtol=1e-6)


@pytest.fixture(scope="module")
def paired_firing():
    rng = np.random.default_rng(3)
    n = 50
    fires = rng.random((n, 8)) < 0.3
    fires[:, 6], fires[:, 7] = fires[:, 4], fires[:, 5]
    j = np.cumsum(fires * 0.125, 0)
    j -= j[:1]
    q = np.asarray(moment_matrix(LX, LY, LZY, LZZ))
    return j, q


def test_stacked_systems_reproduce_the_balance(paired_firing):
    j, q = paired_firing
    f = np.array([0.7, 0.71, 0.72, 0.73, 0.74, 0.75, 0.74, 0.75])
    v = np.asarray(angular_impulse(q, j * f))  # noise-free V = Q J
    u, y = system_xy(v, j, q)                   # Eq 19
    assert u.shape == (2 * len(j), 4)
    np.testing.assert_allclose(np.asarray(u) @ f[:4], y, atol=1e-13)
    u, y = system_z(v, j, q)                    # Eq 20
    np.testing.assert_allclose(np.asarray(u) @ f[4:], y, atol=1e-13)
    assert np.linalg.matrix_rank(np.asarray(u)) == 2  # Y thrusters fired in pairs
    u, y = system_zz(v, j, q)                   # Eq 21
    np.testing.assert_allclose(np.asarray(u) @ f[[4, 5]], y, atol=1e-13)
    f1 = np.full(8, 0.75)
    v1 = np.asarray(angular_impulse(q, j * f1))
    u, y = system_zzz(v1, j, q)                 # Eq 22
    np.testing.assert_allclose(np.asarray(u)[:, 0] * 0.75, y, atol=1e-13)
    u, y = system_xyz(v1, j, q)                 # Eq 23
    assert u.shape == (3 * len(j), 1)
    np.testing.assert_allclose(np.asarray(u)[:, 0] * 0.75, y, atol=1e-13)
