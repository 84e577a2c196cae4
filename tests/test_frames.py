"""Tier (a): attitude conventions (Brown Eq 2) — properties checked with hypothesis."""

from __future__ import annotations

import jax
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from cassini_bayes.frames import (angle_between, dcm, dcm_body_to_inertial, quat_canonical,
                                  quat_conjugate, quat_continuous, quat_error_angle,
                                  quat_from_dcm, quat_multiply, quat_to_rotvec, rotvec_to_quat,
                                  skew)

# jitted once: hypothesis calls these with many values of the same shape
_dcm = jax.jit(dcm)
_from_dcm = jax.jit(quat_from_dcm)
_mul = jax.jit(quat_multiply)
_to_rv = jax.jit(quat_to_rotvec)
_from_rv = jax.jit(rotvec_to_quat)

finite = st.floats(-1.0, 1.0, allow_nan=False, allow_infinity=False)
quats = st.tuples(finite, finite, finite, finite).filter(
    lambda v: np.linalg.norm(v) > 0.1).map(lambda v: np.array(v) / np.linalg.norm(v))
rotvecs = st.tuples(finite, finite, finite).map(lambda v: np.array(v) * 3.0).filter(
    lambda v: np.linalg.norm(v) < np.pi - 1e-3)
SETTINGS = settings(max_examples=60, deadline=None)


def test_dcm_is_brown_eq2():
    q = np.array([0.1, -0.3, 0.5, 0.8])
    q = q / np.linalg.norm(q)
    q1, q2, q3, q4 = q
    # Brown (2012) Eq 2: the matrix inside the inverse (inertial -> body)
    printed = np.array([
        [q1**2 - q2**2 - q3**2 + q4**2, 2 * (q1 * q2 + q3 * q4), 2 * (q1 * q3 - q2 * q4)],
        [2 * (q1 * q2 - q3 * q4), -q1**2 + q2**2 - q3**2 + q4**2, 2 * (q2 * q3 + q1 * q4)],
        [2 * (q1 * q3 + q2 * q4), 2 * (q2 * q3 - q1 * q4), -q1**2 - q2**2 + q3**2 + q4**2]])
    np.testing.assert_allclose(dcm(q), printed, atol=1e-15)
    np.testing.assert_allclose(dcm_body_to_inertial(q), printed.T, atol=1e-15)


@SETTINGS
@given(quats)
def test_dcm_is_a_rotation_and_sign_invariant(q):
    a = np.asarray(_dcm(q))
    np.testing.assert_allclose(a @ a.T, np.eye(3), atol=1e-13)
    assert np.isclose(np.linalg.det(a), 1.0, atol=1e-13)
    np.testing.assert_allclose(np.asarray(_dcm(-q)), a, atol=1e-15)


@SETTINGS
@given(quats)
def test_dcm_quaternion_round_trip(q):
    back = np.asarray(_from_dcm(_dcm(q)))
    # the same attitude: back = ±q (the sign is free when q4 = 0)
    assert min(np.max(np.abs(back - q)), np.max(np.abs(back + q))) < 1e-12
    assert back[3] >= 0
    if q[3] > 1e-6:
        np.testing.assert_allclose(back, np.asarray(quat_canonical(q)), atol=1e-12)


@SETTINGS
@given(quats, quats)
def test_composition_matches_matrix_product(a, b):
    np.testing.assert_allclose(np.asarray(_dcm(_mul(a, b))),
                               np.asarray(_dcm(a)) @ np.asarray(_dcm(b)), atol=1e-13)


@SETTINGS
@given(quats)
def test_conjugate_is_inverse(q):
    np.testing.assert_allclose(np.asarray(_dcm(quat_conjugate(q))), np.asarray(_dcm(q)).T,
                               atol=1e-13)


@SETTINGS
@given(rotvecs)
def test_rotvec_round_trip(theta):
    np.testing.assert_allclose(np.asarray(_to_rv(_from_rv(theta))), theta, atol=1e-12)


def test_small_rotation_and_kinematics():
    theta = np.array([1e-7, -2e-7, 3e-7])
    np.testing.assert_allclose(np.asarray(dcm(rotvec_to_quat(theta))),
                               np.eye(3) - np.asarray(skew(theta)), atol=1e-13)
    # rotating the frame about +Z by 90 deg: an inertial +X vector reads as body -Y
    q = rotvec_to_quat(np.array([0.0, 0.0, np.pi / 2]))
    np.testing.assert_allclose(np.asarray(dcm(q)) @ [1.0, 0, 0], [0, -1.0, 0], atol=1e-15)


def test_sign_flips_and_angles():
    q = np.asarray(rotvec_to_quat(np.array([[0.1, 0, 0], [0.2, 0, 0], [0.3, 0, 0]])))
    flipped = q * np.array([[1.0], [-1.0], [1.0]])
    np.testing.assert_allclose(np.asarray(quat_continuous(flipped)), q, atol=1e-15)
    assert float(quat_error_angle(q[0], -q[0])) < 1e-7
    assert np.isclose(float(quat_error_angle(q[2], q[0])), 0.2, atol=1e-12)
    assert np.isclose(float(angle_between(np.array([1e-9, 1.0, 0]), np.array([0, 1.0, 0]))), 1e-9)
