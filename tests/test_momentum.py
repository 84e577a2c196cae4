"""Tier (a): the momentum model of Feldman & Lee Eqs 2-11 on exactly conserved telemetry."""

from __future__ import annotations

import numpy as np
import pytest

from cassini_bayes.physics.momentum import (free_momentum_system, inertia_matrix, inertia_vector,
                                            inertial_momentum, q_vector, regressor,
                                            stacked_system, wheel_momentum_body)
from cassini_bayes.spacecraft import CASSINI_WHEEL_AXES
from kinematics import rotvec_to_quat_np, slew_segments, wheels_for_conserved_momentum

I_TRUE = np.array([[8655.2, -144.0, 132.1], [-144.0, 7922.7, 192.1], [132.1, 192.1, 4586.2]])
J_W = np.array([0.161, 0.160, 0.161])
H_N = np.array([4.0, -1.0, 2.5])


@pytest.fixture(scope="module")
def slew():
    q0 = rotvec_to_quat_np(np.array([-0.4, 0.1, 0.9]))
    t, q, w = slew_segments(q0, [((1, 0, 0), 0.5, 400.0), ((0, 1, 1), -0.7, 500.0)], 5.0, 60.0)
    rates, h = wheels_for_conserved_momentum(t, q, w, I_TRUE, H_N, CASSINI_WHEEL_AXES, J_W)
    return t, q, w, rates, h


def test_inertia_vector_round_trip_and_order():
    pi = inertia_vector(I_TRUE)
    np.testing.assert_array_equal(pi, [8655.2, 7922.7, 4586.2, -144.0, 132.1, 192.1])
    np.testing.assert_array_equal(inertia_matrix(pi), I_TRUE)


def test_regressor_reproduces_i_omega():
    w = np.array([[1e-3, -2e-3, 5e-4], [0.0, 1e-3, 0.0]])
    np.testing.assert_allclose(np.asarray(regressor(w)) @ inertia_vector(I_TRUE), w @ I_TRUE.T,
                               rtol=1e-14)


def test_wheel_momentum_matches_t_matrix_and_ignores_off_wheels(slew):
    t, q, w, rates, h = slew
    np.testing.assert_allclose(wheel_momentum_body(rates, CASSINI_WHEEL_AXES, J_W), h,
                               rtol=1e-12, atol=1e-12)
    r = np.array([[10.0, np.nan, 5.0]])
    np.testing.assert_allclose(wheel_momentum_body(r, CASSINI_WHEEL_AXES, J_W),
                               [(10.0 * 0.161) * CASSINI_WHEEL_AXES[0]
                                + (5.0 * 0.161) * CASSINI_WHEEL_AXES[2]])


def test_inertial_momentum_is_conserved(slew):
    t, q, w, rates, h = slew
    hn = np.asarray(inertial_momentum(q, w, I_TRUE, h))  # Eq 3
    np.testing.assert_allclose(hn, np.broadcast_to(H_N, hn.shape), rtol=0, atol=1e-12)


def test_eq9_i_omega_equals_q_vector(slew):
    t, q, w, rates, h = slew
    # sample 0 is quiescent, so Eq 6 anchored there gives I w = Q (Eq 9) at every sample
    np.testing.assert_allclose(np.asarray(q_vector(q, h, 0)), w @ I_TRUE.T, atol=1e-11)
    s, gamma = stacked_system(q, w, h)  # Eq 11
    np.testing.assert_allclose(np.asarray(s) @ inertia_vector(I_TRUE), gamma, atol=1e-11)


def test_free_momentum_system_holds_at_truth(slew):
    t, q, w, rates, h = slew
    m, y = free_momentum_system(q, w, h, t, torque=True)
    theta = np.concatenate([inertia_vector(I_TRUE), H_N, np.zeros(3)])
    np.testing.assert_allclose(np.asarray(m) @ theta, y, atol=1e-11)
