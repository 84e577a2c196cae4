"""Chebyshev polynomial segments of a vector (Lee §3.3.2, Eqs 15-18).

A segment ``[t_s, t_f]`` holds, for one order ``n`` shared by the three axes, the coefficients
``C_i`` of ``Σ_{i=0..n} C_i T_i(τ)`` for x, y and z, with the normalised time
``τ = (2t − t_f − t_s)/(t_f − t_s)``: ``3(n+1)`` numbers and the segment's end time, the
``3(n+1)+1`` of Lee §3.3.2 (each segment starts where the one before ended).

The fit interpolates at the ``n+1`` Chebyshev nodes ``τ_j = cos(π(j+½)/(n+1))``, the zeros of
``T_{n+1}``; the coefficients follow from the discrete form of the orthogonality of Eq 18,
``C_i = (2−δ_i0)/(n+1) Σ_j f(τ_j) T_i(τ_j)``. Its error is close to the minimax one of Eq 17 and
equi-oscillates (for a smooth vector it is nearly ``C_{n+1} T_{n+1}(τ)``).
Evaluation builds ``T_k`` by the recurrence of Eq 16.
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from cassini_bayes.ivp._checks import MAX_ORDER, check_finite, check_interval, check_order

__all__ = ["ChebyshevSegments", "chebyshev_nodes", "chebyshev_fit", "chebyshev_sum",
           "normalised_time", "coefficient_count"]


def normalised_time(t, t_s, t_f):
    """Lee §3.3.2: ``τ = (2t − t_f − t_s)/(t_f − t_s)``, in [−1, 1] over the segment."""
    return (2.0 * t - t_f - t_s) / (t_f - t_s)


def chebyshev_sum(tau, coeffs, xp=jnp):
    """``Σ_i C_i T_i(τ)`` per axis, ``T_i`` by the recurrence of Lee Eq 16.

    ``tau`` shape ``(N,)``; ``coeffs`` shape ``(N, 3, n+1)`` or ``(3, n+1)``; returns ``(N, 3)``.
    ``xp`` is ``jax.numpy`` (default) or ``numpy``.
    """
    tau = tau[:, None]
    if coeffs.ndim == 2:
        coeffs = coeffs[None]
    t_prev, t_cur = xp.ones_like(tau), tau          # Eq 16: T_0 = 1, T_1 = τ
    total = coeffs[..., 0] * t_prev
    n1 = coeffs.shape[-1]
    if n1 > 1:
        total = total + coeffs[..., 1] * t_cur
    for k in range(2, n1):
        t_prev, t_cur = t_cur, 2.0 * tau * t_cur - t_prev   # Eq 16: T_k = 2τ T_{k-1} − T_{k-2}
        total = total + coeffs[..., k] * t_cur
    return total


def chebyshev_nodes(order: int) -> np.ndarray:
    """The ``order+1`` zeros of ``T_{order+1}``: ``τ_j = cos(π(j+½)/(order+1))``."""
    j = np.arange(order + 1)
    return np.cos(np.pi * (j + 0.5) / (order + 1))


def chebyshev_fit(f: Callable[[np.ndarray], np.ndarray], t_s: float, t_f: float,
                  order: int) -> np.ndarray:
    """Coefficients ``(3, order+1)`` interpolating the vector function ``f`` (times (N,) s →
    (N, 3)) at the Chebyshev nodes of ``[t_s, t_f]`` (module docstring)."""
    tau = chebyshev_nodes(order)
    t = 0.5 * (t_f + t_s) + 0.5 * (t_f - t_s) * tau
    y = np.asarray(f(t), float)                       # (n+1, 3)
    k = np.arange(order + 1)
    basis = np.cos(np.outer(k, np.pi * (np.arange(order + 1) + 0.5) / (order + 1)))  # T_k(τ_j)
    c = (2.0 / (order + 1)) * basis @ y               # discrete Eq 18
    c[0] *= 0.5
    return c.T


def coefficient_count(order: int) -> int:
    """Numbers an order-``n`` segment needs: ``3(n+1)+1`` (Lee §3.3.2)."""
    return 3 * (int(order) + 1) + 1


class ChebyshevSegments(NamedTuple):
    """A list of contiguous Chebyshev segments of one vector.

    Attributes
    ----------
    bounds_s : segment boundaries, s, shape ``(S+1,)``, increasing; segment ``k`` is
        ``[bounds_s[k], bounds_s[k+1]]``.
    coeffs : ``(S, 3, 13)`` coefficients ``C_i`` per segment and axis (zero above its order), in
        the vector's unit (m).
    orders : ``(S,)`` order ``n`` of each segment (≤ 12).
    """

    bounds_s: Array
    coeffs: Array
    orders: Array

    @classmethod
    def from_segments(cls, bounds_s, coeffs_list) -> "ChebyshevSegments":
        """From boundaries ``(S+1,)`` and a list of ``S`` arrays ``(3, n_k+1)`` (checked:
        increasing boundaries, orders ≤ 12, finite coefficients)."""
        bounds = np.asarray(bounds_s, float)
        check_finite(bounds, "bounds_s")
        if bounds.ndim != 1 or bounds.size != len(coeffs_list) + 1 or bounds.size < 2:
            from cassini_bayes.errors import InputError
            raise InputError(f"bounds_s must have one more entry than there are segments "
                             f"({len(coeffs_list)}), got shape {bounds.shape}")
        padded = np.zeros((len(coeffs_list), 3, MAX_ORDER + 1))
        orders = np.zeros(len(coeffs_list), int)
        for k, c in enumerate(coeffs_list):
            check_interval(bounds[k], bounds[k + 1], f"segment {k}")
            c = np.asarray(c, float)
            check_order(c.shape[-1] - 1, f"the order of segment {k}")
            check_finite(c, f"the coefficients of segment {k}")
            padded[k, :, :c.shape[-1]] = c
            orders[k] = c.shape[-1] - 1
        return cls(jnp.asarray(bounds), jnp.asarray(padded), jnp.asarray(orders))

    @property
    def t_start_s(self) -> float:
        return float(self.bounds_s[0])

    @property
    def t_end_s(self) -> float:
        return float(self.bounds_s[-1])

    @property
    def n_coefficients(self) -> int:
        """Numbers stored, ``Σ 3(n_k+1)+1`` (Lee §3.3.2)."""
        return int(sum(coefficient_count(n) for n in np.asarray(self.orders)))

    def position(self, t_s) -> Array:
        """The vector at times ``t_s`` (s, any shape), shape ``t_s.shape + (3,)``; times outside
        ``[t_start_s, t_end_s]`` use the nearest segment's polynomial (the vector tree refuses
        them)."""
        t = jnp.asarray(t_s, float)
        return _evaluate(self.bounds_s, self.coeffs, t.reshape(-1)).reshape(t.shape + (3,))


@jax.jit
def _evaluate(bounds, coeffs, t):
    k = jnp.clip(jnp.searchsorted(bounds, t, side="right") - 1, 0, bounds.shape[0] - 2)
    t_s, t_f = bounds[k], bounds[k + 1]
    return chebyshev_sum(normalised_time(t, t_s, t_f), coeffs[k])
