"""The cumulative trapezoid: exact on a piecewise-linear integrand, NumPy and JAX alike."""

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.physics.quadrature import cumulative_trapezoid


def test_exact_on_linear_integrands_in_any_trailing_shape():
    t = np.array([0.0, 0.5, 1.5, 4.0])
    y = (2.0 * t[:, None, None] + 1.0) * np.arange(1, 7).reshape(1, 2, 3)  # ∫ = t² + t
    out = cumulative_trapezoid(y, t)
    assert isinstance(out, np.ndarray) and out.shape == (4, 2, 3)
    np.testing.assert_allclose(out, (t**2 + t)[:, None, None] * np.arange(1, 7).reshape(1, 2, 3),
                               rtol=1e-14)


def test_jax_inputs_give_the_numpy_numbers_under_jit():
    t = np.cumsum(np.random.default_rng(0).uniform(0.1, 1.0, 50))
    y = np.sin(t)[:, None] * np.array([1.0, -2.0, 0.5])
    ref = cumulative_trapezoid(y, t)
    out = jax.jit(cumulative_trapezoid)(jnp.asarray(y), jnp.asarray(t))
    assert isinstance(out, jax.Array)
    np.testing.assert_allclose(np.asarray(out), ref, rtol=1e-12, atol=1e-15)
