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


@pytest.fixture(scope="module")
def prepared_event():
    """A prepared mixed-width ESPA event (robust, inertia fixed) and the model's own left side
    as a function of the wheel momentum and the body rates."""
    import jax.numpy as jnp

    from cassini_bayes.estimators.leak import interval_means
    from cassini_bayes.inference.thrust import prepare_thrust
    from cassini_bayes.inference.thrust.likelihood import PulseLayout
    from cassini_bayes.inference.thrust.time_tags import left_side_at_times

    scenario = load_scenario("biasing_espa_bus_mixed_widths")
    sim = simulate(jax.random.key(1), scenario)
    sc = scenario.prior
    p = prepare_thrust([(sim.telemetry, sim.pulses)], sc, mode="thruster", robust=True,
                       flex="off")
    ev = jax.tree_util.tree_map(lambda x: np.asarray(x)[0], p.data.events)
    lay = PulseLayout(*(np.asarray(x)[0] for x in p.data.events.pulses))
    q_f = np.asarray(sc.moment_matrix) * p.thrust_pred
    inertia = np.asarray(sc.inertia, float)

    def left(h, omega, omega_mid, h_mid):
        f = left_side_at_times(ev.t, omega, h, lay, inertia, q_f, p.tau.median(), omega_mid,
                               h_mid)
        return f(jnp.asarray(ev.t))[0][:sim.telemetry.n]

    return sim, sc, p, ev, inertia, left, interval_means


def _relative(col, want):
    """Largest difference of two (n, 3) columns over the second's size, first rows aligned
    (the event's offset absorbs a constant)."""
    want = want - want[:1]
    return np.max(np.abs((col - col[:1]) - want)) / np.max(np.abs(want))


def test_wheel_columns_follow_the_rate_step_correction(prepared_event):
    """In the prepared problem each wheel tilt column is minus the derivative of the left side
    *as the model computes it*: the trapezoid's ``ΔG`` and its correction across the pulses'
    rate steps (:func:`~cassini_bayes.physics.impulse.rate_step_correction`, linear in the
    wheels' momentum; measured ≤ 6e-13 of the column's size, allowed 1e-8). Without the
    correction's part (:func:`nuisance_columns` with no ``d_theta``) a tilt column is off by
    7-15 % of its size on this event (allowed: more than 1 %): the test fails there."""
    sim, sc, p, ev, inertia, left, interval_means = prepared_event
    n = sim.telemetry.n
    _, _, per_wheel = wheel_momentum(sim.telemetry, sc)
    h0 = np.asarray(ev.h_wheels)[:n]

    def at(h):
        h = np.r_[h, np.repeat(h[-1:], ev.t.size - n, 0)]
        return np.asarray(left(h, ev.omega, ev.omega_mid, interval_means(h)))

    base = at(h0)
    plain = nuisance_columns(p.layout, 0, np.asarray(sim.telemetry.t),
                             np.asarray(sim.telemetry.omega), inertia, h0, per_wheel)
    a0 = p.layout.slices["wheel_axes"].start
    worst = 0.0
    for k, name in enumerate(p.layout.wheels):
        for j in range(2):
            moved = h0 + EPS * per_wheel[name][:, None] * p.layout.tilt_u[k, j]
            want = -(at(moved) - base) / EPS
            col = np.asarray(ev.nu_cols)[a0 + 2 * k + j].T[:n]
            assert _relative(col, want) < 1e-8, (name, j)
            worst = max(worst, _relative(plain[:, :, a0 + 2 * k + j], want))
    assert worst > 1e-2


def test_gyro_columns_are_the_left_sides_derivative(prepared_event):
    """Each gyro bias and scale-factor column is minus the derivative (a JVP, exact) of the
    model's left side in that error, ``ω = ω_meas − b − s ∘ ω_meas``: ``I δω``, the ``ΔG`` of
    Eq 15 (``δω × (I ω + H)`` and ``ω × I δω``) and the rate-step correction (measured ≤ 2e-15,
    allowed 1e-8). With ``I diag(ω) s`` alone, the scale columns were off by 3-14 % on this
    event, and ``∫ b × H_w dt`` alone left the bias columns 0.04-0.08 % off: the test fails
    there."""
    import jax.numpy as jnp

    sim, sc, p, ev, inertia, left, interval_means = prepared_event
    n = sim.telemetry.n
    w0 = np.asarray(ev.omega)
    sl = p.layout.slices
    for block, shape in (("gyro_bias", lambda a: np.eye(3)[a] + 0.0 * w0),
                         ("gyro_scale", lambda a: w0[:, a:a + 1] * np.eye(3)[a])):
        for a in range(3):
            dw = -shape(a)
            _, d_left = jax.jvp(lambda w, wm: left(ev.h_wheels, w, wm, ev.h_mid),
                                (jnp.asarray(w0), jnp.asarray(ev.omega_mid)),
                                (jnp.asarray(dw), jnp.asarray(interval_means(dw))))
            col = np.asarray(ev.nu_cols)[sl[block].start + a].T[:n]
            assert _relative(col, -np.asarray(d_left)) < 1e-8, (block, a)
