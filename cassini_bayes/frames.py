"""Attitude conventions: quaternions, direction-cosine matrices and sphere helpers (pure JAX).

The convention is the one of Brown (2012) Eq 2 and docs/design.md §3:

* a quaternion ``q = (q1, q2, q3, q4)`` has its vector part first and its scalar ``q4`` last;
* it rotates inertial (J2000) components into body components: ``v_B = A(q) v_N``;
* ``A(q) = (q4² − |q_v|²) 1 + 2 q_v q_vᵀ − 2 q4 [q_v×]``, the matrix inside Brown Eq 2, whose
  inverse (transpose) is Brown's ``ᴵC_B``; Feldman & Lee's ``P(t)`` is ``A(q(t))``.

``q`` and ``−q`` are the same attitude: ``A(q) = A(−q)``. Products are defined so that
``dcm(quat_multiply(a, b)) == dcm(a) @ dcm(b)`` (Shuster's order), hence the kinematics
``q(t + dt) = quat_multiply(rotvec_to_quat(ω dt), q(t))`` for a body rate ``ω`` (rad/s).

All functions accept leading batch dimensions and are jit/vmap/grad friendly.
"""

from __future__ import annotations

import jax.numpy as jnp
from jax import Array

__all__ = [
    "skew",
    "dcm",
    "dcm_body_to_inertial",
    "quat_conjugate",
    "quat_multiply",
    "quat_normalize",
    "quat_canonical",
    "quat_continuous",
    "quat_from_dcm",
    "rotvec_to_quat",
    "quat_to_rotvec",
    "small_rotation_quat",
    "quat_error_angle",
    "angle_between",
    "unit",
    "cone_angle_from_z",
]


def skew(v: Array) -> Array:
    """Cross-product matrix ``[v×]`` such that ``[v×] w = v × w``; shape ``(..., 3, 3)``."""
    v = jnp.asarray(v)
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    o = jnp.zeros_like(x)
    return jnp.stack(
        [jnp.stack([o, -z, y], -1), jnp.stack([z, o, -x], -1), jnp.stack([-y, x, o], -1)], -2
    )


def dcm(q: Array) -> Array:
    """Direction-cosine matrix ``A(q)``, inertial → body (Brown Eq 2, the matrix inside the
    inverse).

    ``q`` need not be normalised: it is normalised first, so ``dcm`` is always a rotation.
    """
    q = quat_normalize(q)
    qv, q4 = q[..., :3], q[..., 3]
    eye = jnp.broadcast_to(jnp.eye(3, dtype=q.dtype), q.shape[:-1] + (3, 3))
    return (
        (q4**2 - jnp.sum(qv * qv, -1))[..., None, None] * eye
        + 2.0 * qv[..., :, None] * qv[..., None, :]
        - 2.0 * q4[..., None, None] * skew(qv)
    )


def dcm_body_to_inertial(q: Array) -> Array:
    """Brown's ``ᴵC_B = A(q)⁻¹ = A(q)ᵀ`` (body → inertial), Feldman & Lee's ``P⁻¹``."""
    return jnp.swapaxes(dcm(q), -1, -2)


def quat_conjugate(q: Array) -> Array:
    """Inverse rotation: ``dcm(quat_conjugate(q)) == dcm(q).T``."""
    q = jnp.asarray(q)
    return jnp.concatenate([-q[..., :3], q[..., 3:]], -1)


def quat_multiply(a: Array, b: Array) -> Array:
    """Quaternion product with ``dcm(quat_multiply(a, b)) == dcm(a) @ dcm(b)`` (scalar last)."""
    a = jnp.asarray(a)
    b = jnp.asarray(b)
    av, a4 = a[..., :3], a[..., 3:]
    bv, b4 = b[..., :3], b[..., 3:]
    vec = a4 * bv + b4 * av - jnp.cross(av, bv)
    sca = a4 * b4 - jnp.sum(av * bv, -1, keepdims=True)
    return jnp.concatenate([vec, sca], -1)


def quat_normalize(q: Array) -> Array:
    """``q / |q|``."""
    q = jnp.asarray(q)
    return q / jnp.linalg.norm(q, axis=-1, keepdims=True)


def quat_canonical(q: Array) -> Array:
    """The representative of ``±q`` with ``q4 ≥ 0`` (sign-flip handling)."""
    q = jnp.asarray(q)
    return jnp.where(q[..., 3:] < 0, -q, q)


def quat_continuous(q: Array) -> Array:
    """Flip signs along a time series ``(n, 4)`` so that consecutive quaternions agree in sign.

    Telemetry may switch between ``q`` and ``−q`` (the same attitude); this removes the jumps so
    differences and averages of ``q`` are meaningful. ``A(q)`` is unchanged.
    """
    q = jnp.asarray(q)
    dots = jnp.sum(q[1:] * q[:-1], -1)
    flips = jnp.concatenate([jnp.zeros((1,), bool), dots < 0])
    sign = jnp.where(jnp.cumsum(flips) % 2 == 1, -1.0, 1.0).astype(q.dtype)
    return q * sign[:, None]


def quat_from_dcm(a: Array) -> Array:
    """Quaternion (scalar last, ``q4 ≥ 0``) of a rotation matrix, by Shepperd's method."""
    a = jnp.asarray(a)
    tr = jnp.trace(a, axis1=-2, axis2=-1)
    d0, d1, d2 = a[..., 0, 0], a[..., 1, 1], a[..., 2, 2]
    # For A = A(q): A[1,2]-A[2,1] = 4 q1 q4, A[2,0]-A[0,2] = 4 q2 q4, A[0,1]-A[1,0] = 4 q3 q4.
    c4 = jnp.stack(
        [a[..., 1, 2] - a[..., 2, 1], a[..., 2, 0] - a[..., 0, 2], a[..., 0, 1] - a[..., 1, 0],
         1.0 + tr], -1)
    c1 = jnp.stack(
        [1.0 + 2 * d0 - tr, a[..., 0, 1] + a[..., 1, 0], a[..., 0, 2] + a[..., 2, 0],
         a[..., 1, 2] - a[..., 2, 1]], -1)
    c2 = jnp.stack(
        [a[..., 0, 1] + a[..., 1, 0], 1.0 + 2 * d1 - tr, a[..., 1, 2] + a[..., 2, 1],
         a[..., 2, 0] - a[..., 0, 2]], -1)
    c3 = jnp.stack(
        [a[..., 0, 2] + a[..., 2, 0], a[..., 1, 2] + a[..., 2, 1], 1.0 + 2 * d2 - tr,
         a[..., 0, 1] - a[..., 1, 0]], -1)
    cands = jnp.stack([c1, c2, c3, c4], -2)
    pick = jnp.argmax(jnp.stack([d0, d1, d2, tr], -1), -1)
    q = jnp.take_along_axis(cands, pick[..., None, None], axis=-2)[..., 0, :]
    return quat_canonical(quat_normalize(q))


def rotvec_to_quat(theta: Array) -> Array:
    """Quaternion of the rotation that turns the *frame* by rotation vector ``theta`` (rad).

    ``dcm(rotvec_to_quat(θ)) ≈ 1 − [θ×]`` for small ``θ``; exact for any angle. A body turning at
    ``ω`` for ``dt`` has ``q(t + dt) = quat_multiply(rotvec_to_quat(ω dt), q(t))``.
    """
    theta = jnp.asarray(theta)
    ang2 = jnp.sum(theta * theta, -1, keepdims=True)
    ang = jnp.sqrt(ang2 + 1e-300)
    half = 0.5 * ang
    # sin(x/2)/x with a Taylor branch near 0 so gradients stay finite.
    small = ang2 < 1e-12
    sinc = jnp.where(small, 0.5 - ang2 / 48.0, jnp.sin(half) / jnp.where(small, 1.0, ang))
    return jnp.concatenate([theta * sinc, jnp.cos(half)], -1)


def quat_to_rotvec(q: Array) -> Array:
    """Rotation vector (rad) of ``q`` (the shorter of ``±q``); inverse of :func:`rotvec_to_quat`."""
    q = quat_canonical(quat_normalize(q))
    qv, q4 = q[..., :3], q[..., 3:]
    s = jnp.linalg.norm(qv, axis=-1, keepdims=True)
    ang = 2.0 * jnp.arctan2(s, q4)
    small = s < 1e-12
    scale = jnp.where(small, 2.0 / jnp.where(small, q4, 1.0), ang / jnp.where(small, 1.0, s))
    return qv * scale


def small_rotation_quat(theta: Array) -> Array:
    """First-order quaternion ``(θ/2, 1)`` normalised: a small rotation error of ``theta`` rad."""
    theta = jnp.asarray(theta)
    return quat_normalize(jnp.concatenate([0.5 * theta, jnp.ones_like(theta[..., :1])], -1))


def quat_error_angle(a: Array, b: Array) -> Array:
    """Angle (rad) of the rotation taking attitude ``b`` to ``a``; 0 for ``a = ±b``."""
    a = quat_normalize(a)
    b = quat_normalize(b)
    d = jnp.abs(jnp.sum(a * b, -1))
    return 2.0 * jnp.arccos(jnp.clip(d, 0.0, 1.0))


def unit(v: Array) -> Array:
    """``v / |v|`` along the last axis."""
    v = jnp.asarray(v)
    return v / jnp.linalg.norm(v, axis=-1, keepdims=True)


def angle_between(a: Array, b: Array) -> Array:
    """Angle (rad) between vectors ``a`` and ``b``, accurate for tiny and near-π angles."""
    a = jnp.asarray(a)
    b = jnp.asarray(b)
    return jnp.arctan2(jnp.linalg.norm(jnp.cross(a, b), axis=-1), jnp.sum(a * b, -1))


def cone_angle_from_z(v: Array) -> Array:
    """Angle (rad) between ``v`` and body +Z (54.7356° for every Cassini wheel axis)."""
    v = jnp.asarray(v)
    return angle_between(v, jnp.broadcast_to(jnp.array([0.0, 0.0, 1.0], v.dtype), v.shape))
