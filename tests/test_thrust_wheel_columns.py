"""The thrust model's wheel-error columns are the change of Feldman & Lee Eq 17's left side: a
wheel's spin-inertia scale or axis tilt changes its momentum ``H`` and, through Eq 15, the
gyroscopic impulse ``ΔG`` of that momentum."""

from __future__ import annotations

import jax
import numpy as np
import pytest

from cassini_bayes.inference.nuisance import nuisance_layout
from cassini_bayes.inference.thrust.columns import nuisance_columns, wheel_momentum
from cassini_bayes.physics.impulse import impulse_lhs
from cassini_bayes.simulate import load_scenario, simulate

EPS = 1e-3


@pytest.fixture(scope="module")
def espa_columns():
    scenario = load_scenario("biasing_espa_bus")
    tel = simulate(jax.random.key(0), scenario).telemetry
    sc = scenario.prior
    h, _, per_wheel = wheel_momentum(tel, sc)
    layout = nuisance_layout(sc, 1, sorted(tel.active_wheels()))
    cols = nuisance_columns(layout, 0, np.asarray(tel.t), np.asarray(tel.omega),
                            np.asarray(sc.inertia), h, per_wheel)
    wheels = {w.name: (np.asarray(w.axis, float), float(w.inertia)) for w in sc.wheels
              if w.name in layout.wheels}
    return sc, tel, layout, cols - cols[:1], wheels      # the offset absorbs the first row


def _lhs(sc, tel, wheels) -> np.ndarray:
    """Eq 17's left side (n, 3) N m s with the given (axis, spin inertia) per wheel name."""
    h = np.zeros((tel.n, 3))
    for name, (axis, inertia) in wheels.items():
        h += inertia * np.nan_to_num(np.asarray(tel.wheel_rate(name)))[:, None] * axis[None]
    return np.asarray(impulse_lhs(tel.t, tel.omega, np.asarray(sc.inertia), h))


def _moved(wheels, name, axis_step=0.0, scale=1.0):
    out = dict(wheels)
    axis, inertia = wheels[name]
    out[name] = (axis + axis_step, inertia * scale)
    return out


def test_wheel_columns_are_the_left_sides_derivative(espa_columns):
    """Each wheel-scale and axis-tilt column of ``ν`` is minus the derivative of Eq 17's left
    side in that wheel error (linear, so a finite difference is exact to rounding: measured
    ≤ 1e-12 of the column's size; allowed 1e-8). Without the ``ΔG`` part (``∫ ω × J ρ g dt``)
    the scale columns are off by 2.9-3.4 % of their size on this event: the test fails there."""
    sc, tel, layout, cols, wheels = espa_columns
    base = _lhs(sc, tel, wheels)
    checks = [(name, layout.wheel_block.start + k, _moved(wheels, name, scale=1 + EPS))
              for k, name in enumerate(layout.scale_wheels)]
    a0 = layout.slices["wheel_axes"].start
    checks += [(name, a0 + 2 * k + j, _moved(wheels, name, axis_step=EPS * layout.tilt_u[k, j]))
               for k, name in enumerate(layout.wheels) for j in range(2)]
    assert len(checks) == 3 * len(layout.wheels)
    for name, col, moved in checks:
        want = -(_lhs(sc, tel, moved) - base) / EPS
        assert np.max(np.abs(cols[:, :, col] - want)) < 1e-8 * np.max(np.abs(want)), (name, col)
