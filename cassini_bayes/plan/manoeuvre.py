"""A planned manoeuvre as a sequence of slews that can be flown, and its commanded profile in JAX.

**Parameters that stay within the limits by construction.** ``N`` eigen-axis slews run one after
another, each preceded and followed by the limits' quiet time. Slew ``j`` has an axis ``e_j``
(any 3-vector, normalised), a share of the time left for slewing (softmax over the slews), a
peak rate and an acceleration, each a logistic fraction of the largest the limits allow about
``e_j``:

* rate: ``min(|ω|_max, 1/‖e ⊘ ω_axis,max‖)`` (the body-rate limit, and the per-axis limits as
  the ellipsoid inside their box: conservative and smooth);
* acceleration: ``min(α_max, s τ_max / max_k |(P I e)_k|)``, ``P I`` the controller's
  allocation of the body torque ``I α`` to the wheels (:func:`~cassini_bayes.plan.limits.
  torque_per_accel`) and ``s`` :data:`~cassini_bayes.plan.limits.ACCEL_TORQUE_SHARE`.

The angle follows from the slew's duration ``D``, rate ``r`` and acceleration ``a``: a
trapezoid, ``r (D − r/a)`` when ``D ≥ 2 r/a``, else a triangle, ``a D²/4`` (the profile of
:func:`cassini_bayes.simulate.controllers.slew_profile`, which flies it). So every slew fits its
slot and no command exceeds a rate or acceleration limit; the wheel speed, torque and momentum
are checked on the simulated flight (:mod:`cassini_bayes.plan.flight`).

:func:`command` is :func:`cassini_bayes.simulate.controllers.command_profile` in JAX (the same
formulas; a test checks they agree), so the simulator can be differentiated with respect to the
slews.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.frames import quat_multiply, rotvec_to_quat

__all__ = [
    "RATE_MARGIN",
    "SlewBounds",
    "SlewParams",
    "Slews",
    "accel_limit",
    "command",
    "initial_params",
    "rate_limit",
    "slew_profile",
    "slew_table",
    "slews_from_params",
]

RATE_MARGIN = 0.95
"""Planned slews peak at most at this fraction of the rate limit: the controller, flying the true
spacecraft with the predicted inertia, overshoots its command by a little."""


class SlewBounds(NamedTuple):
    """What bounds each slew (NumPy constants, SI).

    n : number of slews. duration_s, quiet_s : the plan's length and the rest around each slew.
    rate_max : largest |ω| (rad/s); axis_rate_max : (3,) per body axis (rad/s, large: none).
    accel_max : cap of the acceleration (rad/s², large: none). torque_per_accel : (k, 3) wheel
    torque per unit body acceleration. torque_max : the wheels' share of torque for slewing, N m.
    """

    n: int
    duration_s: float
    quiet_s: float
    rate_max: float
    axis_rate_max: np.ndarray
    accel_max: float
    torque_per_accel: np.ndarray
    torque_max: float

    @property
    def slewing_s(self) -> float:
        """Time left for slewing after the ``n + 1`` quiet periods, s."""
        return self.duration_s - (self.n + 1) * self.quiet_s


class SlewParams(NamedTuple):
    """Unconstrained parameters of ``n`` slews: ``axis`` (n, 3), ``share``, ``rate``,
    ``accel`` (n,) (module docstring)."""

    axis: jax.Array
    share: jax.Array
    rate: jax.Array
    accel: jax.Array


class Slews(NamedTuple):
    """Flyable slews (SI): start times (n,) s, unit axes (n, 3), angles (n,) rad (≥ 0), peak
    rates (n,) rad/s, accelerations (n,) rad/s², durations (n,) s."""

    t_start_s: jax.Array
    axis: jax.Array
    angle_rad: jax.Array
    rate_rad_s: jax.Array
    accel_rad_s2: jax.Array
    duration_s: jax.Array


_LARGE = 1e6


def rate_limit(b: SlewBounds, e):
    """Largest planned peak rate about unit axes ``e`` (..., 3), rad/s (module docstring)."""
    axis_rate = np.minimum(b.axis_rate_max, _LARGE * b.rate_max)
    ellipse = 1.0 / jnp.sqrt(jnp.sum((e / axis_rate.reshape((1,) * (jnp.ndim(e) - 1) + (3,))) ** 2,
                                      -1))
    return RATE_MARGIN * jnp.minimum(b.rate_max, ellipse)


def accel_limit(b: SlewBounds, e):
    """Largest planned acceleration about unit axes ``e`` (..., 3), rad/s² (module docstring)."""
    need = jnp.max(jnp.abs(e @ b.torque_per_accel.T), -1)        # N m per rad/s², worst wheel
    return jnp.minimum(min(b.accel_max, _LARGE), b.torque_max / need)


def slews_from_params(p: SlewParams, b: SlewBounds) -> Slews:
    """The slews of parameters ``p`` within bounds ``b`` (module docstring)."""
    e = p.axis / jnp.linalg.norm(p.axis, axis=-1, keepdims=True)
    # 1e-6 of the time kept free, so that written and re-read numbers still fit the run
    dur = (1.0 - 1e-6) * b.slewing_s * jax.nn.softmax(p.share)
    rate = rate_limit(b, e) * jax.nn.sigmoid(p.rate)
    acc = accel_limit(b, e) * jax.nn.sigmoid(p.accel)
    trap = dur >= 2.0 * rate / acc
    angle = jnp.where(trap, rate * (dur - rate / acc), 0.25 * acc * dur ** 2)
    rate = jnp.where(trap, rate, 0.5 * acc * dur)             # a triangle peaks below the limit
    t0 = b.quiet_s + jnp.concatenate([jnp.zeros(1), jnp.cumsum(dur + b.quiet_s)[:-1]])
    return Slews(t0, e, angle, rate, acc, dur)


def initial_params(b: SlewBounds, axes=None) -> SlewParams:
    """A start for the optimiser: equal time shares, rate and acceleration near their limits,
    axes cycling through ``X, Y, Z, −X, −Y, −Z`` (Feldman & Lee's slews, Fig. B3) unless
    given."""
    if axes is None:
        cycle = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, -1, 0], [0, 0, -1]],
                         float)
        axes = cycle[np.arange(b.n) % 6]
        axes = axes + 0.05 * np.roll(axes, 1, axis=1)   # off the coordinate axes: gradients
    return SlewParams(jnp.asarray(axes, float), jnp.zeros(b.n), jnp.full(b.n, 3.0),
                      jnp.full(b.n, 3.0))


def slew_profile(t, t0, angle, rate, accel):
    """``(θ, θ̇, θ̈)`` at times ``t`` of one slew of :func:`cassini_bayes.simulate.controllers.
    slew_profile` (trapezoid, or triangle when the rate is not reached), in JAX."""
    tt = t - t0
    sgn = jnp.sign(angle)
    big = jnp.abs(angle)
    ta = rate / accel
    tri = accel * ta * ta >= big
    ta = jnp.where(tri, jnp.sqrt(big / accel), ta)
    tc = jnp.where(tri, 0.0, (big - accel * ta * ta) / rate)
    wpk = accel * ta
    t1, t2, t3 = ta, ta + tc, 2.0 * ta + tc
    z = jnp.zeros_like(tt)
    th = jnp.select([tt <= 0, tt <= t1, tt <= t2, tt <= t3],
                    [z, 0.5 * accel * tt ** 2, 0.5 * accel * ta ** 2 + wpk * (tt - t1),
                     big - 0.5 * accel * (t3 - tt) ** 2], big + z)
    w = jnp.select([tt <= 0, tt <= t1, tt <= t2, tt <= t3],
                   [z, accel * tt, wpk + z, accel * (t3 - tt)], z)
    a = jnp.select([tt <= 0, tt < t1, tt < t2, tt < t3], [z, accel + z, z, -accel + z], z)
    return sgn * th, sgn * w, sgn * a


def command(t, q0, slews: Slews):
    """Commanded ``[q (4), ω (3), α (3)]`` (n, 10) at times ``t`` (s) of sequential slews from
    the attitude ``q0``: :func:`cassini_bayes.simulate.controllers.command_profile` in JAX."""
    n = t.shape[0]
    q = jnp.broadcast_to(jnp.asarray(q0, float), (n, 4))
    w = jnp.zeros((n, 3))
    a = jnp.zeros((n, 3))
    for j in range(slews.t_start_s.shape[0]):
        e = slews.axis[j]
        th, dth, ddth = slew_profile(t, slews.t_start_s[j], slews.angle_rad[j],
                                     slews.rate_rad_s[j], slews.accel_rad_s2[j])
        q = quat_multiply(rotvec_to_quat(th[:, None] * e[None]), q)
        w = w + dth[:, None] * e[None]
        a = a + ddth[:, None] * e[None]
    return jnp.concatenate([q, w, a], 1)


def slew_table(s: Slews) -> list[dict]:
    """The slews as a scenario's ``[[slew]]`` entries (the file's units)."""
    out = []
    for j in range(np.shape(s.t_start_s)[0]):
        out.append({"t_start_s": float(s.t_start_s[j]),
                    "axis": [float(x) for x in np.asarray(s.axis[j])],
                    "angle_deg": float(np.rad2deg(s.angle_rad[j])),
                    "rate_mrad_s": float(s.rate_rad_s[j]) * 1e3,
                    "accel_mrad_s2": float(s.accel_rad_s2[j]) * 1e3})
    return out
