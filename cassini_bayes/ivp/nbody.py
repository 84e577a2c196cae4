"""The trajectories the IVP fits, generated: an n-body integration of the Sun, the Earth–Moon
barycentre, Jupiter, Saturn (with its J2), Titan and a spacecraft on a close Titan flyby.

No ephemeris can be downloaded here, so the bodies start from documented osculating elements
(:data:`PLANETS`, :data:`TITAN`, :class:`Flyby`; docs/ivp.md lists them) at the epoch ``t = 0``,
the flyby's closest approach, and move under their mutual point-mass gravity plus the J2 of
Saturn's oblateness on Titan and the spacecraft (the spacecraft's mass is neglected). Integrated
backward and forward from ``t = 0`` by SciPy's DOP853 (8th order) at ``rtol = 1e-12``; the
solution's dense output gives any body's position at any time within the span.

Frame: ICRF / EME2000 equatorial axes, origin the barycentre of the bodies; SI units.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from cassini_bayes.errors import InputError

__all__ = ["AU_M", "BODIES", "GM", "PLANETS", "TITAN", "Flyby", "NBodySolution",
           "elements_to_state", "initial_state", "integrate_flyby"]

AU_M = 1.495978707e11
OBLIQUITY_RAD = np.radians(23.439291)            # J2000 ecliptic to equator
BODIES = ("sun", "earth", "jupiter", "saturn", "titan", "spacecraft")
# G M, m^3/s^2 (JPL): Sun; Earth + Moon; Jupiter system; Saturn without Titan; Titan
GM = {"sun": 1.32712440041e20, "earth": 4.03503235e14, "jupiter": 1.26712764e17,
      "saturn": 3.7931208e16, "titan": 8.9781382e12, "spacecraft": 0.0}
SATURN_J2 = 0.0162907                            # at the reference radius below
SATURN_RADIUS_M = 60330e3
SATURN_POLE_RA_DEC_DEG = (40.589, 83.537)        # IAU, ICRF
TITAN_RADIUS_M = 2574.73e3

# J2000 osculating elements about the Sun, ecliptic J2000 (Standish's approximate elements):
# a (AU), e, i (deg), longitude of the node Ω, argument of perihelion ω, mean anomaly M (deg).
PLANETS = {
    "earth": (1.00000261, 0.01671123, -0.00001531, 0.0, 102.93768193, 357.52688973),
    "jupiter": (5.20288700, 0.04838624, 1.30439695, 100.47390909, 274.25457074, 19.66796068),
    "saturn": (9.53667594, 0.05386179, 2.48599187, 113.66242448, 338.93645383, 317.35536592),
}
# Titan about Saturn, in Saturn's equatorial frame (x: ascending node of Saturn's equator on the
# ICRF equator): a (m), e, i, Ω, ω, M (deg)
TITAN = (1221870e3, 0.0288, 0.3485, 0.0, 180.0, 30.0)


@dataclass(frozen=True)
class Flyby:
    """The spacecraft's closest approach to Titan at ``t = 0``.

    Attributes
    ----------
    altitude_m : height above Titan's surface at closest approach, m.
    v_inf_m_s : speed relative to Titan far from it (hyperbolic excess), m/s.
    out_of_plane_deg : angle of the closest-approach velocity from Titan's own velocity,
        turned towards the normal of Titan's orbit (110°: the spacecraft stays bound to Saturn,
        on a 20-37 Saturn-radius orbit over the months around the flyby).
    """

    altitude_m: float = 1000e3
    v_inf_m_s: float = 5500.0
    out_of_plane_deg: float = 110.0


def _rot(axis: int, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    m = np.eye(3)
    m[i, i] = c
    m[i, j] = -s
    m[j, i] = s
    m[j, j] = c
    return m


def elements_to_state(a: float, e: float, i_deg: float, node_deg: float, peri_deg: float,
                      mean_anomaly_deg: float, mu: float) -> tuple[np.ndarray, np.ndarray]:
    """Position (m) and velocity (m/s) of an elliptic orbit from its classical elements (angles
    in degrees), in the frame the elements refer to. Kepler's equation by Newton's method."""
    m = np.radians(mean_anomaly_deg)
    ecc_anom = m + e * np.sin(m)
    for _ in range(50):
        ecc_anom -= (ecc_anom - e * np.sin(ecc_anom) - m) / (1 - e * np.cos(ecc_anom))
    cos_e, sin_e = np.cos(ecc_anom), np.sin(ecc_anom)
    b = a * np.sqrt(1 - e * e)
    r_pf = np.array([a * (cos_e - e), b * sin_e, 0.0])
    edot = np.sqrt(mu / a ** 3) / (1 - e * cos_e)
    v_pf = np.array([-a * sin_e * edot, b * cos_e * edot, 0.0])
    rot = _rot(2, np.radians(node_deg)) @ _rot(0, np.radians(i_deg)) @ _rot(2, np.radians(peri_deg))
    return rot @ r_pf, rot @ v_pf


def saturn_pole() -> np.ndarray:
    """Unit vector of Saturn's north pole, ICRF."""
    ra, dec = np.radians(SATURN_POLE_RA_DEC_DEG)
    return np.array([np.cos(dec) * np.cos(ra), np.cos(dec) * np.sin(ra), np.sin(dec)])


def initial_state(flyby: Flyby = Flyby()) -> tuple[np.ndarray, np.ndarray]:
    """Barycentric positions (6, 3) m and velocities (6, 3) m/s of :data:`BODIES` at ``t = 0``."""
    ecl_to_eq = _rot(0, OBLIQUITY_RAD)
    helio_r, helio_v = {"sun": np.zeros(3)}, {"sun": np.zeros(3)}
    for name, el in PLANETS.items():
        a, *rest = el
        mu = GM["sun"] + GM[name] + (GM["titan"] if name == "saturn" else 0.0)
        r, v = elements_to_state(a * AU_M, *rest, mu=mu)
        helio_r[name], helio_v[name] = ecl_to_eq @ r, ecl_to_eq @ v
    pole = saturn_pole()
    node = np.cross([0.0, 0.0, 1.0], pole)
    node /= np.linalg.norm(node)
    sat_eq = np.column_stack([node, np.cross(pole, node), pole])   # Saturn equator → ICRF
    r_t, v_t = elements_to_state(*TITAN, mu=GM["saturn"] + GM["titan"])
    r_t, v_t = sat_eq @ r_t, sat_eq @ v_t
    # Saturn and Titan about their barycentre, which follows the Saturn elements above
    f_t = GM["titan"] / (GM["saturn"] + GM["titan"])
    bary_r, bary_v = helio_r.pop("saturn"), helio_v.pop("saturn")
    helio_r["saturn"], helio_v["saturn"] = bary_r - f_t * r_t, bary_v - f_t * v_t
    helio_r["titan"], helio_v["titan"] = bary_r + (1 - f_t) * r_t, bary_v + (1 - f_t) * v_t
    # the flyby: closest approach at t = 0
    h = np.cross(r_t, v_t)
    h /= np.linalg.norm(h)
    along = v_t / np.linalg.norm(v_t)
    gamma = np.radians(flyby.out_of_plane_deg)
    w = np.cos(gamma) * along + np.sin(gamma) * h                 # velocity direction at CA
    u = -r_t / np.linalg.norm(r_t)
    u = u - (u @ w) * w
    u /= np.linalg.norm(u)                                         # CA on Titan's Saturn side
    r_ca = TITAN_RADIUS_M + flyby.altitude_m
    v_ca = np.sqrt(flyby.v_inf_m_s ** 2 + 2 * GM["titan"] / r_ca)
    helio_r["spacecraft"] = helio_r["titan"] + r_ca * u
    helio_v["spacecraft"] = helio_v["titan"] + v_ca * w
    r = np.array([helio_r[b] for b in BODIES])
    v = np.array([helio_v[b] for b in BODIES])
    gm = np.array([GM[b] for b in BODIES])
    r -= (gm[:, None] * r).sum(0) / gm.sum()                       # barycentric
    v -= (gm[:, None] * v).sum(0) / gm.sum()
    return r, v


def _accelerations(r: np.ndarray, gm: np.ndarray, pole: np.ndarray) -> np.ndarray:
    d = r[None, :, :] - r[:, None, :]                  # d[i, j] = r_j − r_i
    dist3 = np.sum(d * d, axis=-1) ** 1.5
    np.fill_diagonal(dist3, np.inf)
    acc = np.einsum("j,ijk,ij->ik", gm, d, 1.0 / dist3)
    # Saturn's J2 on Titan and the spacecraft, and its reaction on Saturn
    s = BODIES.index("saturn")
    for k in (BODIES.index("titan"), BODIES.index("spacecraft")):
        rel = r[k] - r[s]
        rn = np.linalg.norm(rel)
        z = rel @ pole / rn
        a_j2 = -1.5 * SATURN_J2 * gm[s] * SATURN_RADIUS_M ** 2 / rn ** 4 * (
            (1 - 5 * z * z) * rel / rn + 2 * z * pole)
        acc[k] += a_j2
        acc[s] -= gm[k] / gm[s] * a_j2
    return acc


class NBodySolution(NamedTuple):
    """The integrated bodies over ``[t_start_s, t_end_s]`` (dense output of both directions)."""

    backward: object
    forward: object
    t_start_s: float
    t_end_s: float
    flyby: Flyby

    def positions(self, t_s) -> np.ndarray:
        """Barycentric positions (m), shape ``t.shape + (6, 3)``, of :data:`BODIES`."""
        t = np.asarray(t_s, float)
        if np.any(t < self.t_start_s - 1e-6) or np.any(t > self.t_end_s + 1e-6):
            raise InputError(f"times outside the integrated span [{self.t_start_s:g}, "
                             f"{self.t_end_s:g}] s")
        flat = t.reshape(-1)
        out = np.empty((flat.size, 6 * 6))
        back = flat < 0
        if back.any():
            out[back] = self.backward(flat[back]).T
        if (~back).any():
            out[~back] = self.forward(flat[~back]).T
        return out[:, :18].reshape(t.shape + (6, 3))

    def relative(self, base: str, head: str):
        """The vector from ``base`` to ``head`` as a function of time: t (N,) s → (N, 3) m."""
        i, j = BODIES.index(base), BODIES.index(head)
        return lambda t: (lambda p: p[..., j, :] - p[..., i, :])(self.positions(t))

    def state(self, body: str, t_s: float, base: str) -> tuple[np.ndarray, np.ndarray]:
        """Position (m) and velocity (m/s) of ``body`` relative to ``base`` at one time."""
        sol = self.backward if t_s < 0 else self.forward
        y = sol(float(t_s))
        r, v = y[:18].reshape(6, 3), y[18:].reshape(6, 3)
        i, j = BODIES.index(base), BODIES.index(body)
        return r[j] - r[i], v[j] - v[i]


def integrate_flyby(t_start_s: float, t_end_s: float, flyby: Flyby = Flyby(),
                    rtol: float = 1e-12) -> NBodySolution:
    """Integrate the bodies from ``t = 0`` (closest approach) back to ``t_start_s`` ≤ 0 and on to
    ``t_end_s`` ≥ 0 (s)."""
    from scipy.integrate import solve_ivp

    if not (t_start_s <= 0 <= t_end_s) or t_start_s == t_end_s:
        raise InputError(f"the span [{t_start_s:g}, {t_end_s:g}] s must contain the closest "
                         "approach t = 0")
    r0, v0 = initial_state(flyby)
    gm = np.array([GM[b] for b in BODIES])
    pole = saturn_pole()

    def rhs(_t, y):
        r = y[:18].reshape(6, 3)
        return np.concatenate([y[18:], _accelerations(r, gm, pole).reshape(-1)])

    y0 = np.concatenate([r0.reshape(-1), v0.reshape(-1)])
    # atol: 1 mm and 1 nm/s, far below what a 40 µrad direction at 3500 km needs (0.14 km)
    atol = np.concatenate([np.full(18, 1e-3), np.full(18, 1e-9)])
    sols = []
    for end in (min(t_start_s, -1.0), max(t_end_s, 1.0)):
        s = solve_ivp(rhs, (0.0, end), y0, method="DOP853", rtol=rtol, atol=atol,
                      dense_output=True)
        if not s.success:  # pragma: no cover - smooth motion, no collision in the scenario
            raise RuntimeError(f"n-body integration failed: {s.message}")
        sols.append(s.sol)
    return NBodySolution(sols[0], sols[1], float(t_start_s), float(t_end_s), flyby)
