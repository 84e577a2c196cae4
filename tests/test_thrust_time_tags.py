"""The time tags' gyroscopic terms of the robust thrust model (inference/thrust/time_tags.py)."""

import numpy as np

from cassini_bayes.inference.thrust.time_tags import (TAG_VARIANCE_SHARE, events_tag_steps,
                                                      gyro_tag_terms, tag_step_columns)
from cassini_bayes.physics.quadrature import cumulative_trapezoid


def _event(n=60, seed=0):
    """Rates with a step at a few samples (pulses) and a large wheel momentum."""
    rng = np.random.default_rng(seed)
    t = np.arange(n, dtype=float)
    omega = 1e-3 * np.cumsum(rng.normal(size=(n, 3)) * (rng.random((n, 1)) < 0.2), 0)
    h = np.array([20.0, -5.0, 3.0]) + 0.01 * rng.normal(size=(n, 3))
    return t, omega, h, np.diag([300.0, 250.0, 200.0])


def _trapezoid_gyro(t, omega, h, inertia):
    f = np.cross(omega, omega @ inertia.T + h)
    return np.asarray(cumulative_trapezoid(f, t))


def test_columns_and_own_terms_are_the_trapezoids_first_order_change():
    """Tags moved by δ (none on the first sample) change the trapezoid of ∫ ω × (Iω + H) dt by
    Σ δ_i (own term at i + step after i), to first order: checked against the trapezoid itself
    (relative 1e-6 at δ of 1e-6 s; the second order is δ² ~ 1e-12)."""
    t, omega, h, inertia = _event()
    n = t.size
    tiny = np.eye(3) * 1e-30                       # every step and own term kept
    kw = dict(t=t[None], omega=omega[None], h_wheels=h[None], mask=np.ones((1, n)),
              wheel_cov=np.zeros((1, 3, 3)))
    noise = np.array([[1e-15, 0.0]])
    cols = tag_step_columns(t, omega, h, np.ones(n), inertia, tiny, 1.0)
    own = gyro_tag_terms(kw, inertia, noise, 1.0)[0]            # (3, n) per second of δ
    delta = 1e-6 * np.random.default_rng(1).normal(size=n)
    delta[0] = 0.0
    change = _trapezoid_gyro(t + delta, omega, h, inertia) - _trapezoid_gyro(t, omega, h, inertia)
    idx = 1 + np.arange(n - 2)
    assert cols.shape == (n - 2, 3, n)
    predicted = np.einsum("p,pan->na", delta[idx], cols) + (own * delta[None, :]).T
    # the last sample's δ moves only itself (its own term)
    np.testing.assert_allclose(predicted, change, rtol=1e-6, atol=1e-6 * np.abs(change).max())


def test_only_the_steps_that_matter_get_columns():
    """Smooth rates (no pulse) leave a walk far below the noise: no column; a noise level that
    makes the steps large keeps the largest ones until the rest is below the share."""
    t = np.arange(50.0)
    omega = np.tile([1e-4, 0.0, 0.0], (50, 1))
    h = np.tile([10.0, 0.0, 0.0], (50, 1))
    inertia = np.diag([300.0, 250.0, 200.0])
    assert tag_step_columns(t, omega, h, np.ones(50), inertia, np.eye(3) * 1e-8, 0.01).shape[0] == 0
    t, omega, h, inertia = _event()
    b = np.eye(3) * 1e-10
    cols = tag_step_columns(t, omega, h, np.ones(t.size), inertia, b, 0.01)
    f = np.cross(omega, omega @ inertia.T + h)
    var = 0.01**2 * np.sum((0.5 * (f[:-2] - f[2:]))**2, 1) / 1e-10
    assert 0 < cols.shape[0] < t.size - 2
    left = np.sort(var)[::-1][cols.shape[0]:].sum()
    assert left <= TAG_VARIANCE_SHARE < left + np.sort(var)[::-1][cols.shape[0] - 1]


def test_each_event_gets_its_own_block():
    """Two events: the second's columns are zero in the first event and the reverse."""
    t, omega, h, inertia = _event()
    n = t.size
    kw = dict(t=np.stack([t, t]), omega=np.stack([omega, 2 * omega]), h_wheels=np.stack([h, h]),
              mask=np.ones((2, n)), wheel_cov=np.zeros((2, 3, 3)))
    cols = events_tag_steps(kw, inertia, np.array([[1e-6, 0.0], [1e-6, 0.0]]), 0.01)
    per = [tag_step_columns(t, w, h, np.ones(n), inertia, 1e-12 * inertia @ inertia, 0.01)
           for w in (omega, 2 * omega)]
    p0 = per[0].shape[0]
    assert cols.shape[1] == p0 + per[1].shape[0]
    np.testing.assert_array_equal(cols[0, :p0], per[0])
    np.testing.assert_array_equal(cols[1, p0:], per[1])
    assert not cols[0, p0:].any() and not cols[1, :p0].any()
