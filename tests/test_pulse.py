"""Tier (a): thruster pulse response of Feldman & Lee §V (closed form vs. numerical integral)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import quad

from cassini_bayes.physics.pulse import (impulse_ratio, mix_ratio, pulse_impulse,
                                         pulse_impulse_area, pulse_impulse_until,
                                         thrust_profile)

CASES = [(0.125, 0.005, 0.020, 0.065), (0.250, 0.005, 0.020, 0.065), (0.125, 0.005, 0.020, 0.040),
         (0.750, 0.003, 0.015, 0.090), (0.010, 0.005, 0.025, 0.040),
         (0.125, 0.0, 0.045, 0.045)]   # a first-order valve: no delay, rise = fall


_profile = jax.jit(thrust_profile)


def _integral(width, td, tr, tf, upper):
    f = lambda t: float(_profile(t, width, td, tr, tf))  # noqa: E731
    pts = [p for p in (td, width, width + td) if p < upper]
    return quad(f, 0.0, upper, points=pts or None, limit=200, epsabs=1e-14, epsrel=1e-12)[0]


@pytest.mark.parametrize("width, td, tr, tf", CASES)
def test_closed_form_equals_integral_of_profile(width, td, tr, tf):
    """The §V closed form is the exact area under the thrust profile (for Δ ≥ τd)."""
    if width < td:
        pytest.skip("the printed closed form assumes Δ ≥ τd")
    total = _integral(width, td, tr, tf, width + td + 40 * tf)
    assert np.isclose(float(pulse_impulse(width, td, tr, tf)), total, rtol=1e-9, atol=1e-13)


@pytest.mark.parametrize("width, td, tr, tf", CASES)
def test_impulse_until_equals_partial_integral(width, td, tr, tf):
    for upper in (0.5 * td, td + 0.3 * width, width, width + 0.5 * td, width + td + tf, 5.0):
        got = float(pulse_impulse_until(upper, width, td, tr, tf))
        assert np.isclose(got, _integral(width, td, tr, tf, upper), rtol=1e-9, atol=1e-13)
    assert float(pulse_impulse_until(-1.0, width, td, tr, tf)) == 0.0


@pytest.mark.parametrize("width, td, tr, tf", CASES)
def test_impulse_area_is_the_integral_of_the_impulse_so_far(width, td, tr, tf):
    """``pulse_impulse_area`` equals the quadrature of ``pulse_impulse_until`` (rtol 1e-9), is 0
    before the command, and once the pulse has decayed grows as ``j_∞ (t − c)`` with ``c`` the
    thrust profile's centroid."""
    until = jax.jit(pulse_impulse_until)
    for upper in (0.5 * td, td + 0.3 * width, width, width + 0.5 * td, width + td + tf, 1.0):
        pts = [p for p in (td, width, width + td) if 0 < p < upper]
        want = quad(lambda s: float(until(s, width, td, tr, tf)), 0.0, upper, points=pts or None,
                    limit=200, epsabs=1e-15, epsrel=1e-12)[0]
        got = float(pulse_impulse_area(upper, width, td, tr, tf))
        assert np.isclose(got, want, rtol=1e-9, atol=1e-15)
    assert float(pulse_impulse_area(-1.0, width, td, tr, tf)) == 0.0
    end = width + td + 60 * tf
    j_inf = float(pulse_impulse_until(end, width, td, tr, tf))
    moment = quad(lambda s: s * float(_profile(s, width, td, tr, tf)), 0.0, end,
                  points=[p for p in (td, width, width + td) if p > 0] or None, limit=200,
                  epsabs=1e-15, epsrel=1e-12)[0]
    assert np.isclose(float(pulse_impulse_area(end, width, td, tr, tf)),
                      j_inf * end - moment, rtol=1e-9)


def test_impulse_until_derivative_is_the_profile():
    width, td, tr, tf = CASES[0]
    d = jax.grad(lambda t: pulse_impulse_until(t, width, td, tr, tf))
    for t in (0.001, 0.05, 0.127, 0.2, 0.5):
        assert np.isclose(float(d(t)), float(thrust_profile(t, width, td, tr, tf)), atol=1e-12)


def test_impulse_until_tends_to_pulse_impulse():
    width, td, tr, tf = CASES[0]
    assert np.isclose(float(pulse_impulse_until(100.0, width, td, tr, tf)),
                      float(pulse_impulse(width, td, tr, tf)), rtol=1e-14)


def test_thrust_scales_linearly_and_ratio_above_one_when_fall_exceeds_rise():
    assert np.isclose(float(pulse_impulse(0.125, 0.005, 0.02, 0.065, thrust_n=0.75)),
                      0.75 * float(pulse_impulse(0.125, 0.005, 0.02, 0.065)))
    assert float(impulse_ratio(0.125)) > 1.0
    assert float(impulse_ratio(0.125, tau_rise_s=0.05, tau_fall_s=0.02)) < 1.0


def test_gradients_in_time_constants_are_finite_and_match_differences():
    f = lambda tf: mix_ratio(jnp.array([0.125, 0.25]), jnp.array([3.0, 1.0]), tau_fall_s=tf)  # noqa
    g = float(jax.grad(f)(0.065))
    h = 1e-6
    assert np.isclose(g, (float(f(0.065 + h)) - float(f(0.065 - h))) / (2 * h), rtol=1e-6)


@pytest.mark.parametrize("tau", [0.038, 0.045, 0.054])
def test_first_order_valve_impulse_is_thrust_times_width(tau):
    """τd = 0, τr = τf = τ: ``(Δ+τ) + τ(e^{−Δ/τ} − 1) − τ e^{−Δ/τ} = Δ`` exactly, for every width
    (the rise's deficit equals the tail's excess), so impulses alone carry no time constant;
    the long-pulse excess ``c = τf − τr e^{−τd/τr}`` is 0."""
    from cassini_bayes.inference.thrust import long_pulse_excess

    widths = np.array([0.001, 0.125, 0.25, 0.5, 0.75, 2.0])
    np.testing.assert_allclose(np.asarray(pulse_impulse(widths, 0.0, tau, tau, 0.7)),
                               0.7 * widths, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(np.asarray(pulse_impulse_until(10.0, widths, 0.0, tau, tau)),
                               widths, rtol=1e-12, atol=1e-15)
    assert float(long_pulse_excess(0.0, tau, tau)) == 0.0


# τd = 0 exactly puts the clipped phases' ends on ties, where the formula's operation-by-operation
# derivative is a convention of ``jnp.clip``, not a derivative (a sampler never sees τd = 0)
@pytest.mark.parametrize("width, td, tr, tf",
                         [(w, max(td, 1e-6), tr, tf) for w, td, tr, tf in CASES]
                         + [(0.003, 0.005, 0.020, 0.065)])
def test_stated_derivatives_equal_those_of_the_formulas(width, td, tr, tf):
    """The closed-form derivatives of :func:`pulse_impulse` and :func:`pulse_impulse_until` in
    every argument (thrust included) equal the derivatives of their formulas, operation by
    operation (``.fun``, the undecorated function), at times in every phase: before the delay,
    rising, held, decaying, long after; a pulse shorter than its delay and a near-first-order
    valve (τd = 1 µs) included. Exact
    arithmetic on both sides: tolerance 1e-10 relative."""
    times = np.array([0.5 * td, td + 0.3 * width, width + 0.5 * td, width + td + 0.03,
                      width + td + 1.0]) + 1e-4
    for t in times:
        args = (t, width, td, tr, tf, 0.7)
        got = jax.jacfwd(pulse_impulse_until, argnums=tuple(range(6)))(*args)
        want = jax.jacfwd(pulse_impulse_until.fun, argnums=tuple(range(6)))(*args)
        np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=1e-10, atol=1e-13)
    args = (width, td, tr, tf, 0.7)
    got = jax.jacrev(pulse_impulse, argnums=tuple(range(5)))(*args)
    want = jax.jacrev(pulse_impulse.fun, argnums=tuple(range(5)))(*args)
    np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=1e-10, atol=1e-13)
