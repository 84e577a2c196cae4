"""The impulse-bit coordinates of the per-thruster thrust fit
(:func:`cassini_bayes.inference.thrust.coords.physical`): where every thruster fires at one
width the sampler sees ``log b = log F + log j(Δ; τ)`` (shifted to ``log F`` at the prior-median
time constants), an exact reparameterisation: the same physical point has the same log density
in both coordinates.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from cassini_bayes.inference.thrust.coords import log_bit_shift, physical, bit_widths
from cassini_bayes.inference.thrust.data import prepare_thrust
from cassini_bayes.inference.thrust.model import log_density
from cassini_bayes.inference.thrust.prior import THRUST_PRIOR_LOG_SD
from cassini_bayes.simulate import load_scenario, simulate


def test_bit_widths_only_where_every_parameter_fires_at_one_width():
    width = np.array([[0.125, 0.125, 0.125, 0.0], [0.125, 0.125, 0.0, 0.0]])
    thruster = np.array([[0, 1, 0, 7], [1, 0, 0, 0]])
    np.testing.assert_array_equal(bit_widths(width, thruster, np.arange(3)), [0.125, 0.125, 0])
    np.testing.assert_array_equal(bit_widths(width, thruster, np.zeros(3, int)), [0.125])
    two = width.copy()
    two[1, 0] = 0.25                   # thruster 1 fires at 125 and 250 ms
    assert bit_widths(two, thruster, np.arange(3)) is None
    assert bit_widths(two, thruster, np.zeros(3, int)) is None
    assert bit_widths(np.zeros((1, 3)), np.zeros((1, 3), int), np.arange(2)) is None


@pytest.fixture(scope="module")
def espa():
    scenario = load_scenario("biasing_espa_bus")
    run = simulate(jax.random.key(0), scenario)
    return prepare_thrust([(run.telemetry, run.pulses)], scenario.prior, mode="thruster")


def test_bit_coordinates_are_an_exact_reparameterisation(espa):
    """At 20 random points: the log density in impulse-bit coordinates equals the log-F
    density at the same physical point (the map is unit-triangular, so no Jacobian term), to
    1e-3 absolute: the densities are ~-3.5e7 here and differ by rounding (≤ 2e-5 seen); the
    prior taken in the sampler's coordinates instead of the physical point's is off by ≥ 0.04."""
    kw = espa.data
    assert kw.bit_width is not None and np.allclose(kw.bit_width, 0.125)
    kw_f = kw._replace(bit_width=None)
    n_f, n_c = espa.n_f, espa.n_c
    basis = np.asarray(kw.f_basis)
    rng = np.random.default_rng(3)
    for _ in range(20):
        theta = 0.5 * rng.standard_normal(kw.centre.shape)     # about the prior's centre
        p = physical(jnp.asarray(theta), kw, n_f, n_c, False)
        assert np.all(np.isfinite(p.tau))
        x = basis @ theta[:n_f + n_c]
        x[:n_f] -= np.asarray(log_bit_shift(p.tau, kw)) / THRUST_PRIOR_LOG_SD
        theta_f = theta.copy()
        theta_f[:n_f + n_c] = basis.T @ x
        p_f = physical(jnp.asarray(theta_f), kw_f, n_f, n_c, False)
        np.testing.assert_allclose(p_f.thrust, p.thrust, rtol=1e-12)
        np.testing.assert_allclose(p_f.com, p.com, rtol=1e-9, atol=1e-15)
        a = float(log_density(jnp.asarray(theta), kw, n_f, n_c, False))
        b = float(log_density(jnp.asarray(theta_f), kw_f, n_f, n_c, False))
        assert np.isfinite(a)
        assert a == pytest.approx(b, rel=0, abs=1e-3)


def test_bit_coordinates_are_log_f_at_the_prior_median(espa):
    """At the prior-median time constants the shift is zero: the coordinates equal today's."""
    kw = espa.data
    tp = espa.tau
    np.testing.assert_allclose(log_bit_shift(jnp.asarray(tp.median()), kw), 0.0, atol=1e-12)
    off = np.asarray(log_bit_shift(jnp.asarray(tp.median() * 1.3), kw))
    assert np.all(np.abs(off) > 1e-3)


def test_impulse_bit_draws_and_their_report():
    """fit_thrust adds ``bit`` (N s) for the fired thrusters where every thruster fires at one
    width: each draw's ``F_s j(Δ_s; τ)`` (Feldman & Lee §V; exact), and the summary's
    ``thrust_design["impulse_bits"]`` and the report's thrust-design section state them as the
    identified quantity with their width."""
    from types import SimpleNamespace

    import arviz as az

    from cassini_bayes.api._thrust import _impulse_bits_block
    from cassini_bayes.inference.thrust.fit import _add_impulse_bits
    from cassini_bayes.physics.pulse import pulse_impulse
    from cassini_bayes.report._sections import thrust_design_section

    names = ["A1", "A2", "A3"]
    rng = np.random.default_rng(5)
    draws = {"F": rng.uniform(0.9, 1.1, (2, 5, 3)), "tau_delay": rng.uniform(0.003, 0.006, (2, 5)),
             "tau_rise": rng.uniform(0.01, 0.02, (2, 5)),
             "tau_fall": rng.uniform(0.03, 0.05, (2, 5))}
    idata = az.from_dict(posterior=draws, dims={"F": ["thruster"]}, coords={"thruster": names})
    kw = SimpleNamespace(bit_width=np.array([0.125, 0.0, 0.25]))
    _add_impulse_bits(idata, SimpleNamespace(data=kw, thrusters=tuple(names)))
    bit = idata.posterior["bit"]
    assert list(bit.bit_thruster.values) == ["A1", "A3"]
    assert bit.attrs["width_s"] == [0.125, 0.25]
    want = draws["F"][1, 3, 2] * float(pulse_impulse(0.25, *(draws[n][1, 3] for n in
                                                            ("tau_delay", "tau_rise", "tau_fall"))))
    assert float(bit.values[1, 3, 1]) == pytest.approx(want, rel=1e-12)
    params = {"bit[A1]": {"mean": 0.1712, "sd": 0.0011, "q05": 0.1695, "q95": 0.1731}}
    block = _impulse_bits_block(bit, params)
    assert block["width_s"] == {"A1": 0.125, "A3": 0.25}
    html = str(thrust_design_section({"thrust_design": {
        "singular_values": [3.0], "rank": 1, "parameters": 11, "thrust_rank": 1,
        "thrusters": names, "identified": names, "not_fired": ["A2"], "combinations": [],
        "com_told": {}, "impulse_bits": block}}))
    assert "impulse bit" in html and "0.1712" in html and "125" in html
