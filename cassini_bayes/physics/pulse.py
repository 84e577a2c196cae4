"""Thruster pulse response: thrust profile, exact pulse impulse and the impulse ratio ``R``.

Feldman & Lee (2006) §V describe a commanded pulse of width ``Δ`` (s): no thrust for the valve
delay ``τd``; then an exponential rise with time constant ``τr`` towards the steady thrust ``F``;
after the command ends the thrust is held for another ``τd`` and then decays with time constant
``τf``. The profile used here (docs/design.md §6) is

* ``0``                              for ``t < τd``,
* ``F (1 − e^{−t/τr})``              for ``τd ≤ t < Δ``,
* ``F (1 − e^{−Δ/τr})``              for ``Δ ≤ t < Δ + τd``,
* ``F (1 − e^{−Δ/τr}) e^{−(t−Δ−τd)/τf}``  for ``t ≥ Δ + τd``,

whose integral is exactly the closed form printed in Feldman & Lee §V (valid for ``Δ ≥ τd``):
``F [(Δ + τf) + τr (e^{−Δ/τr} − e^{−τd/τr}) − (τf + τd) e^{−Δ/τr}]``.

The family includes a first-order valve, ``τd = 0`` and ``τr = τf = τ`` (thrust ``F(1 − e^{−t/τ})``
while commanded, then an exponential decay with the same ``τ``): its impulse is exactly ``F Δ``,
``(Δ + τ) + τ (e^{−Δ/τ} − 1) − τ e^{−Δ/τ} = Δ``, for every width.

All times in seconds, thrust in newtons. Functions broadcast over arrays and are differentiable.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jax import Array
from jax.custom_derivatives import SymbolicZero

__all__ = [
    "TAU_DELAY_S",
    "TAU_RISE_S",
    "TAU_FALL_S",
    "thrust_profile",
    "pulse_impulse",
    "impulse_ratio",
    "mix_ratio",
    "pulse_impulse_until",
    "pulse_impulse_area",
]

# Manufacturer's time constants (Feldman & Lee 2006 §V): delay 5 ms, rise 20 ms, fall 65 ms.
TAU_DELAY_S = 0.005
TAU_RISE_S = 0.020
TAU_FALL_S = 0.065


def thrust_profile(t_s, width_s, tau_delay_s, tau_rise_s, tau_fall_s, thrust_n=1.0) -> Array:
    """Thrust (N) at ``t_s`` after a pulse command of width ``width_s`` (Feldman & Lee §V)."""
    t = jnp.asarray(t_s)
    w, td, tr, tf = (jnp.asarray(x) for x in (width_s, tau_delay_s, tau_rise_s, tau_fall_s))
    held = 1.0 - jnp.exp(-w / tr)
    rising = jnp.where(t >= td, 1.0 - jnp.exp(-jnp.clip(t, 0.0) / tr), 0.0)
    decay = held * jnp.exp(-jnp.clip(t - w - td, 0.0) / tf)
    shape = jnp.where(t < w, rising, jnp.where(t < w + td, held, decay))
    return thrust_n * shape


@jax.custom_jvp
def pulse_impulse(width_s, tau_delay_s, tau_rise_s, tau_fall_s, thrust_n=1.0) -> Array:
    """Impulse (N s) of one pulse: Feldman & Lee (2006) §V closed form.

    ``F [(Δ + τf) + τr (e^{−Δ/τr} − e^{−τd/τr}) − (τf + τd) e^{−Δ/τr}]``; exact for the profile
    of :func:`thrust_profile` when ``Δ ≥ τd``. Its derivatives are stated in closed form
    (:func:`_pulse_impulse_jvp`): a sampler differentiates it in the time constants at every
    step, and the stated form is a few fused operations where the derivative of the formula,
    operation by operation, was some twenty.
    """
    w, td, tr, tf = (jnp.asarray(x) for x in (width_s, tau_delay_s, tau_rise_s, tau_fall_s))
    e_w = jnp.exp(-w / tr)
    # Feldman & Lee (2006) §V, impulse of a pulse of commanded width Δ
    return thrust_n * ((w + tf) + tr * (e_w - jnp.exp(-td / tr)) - (tf + td) * e_w)


def _tangent(terms) -> Array:
    """Sum of ``∂f/∂x · dx`` over the arguments whose tangent ``dx`` is not a symbolic zero."""
    out = [d * t for d, t in terms if not isinstance(t, SymbolicZero)]
    return sum(out[1:], out[0]) if out else 0.0


def _pulse_impulse_jvp(primals, tangents):
    """Derivatives of :func:`pulse_impulse` (``φ`` its value per newton, ``e_w = e^{−Δ/τr}``,
    ``e_d = e^{−τd/τr}``): ``∂φ/∂Δ = 1 − e_w + (τf + τd) e_w/τr``, ``∂φ/∂τd = e_d − e_w``,
    ``∂φ/∂τr = e_w (1 + Δ/τr) − e_d (1 + τd/τr) − (τf + τd) e_w Δ/τr²``, ``∂φ/∂τf = 1 − e_w``."""
    w, td, tr, tf, f = (jnp.asarray(x) for x in primals)
    e_w, e_d = jnp.exp(-w / tr), jnp.exp(-td / tr)
    phi = (w + tf) + tr * (e_w - e_d) - (tf + td) * e_w
    dw = 1.0 - e_w + (tf + td) * e_w / tr
    dtd = e_d - e_w
    dtr = e_w * (1.0 + w / tr) - e_d * (1.0 + td / tr) - (tf + td) * e_w * w / tr**2
    dtf = 1.0 - e_w
    out = f * phi
    tangent = _tangent([(f * dw, tangents[0]), (f * dtd, tangents[1]), (f * dtr, tangents[2]),
                        (f * dtf, tangents[3]), (phi, tangents[4])])
    return out, jnp.broadcast_to(tangent, out.shape)


pulse_impulse.defjvp(_pulse_impulse_jvp, symbolic_zeros=True)


def impulse_ratio(width_s, tau_delay_s=TAU_DELAY_S, tau_rise_s=TAU_RISE_S,
                  tau_fall_s=TAU_FALL_S) -> Array:
    """``R = actual impulse / (F Δ)`` for one pulse (Feldman & Lee §V: 1.395 at 125 ms)."""
    return pulse_impulse(width_s, tau_delay_s, tau_rise_s, tau_fall_s) / jnp.asarray(width_s)


def mix_ratio(widths_s, counts=None, tau_delay_s=TAU_DELAY_S, tau_rise_s=TAU_RISE_S,
              tau_fall_s=TAU_FALL_S) -> Array:
    """``R`` of a pulse mix: total actual impulse over ``F Σ Δ`` (Feldman & Lee §V: 1.3406).

    ``widths_s`` along the last axis; ``counts`` (same shape, default ones) repeats each width.
    """
    w = jnp.asarray(widths_s)
    n = jnp.ones_like(w) if counts is None else jnp.asarray(counts, dtype=w.dtype)
    imp = pulse_impulse(w, tau_delay_s, tau_rise_s, tau_fall_s)
    return jnp.sum(n * imp, -1) / jnp.sum(n * w, -1)


@jax.custom_jvp
def pulse_impulse_until(t_s, width_s, tau_delay_s, tau_rise_s, tau_fall_s, thrust_n=1.0) -> Array:
    """Impulse (N s) a pulse has delivered by ``t_s`` after its command (integral of the profile).

    Tends to :func:`pulse_impulse` as ``t → ∞``. Used to predict the accumulated angular impulse
    at telemetry times that fall inside a pulse's tail. Derivatives stated in closed form
    (:func:`_pulse_impulse_until_jvp`; in ``t`` the profile, :func:`thrust_profile`).
    """
    t = jnp.asarray(t_s)
    w, td, tr, tf = (jnp.asarray(x) for x in (width_s, tau_delay_s, tau_rise_s, tau_fall_s))
    # Phase 1: rising, from td to min(t, w).
    t1 = jnp.clip(t, td, jnp.maximum(w, td))
    rise = (t1 - td) + tr * (jnp.exp(-t1 / tr) - jnp.exp(-td / tr))
    held = 1.0 - jnp.exp(-w / tr)
    # Phase 2: held, from w to min(t, w + td).
    t2 = jnp.clip(t, w, w + td)
    hold = held * (t2 - w)
    # Phase 3: decaying, from w + td to t.
    t3 = jnp.clip(t - w - td, 0.0)
    tail = held * tf * (1.0 - jnp.exp(-t3 / tf))
    return thrust_n * (rise + hold + tail)


def _pulse_impulse_until_jvp(primals, tangents):
    """Derivatives of :func:`pulse_impulse_until`, phase by phase (``t1``, ``t2``, ``t3`` the
    clipped times of the rising, held and decaying phases; on a phase boundary the one-sided
    derivative of the later phase, where the function has a kink only in ``t`` and ``Δ``)."""
    t, w, td, tr, tf, f = (jnp.asarray(x) for x in primals)
    hi1 = jnp.maximum(w, td)
    t1 = jnp.clip(t, td, hi1)
    e1, e_d, e_w = jnp.exp(-t1 / tr), jnp.exp(-td / tr), jnp.exp(-w / tr)
    rise = (t1 - td) + tr * (e1 - e_d)
    held = 1.0 - e_w
    t2 = jnp.clip(t, w, w + td)
    t3 = jnp.maximum(t - w - td, 0.0)
    e3 = jnp.exp(-t3 / tf)
    decaying = t > w + td
    phi = rise + held * (t2 - w) + held * tf * (1.0 - e3)
    # ∂t1/∂τd: t1 is τd itself before the rise starts, or (a pulse shorter than its delay) after
    dt1_dtd = ((t < td) | ((t > hi1) & (td > w))).astype(phi.dtype)
    dheld_dtr = -e_w * w / tr**2
    dtd = dt1_dtd * (1.0 - e1) - 1.0 + e_d + jnp.where(decaying, held * (1.0 - e3), 0.0)
    dtr = (e1 * (1.0 + t1 / tr) - e_d * (1.0 + td / tr)
           + dheld_dtr * ((t2 - w) + tf * (1.0 - e3)))
    dtf = held * ((1.0 - e3) - t3 / tf * e3)
    d_t = jnp.where((t > td) & (t < hi1), 1.0 - e1,
                    jnp.where((t >= w) & (t < w + td), held, jnp.where(decaying, held * e3, 0.0)))
    # ∂/∂Δ: the rise ends at Δ (when it is still rising then), the held level, the phases' ends
    dheld_dw = e_w / tr
    dt2_dw = ((t < w) | decaying).astype(phi.dtype)
    dw = (jnp.where((t > hi1) & (w > td), 1.0 - e1, 0.0)
          + dheld_dw * (t2 - w) + held * (dt2_dw - 1.0)
          + dheld_dw * tf * (1.0 - e3) - jnp.where(decaying, held * e3, 0.0))
    out = f * phi
    tangent = _tangent([(f * d_t, tangents[0]), (f * dw, tangents[1]), (f * dtd, tangents[2]),
                        (f * dtr, tangents[3]), (f * dtf, tangents[4]), (phi, tangents[5])])
    return out, jnp.broadcast_to(tangent, out.shape)


pulse_impulse_until.defjvp(_pulse_impulse_until_jvp, symbolic_zeros=True)


def pulse_impulse_area(t_s, width_s, tau_delay_s, tau_rise_s, tau_fall_s) -> Array:
    """``∫_0^t j(s) ds`` (N s² per N of thrust, i.e. s²): the integral of the impulse a pulse has
    delivered (:func:`pulse_impulse_until`) from its command to ``t_s`` after it, phase by phase
    in closed form. Once the pulse has decayed it is ``j_∞ (t − c)``, ``c`` the centroid of the
    thrust profile after the command; it measures where inside a sample interval the impulse
    arrived, what the trapezoidal gyroscopic impulse needs (:mod:`cassini_bayes.inference.thrust`).
    """
    t = jnp.asarray(t_s)
    w, td, tr, tf = (jnp.asarray(x) for x in (width_s, tau_delay_s, tau_rise_s, tau_fall_s))
    e_d = jnp.exp(-td / tr)
    hi1 = jnp.maximum(w, td)
    # rising: ∫ (s − τd) + τr (e^{−s/τr} − e^{−τd/τr}) ds from τd to min(t, max(Δ, τd)), then
    # held at its end value
    u = jnp.clip(t, td, hi1)
    rise = 0.5 * (u - td)**2 + tr**2 * (e_d - jnp.exp(-u / tr)) - tr * e_d * (u - td)
    rise_end = (hi1 - td) + tr * (jnp.exp(-hi1 / tr) - e_d)
    rise = rise + jnp.maximum(t - hi1, 0.0) * rise_end
    held = 1.0 - jnp.exp(-w / tr)
    # held for τd after the command ends: ∫ held (s − Δ) ds, then held τd
    v = jnp.clip(t, w, w + td)
    hold = held * (0.5 * (v - w)**2 + jnp.maximum(t - w - td, 0.0) * td)
    # decaying: ∫ held τf (1 − e^{−x/τf}) dx
    x = jnp.maximum(t - w - td, 0.0)
    tail = held * tf * (x - tf * (1.0 - jnp.exp(-x / tf)))
    return rise + hold + tail
