"""Monte Carlo mass-property analysis of the RWA4 axis (Brown 2012 §III.B)."""

from __future__ import annotations

import jax
import numpy as np
import pytest

from cassini_bayes.analysis.mass_property import (
    ARTICULATION_CONE_RAD,
    RWA1_PHI_RAD,
    axis_on_cone,
    flight_estimate_box,
    mass_property_mc,
    rcs_axis_error_rad,
    requirement_box,
    sample_assumed_inertia,
    summarise_errors,
)
from cassini_bayes.analysis.paper_facts import TABLE1
from cassini_bayes.spacecraft import load_spacecraft

CONE = (np.radians(-30.0), np.radians(210.0))


@pytest.fixture(scope="module")
def sc():
    return load_spacecraft("cassini_post_probe")


def test_cone_passes_through_the_fixed_wheel_axes(sc):
    # Brown (2012) §I: RWA4 articulates on the 54.7356° cone; RWA1 at 90°, RWA2 210°, RWA3 −30°.
    assert np.degrees(ARTICULATION_CONE_RAD) == pytest.approx(54.7356, abs=5e-5)
    for name, phi_deg in (("RWA1", 90.0), ("RWA2", 210.0), ("RWA3", -30.0)):
        u = np.asarray(axis_on_cone(np.radians(phi_deg)))
        np.testing.assert_allclose(u, sc.wheel(name).axis, atol=1e-9)


def test_no_error_when_assumed_inertia_is_true(sc):
    phi = np.linspace(-np.pi, np.pi, 101)
    err = np.asarray(rcs_axis_error_rad(sc.inertia, sc.inertia, axis_on_cone(phi)))
    assert err.shape == (101,)
    assert np.all(err < 1e-12)


def test_error_of_a_scaled_moment_is_exact():
    # Diagonal I, Î = I with Ixx scaled by (1 + d): û ∝ ((1+d) sinθ cosφ, sinθ sinφ, cosθ); at
    # φ = 0 the angle is atan((1 + d) tanθ) − θ.
    inertia = np.diag([8000.0, 7000.0, 4000.0])
    d, theta = 0.1, ARTICULATION_CONE_RAD
    assumed = np.diag([8000.0 * (1 + d), 7000.0, 4000.0])
    err = float(rcs_axis_error_rad(inertia, assumed, axis_on_cone(0.0)))
    assert err == pytest.approx(np.arctan((1 + d) * np.tan(theta)) - theta, rel=1e-12)
    # a uniform scale of the whole tensor changes nothing
    assert float(rcs_axis_error_rad(inertia, 1.07 * inertia, axis_on_cone(0.3))) < 1e-12


def test_batched_true_inertia_matches_single(sc):
    key = jax.random.key(3)
    assumed = sample_assumed_inertia(key, sc.inertia, requirement_box(), 2000)[:5]
    u = axis_on_cone(np.linspace(0, 3, 5))
    single = np.asarray(rcs_axis_error_rad(sc.inertia, assumed, u))
    batched = np.asarray(rcs_axis_error_rad(np.broadcast_to(sc.inertia, (5, 3, 3)), assumed, u))
    np.testing.assert_allclose(single, batched, rtol=1e-10)


def test_samples_stay_in_the_box(sc):
    box = requirement_box(0.10, 75.0)
    i_hat = np.asarray(sample_assumed_inertia(jax.random.key(0), sc.inertia, box, 20_000))
    frac = np.diagonal(i_hat, axis1=1, axis2=2) / np.diag(sc.inertia) - 1
    assert np.all(np.abs(frac) <= 0.10 + 1e-12)
    prod = i_hat[:, [0, 0, 1], [1, 2, 2]] - sc.inertia[[0, 0, 1], [1, 2, 2]]
    assert np.all(np.abs(prod) <= 75.0 + 1e-9)
    np.testing.assert_allclose(i_hat, np.swapaxes(i_hat, 1, 2))  # symmetric
    # uniform within the bounds: both ends of every interval are reached (20 000 draws)
    assert np.all(frac.max(0) > 0.099) and np.all(frac.min(0) < -0.099)


def test_error_grows_with_the_perturbation(sc):
    # Common random numbers (same key) so the comparison is of the box size alone; the error is
    # first order in the perturbation, so the 99th percentile is close to proportional to the scale.
    key = jax.random.key(11)
    box = requirement_box()
    p99 = [summarise_errors(mass_property_mc(key, sc.inertia, box.scaled(s), 20_000,
                                             phi_range_rad=CONE).error_rad).p99_deg
           for s in (0.1, 0.2, 0.5, 1.0)]
    assert np.all(np.diff(p99) > 0)
    assert p99[1] / p99[0] == pytest.approx(2.0, rel=0.02)


def test_flight_estimate_box_spans_table1(sc):
    box = flight_estimate_box(("pre_soi", "post_prm", "post_probe"))
    pred = np.array([TABLE1[e]["pred"] for e in TABLE1], float)
    est = np.array([TABLE1[e]["est"] for e in TABLE1], float)
    moi = (pred[:, :3] - est[:, :3]) / pred[:, :3]   # Feldman & Lee Eq 12 (as a fraction)
    poi = pred[:, 3:] - est[:, 3:]                    # Feldman & Lee Eq 13
    np.testing.assert_allclose(box.moi_low, moi.min(0))
    np.testing.assert_allclose(box.moi_high, moi.max(0))
    np.testing.assert_allclose(box.poi_low, poi.min(0))
    np.testing.assert_allclose(box.poi_high, poi.max(0))
    # Post-PRM Izz: (4449 − 4223)/4449 = +5.08 % (Table 1)
    assert round(100 * box.moi_high[2], 2) == 5.08
    with pytest.raises(ValueError, match="unknown epoch"):
        flight_estimate_box(("launch",))


def test_hundred_thousand_draws_run(sc):
    key = jax.random.key(20260315)
    d = mass_property_mc(key, sc.inertia, requirement_box(), 100_000, phi_range_rad=CONE)
    assert d.error_rad.shape == (100_000,) and d.phi_rad.shape == (100_000,)
    e = np.asarray(d.error_rad)
    assert np.all(np.isfinite(e)) and np.all(e >= 0)
    phi = np.asarray(d.phi_rad)
    assert phi.min() >= CONE[0] and phi.max() <= CONE[1]
    again = mass_property_mc(key, sc.inertia, requirement_box(), 100_000, phi_range_rad=CONE)
    np.testing.assert_array_equal(e, np.asarray(again.error_rad))  # keys, not hidden state
    s = summarise_errors(e)
    assert s.p50_deg < s.p95_deg < s.p99_deg <= s.max_deg


def test_rwa1_axis_fixed_and_normal_distribution(sc):
    key = jax.random.key(5)
    d = mass_property_mc(key, sc.inertia, flight_estimate_box(), 2000, distribution="normal")
    np.testing.assert_allclose(np.asarray(d.phi_rad), RWA1_PHI_RAD)
    assert np.all(np.isfinite(np.asarray(d.error_rad)))
    with pytest.raises(ValueError, match="distribution"):
        mass_property_mc(key, sc.inertia, flight_estimate_box(), 2000, distribution="cauchy")


def test_reduction_agrees_with_the_rcs_least_squares_estimator(sc):
    """``û ∝ Î I⁻¹ u`` is what Brown's Eq 1 estimator returns on drift data at a fixed attitude."""
    rwa4 = pytest.importorskip("cassini_bayes.estimators.rwa4")
    n, j4, d_rho = 20, 0.1595, 200 * 2 * np.pi / 60        # +200 rpm spin-up (Brown §III.B)
    u_true = np.asarray(axis_on_cone(np.radians(40.0)))
    omega_b = -j4 * d_rho * np.linalg.solve(sc.inertia, u_true)   # I Δω = −J Δρ u
    omega = np.vstack([np.zeros((n, 3)), np.tile(omega_b, (n, 1))])
    rates = np.zeros((2 * n, 4))
    rates[n:, 3] = d_rho
    q = np.tile([0.0, 0.0, 0.0, 1.0], (2 * n, 1))
    mask_a = np.arange(2 * n) < n
    axes = np.vstack([sc.wheel_axes[:3], u_true])
    assumed = np.asarray(sample_assumed_inertia(jax.random.key(2), sc.inertia, requirement_box(),
                                                2000))[0]
    fit = rwa4.fit_axis_rcs(q, omega, rates, axes, np.full(4, j4), assumed, mask_a, ~mask_a)
    expect = float(rcs_axis_error_rad(sc.inertia, assumed, u_true))
    assert expect > np.radians(0.1)
    assert rwa4.axis_error_deg(fit.axis, u_true) == pytest.approx(np.degrees(expect), rel=1e-8)


def test_single_element_box():
    box = flight_estimate_box()
    izz = box.only(2)
    np.testing.assert_array_equal(izz.moi_low, [0.0, 0.0, box.moi_low[2]])
    np.testing.assert_array_equal(izz.moi_high, [0.0, 0.0, box.moi_high[2]])
    np.testing.assert_array_equal(izz.poi_low, 0.0)
    ixz = box.only(4)
    np.testing.assert_array_equal(ixz.poi_low, [0.0, box.poi_low[1], 0.0])
    np.testing.assert_array_equal(ixz.moi_high, 0.0)
