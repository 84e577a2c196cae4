"""Impulse model of Feldman & Lee (2006) Eqs 14-23 (pure JAX): thruster geometry.

Thrusters are ordered ``Z1 Z2 Z3 Z4 Y1 Y2 Y3 Y4`` (A-branch, DESIGN.md §3). Their locations are
those listed with Eq 16: ``Z1..Z4`` at ``[±Lx, ±Ly, Lzz]`` and ``Y1..Y4`` at ``[±Lx, ±Ly, Lzy]``.
The Z-facing thrusters push along −Z, ``Y1, Y2`` along −Y and ``Y3, Y4`` along +Y: these are the
directions for which ``r × F`` reproduces every entry of the moment matrix of Eq 16 (so that, as
the paper says, Y2 with Y4 turns the spacecraft about +Z).
"""

from __future__ import annotations

import jax.numpy as jnp
from jax import Array

__all__ = [
    "THRUSTER_NAMES",
    "thruster_positions",
    "thruster_directions",
    "moment_matrix",
]

THRUSTER_NAMES = ("Z1", "Z2", "Z3", "Z4", "Y1", "Y2", "Y3", "Y4")

_SIGNS_XY = jnp.array([[1, 1], [-1, 1], [-1, -1], [1, -1]] * 2, dtype=float)
_DIRECTIONS = jnp.array(
    [[0, 0, -1]] * 4 + [[0, -1, 0], [0, -1, 0], [0, 1, 0], [0, 1, 0]], dtype=float
)


def thruster_positions(lx_m, ly_m, lzy_m, lzz_m) -> Array:
    """Thruster locations (8, 3) in metres, as listed with Feldman & Lee Eq 16."""
    z = jnp.concatenate([jnp.full((4,), lzz_m), jnp.full((4,), lzy_m)])
    return jnp.stack([_SIGNS_XY[:, 0] * lx_m, _SIGNS_XY[:, 1] * ly_m, z], -1)


def thruster_directions() -> Array:
    """Unit thrust directions (8, 3) in body axes (see the module docstring)."""
    return _DIRECTIONS


def moment_matrix(lx_m, ly_m, lzy_m, lzz_m, com_m=(0.0, 0.0, 0.0)) -> Array:
    """Moment matrix ``Q`` (3, 8), N m per newton of thrust, Feldman & Lee Eq 16.

    Column ``s`` is ``(r_s − e) × d_s`` with ``e = [eX, eY, eZ]`` the centre of mass (m).
    """
    r = thruster_positions(lx_m, ly_m, lzy_m, lzz_m) - jnp.asarray(com_m)
    # Feldman & Lee Eq 16: Q = [(r_s - e) x d_s]_s
    return jnp.cross(r, _DIRECTIONS).T
