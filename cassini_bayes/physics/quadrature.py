"""The cumulative trapezoid on telemetry samples, one rule for every running integral.

Feldman & Lee Eq 15's gyroscopic impulse, the nuisance columns' integrated torques and wheel
momenta, and the plans' predicted columns all integrate sampled quantities from the first
sample; they use this rule so that they agree to the last bit.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

__all__ = ["cumulative_trapezoid"]


def cumulative_trapezoid(y, t):
    """``∫_{t_0}^{t_i} y dt`` (n, …) by the trapezoid rule on the samples ``t`` (n,) s, 0 at the
    first sample; ``y`` (n, …) in any trailing shape. JAX arrays (traced ones included) give a
    JAX array, anything else a NumPy array: NumPy callers keep NumPy's arithmetic."""
    xp = jnp if isinstance(y, jax.Array) or isinstance(t, jax.Array) else np
    y = xp.asarray(y)
    dt = xp.diff(xp.asarray(t)).reshape((-1,) + (1,) * (y.ndim - 1))
    steps = 0.5 * (y[1:] + y[:-1]) * dt
    return xp.concatenate([xp.zeros_like(y[:1]), xp.cumsum(steps, 0)], 0)
