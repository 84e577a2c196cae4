"""Goodyear's universal-variable conic propagation (Lee §3.3.1, Eqs 12-14).

Tier (a): against an independent propagator, SciPy's DOP853 integrating r̈ = −μ r/|r|³ at
rtol 2.3e-14 (its tightest), to 1e-9 relative in position over several orbits, forward and
backward, on elliptic, near-parabolic and hyperbolic motion; the paper's straight-line remark;
exact derivatives; and a hypothesis sweep of random states that must never give a NaN.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from cassini_bayes.errors import InputError
from cassini_bayes.ivp import conic
from cassini_bayes.ivp.conic import fg_coefficients, goodyear_series, propagate_conic

MU_SATURN = 3.7931208e16   # m^3/s^2
R = 1.2e9                  # m, about Titan's distance


def dop853(r0, v0, mu, dt):
    """The reference: the two-body equation integrated by DOP853 at its tightest tolerance."""
    def rhs(_t, y):
        return np.concatenate([y[3:], -mu * y[:3] / np.linalg.norm(y[:3]) ** 3])

    s = solve_ivp(rhs, (0.0, dt), np.concatenate([r0, v0]), method="DOP853", rtol=2.3e-14,
                  atol=1e-30)
    assert s.success
    return s.y[:3, -1], s.y[3:, -1]


def state(e: float, nu_deg: float = 40.0, incl_deg: float = 25.0):
    """State at true anomaly ``nu`` of an orbit of eccentricity ``e`` and periapsis R/3."""
    q = R / 3
    p = q * (1 + e)
    nu = np.radians(nu_deg)
    r = p / (1 + e * np.cos(nu))
    h = np.sqrt(MU_SATURN * p)
    r_pf = r * np.array([np.cos(nu), np.sin(nu), 0.0])
    v_pf = MU_SATURN / h * np.array([-np.sin(nu), e + np.cos(nu), 0.0])
    c, s = np.cos(np.radians(incl_deg)), np.sin(np.radians(incl_deg))
    rot = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    return rot @ r_pf, rot @ v_pf


def period(r0, v0, mu):
    a = 1.0 / (2.0 / np.linalg.norm(r0) - v0 @ v0 / mu)
    return 2 * np.pi * np.sqrt(a ** 3 / mu)


# (name, eccentricity, time span in periods for ellipses, in days otherwise)
CASES = [("elliptic e=0.3", 0.3, 3.7), ("elliptic e=0.9", 0.9, 3.3),
         ("near-parabolic e=1-1e-6", 1 - 1e-6, 30.0), ("near-parabolic e=1+1e-6", 1 + 1e-6, 30.0),
         ("hyperbolic e=2.5", 2.5, 30.0)]


@pytest.mark.parametrize("name, e, span", CASES, ids=[c[0] for c in CASES])
@pytest.mark.parametrize("direction", [1.0, -1.0], ids=["forward", "backward"])
def test_agrees_with_dop853(name, e, span, direction):
    r0, v0 = state(e)
    dt = direction * (span * period(r0, v0, MU_SATURN) if e < 0.99 else span * 86400.0)
    r_ref, v_ref = dop853(r0, v0, MU_SATURN, dt)
    r, v = propagate_conic(r0, v0, MU_SATURN, dt)
    assert np.linalg.norm(np.asarray(r) - r_ref) / np.linalg.norm(r_ref) < 1e-9
    assert np.linalg.norm(np.asarray(v) - v_ref) / np.linalg.norm(v_ref) < 1e-9


def test_a_wrong_mu_fails_the_same_comparison():
    """The comparison can fail: μ off by 1e-6 moves the e = 0.3 orbit by more than 1e-9."""
    r0, v0 = state(0.3)
    dt = 3.7 * period(r0, v0, MU_SATURN)
    r_ref, _ = dop853(r0, v0, MU_SATURN, dt)
    r, _ = propagate_conic(r0, v0, MU_SATURN * (1 + 1e-6), dt)
    assert np.linalg.norm(np.asarray(r) - r_ref) / np.linalg.norm(r_ref) > 1e-7


def test_series_match_the_closed_forms():
    """s_k of Eq 13 are cos/cosh forms: s0 = cosh(√α Ψ), s1 = sinh(√α Ψ)/√α, s2 = (s0 − 1)/α,
    s3 = (s1 − Ψ)/α; for α < 0 the trigonometric ones; for α = 0 Ψᵏ/k!."""
    psi = np.array([1e-3, 0.7, 3.0, 25.0])
    for alpha in (2.3, -2.3):
        x = np.sqrt(abs(alpha)) * psi
        c0, c1 = (np.cosh(x), np.sinh(x)) if alpha > 0 else (np.cos(x), np.sin(x))
        s1_ref = c1 / np.sqrt(abs(alpha))
        ref = (c0, s1_ref, (c0 - 1) / alpha, (s1_ref - psi) / alpha)
        got = goodyear_series(psi, np.full_like(psi, alpha))
        for k, (g, r) in enumerate(zip(got, ref)):
            # the closed forms of s2, s3 cancel at small Ψ: compare where they are accurate
            ok = psi > (0.1 if k >= 2 else 0.0)
            np.testing.assert_allclose(np.asarray(g)[ok], r[ok], rtol=1e-12, err_msg=f"s{k}")
    got = goodyear_series(psi, np.zeros_like(psi))
    for k in range(4):
        np.testing.assert_allclose(np.asarray(got[k]), psi ** k / np.prod(np.arange(1, k + 1)),
                                   rtol=1e-15)


def test_first_terms_give_the_straight_line():
    """Lee §3.3.1: keeping only the first terms of F, G (Eq 14) gives r = r0 + (t − t0) v0 and
    v = v0. With μ = 0 every other term vanishes: F = 1, G = Δt, F' = 0, G' = 1 exactly."""
    r0, v0 = jnp.array([7e6, -2e6, 1e6]), jnp.array([300.0, 7.5e3, -1e3])
    for dt in (1234.5, -5e4, 3e7):
        F, G, Fd, Gd, _ = fg_coefficients(r0, v0, 0.0, dt)
        assert (float(F), float(Fd), float(Gd)) == (1.0, 0.0, 1.0)
        assert abs(float(G) - dt) <= 1e-12 * abs(dt)
        r, v = propagate_conic(r0, v0, 0.0, dt)
        np.testing.assert_allclose(np.asarray(r), np.asarray(r0 + dt * v0), rtol=1e-13)
        np.testing.assert_allclose(np.asarray(v), np.asarray(v0), rtol=1e-15)
    # a small μ departs from the straight line in proportion to μ (the terms dropped are
    # μ s2/|r0| and μ s3): doubling μ doubles the gap
    dt = 100.0

    def gap(mu):
        r, _ = propagate_conic(r0, v0, mu, dt)
        return np.linalg.norm(np.asarray(r - (r0 + dt * v0)))

    assert gap(2e6) / gap(1e6) == pytest.approx(2.0, rel=1e-4)


def test_many_states_and_times_broadcast():
    r0, v0 = state(0.3)
    dts = np.linspace(-1e6, 1e6, 7)
    r, v = propagate_conic(np.tile(r0, (5, 1, 1)), np.tile(v0, (5, 1, 1)),
                           np.full((5, 7), MU_SATURN), np.tile(dts, (5, 1)))
    assert r.shape == v.shape == (5, 7, 3)
    one, _ = propagate_conic(r0, v0, MU_SATURN, dts[3])
    np.testing.assert_allclose(np.asarray(r[2, 3]), np.asarray(one), rtol=1e-15)


def test_compiles_once_per_shape():
    r0, v0 = state(0.5)
    propagate_conic(r0, v0, MU_SATURN, np.linspace(0, 1e5, 11))
    size = conic._propagate._cache_size()
    propagate_conic(r0 * 1.1, v0, MU_SATURN * 0.9, np.linspace(-1e5, 0, 11))
    assert conic._propagate._cache_size() == size


def test_derivatives_are_exact():
    """jax.grad through the implicit Newton step equals central finite differences and the
    forward-mode Jacobian."""
    r0, v0 = (jnp.asarray(x) for x in state(0.6))
    dt = 2.5e5

    def x_of(mu, r0, v0, dt):
        return propagate_conic(r0, v0, mu, dt).r[0]

    g = jax.grad(x_of, argnums=(0, 1, 2, 3))(MU_SATURN, r0, v0, dt)
    h = 1e-6
    fd_mu = (x_of(MU_SATURN * (1 + h), r0, v0, dt) - x_of(MU_SATURN * (1 - h), r0, v0, dt)) / (
        2 * h * MU_SATURN)
    assert float(g[0]) == pytest.approx(float(fd_mu), rel=1e-6)
    fd_dt = (x_of(MU_SATURN, r0, v0, dt + 1.0) - x_of(MU_SATURN, r0, v0, dt - 1.0)) / 2.0
    v_dt = propagate_conic(r0, v0, MU_SATURN, dt).v[0]
    assert float(g[3]) == pytest.approx(float(v_dt), rel=1e-9)   # ∂r/∂t = v
    assert float(g[3]) == pytest.approx(float(fd_dt), rel=1e-6)
    jf = jax.jacfwd(lambda r: propagate_conic(r, v0, MU_SATURN, dt).r)(r0)
    jr = jax.jacrev(lambda r: propagate_conic(r, v0, MU_SATURN, dt).r)(r0)
    np.testing.assert_allclose(np.asarray(jf), np.asarray(jr), rtol=1e-9, atol=1e-12)


def invariants(r, v, mu):
    h = np.cross(r, v)
    energy = 0.5 * np.sum(v * v, -1) - mu / np.linalg.norm(r, axis=-1)
    return h, energy


@settings(max_examples=600, deadline=None, derandomize=True)
@given(log_r=st.floats(3.0, 12.0), speed=st.floats(0.0, 3.0), gamma=st.floats(-1.5, 1.5),
       log_mu=st.one_of(st.just(-np.inf), st.floats(5.0, 21.0)),
       log_dt=st.floats(-3.0, 9.0), backward=st.booleans(), theta=st.floats(0.0, 6.28))
def test_random_states_never_fail(log_r, speed, gamma, log_mu, log_dt, backward, theta):
    """Any state (1 km - 1e9 km, speed 0-3 × escape speed, any flight-path angle, μ = 0 or
    1e5-1e21 m³/s², |Δt| 1 ms - 30 years, either sign): a finite answer that conserves the
    angular momentum and energy. It comes back to the start when propagated back, except through
    a collision (periapsis below 1e-3 |r0|, where r = 0 is singular), after more than 1e5
    periods (the whole periods removed cost k·P·ε of phase) or across a change of distance
    beyond 1e4× (an ill-conditioned return: rounding far out is magnified close in)."""
    r = 10.0 ** log_r
    mu = 0.0 if np.isinf(log_mu) else 10.0 ** log_mu
    v_esc = np.sqrt(2 * mu / r) if mu > 0 else 10.0 ** (log_r / 2)
    r0 = r * np.array([np.cos(theta), np.sin(theta), 0.3])
    v0 = speed * v_esc * np.array([-np.sin(theta + gamma), np.cos(theta + gamma), 0.1])
    dt = (-1.0 if backward else 1.0) * 10.0 ** log_dt
    rr, vv = (np.asarray(x) for x in propagate_conic(r0, v0, mu, dt))
    assert np.all(np.isfinite(rr)) and np.all(np.isfinite(vv))
    h0, e0 = invariants(r0, v0, mu)
    h1, e1 = invariants(rr, vv, mu)
    scale_h = np.linalg.norm(r0) * np.linalg.norm(v0) + np.linalg.norm(rr) * np.linalg.norm(vv)
    assert np.linalg.norm(h1 - h0) <= 1e-9 * scale_h + 1e-300
    scale_e = 0.5 * (v0 @ v0 + vv @ vv) + mu / np.linalg.norm(r0) + mu / np.linalg.norm(rr)
    assert abs(e1 - e0) <= 1e-9 * scale_e
    if mu > 0:
        energy = e0
        ecc = np.sqrt(max(0.0, 1 + 2 * energy * (h0 @ h0) / mu ** 2))
        q = (h0 @ h0) / (mu * (1 + ecc))
        periods = abs(dt) / (2 * np.pi * np.sqrt((-mu / (2 * energy)) ** 3 / mu)) \
            if energy < 0 else 0.0
        if q < 1e-3 * r or periods > 1e5:
            return
    if np.linalg.norm(rr) > 1e4 * r:
        return
    back, _ = (np.asarray(x) for x in propagate_conic(rr, vv, mu, -dt))
    assert np.linalg.norm(back - r0) <= 1e-7 * (np.linalg.norm(r0) + np.linalg.norm(rr))


def test_ten_thousand_random_states_at_once():
    """The vectorised path on 10⁴ random states and times: no NaN, invariants kept."""
    rng = np.random.default_rng(33)
    n = 10_000
    r0 = rng.normal(size=(n, 3)) * 10.0 ** rng.uniform(4, 11, (n, 1))
    mu = np.where(rng.uniform(size=n) < 0.05, 0.0, 10.0 ** rng.uniform(8, 20, n))
    v_esc = np.sqrt(2 * np.maximum(mu, 1e6) / np.linalg.norm(r0, axis=1))
    v0 = rng.normal(size=(n, 3)) / np.sqrt(3) * (v_esc * rng.uniform(0, 2.5, n))[:, None]
    dt = rng.choice([-1, 1], n) * 10.0 ** rng.uniform(-2, 8, n)
    r, v = (np.asarray(x) for x in propagate_conic(r0, v0, mu, dt))
    assert np.isfinite(r).all() and np.isfinite(v).all()
    h0, e0 = invariants(r0, v0, mu)
    h1, e1 = invariants(r, v, mu)
    scale = np.linalg.norm(r0, axis=1) * np.linalg.norm(v0, axis=1) + \
        np.linalg.norm(r, axis=1) * np.linalg.norm(v, axis=1)
    assert np.all(np.linalg.norm(h1 - h0, axis=1) <= 1e-9 * scale + 1e-300)


@pytest.mark.parametrize("args, words", [
    (([1.0, 0, 0], [0, 1.0, 0], -1.0, 1.0), ["mu", "negative"]),
    (([0.0, 0, 0], [0, 1.0, 0], 1.0, 1.0), ["r0", "zero vector"]),
    (([1.0, np.nan, 0], [0, 1.0, 0], 1.0, 1.0), ["r0", "non-finite"]),
    (([1.0, 0, 0], [0, np.inf, 0], 1.0, 1.0), ["v0", "non-finite"]),
    (([1.0, 0, 0], [0, 1.0, 0], 1.0, np.nan), ["dt", "non-finite"]),
    (([1.0, 0], [0, 1.0, 0], 1.0, 1.0), ["r0", "3-vectors"]),
])
def test_bad_input_is_one_line(args, words):
    with pytest.raises(InputError) as e:
        propagate_conic(*args)
    msg = str(e.value)
    assert "\n" not in msg and all(w in msg for w in words), msg
