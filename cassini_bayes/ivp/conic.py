"""Conic propagation by Goodyear's universal-variable method (Lee §3.3.1, Eqs 12-14).

Given the position ``r0`` (m) and velocity ``v0`` (m/s) of a body relative to its central body at
``t0`` and the gravitational parameter ``mu`` (m³/s², G times the sum of the two masses), the
state at ``t0 + dt`` is ``r = F r0 + G v0``, ``v = F' r0 + G' v0`` (Eq 12), where F, G, F', G'
(Eq 14) are built from Goodyear's series ``s0 … s3`` of the universal variable ``Ψ`` that solves
Kepler's equation in the form of Eq 13. One formula covers elliptic (``α < 0``), parabolic
(``α = 0``) and hyperbolic (``α > 0``) motion and the straight line (``mu = 0``), forward and
backward in time.

How it never fails (Goodyear 1965):

* the series are summed at ``Ψ / 2ⁿ``, where ``|α Ψ²| ≤ 1`` and a dozen terms reach machine
  precision, and brought back by the double-argument formulas ``s0(2Ψ) = 1 + 2α s1²``,
  ``s1(2Ψ) = 2 s0 s1``, ``s2(2Ψ) = 2 s1²``, ``s3(2Ψ) = 2 s3 + 2 s1 s2``;
* Eq 13's left side is ``t(Ψ) − dt`` with ``dt/dΨ = |r| > 0``: monotone, one root. Newton's
  steps are kept inside a bracket of the root and replaced by bisection when they leave it;
  an elliptic ``dt`` is first reduced to within half a period of zero (whole periods change
  nothing), which bounds the root by one period of ``Ψ``, ``2π/√−α``;
* ``dt < 0`` is solved as ``|dt|`` with ``σ0 → −σ0`` (``s_k(−Ψ) = (−1)ᵏ s_k(Ψ)``).

Pure JAX: jit, vmap and grad. The root is found without gradient and one last Newton step
carries the derivatives (implicit function theorem), so ``jax.grad`` and ``jax.jacfwd`` give
the exact derivatives of the propagated state.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array
from numpy.typing import ArrayLike

__all__ = ["Conic", "ConicState", "goodyear_series", "fg_coefficients", "propagate_conic",
           "propagate_conic_unchecked", "solve_universal_anomaly"]

_TERMS = 13          # series terms at |α Ψ²| <= 1: the last is 1/27! ≈ 9e-29 of the first
_MAX_DOUBLINGS = 12  # |α Ψ²| up to 4^12: √|α| Ψ ≈ 4096, beyond cosh's range (710)
_MAX_ITER = 300      # the bracket halves at least every other step: ~2 × 60 steps to 1 ulp
_EXPAND = 200        # bracket expansions (×4 each) of hyperbolic/parabolic motion
# 1/(2j+k)! for the series terms j and the functions k = 0..3
_INV_FACT = np.array([[1.0 / math.factorial(2 * j + k) for k in range(4)] for j in range(_TERMS)])


class ConicState(NamedTuple):
    """A propagated state: ``r`` (m) and ``v`` (m/s), shape ``(..., 3)`` each."""

    r: Array
    v: Array


class Conic(NamedTuple):
    """A conic: the state ``r0`` (m), ``v0`` (m/s) at epoch ``t0_s`` (s) about a central body of
    gravitational parameter ``mu`` (m³/s²). ``r0``, ``v0`` and ``mu`` are Lee's "seven
    parameters" (§3.3); the epoch is the "(and time)"."""

    r0: Array
    v0: Array
    mu: float
    t0_s: float

    def state(self, t_s) -> ConicState:
        """The state at times ``t_s`` (s), shape ``(..., 3)``."""
        return propagate_conic(self.r0, self.v0, self.mu, jnp.asarray(t_s) - self.t0_s)

    def position(self, t_s) -> Array:
        """The position (m) at times ``t_s`` (s), shape ``t_s.shape + (3,)``."""
        return self.state(t_s).r


def goodyear_series(psi: Array, alpha: Array) -> tuple[Array, Array, Array, Array]:
    """Goodyear's ``s0, s1, s2, s3`` (Lee Eq 13) of the universal variable ``psi`` for
    ``alpha = |v0|² − 2 mu/|r0|``.

    ``s_k = Σ_j α^j Ψ^(2j+k) / (2j+k)!``, summed at ``Ψ/2ⁿ`` (``|αΨ²/4ⁿ| ≤ 1``) and doubled back
    ``n`` times. Elementwise; any shapes that broadcast.
    """
    psi, alpha = jnp.broadcast_arrays(jnp.asarray(psi, float), jnp.asarray(alpha, float))
    z = alpha * psi * psi
    az = jnp.abs(z)
    n = jnp.where(az > 1.0, jnp.ceil(jnp.log(jnp.where(az > 1.0, az, 2.0)) / math.log(4.0)), 0.0)
    n = jnp.clip(n, 0.0, _MAX_DOUBLINGS)
    x = psi * jnp.exp2(-n)            # exact scaling by a power of two
    zx = alpha * x * x

    def horner(j, c):                 # Σ_j zx^j / (2j+k)!, k = 0..3, from the last term down
        return tuple(ck * zx + jnp.asarray(_INV_FACT)[_TERMS - 2 - j, k] for k, ck in enumerate(c))

    last = tuple(jnp.full_like(zx, _INV_FACT[_TERMS - 1, k]) for k in range(4))
    c = jax.lax.fori_loop(0, _TERMS - 1, horner, last)
    s = (c[0], x * c[1], x * x * c[2], x * x * x * c[3])

    def double(i, s):                 # s_k(2Ψ) from s_k(Ψ), applied n times
        s0, s1, s2, s3 = s
        new = (1.0 + 2.0 * alpha * s1 * s1, 2.0 * s0 * s1, 2.0 * s1 * s1,
               2.0 * s3 + 2.0 * s1 * s2)
        return tuple(jnp.where(i < n, a, b) for a, b in zip(new, s))

    s0, s1, s2, s3 = jax.lax.fori_loop(0, _MAX_DOUBLINGS, double, s)
    return s0, s1, s2, s3


def _kepler(psi, dt, r0n, sigma0, mu, alpha):
    """Eq 13's left side (with sign flipped: ``t(Ψ) − dt``) and its derivative ``|r|``."""
    s0, s1, s2, s3 = goodyear_series(psi, alpha)
    f = r0n * s1 + sigma0 * s2 + mu * s3 - dt
    r = r0n * s0 + sigma0 * s1 + mu * s2
    return f, r


def solve_universal_anomaly(dt, r0n, sigma0, mu, alpha):
    """``Ψ`` solving Lee Eq 13 for a scalar state (no gradient; see :func:`propagate_conic`).

    ``dt`` (s) is reduced beforehand for elliptic motion; ``r0n = |r0|`` (m), ``sigma0 = r0·v0``
    (m²/s), ``mu`` (m³/s²), ``alpha = |v0|² − 2mu/|r0|`` (m²/s²).
    """
    sign = jnp.where(dt < 0, -1.0, 1.0)
    adt, sg = jnp.abs(dt), sign * sigma0     # solve forward: s_k(−Ψ) = (−1)^k s_k(Ψ)
    elliptic = alpha < 0
    beta = jnp.where(elliptic, -alpha, 1.0)
    psi_period = 2.0 * jnp.pi / jnp.sqrt(beta)   # Ψ of one whole period (elliptic)

    # bracket [lo, hi] with f(lo) <= 0 <= f(hi); hyperbolic/parabolic: expand ×4 from dt/|r0|
    hi0 = jnp.maximum(adt / r0n, 1e-300)

    def expand_cond(c):
        lo, hi, k = c
        f, _ = _kepler(hi, adt, r0n, sg, mu, alpha)
        return jnp.isfinite(f) & (f < 0) & (k < _EXPAND) & ~elliptic   # overflow: past the root

    def expand_body(c):
        lo, hi, k = c
        return hi, hi * 4.0, k + 1

    lo, hi, _ = jax.lax.while_loop(expand_cond, expand_body, (0.0 * hi0, hi0, 0))
    hi = jnp.where(elliptic, psi_period, hi)
    lo = jnp.where(elliptic, 0.0, lo)
    # first guess: mean motion (elliptic), else the bracket's middle
    guess = jnp.where(elliptic, adt * beta / jnp.where(mu > 0, mu, 1.0), 0.5 * (lo + hi))
    guess = jnp.where((guess > lo) & (guess < hi), guess, 0.5 * (lo + hi))

    def cond(c):
        psi, lo, hi, dx_old, k, done = c
        return ~done & (k < _MAX_ITER)

    def body(c):
        psi, lo, hi, dx_old, k, _ = c
        f, r = _kepler(psi, adt, r0n, sg, mu, alpha)
        past = (f >= 0) | ~jnp.isfinite(f)     # s_k overflow only far past the root
        lo = jnp.where((f <= 0) & jnp.isfinite(f), psi, lo)
        hi = jnp.where(past, psi, hi)
        # Newton inside the bracket while its steps at least halve (rtsafe); else bisection,
        # e.g. where Newton would creep down an exponential from its far side
        step = f / r
        new = psi - step
        newton_ok = (new > lo) & (new < hi) & jnp.isfinite(new) \
            & (jnp.abs(step) <= 0.5 * dx_old)
        dx = jnp.where(newton_ok, jnp.abs(step), 0.5 * (hi - lo))
        new = jnp.where(newton_ok, new, 0.5 * (lo + hi))
        eps = jnp.finfo(float).eps
        done = (dx <= 4 * eps * jnp.abs(new)) | (f == 0)
        return new, lo, hi, dx, k + 1, done

    psi, *_ = jax.lax.while_loop(cond, body, (guess, lo, hi, hi - lo, 0, adt == 0))
    return jnp.where(adt == 0, 0.0, sign * psi)


def _reduced_dt(dt, mu, alpha):
    """``dt`` less the whole periods of elliptic motion (to within half a period of zero)."""
    elliptic = (alpha < 0) & (mu > 0)
    beta = jnp.where(elliptic, -alpha, 1.0)
    period = 2.0 * jnp.pi * jnp.where(elliptic, mu, 1.0) / beta ** 1.5
    k = jnp.where(elliptic, jnp.round(dt / period), 0.0)
    return dt - k * period


def fg_coefficients(r0, v0, mu, dt):
    """Lee Eq 14: ``F, G, F', G'`` and ``|r|`` for one state (``r0`` (3,) m, ``v0`` (3,) m/s,
    ``mu`` m³/s², ``dt`` s)."""
    r0n = jnp.sqrt(jnp.sum(r0 * r0))
    sigma0 = jnp.sum(r0 * v0)                      # Eq 13: σ0 = r0ᵀ v0
    alpha = jnp.sum(v0 * v0) - 2.0 * mu / r0n      # Eq 13: α = v0ᵀ v0 − 2μ/|r0|
    dtr = _reduced_dt(dt, mu, alpha)
    psi_star = jax.lax.stop_gradient(solve_universal_anomaly(
        jax.lax.stop_gradient(dtr), jax.lax.stop_gradient(r0n),
        jax.lax.stop_gradient(sigma0), jax.lax.stop_gradient(mu),
        jax.lax.stop_gradient(alpha)))
    # one Newton step from the root carries dΨ/d(inputs) = −(∂f/∂inputs)/|r| (implicit function)
    f, rn = _kepler(psi_star, dtr, r0n, sigma0, mu, alpha)
    psi = psi_star - f / rn
    s0, s1, s2, s3 = goodyear_series(psi, alpha)
    rn = r0n * s0 + sigma0 * s1 + mu * s2          # Eq 14: |r|
    F = 1.0 - mu * s2 / r0n                        # Eq 14
    G = dtr - mu * s3
    Fd = -mu * s1 / (rn * r0n)
    Gd = 1.0 - mu * s2 / rn
    return F, G, Fd, Gd, rn


def _propagate_one(r0, v0, mu, dt):
    F, G, Fd, Gd, _ = fg_coefficients(r0, v0, mu, dt)
    return F * r0 + G * v0, Fd * r0 + Gd * v0      # Eq 12


_propagate = jax.jit(jnp.vectorize(_propagate_one, signature="(3),(3),(),()->(3),(3)"))


def propagate_conic_unchecked(r0, v0, mu, dt) -> ConicState:
    """:func:`propagate_conic` without the input checks (for use inside ``jit``/``grad``)."""
    r0, v0, mu, dt = (jnp.asarray(x, float) for x in (r0, v0, mu, dt))
    batch = jnp.broadcast_shapes(r0.shape[:-1], v0.shape[:-1], mu.shape, dt.shape)
    r, v = _propagate(jnp.broadcast_to(r0, batch + (3,)), jnp.broadcast_to(v0, batch + (3,)),
                      jnp.broadcast_to(mu, batch), jnp.broadcast_to(dt, batch))
    return ConicState(r, v)


def _concrete(x) -> np.ndarray | None:
    """``x`` as a NumPy array, or ``None`` when it is a JAX tracer (inside jit/grad/vmap)."""
    if isinstance(x, jax.core.Tracer):
        return None
    return np.asarray(x, dtype=float)


def propagate_conic(r0: ArrayLike, v0: ArrayLike, mu: ArrayLike, dt: ArrayLike) -> ConicState:
    """Propagate ``(r0, v0)`` over ``dt`` on the conic about a body of parameter ``mu``
    (Lee Eqs 12-14, Goodyear's method).

    Parameters
    ----------
    r0 : position relative to the central body, m, shape ``(..., 3)``.
    v0 : velocity relative to the central body, m/s, shape ``(..., 3)``.
    mu : gravitational parameter G(m1 + m2), m³/s², ≥ 0 (0: straight line), shape ``(...)``.
    dt : ``t − t0``, s, positive or negative, shape ``(...)``.

    The shapes broadcast (many states, many times, or both). Returns a :class:`ConicState`.
    Concrete inputs are checked (:class:`~cassini_bayes.errors.InputError`: a negative ``mu``,
    a zero ``r0``, a non-finite value, a last axis not of length 3); traced ones (inside
    ``jit``/``grad``) are not.
    """
    from cassini_bayes.ivp._checks import (check_finite, check_mu, check_nonzero_vectors,
                                           check_vectors)

    c_r0, c_v0, c_mu, c_dt = (_concrete(x) for x in (r0, v0, mu, dt))
    if c_r0 is not None:
        check_vectors(c_r0, "r0")
        check_finite(c_r0, "r0")
        check_nonzero_vectors(c_r0, "r0")
    if c_v0 is not None:
        check_vectors(c_v0, "v0")
        check_finite(c_v0, "v0")
    if c_mu is not None:
        check_mu(c_mu, "mu")
    if c_dt is not None:
        check_finite(c_dt, "dt")
    return propagate_conic_unchecked(r0, v0, mu, dt)
