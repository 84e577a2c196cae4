"""How much of each limit a flight uses, read from its telemetry (not from the commands).

Per sample, as a fraction of the limit (:func:`usage`):

* ``body_rate``: ``|ω|`` over the body-rate limit, and ``axis_rate``: the largest
  ``|ω_i| / ω_i,max`` over the body axes (when the limits give them);
* ``wheel_speed``: the largest ``|ρ_k|`` over the wheel-speed limit;
* ``wheel_momentum``: the largest ``J_k |ρ_k|`` over the momentum limit;
* ``wheel_torque``: the largest motor torque ``J_k Δ(ρ_k + g_k·ω)/Δt`` between samples (the
  wheel's absolute momentum changes only by its motor torque: ``ḣ_k = u_k``, docs/design.md
  §6) over the torque limit. It is the torque averaged over a sample period, what telemetry
  can show.

The same formulas serve the optimiser (JAX, a smooth penalty on what passes a margin) and the
report (NumPy, the largest value of each).
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from cassini_bayes.plan.limits import Limits

__all__ = ["QUANTITIES", "WHEEL_MARGIN", "largest_usage", "penalty", "usage"]

WHEEL_MARGIN = 0.9
"""The optimiser keeps the wheels below this fraction of their speed, momentum and torque limits
on the nominal flight: the true spacecraft differs from the plan's (its inertia, wheel errors,
torques)."""
QUANTITIES = ("body_rate", "axis_rate", "wheel_speed", "wheel_momentum", "wheel_torque")


def usage(t, omega, wheel_rates, axes, j, on, limits: Limits) -> dict:
    """Per-sample fractions of each limit (module docstring); ``axes`` (k, 3), ``j`` (k,) kg m²,
    ``on`` (k,) 0/1 for the wheels running. Works on NumPy or JAX arrays."""
    xp = jnp if not isinstance(omega, np.ndarray) else np
    on = np.asarray(on, float)
    rho = xp.where(on[None] > 0, xp.nan_to_num(wheel_rates), 0.0)
    out = {"body_rate": xp.sqrt(xp.sum(omega * omega, -1)) / limits.rate_max_rad_s,
           "wheel_speed": xp.max(xp.abs(rho), -1) / limits.wheel_rate_max_rad_s}
    axis_max = np.asarray(limits.axis_rate_max_rad_s, float)
    if np.all(np.isfinite(axis_max)):
        out["axis_rate"] = xp.max(xp.abs(omega) / axis_max[None], -1)
    if np.isfinite(limits.wheel_momentum_max_nms):
        out["wheel_momentum"] = (xp.max(xp.abs(rho) * np.asarray(j, float)[None], -1)
                                 / limits.wheel_momentum_max_nms)
    # h_k = J_k (ρ_k + g_k·ω)
    absolute = (rho + omega @ np.asarray(axes, float).T) * np.asarray(j, float)[None]
    torque = xp.abs(xp.diff(absolute, axis=0)) / xp.diff(t)[:, None]
    out["wheel_torque"] = xp.max(torque * on[None], -1) / limits.wheel_torque_max_nm
    return out


def largest_usage(t, omega, wheel_rates, axes, j, on, limits: Limits) -> dict[str, float]:
    """The largest fraction of each limit over the flight (NumPy floats)."""
    u = usage(np.asarray(t, float), np.asarray(omega, float), np.asarray(wheel_rates, float),
              axes, j, on, limits)
    return {k: float(np.max(v)) for k, v in u.items()}


def penalty(t, omega, wheel_rates, axes, j, on, limits: Limits):
    """Smooth penalty (JAX): the squared excess over the margins, summed over the samples
    (body rates over 1, the wheels over :data:`WHEEL_MARGIN`)."""
    u = usage(t, omega, wheel_rates, axes, j, on, limits)
    total = 0.0
    for name, v in u.items():
        margin = 1.0 if name in ("body_rate", "axis_rate") else WHEEL_MARGIN
        total = total + jnp.sum(jnp.maximum(v - margin, 0.0) ** 2)
    return total
