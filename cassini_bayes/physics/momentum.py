"""Momentum model of Feldman & Lee (2006) Eqs 2-11 (pure JAX).

During a reaction-wheel slew the total angular momentum in inertial axes,

    H_N(t) = A(q(t))ᵀ [I ω(t) + Σ_k J_k ρ_k(t) g_k]          (Feldman & Lee Eq 3),

is conserved (up to the small external torque of their Appendix A). ``A(q)`` is
:func:`cassini_bayes.frames.dcm` (their ``P``), ``ω`` the body rate (rad/s), ``ρ_k`` the spin rate
(rad/s) of wheel ``k`` about its unit axis ``g_k`` (body axes) and ``J_k`` its spin inertia (kg m²).

Parameter vector convention (docs/design.md §3): ``π = (Ixx, Iyy, Izz, Ixy, Ixz, Iyz)`` (kg m²) with
``I[0,1] = Ixy`` the matrix entry. The paper's Eq 10 orders the unknowns ``(Ixx, Ixy, Ixz, Iyy,
Iyz, Izz)``; the regressor here is the same matrix with its columns permuted to our order.
"""

from __future__ import annotations

import jax.numpy as jnp
from jax import Array

from cassini_bayes.frames import dcm
from cassini_bayes.names import INERTIA_NAMES

__all__ = [
    "INERTIA_NAMES",
    "inertia_matrix",
    "inertia_vector",
    "wheel_momentum_body",
    "inertial_momentum",
    "q_vector",
    "regressor",
    "stacked_system",
    "free_momentum_system",
]



def inertia_matrix(pi: Array) -> Array:
    """Symmetric 3×3 inertia (kg m²) from ``π = (Ixx, Iyy, Izz, Ixy, Ixz, Iyz)``."""
    pi = jnp.asarray(pi)
    xx, yy, zz, xy, xz, yz = (pi[..., i] for i in range(6))
    return jnp.stack(
        [jnp.stack([xx, xy, xz], -1), jnp.stack([xy, yy, yz], -1), jnp.stack([xz, yz, zz], -1)],
        -2,
    )


def inertia_vector(inertia: Array) -> Array:
    """``π = (Ixx, Iyy, Izz, Ixy, Ixz, Iyz)`` from a 3×3 inertia matrix (kg m²)."""
    m = jnp.asarray(inertia)
    return jnp.stack(
        [m[..., 0, 0], m[..., 1, 1], m[..., 2, 2], m[..., 0, 1], m[..., 0, 2], m[..., 1, 2]], -1
    )


def wheel_momentum_body(rates_rad_s: Array, axes: Array, inertias_kgm2: Array) -> Array:
    """Wheel momentum in body axes (N m s), Feldman & Lee Eq 2: ``H_RWA = T I_RWA ρ``.

    ``rates_rad_s`` (..., k) spin rates about each wheel's own axis, relative to the body;
    ``axes`` (k, 3) unit spin axes in body axes (the columns of ``T``); ``inertias_kgm2`` (k,).
    NaN rates (a wheel that is off) count as zero.
    """
    rates = jnp.nan_to_num(jnp.asarray(rates_rad_s))
    j = jnp.broadcast_to(jnp.asarray(inertias_kgm2, dtype=rates.dtype), rates.shape)
    return (rates * j) @ jnp.asarray(axes)


def inertial_momentum(q: Array, omega_rad_s: Array, inertia: Array, h_wheels_body: Array) -> Array:
    """Total momentum in inertial axes (N m s), Feldman & Lee Eq 3: ``Aᵀ (I ω + H_RWA)``."""
    h_body = jnp.einsum("ij,...j->...i", jnp.asarray(inertia), omega_rad_s) + h_wheels_body
    return jnp.einsum("...ji,...j->...i", dcm(q), h_body)


def q_vector(q: Array, h_wheels_body: Array, ref: int = 0) -> Array:
    """``Q(t) = P(t) P(t_ref)⁻¹ H_RWA(t_ref) − H_RWA(t)`` (N m s), Feldman & Lee Eq 6.

    Anchors the conserved momentum on sample ``ref``, assumed quiescent (``ω(t_ref) ≈ 0``, Eq 4).
    ``I ω(t) = Q(t)`` then holds at every sample (Eq 9).
    """
    a = dcm(q)
    h_n0 = a[ref].T @ h_wheels_body[ref]
    return jnp.einsum("...ij,j->...i", a, h_n0) - h_wheels_body


def regressor(omega_rad_s: Array) -> Array:
    """Per-sample 3×6 regressor ``S(ω)`` with ``I ω = S(ω) π`` (Feldman & Lee Eq 10), (..., 3, 6).

    Columns in the order ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)``.
    """
    w = jnp.asarray(omega_rad_s)
    wx, wy, wz = w[..., 0], w[..., 1], w[..., 2]
    o = jnp.zeros_like(wx)
    row_x = jnp.stack([wx, o, o, wy, wz, o], -1)
    row_y = jnp.stack([o, wy, o, wx, o, wz], -1)
    row_z = jnp.stack([o, o, wz, o, wx, wy], -1)
    return jnp.stack([row_x, row_y, row_z], -2)


def stacked_system(q: Array, omega_rad_s: Array, h_wheels_body: Array, ref: int = 0):
    """The stacked least-squares system ``S π = Γ`` of Feldman & Lee Eq 11.

    Returns ``S`` (3N, 6) and ``Γ`` (3N,), the per-sample blocks of :func:`regressor` and
    :func:`q_vector` stacked in time order.
    """
    s = regressor(omega_rad_s)
    gamma = q_vector(q, h_wheels_body, ref)
    return s.reshape(-1, 6), gamma.reshape(-1)


def free_momentum_system(q: Array, omega_rad_s: Array, h_wheels_body: Array, t_s: Array,
                         torque: bool = False):
    """Linear system for the variant with the inertial momentum (and torque) unknown.

    Model: ``A(q_t)ᵀ (I ω_t + H_RWA,t) = H_0 + T_N (t − t_0)`` with unknowns ``θ = (π, H_0)`` or
    ``θ = (π, H_0, T_N)`` (T_N a constant inertial external torque, N m; Feldman & Lee App. A).
    Rearranged per sample: ``[Aᵀ S(ω), −1, −(t − t0) 1] θ = −Aᵀ H_RWA``. Unlike Eq 6 it needs no
    quiescent anchor sample, so noise in the first sample does not bias every row.

    Returns ``M`` (3N, 9 or 12) and ``y`` (3N,).
    """
    a_t = jnp.swapaxes(dcm(q), -1, -2)
    s = jnp.einsum("nij,njk->nik", a_t, regressor(omega_rad_s))
    n = s.shape[0]
    eye = jnp.broadcast_to(-jnp.eye(3, dtype=s.dtype), (n, 3, 3))
    blocks = [s, eye]
    if torque:
        dt = (jnp.asarray(t_s) - jnp.asarray(t_s)[0])[:, None, None]
        blocks.append(eye * dt)
    m = jnp.concatenate(blocks, -1)
    y = -jnp.einsum("nji,nj->ni", dcm(q), h_wheels_body)
    return m.reshape(3 * n, -1), y.reshape(-1)
