"""Spacecraft hardware geometry: wheel axes and their tilts, thrusters, moment matrices.

Cassini's wheel axes (Feldman & Lee App. A) and its ``[thrusters]`` shorthand (the lever arms of
Feldman & Lee Eq 16, expanded to its eight thrusters). Lengths in m, axes unit vectors in body
axes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from cassini_bayes.names import THRUSTER_NAMES

# Feldman & Lee (2006) App. A: RWA → body matrix T; its columns are the spin axes of RWA1-3.
_S2, _S3, _S6 = np.sqrt(2.0), np.sqrt(3.0), np.sqrt(6.0)
CASSINI_T = np.array(
    [[0.0, -1.0 / _S2, 1.0 / _S2], [_S2 / _S3, -1.0 / _S6, -1.0 / _S6], [1 / _S3, 1 / _S3, 1 / _S3]]
)
CASSINI_WHEEL_AXES = CASSINI_T.T.copy()  # rows: RWA1, RWA2, RWA3 spin axes (body)

# Feldman & Lee (2006) Eq 16: Z1..Z4 at [±Lx, ±Ly, Lzz], Y1..Y4 at [±Lx, ±Ly, Lzy]; the Z-facing
# thrusters push along −Z, Y1, Y2 along −Y and Y3, Y4 along +Y (the directions for which r × F
# reproduces every entry of Eq 16's moment matrix, so that Y2 with Y4 turns about +Z).
_EQ16_SIGNS_XY = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]] * 2, dtype=float)
_EQ16_DIRECTIONS = np.array([[0, 0, -1]] * 4 + [[0, -1, 0], [0, -1, 0], [0, 1, 0], [0, 1, 0]],
                            dtype=float)


def wheel_tilt_basis(axis) -> np.ndarray:
    """(2, 3) orthonormal pair ``u_1, u_2`` perpendicular to the unit spin ``axis``.

    The two small-angle tilt directions of a wheel axis (a rotation about the axis itself changes
    nothing): ``u_1 = axis × e / |axis × e|`` with ``e`` the body axis least aligned with ``axis``,
    ``u_2 = axis × u_1``. Shared by the simulator (true axes) and the robust models (nuisance).
    """
    g = np.asarray(axis, float) / np.linalg.norm(axis)
    e = np.zeros(3)
    e[np.argmin(np.abs(g))] = 1.0
    u1 = np.cross(g, e)
    u1 /= np.linalg.norm(u1)
    return np.stack([u1, np.cross(g, u1)])


def tilted_axis(axis, tilt_rad) -> np.ndarray:
    """The unit ``axis`` tilted by ``tilt_rad = (a_1, a_2)`` rad along :func:`wheel_tilt_basis`."""
    g = np.asarray(axis, float) + np.asarray(tilt_rad, float) @ wheel_tilt_basis(axis)
    return g / np.linalg.norm(g)


@dataclass(frozen=True)
class WheelCone:
    """The cone a wheel's spin axis lies on at any articulation angle: ``angle_deg`` from the
    unit ``axis`` (body axes), known to ``sd_deg`` (1 sd, the mechanical cant tolerance).
    Cassini's RWA4: 54.7356° from +Z (Brown §I)."""

    axis: np.ndarray
    angle_deg: float
    sd_deg: float = 1.0


QUIET_WHEEL_TOL_RPM = 2.0
"""A ``[[wheel]]`` entry's default ``quiet_tol_rpm``, rpm: the largest change of the wheel's rate
within a quiet window (``cassini_bayes.windows.quiet_mask``). A wheel rate: the papers' quiet
windows and the pinned wheel-axis fits rest on it; a spacecraft whose slews change its wheels by
less within 10 s states its own (docs/model_file.md)."""


@dataclass(frozen=True)
class Wheel:
    """A reaction wheel: ``axis`` unit vector in body axes, ``inertia`` kg m² about it.

    ``inertia_sd_frac``: this wheel's spin-inertia knowledge (one sd, a fraction), overriding
    ``[wheel_knowledge] inertia_sd_frac`` for it; ``None`` when the file does not give one.
    ``max_speed_rpm``, ``max_torque_nm``: the simulator's limits on its rate and motor torque
    (``inf`` when the file gives none). ``articulated``: its axis can be moved in flight (Cassini's
    RWA4, Brown §I), so the input checks take the model's axis as unknown. ``cone``: the
    articulation cone its axis lies on (the wheel-axis fit's ``cone`` prior and its adequacy
    check; ``None``: none known). ``reference``, ``reference_tol_deg``: the wheel whose axis
    this one must match and how closely (Cassini's RWA4 replacing RWA1 within ±2°, Brown §I),
    reported by the wheel-axis fit; ``None`` when the file gives none. ``quiet_tol_rpm``: the
    largest change of its rate within a quiet window, rpm (:data:`QUIET_WHEEL_TOL_RPM` unless
    the file gives one).
    """

    name: str
    axis: np.ndarray
    inertia: float
    inertia_sd_frac: float | None = None
    max_speed_rpm: float = float("inf")
    max_torque_nm: float = float("inf")
    articulated: bool = False
    cone: WheelCone | None = None
    reference: str | None = None
    reference_tol_deg: float | None = None
    quiet_tol_rpm: float = QUIET_WHEEL_TOL_RPM


@dataclass(frozen=True)
class Thruster:
    """A thruster: ``position`` (3,) m in body axes from the predicted centre of mass,
    ``direction`` (3,) the unit vector of its force on the spacecraft; ``thrust_n`` its nominal
    steady thrust (N; ``None``: the model's ``[thrust] F``) and ``branch`` its redundancy branch
    (``""`` when none is named)."""

    name: str
    position: np.ndarray
    direction: np.ndarray
    thrust_n: float | None = None
    branch: str = ""


def eq16_thrusters(lx_m: float, ly_m: float, lzy_m: float, lzz_m: float) -> tuple[Thruster, ...]:
    """Cassini's eight thrusters ``Z1 … Y4`` from the lever arms of Feldman & Lee Eq 16 (m):
    ``Z1..Z4`` at ``[±Lx, ±Ly, Lzz]`` pushing along −Z, ``Y1..Y4`` at ``[±Lx, ±Ly, Lzy]``
    pushing along −Y (``Y1, Y2``) and +Y (``Y3, Y4``); branch A."""
    z = np.array([lzz_m] * 4 + [lzy_m] * 4, float)
    pos = np.stack([_EQ16_SIGNS_XY[:, 0] * lx_m, _EQ16_SIGNS_XY[:, 1] * ly_m, z], -1)
    return tuple(Thruster(n, pos[k], _EQ16_DIRECTIONS[k].copy(), None, "A")
                 for k, n in enumerate(THRUSTER_NAMES))


def moment_matrix(thrusters: Sequence[Thruster], com_m=(0.0, 0.0, 0.0)) -> np.ndarray:
    """(3, m) torque per newton of each thruster, N m / N: column ``s`` is ``(r_s − e) × d_s``
    with ``e`` the centre of mass (m) in the frame of the positions (Feldman & Lee Eq 16)."""
    if not thrusters:
        return np.zeros((3, 0))
    pos = np.stack([s.position for s in thrusters])
    dirs = np.stack([s.direction for s in thrusters])
    # Feldman & Lee Eq 16: Q = [(r_s - e) x d_s]_s
    return np.cross(pos - np.asarray(com_m, float)[None, :], dirs).T


def eq16_moment_matrix(lx_m: float, ly_m: float, lzy_m: float, lzz_m: float,
                       com_m=(0.0, 0.0, 0.0)) -> np.ndarray:
    """(3, 8) moment matrix of Feldman & Lee Eq 16 from its lever arms and centre of mass (m)."""
    return moment_matrix(eq16_thrusters(lx_m, ly_m, lzy_m, lzz_m), com_m)


