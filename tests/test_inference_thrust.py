"""Thrust and pulse time-constant posterior (cassini_bayes.inference.thrust).

Fast tests check the model's pieces exactly; the recovery tests simulate biasing events and
sample, so they are marked ``slow``.
"""

from __future__ import annotations

import warnings
from functools import partial
from types import SimpleNamespace

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import stats

from cassini_bayes.errors import InputError
from cassini_bayes.inference.thrust import (TAU_NAMES, draw_tau_prior, prepare_thrust,
                                            pulse_layout, tau_prior, thruster_impulse, thrust_names)
from cassini_bayes.physics.impulse import impulse_from_pulses
from cassini_bayes.spacecraft import load_spacecraft
from cassini_bayes.telemetry import PulseLog, Telemetry
from margins import DIVERGENCES_MAX, assert_mixed


def _pulses(seed=0, n_pulses=40, span=200.0):
    rng = np.random.default_rng(seed)
    t_on = np.sort(rng.uniform(1.0, span - 5.0, n_pulses)).round(3)
    thr = rng.integers(0, 8, n_pulses)
    width = rng.choice([0.125, 0.25, 0.5, 0.75], n_pulses)
    return t_on, thr, width


# rows of Q that pick thrusters (0, 1, 2), (3, 4, 5), (6, 7): thruster_impulse gives j itself
_PICK = [np.eye(8)[:3], np.eye(8)[3:6], np.eye(8)[[6, 7, 7]]]


def _impulse_per_thruster(layout, tau):
    """(n, 8) s: the per-newton impulse ``j`` of :func:`thruster_impulse`, three thrusters at a
    time."""
    j = [np.asarray(thruster_impulse(layout, jnp.asarray(q), *tau)) for q in _PICK]
    return np.concatenate([j[0], j[1], j[2][:2]]).T


def test_sparse_pulse_impulse_equals_dense():
    """The O(m K) accumulation equals physics.impulse_from_pulses (Feldman & Lee §V profile),
    the pulses in any order."""
    t = np.arange(0.0, 200.0, 1.0)
    t_on, thr, width = _pulses()
    order = np.random.default_rng(1).permutation(t_on.size)
    slot = np.searchsorted(t, t_on)
    k = int(np.ceil((0.75 + 0.02 + 1.5) / 1.0)) + 1
    layout = pulse_layout(t, t_on[order], thr[order], width[order], slot[order], k, 8)
    for tau in [(0.005, 0.020, 0.065), (0.003, 0.015, 0.090)]:
        dense = impulse_from_pulses(t, t_on, thr, width, *tau)
        np.testing.assert_allclose(_impulse_per_thruster(layout, tau), np.asarray(dense),
                                   atol=1e-10)


def _event(t, omega, h, rates, wheel_cov, pulses=None):
    """EventData of one event with every sample's time-tag ``rates`` (8, n) and no nuisance
    columns; ``pulses`` ``(t_on, thruster, width)`` (default: none)."""
    from cassini_bayes.inference.gaussian import RankOneRows, column_statistics
    from cassini_bayes.inference.thrust.likelihood import EventData
    from cassini_bayes.physics.impulse import impulse_lhs_basis

    n = t.size
    t_on, thr, width = pulses or (np.zeros(1), np.zeros(1, int), np.zeros(1))
    slot = np.where(width > 0, np.searchsorted(t, t_on), n)
    basis = np.asarray(impulse_lhs_basis(jnp.asarray(t), jnp.asarray(omega),
                                         jnp.asarray(h))).transpose(0, 2, 1)
    none = np.zeros((0, 3, n))
    return EventData(t=t, omega=omega, h_wheels=h, mask=np.ones(n), t_on=t_on, thruster=thr,
                     width=width, slot=slot, pulses=pulse_layout(t, t_on, thr, width, slot, 2, 8),
                     wheel_cov=wheel_cov, nu_cols=none, time_tag_rates=np.asarray(rates),
                     time_tag_gyro=np.zeros((3, n)),
                     rank_one=RankOneRows(np.arange(n), (np.zeros((0, n)),) * 3),
                     lhs_wheels=basis[0],
                     lhs_inertia=basis[1:], nu_stats=column_statistics(none, np.ones(n)),
                     omega_mid=_interval_means(omega), h_mid=_interval_means(h),
                     **_second_order(t, omega, h, t_on, thr, width, slot))


def _second_order(t, omega, h, t_on, thr, width, slot) -> dict:
    """The second-order rate-step fields of :class:`EventData` (the data's changes per interval
    and the thrusters' moments at Feldman & Lee's time constants)."""
    from cassini_bayes.physics.rate_step_moments import interval_moments, step_pairs

    m, p = interval_moments(t, t_on, thr, width, slot, 2, 8, (0.005, 0.020, 0.065))
    change = lambda x: np.diff(x, axis=0, prepend=x[:1]).T  # noqa: E731
    return dict(d_omega=change(omega), d_h=change(h), dt=np.diff(t, prepend=t[:1]),
                step_moments=m, step_pairs=step_pairs(p))


def _interval_means(x):
    """(3, n): the mean of samples ``i − 1`` and ``i`` of ``x`` (n, 3), the first sample at 0."""
    x = np.asarray(x, float)
    return np.concatenate([x[:1], 0.5 * (x[1:] + x[:-1])]).T


def test_offset_marginal_matches_dense_gaussian():
    """The flat-offset marginal with per-sample covariances ``B + m_i m_iᵀ`` equals the dense
    3n-dimensional Gaussian with a N(0, V I) offset as V → ∞ (times (2π V)^{3/2}); masked rows
    drop out; with ``m = 0`` it is the equal-covariance closed form
    ``Σ log N(r_i − r̄; 0, B) + (3/2) log 2π + ½ log|B| − (3/2) log n``."""
    from scipy.linalg import block_diag
    from scipy.stats import multivariate_normal

    from cassini_bayes.inference.gaussian import RankOneRows, column_statistics, offset_marginal

    rng = np.random.default_rng(3)
    n = 6
    a = rng.normal(size=(3, 3))
    b = a @ a.T + 0.5 * np.eye(3)
    r = rng.normal(size=(n + 2, 3)) + np.array([5.0, -3.0, 1.0])
    m = rng.normal(size=(n + 2, 3))
    mask = np.r_[np.ones(n), 0.0, 0.0]
    big = 1e6
    cov = (np.kron(np.eye(n), b) + np.kron(np.ones((n, n)), big * np.eye(3))
           + block_diag(*[np.outer(x, x) for x in m[:n]]))
    dense = multivariate_normal(np.zeros(3 * n), cov).logpdf(r[:n].ravel()) \
        + 1.5 * np.log(2 * np.pi * big)
    none = np.zeros((0, 3, n + 2))
    stats = column_statistics(none, mask)
    rows = RankOneRows(np.arange(n), (np.zeros((0, n)),) * 3)
    got = offset_marginal(jnp.asarray(r.T), jnp.asarray(b), jnp.asarray(m[:n].T),
                          jnp.asarray(mask), rows, none, stats).loglik
    assert float(got) == pytest.approx(dense, abs=1e-4)
    # rows without a rank-one term may be left out of ``rows`` (exactly)
    m_half = np.where(np.arange(n)[:, None] % 2 == 0, m[:n], 0.0)
    full_rows = offset_marginal(jnp.asarray(r.T), jnp.asarray(b), jnp.asarray(m_half.T),
                                jnp.asarray(mask), rows, none, stats).loglik
    some = offset_marginal(jnp.asarray(r.T), jnp.asarray(b), jnp.asarray(m_half[::2].T),
                           jnp.asarray(mask),
                           RankOneRows(np.arange(0, n, 2), (np.zeros((0, 3)),) * 3),
                           none, stats).loglik
    assert float(some) == pytest.approx(float(full_rows), abs=1e-12)
    got0, _, _, d0 = offset_marginal(jnp.asarray(r.T), jnp.asarray(b), jnp.zeros((3, n)),
                                     jnp.asarray(mask), rows, none, stats)
    res = r[:n] - r[:n].mean(0)
    closed = (multivariate_normal(np.zeros(3), b).logpdf(res).sum() + 1.5 * np.log(2 * np.pi)
              + 0.5 * np.linalg.slogdet(b)[1] - 1.5 * np.log(n))
    assert float(got0) == pytest.approx(closed, abs=1e-9)
    np.testing.assert_allclose(np.asarray(d0).T[:n], res, atol=1e-12)


def test_event_likelihood_is_the_density_of_the_rates():
    """With the inertia sampled, the event's likelihood is the density of the measured rates, not
    of ``V = I ω + …``: the dense Gaussian of ``x_i = I⁻¹ r_i`` (covariance ``I⁻¹ Σ_i I⁻ᵀ``, flat
    offset in rate units) equals :func:`event_loglik`'s, which adds ``(n − 1) log|det I|`` to the
    density of ``V``. Without that Jacobian the density grows as ``|det I|⁻ⁿ`` when ``I``, ``F``
    and the wheel inertias shrink together (the common scale the data cannot see), and a sampled
    inertia was pulled 4 % the wrong way on a Table 2 event (test below, slow)."""
    from scipy.linalg import block_diag
    from scipy.stats import multivariate_normal

    from cassini_bayes.inference.thrust.likelihood import (event_loglik, event_residual,
                                                           _noise_cov)
    from cassini_bayes.spacecraft import eq16_moment_matrix as moment_matrix
    from cassini_bayes.physics.momentum import inertia_vector

    rng = np.random.default_rng(5)
    n = 7
    a = rng.normal(size=(3, 3))
    inertia = np.diag([7000.0, 6000.0, 3500.0]) + 50.0 * (a + a.T)
    t = np.arange(float(n))
    omega = 2e-6 * rng.normal(size=(n, 3))          # rad/s, gyro-noise sized
    h = rng.normal(size=3) + 1e-4 * rng.normal(size=(n, 3))   # N m s, a constant + noise
    rates = 0.01 * rng.normal(size=(n, 8))           # s, σ_t ∂j/∂t per thruster
    log_sigma = np.log([2e-6, 1e-3])
    wheel_cov = 0.02 * np.eye(3)
    q = moment_matrix(1.2, 1.6, 2.9, 3.0, jnp.zeros(3))
    m = (0.7 * rates) @ np.asarray(q).T                # the time-tag columns at F = 0.7 N
    ev = _event(t, omega, h, rates.T, wheel_cov)
    pi = inertia_vector(jnp.asarray(inertia))
    st = event_loglik(pi, jnp.full(8, 0.7), (0.005, 0.02, 0.065), jnp.asarray(log_sigma), ev, q)
    r = np.asarray(event_residual(pi, 0.7 * q, (0.005, 0.02, 0.065), ev)).T
    i_inv = np.linalg.inv(inertia)
    b = np.asarray(_noise_cov(jnp.asarray(inertia), jnp.asarray(log_sigma),
                              jnp.asarray(wheel_cov)))
    big = 1e-6   # (rad/s)² offset prior variance, 1e5× the rates' noise variance
    cov = (block_diag(*[i_inv @ (b + np.outer(x, x)) @ i_inv.T for x in m])
           + np.kron(np.ones((n, n)), big * np.eye(3)))
    x = (r @ i_inv.T).ravel()
    dense = multivariate_normal(np.zeros(3 * n), cov).logpdf(x) + 1.5 * np.log(2 * np.pi * big)
    assert float(st.loglik) == pytest.approx(dense, abs=1e-4)


def test_event_likelihood_is_invariant_under_the_common_scale():
    """Scaling the inertia, the thrust and the wheel inertias by one ``s`` (the wheel momentum
    and its noise with them) leaves the event's likelihood unchanged: the data cannot see that
    scale. The time-tag term must scale too — fixed at the predicted thrust, as it once was, it
    made the likelihood pull ``s``, and ``F``, down on time tags wider than stated (0.19 sd of
    ``F`` on ``biasing_day028``, ``benchmarks/time_tag_bias.py``); the check below shows this
    test fails for such a term."""
    from cassini_bayes.inference.thrust.likelihood import event_loglik
    from cassini_bayes.spacecraft import eq16_moment_matrix as moment_matrix
    from cassini_bayes.physics.momentum import inertia_vector

    rng = np.random.default_rng(6)
    n = 9
    t = np.arange(float(n))
    omega = 2e-6 * rng.normal(size=(n, 3))
    h = rng.normal(size=3) + 1e-3 * rng.normal(size=(n, 3))
    rates = 0.01 * rng.normal(size=(8, n))
    q = moment_matrix(1.2, 1.6, 2.9, 3.0, jnp.zeros(3))
    pi = inertia_vector(jnp.asarray(np.diag([7000.0, 6000.0, 3500.0]) + 40.0))
    pulses = (np.array([2.25]), np.array([3]), np.array([0.5]))
    tau = (0.005, 0.02, 0.065)

    def loglik(s, rate_scale=1.0):
        ev = _event(t, omega, s * h, rate_scale * rates, s ** 2 * 0.02 * np.eye(3), pulses)
        return float(event_loglik(s * pi, jnp.full(8, 0.7 * s), tau,
                                   jnp.log(jnp.array([2e-6, 1e-3])), ev, q).loglik)

    base = loglik(1.0)
    for s in (0.97, 1.03):
        assert loglik(s) == pytest.approx(base, abs=1e-6)
        # a time-tag term held at the unscaled thrust breaks the invariance
        assert abs(loglik(s, rate_scale=1.0 / s) - base) > 1e-2


def test_time_tags_wider_than_stated_do_not_move_f():
    """End to end, on the day-028 event: uniform time tags of sd 15 ms (1.5 × the stated 10 ms)
    on every sample move F's Laplace mode by −0.025 sd (se 0.016, 20 draws,
    ``benchmarks/time_tag_bias.py``). With the time-tag term held at the predicted thrust they
    moved it by −0.213 (0.023): the open-world campaigns' bias. Tolerance: the mean of 8 draws
    (se about 0.03) within ±0.1 sd, 2.5 se from the measured mean (false failure about 1 % over
    keys; this key is fixed). Checked once against the fixed term: the mean was −0.17."""
    import importlib.util
    from pathlib import Path

    from cassini_bayes.inference.inertia.knowledge import inertia_prior_gaussian
    from cassini_bayes.simulate import load_scenario, simulate

    spec = importlib.util.spec_from_file_location(
        "time_tag_bias", Path(__file__).parents[1] / "benchmarks" / "time_tag_bias.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    scenario = load_scenario("biasing_day028")
    sim = simulate(jax.random.key(0), scenario)
    every = np.ones(sim.telemetry.n, bool)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        dz = bench.f_shifts(sim.telemetry, sim.pulses, scenario.prior,
                            inertia_prior_gaussian(scenario.prior), every, 0.015, 8,
                            np.random.default_rng(0))
    assert abs(dz.mean()) < 0.1, dz


def test_nuisance_marginal_matches_dense_gaussian():
    """Offsets of two events (flat) and a nuisance ``ν ~ N(0, diag(sd²))`` shared by both,
    integrated out by :func:`offset_marginal` per event and :func:`nuisance_marginal` over the
    events, equal the dense Gaussian of all samples with covariance
    ``⊕(B_e + m_i m_iᵀ) + D diag(sd²) Dᵀ + offsets`` (flat offsets as N(0, V I), V → ∞, times
    (2π V)^{3/2} each); and the conditional mean of ``ν`` equals the dense regression's. Each
    event carries two padded rows (mask 0), which must drop out."""
    from scipy.linalg import block_diag
    from scipy.stats import multivariate_normal

    from cassini_bayes.inference.gaussian import (RankOneRows, column_statistics,
                                                  nuisance_marginal, offset_marginal)

    rng = np.random.default_rng(4)
    n, n_nu, big = 5, 4, 1e6
    sd = np.array([0.5, 2.0, 1.0, 0.3])
    ev = []
    for e in range(2):
        a = rng.normal(size=(3, 3))
        ev.append(dict(b=a @ a.T + 0.5 * np.eye(3), r=rng.normal(size=(n, 3)) + 4.0 * e,
                       m=rng.normal(size=(n, 3)), d=rng.normal(size=(n, 3, n_nu))))
    total, info, score = 0.0, 0.0, 0.0
    mask = jnp.asarray(np.r_[np.ones(n), 0.0, 0.0])   # two padded rows, which must drop out
    for x in ev:
        pad = {k: np.concatenate([x[k], rng.normal(size=(2, *x[k].shape[1:]))])
               for k in ("r", "d")}
        cols = pad["d"].transpose(2, 1, 0)          # (R, 3, n + 2)
        om = offset_marginal(jnp.asarray(pad["r"].T), jnp.asarray(x["b"]), jnp.asarray(x["m"].T),
                             mask,
                             RankOneRows(np.arange(n), tuple(cols[:, a, :n] for a in range(3))),
                             jnp.asarray(cols),
                             column_statistics(cols, mask))
        total, info, score = total + om.loglik, info + om.info, score + om.score
    ll_nu, mean, _ = nuisance_marginal(info, score, jnp.asarray(sd))
    got = float(total + ll_nu)

    blocks = [np.kron(np.eye(n), x["b"]) + block_diag(*[np.outer(v, v) for v in x["m"]])
              + np.kron(np.ones((n, n)), big * np.eye(3)) for x in ev]
    d_all = np.concatenate([x["d"].reshape(3 * n, n_nu) for x in ev])
    cov = block_diag(*blocks) + d_all @ np.diag(sd**2) @ d_all.T
    r_all = np.concatenate([x["r"].ravel() for x in ev])
    dense = multivariate_normal(np.zeros(6 * n), cov).logpdf(r_all) + 2 * 1.5 * np.log(
        2 * np.pi * big)
    assert got == pytest.approx(dense, abs=1e-4)
    nu_mean = np.diag(sd**2) @ d_all.T @ np.linalg.solve(cov, r_all)
    np.testing.assert_allclose(sd * np.asarray(mean), nu_mean, rtol=1e-4, atol=1e-8)


def _dense_loglik(problem, tau_median, time_tag_sd, pi, f8, tau, log_sigma):
    """The robust thrust likelihood written out densely, as it stands before the fast form's
    shortcuts: ``j`` by the sum over every pulse at every sample
    (:func:`~cassini_bayes.physics.impulse.impulse_from_pulses`), ``V`` by
    :func:`~cassini_bayes.physics.impulse.impulse_lhs`, every sample's own time-tag term
    ``m_i m_iᵀ`` (the thrust profile at the prior's median ``τ``, at every sample), and the
    events' offsets (flat) and the nuisance ``ν ~ N(0, diag(sd²))`` integrated out together in
    information form with generic 3×3 inverses and log-determinants."""
    from cassini_bayes.physics.impulse import impulse_lhs
    from cassini_bayes.physics.momentum import inertia_matrix
    from cassini_bayes.physics.pulse import (pulse_impulse_area, pulse_impulse_until,
                                             thrust_profile)
    from cassini_bayes.physics.rate_step_moments import (interval_moments,
                                                         second_order_correction, step_pairs,
                                                         curvature_correction)

    # host copies: data, not traced (a jitted function's captured arrays are traced)
    ev = jax.tree.map(np.asarray, problem.data.events)
    q, nu_sd = np.asarray(problem.data.q_matrix), np.asarray(problem.data.nu_sd)
    inertia = inertia_matrix(pi)
    s2 = jnp.exp(2.0 * log_sigma)
    n_ev = len(problem.n_samples)
    ll = 0.0
    z_list, y_list = [], []
    for e in range(n_ev):
        n = int(problem.n_samples[e])
        keep = np.asarray(ev.width[e]) > 0
        t = ev.t[e][:n]
        t_on, thr, width = (x[e][keep] for x in (ev.t_on, ev.thruster, ev.width))
        v = impulse_lhs(t, ev.omega[e][:n], inertia, ev.h_wheels[e][:n])   # Feldman & Lee Eq 17
        one_hot = (thr[:, None] == np.arange(8)[None, :]).astype(float)
        since = t[:, None] - t_on[None, :]
        # each (sample, pulse)'s time-tag sd, from the layout (pulses sorted by first sample)
        lay, n_pad = ev.pulses, ev.t[e].shape[0]
        order = np.argsort(np.asarray(ev.slot[e]), kind="stable")
        spread = np.zeros((n_pad, ev.width[e].shape[0]))
        valid = lay.at[e] < 8 * n_pad
        spread[lay.at[e][valid] % n_pad, order[np.nonzero(valid)[0]]] = lay.tag_spread[e][valid]
        spread = spread[:n][:, keep]

        def expected(fn, *tau_):
            return sum(w * fn(since - spread * x, width[None, :], *tau_)
                       for x, w in zip(lay.tag_nodes[e], lay.tag_weights[e]))

        j = impulse_from_pulses(t, t_on, thr, width, *tau)                  # (n, 8) s
        # the trapezoidal ΔG's error across the rate steps, every pulse at every sample
        area = pulse_impulse_area(since, width[None, :], *tau) @ one_hot
        j_now = pulse_impulse_until(since, width[None, :], *tau) @ one_hot
        eps = jnp.concatenate([jnp.zeros((1, 8)), jnp.diff(area, axis=0)
                               - 0.5 * np.diff(t)[:, None] * (j_now[1:] + j_now[:-1])])
        a = (eps * f8[None, :]) @ q.T                                       # (n, 3) N m s²
        w_m, h_m = (_interval_means(x[e][:n]).T for x in (ev.omega, ev.h_wheels))
        step = (jnp.cross(jnp.linalg.solve(inertia, a.T).T, w_m @ inertia.T + h_m)
                + jnp.cross(w_m, a))
        # its second-order part, every pulse over every interval (moments at the prior's τ)
        with jax.ensure_compile_time_eval():      # data: computed, not traced
            m2, p2 = interval_moments(t, t_on, thr, width, np.searchsorted(t, t_on), n, 8,
                                      tau_median)
        second = second_order_correction(
            inertia, q * f8[None, :], m2, step_pairs(p2),
            np.diff(ev.omega[e][:n], axis=0, prepend=0.0).T,
            np.diff(ev.h_wheels[e][:n], axis=0, prepend=0.0).T, np.diff(t, prepend=t[0]))
        second = second + curvature_correction(
            inertia, q * f8[None, :], m2, np.diff(ev.omega[e][:n], axis=0, prepend=0.0).T,
            np.diff(ev.h_wheels[e][:n], axis=0, prepend=0.0).T, np.diff(t, prepend=t[0]),
            w_m.T, h_m.T)
        v = v + jnp.cumsum(step, 0) + jnp.cumsum(second, 1).T
        r = v - (j * f8[None, :]) @ q.T
        rates = time_tag_sd * expected(thrust_profile, *tau_median) @ one_hot
        m = (rates * f8[None, :]) @ q.T                                     # (n, 3) N m s
        b = s2[e, 0] * inertia @ inertia + s2[e, 1] * ev.wheel_cov[e]
        cov = b[None] + m[:, :, None] * m[:, None, :]                       # (n, 3, 3)
        prec = jnp.linalg.inv(cov)
        ll = ll - 0.5 * (jnp.einsum("na,nab,nb->", r, prec, r)
                         + jnp.sum(jnp.linalg.slogdet(cov)[1]) + 3 * n * np.log(2 * np.pi))
        ll = ll + (n - 1) * jnp.linalg.slogdet(inertia)[1]                  # |det I| per sample
        offset = np.zeros((n, 3, 3 * n_ev))
        offset[:, :, 3 * e:3 * e + 3] = np.eye(3)
        z = np.concatenate([offset, ev.nu_cols[e][:, :, :n].transpose(2, 1, 0)],
                           -1)                                              # (n, 3, 3E + R)
        pz = jnp.einsum("nab,nbk->nak", prec, z)
        z_list.append(jnp.einsum("nak,nal->kl", z, pz))
        y_list.append(jnp.einsum("nak,na->k", pz, r))
    info = sum(z_list) + np.diag(np.r_[np.zeros(3 * n_ev), 1.0 / nu_sd**2])
    score = sum(y_list)
    ll = (ll + 0.5 * score @ jnp.linalg.solve(info, score) - 0.5 * jnp.linalg.slogdet(info)[1]
          + 1.5 * n_ev * np.log(2 * np.pi) - np.sum(np.log(nu_sd)))
    return ll


def test_log_density_and_gradient_equal_the_dense_likelihood():
    """The likelihood the sampler differentiates (the pulses' sparse layout, the (3, n) layout,
    the rank-one algebra only at samples whose time-tag term double precision represents, the
    stated derivatives of the impulse, of ``inv3_spd`` and of the nuisance integral) equals
    :func:`_dense_loglik`, in value and in gradient with respect to the sampler's vector, at
    random points of the whitened posterior: two events of different lengths (padding), robust
    model, inertia sampled. Tolerance 1e-9 relative (deterministic arithmetic, no sampling;
    measured: the values equal, the gradients within 5e-11 of their largest component); the
    largest time-tag rate 1e-4 off moves the value 1e-8 relative, which fails it."""
    from cassini_bayes.inference.gaussian import nuisance_log_marginal
    from cassini_bayes.inference.inertia.knowledge import inertia_prior_gaussian
    from cassini_bayes.inference.thrust.coords import physical
    from cassini_bayes.inference.thrust.likelihood import event_loglik
    from cassini_bayes.simulate import load_scenario, simulate

    scenario = load_scenario("fsds_biasing")
    res = simulate(jax.random.key(11), scenario)
    sc = scenario.prior
    events = [(res.telemetry.slice(t0, t1), res.pulses) for t0, t1 in ((100, 229), (300, 399))]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # pulses outside each slice are dropped
        problem = prepare_thrust(events, sc, robust=True, inertia=inertia_prior_gaussian(sc))
    kw = problem.data
    n_f = len(problem.names)
    assert kw.nu_sd.shape[0] > 0 and len(set(problem.n_samples)) == 2

    def _args(p):
        return p.inertia, p.per_thruster, p.tau, p.log_sigma

    def fast(pi, f8, tau, log_sigma, ev=kw.events):
        st = jax.vmap(event_loglik, in_axes=(None, None, None, 0, 0, None))(
            pi, f8, (tau[0], tau[1], tau[2]), log_sigma, ev, kw.q_matrix)
        return jnp.sum(st.loglik) + nuisance_log_marginal(jnp.sum(st.info, 0),
                                                          jnp.sum(st.score, 0), kw.nu_sd)

    tau_median = tuple(float(x) for x in tau_prior(sc).median())
    dense = partial(_dense_loglik, problem, tau_median, sc.knowledge.time_tag_sd_s)

    def at(lik):
        return jax.jit(jax.value_and_grad(
            lambda theta: lik(*_args(physical(theta, kw, n_f, 0, True)))))

    rng = np.random.default_rng(8)
    fast_vg, dense_vg = at(fast), at(dense)
    for _ in range(3):
        theta = kw.centre + kw.tril @ jnp.asarray(rng.normal(size=kw.centre.shape[0]))
        (v1, g1), (v2, g2) = fast_vg(theta), dense_vg(theta)
        assert float(v1) == pytest.approx(float(v2), rel=1e-9)
        np.testing.assert_allclose(np.asarray(g1), np.asarray(g2), rtol=1e-9,
                                   atol=1e-9 * float(jnp.max(jnp.abs(g2))))
    # the check can fail: the largest time-tag rate 1e-4 off
    tag = np.asarray(kw.events.time_tag_rates[0])
    top = int(np.argmax(np.abs(tag).max(0)))
    bumped = kw.events._replace(time_tag_rates=kw.events.time_tag_rates.at[0, :, top].multiply(
        1.0 + 1e-4))
    x = _args(physical(theta, kw, n_f, 0, True))
    assert float(fast(*x, ev=bumped)) != pytest.approx(float(dense(*x)), rel=1e-9)


def test_tau_prior_centred_on_manufacturer_ranges_and_holds_first_order_valves():
    """Delay ~ HalfNormal(7 ms): median ≈ the nominal 5 ms, largest density at τd = 0, 85 % of it
    below 10 ms. Rise and fall log-normal, centred on the test ranges (Feldman & Lee §V: rise
    15-25, fall 40-90 ms) and at least as wide as them (±2σ), with log sd 0.45, so the prior
    density of ``log τ`` at a first-order valve (τd = 0, τr = τf = 45 ms) is 0.17 of its peak for
    the rise and 0.81 for the fall (it was e^{−22} for the rise)."""
    sc = load_spacecraft("models/fsds.toml")
    tp = tau_prior(sc)
    ranges = [sc.pulse.tau_rise_range, sc.pulse.tau_fall_range]
    assert tp.delay_scale == sc.pulse.tau_delay_range[1]
    delay = stats.halfnorm(scale=tp.delay_scale)
    assert delay.median() == pytest.approx(0.00472, abs=1e-5)
    assert delay.cdf(0.010) == pytest.approx(0.847, abs=1e-3)
    assert delay.pdf(0.0) == delay.pdf(np.linspace(0, 0.03, 100)).max()
    for mu, sd, (lo, hi) in zip(tp.log_mean, tp.log_sd, ranges):
        assert mu == pytest.approx(0.5 * np.log(lo * hi))
        assert sd >= np.log(hi / lo) / 4 and sd == pytest.approx(0.45)
        d = stats.lognorm(s=sd, scale=np.exp(mu))
        assert d.cdf(hi) - d.cdf(lo) > 0.4
    log_rise, log_fall = (stats.norm(mu, sd) for mu, sd in zip(tp.log_mean, tp.log_sd))
    assert log_rise.pdf(np.log(0.045)) / log_rise.pdf(tp.log_mean[0]) == pytest.approx(0.17,
                                                                                       abs=0.01)
    assert log_fall.pdf(np.log(0.045)) / log_fall.pdf(tp.log_mean[1]) == pytest.approx(0.81,
                                                                                       abs=0.01)
    rise, fall = (stats.lognorm(s=sd, scale=np.exp(mu)) for mu, sd in zip(tp.log_mean, tp.log_sd))
    lo99, hi99 = tp.central(0.99).T
    assert lo99[0] < 5e-5 and np.all(lo99[1:] < 0.038) and np.all(hi99[1:] > 0.054)
    np.testing.assert_allclose(tp.median(), [delay.median(), rise.median(), fall.median()])
    np.testing.assert_allclose(tp.variance(), [delay.var(), rise.var(), fall.var()], rtol=1e-12)
    draws = np.asarray(draw_tau_prior(jax.random.key(0), tp, (20000,)))
    np.testing.assert_allclose(np.median(draws, 0), tp.median(), rtol=0.03)


def test_tau_identification_names_unidentified_and_conflicting_time_constants():
    """Posterior ≈ prior (contraction < 0.1) → "not identified"; a posterior mean outside the
    prior's central 99 % → "disagree"; an identified, agreeing one → nothing."""
    from cassini_bayes.inference.thrust import tau_identification

    tp = tau_prior(load_spacecraft("models/fsds.toml"))
    prior = np.asarray(draw_tau_prior(jax.random.key(3), tp, (4000,)))
    rng = np.random.default_rng(0)
    post = {"tau_delay": prior[:, 0], "tau_rise": rng.normal(0.045, 0.001, 4000),
            "tau_fall": rng.normal(0.200, 0.002, 4000)}
    lines = tau_identification(post, tp)
    assert len(lines) == 2
    assert lines[0].startswith("tau_delay: not identified by the data (posterior/prior "
                               "contraction")
    assert lines[1].startswith("tau_fall: posterior mean 200 ms lies outside the prior's central "
                               "99 % (18.8 to 191 ms)")


def test_sampler_prior_density_is_the_stated_prior():
    """The log prior of the sampler coordinates ``(s_z, a_z, c_z)`` (:func:`tau_from_z`, with its
    Jacobians) is the stated prior's density of ``(τd, τr, τf)`` times ``|∂τ/∂z|`` — checked at
    the papers' profile, at a first-order valve, near τd = 0 (1 µs), at τd = 12 ms and at a
    delay ten times the rise (``τr → 0``, the far tail of ``s``); the map inverts (Lambert W) to
    1e-12."""
    from cassini_bayes.inference.thrust import (A_LOG_SCALE, C_SCALE_S, long_pulse_excess,
                                                rise_deficit)
    from cassini_bayes.inference.thrust.coords import tau_from_z

    sc = load_spacecraft("models/fsds.toml")
    tp = tau_prior(sc)
    kw = SimpleNamespace(tau_delay_scale=jnp.asarray(tp.delay_scale),
                         tau_mu=jnp.asarray(tp.log_mean), tau_sd=jnp.asarray(tp.log_sd),
                         a_mu=jnp.asarray(float(rise_deficit(*tp.median()[:2]))),
                         c_mu=jnp.asarray(float(long_pulse_excess(*tp.median()))))

    def coords(tau):
        a = float(rise_deficit(*tau[:2]))
        return jnp.array([np.arcsinh(np.log(tau[0] / (a - tau[0]))),
                          np.log(a / float(kw.a_mu)) / A_LOG_SCALE,
                          (float(long_pulse_excess(*tau)) - float(kw.c_mu)) / C_SCALE_S])

    for tau in [(0.005, 0.020, 0.065), (1e-6, 0.045, 0.045), (0.0004, 0.030, 0.050),
                (0.012, 0.015, 0.040), (0.020, 0.002, 0.060)]:
        z = coords(tau)
        got_tau, log_p = tau_from_z(z, kw)
        np.testing.assert_allclose(np.asarray(got_tau), tau, rtol=1e-12, atol=1e-15)
        jac = np.linalg.det(np.asarray(jax.jacfwd(lambda v: tau_from_z(v, kw)[0])(z)))
        want = (stats.halfnorm(scale=tp.delay_scale).logpdf(tau[0])
                + sum(stats.lognorm(s=sd, scale=np.exp(mu)).logpdf(x)
                      for mu, sd, x in zip(tp.log_mean, tp.log_sd, tau[1:]))
                + np.log(abs(jac)))
        assert float(log_p) == pytest.approx(want, abs=1e-9)


def test_pulse_on_at_the_first_sample_is_modelled_after_it_with_a_warning(monkeypatch):
    """A pulse commanded 0.2 s before the first sample (and one whose command ended 10 ms before
    it, its thrust still decaying) is kept with one PulseAtStartWarning each; the model's
    impulse from the first sample on is exactly what the profile delivers after it (the free
    offset takes what came before)."""
    from cassini_bayes.physics.pulse import pulse_impulse, pulse_impulse_until
    from cassini_bayes.telemetry import PulseAtStartWarning

    import cassini_bayes.inference.thrust.data as thrust_data

    # the sampler's Laplace whitening is not under test: skip its compilation
    monkeypatch.setattr(thrust_data, "laplace", lambda f, x0, kw, **_: (x0, np.eye(x0.size)))
    sc = load_spacecraft("models/fsds.toml")
    tel = _quiet_telemetry()
    t_on, width = np.array([-0.2, -0.135, 5.0]), np.array([0.5, 0.125, 0.25])
    log = PulseLog(t_on, np.array([0, 5, 2]), width, "p.csv")
    with pytest.warns(PulseAtStartWarning) as rec:
        prob = prepare_thrust([(tel, log)], sc, robust=False)
    lines = [str(w.message) for w in rec if issubclass(w.category, PulseAtStartWarning)]
    assert len(lines) == 2
    assert "Z1 at t_on = -0.2 s" in lines[0] and "Y2 at t_on = -0.135 s" in lines[1]
    assert prob.n_pulses[0] == 3
    kw = prob.data
    tau = (0.005, 0.020, 0.065)
    j = _impulse_per_thruster(jax.tree.map(lambda x: x[0], kw.events.pulses), tau)
    t = np.asarray(tel.t)
    for k, (on, w) in enumerate(zip(t_on[:2], width[:2])):
        col = [0, 5][k]
        want = np.asarray(pulse_impulse_until(t - on, w, *tau))
        np.testing.assert_allclose(j[:, col] - j[0, col], want - want[0], atol=1e-12)
    full = float(pulse_impulse(0.5, *tau))       # Feldman & Lee §V closed form
    assert j[-1, 0] - j[0, 0] == pytest.approx(full - float(pulse_impulse_until(0.2, 0.5, *tau)),
                                               abs=1e-12)


def test_names_and_modes():
    assert thrust_names("mean") == ("F",)
    assert thrust_names("branch") == ("F_Z", "F_Y")
    assert thrust_names("thruster") == ("F",)     # along the model's thrusters: F[Z1] …
    assert TAU_NAMES == ("tau_delay", "tau_rise", "tau_fall")
    with pytest.raises(InputError, match="mode="):
        thrust_names("per-day")


def _quiet_telemetry(n=60):
    t = np.arange(float(n))
    q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    w = np.zeros((n, 3))
    rates = np.full((n, 4), np.nan)
    rates[:, :3] = 10.0
    return Telemetry(t, q, w, rates, source="quiet.csv")


def test_pulses_outside_the_telemetry_are_dropped_with_a_warning(monkeypatch):
    """Issue 28: a pulse log reaching past its telemetry had three pulses dropped in silence
    (``check`` said so, the fit and its summary.json did not): every pulse left out is a
    PulsesDroppedWarning, which the fit functions put in summary.json's warnings; a pulse
    still on at the last sample is modelled and needs no warning."""
    import cassini_bayes.inference.thrust.data as thrust_data
    from cassini_bayes.telemetry import PulseSpanWarning, PulsesDroppedWarning

    monkeypatch.setattr(thrust_data, "laplace", lambda f, x0, kw, **_: (x0, np.eye(x0.size)))
    sc = load_spacecraft("models/fsds.toml")
    tel = _quiet_telemetry()                      # t = 0 … 59 s
    log = PulseLog(np.array([5.0, 58.875, 61.0, 70.0, 80.0]), np.array([0, 1, 2, 2, 2]),
                   np.full(5, 0.25), "p.csv")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        prob = prepare_thrust([(tel, log)], sc, robust=False)
    spans = [w for w in caught if issubclass(w.category, PulseSpanWarning)]
    assert [w.category for w in spans] == [PulsesDroppedWarning]
    assert "p.csv: 3 of 5 pulses lie outside the telemetry span 0..59 s" in str(spans[0].message)
    assert prob.n_pulses[0] == 2


def test_bad_inputs_are_input_errors():
    sc = load_spacecraft("models/fsds.toml")
    tel = _quiet_telemetry()
    with pytest.raises(InputError, match="pulse log"):
        prepare_thrust([(tel, None)], sc)
    outside = PulseLog(np.array([500.0]), np.array([5]), np.array([0.125]), "p.csv")
    with pytest.raises(InputError, match="no pulse"), pytest.warns(UserWarning, match="1 of 1"):
        prepare_thrust([(tel, outside)], sc)
    with pytest.raises(InputError, match="no biasing event"):
        prepare_thrust([], sc)


# --------------------------------------------------------------------------------------------
# Recovery on simulated biasing events (slow: simulation + NUTS)
# --------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def fsds():
    from cassini_bayes.simulate import load_scenario, simulate

    sc = load_scenario("fsds_biasing")
    r = simulate(jax.random.key(11), sc)
    return sc, (r.telemetry, r.pulses)


@pytest.fixture(scope="module")
def days():
    from cassini_bayes.simulate import load_scenario, simulate

    out = []
    for name in ("biasing_day028", "biasing_day049"):
        sc = load_scenario(name)
        r = simulate(jax.random.key(12), sc)
        out.append((sc, (r.telemetry, r.pulses)))
    return out


def _settings(n=400, chains=4):
    from cassini_bayes.inference.runner import SamplerSettings

    return SamplerSettings(chains=chains, warmup=n, draws=n)


@pytest.mark.slow
def test_fsds_thrust_covers_truth(fsds):
    """Mean thrust of the FSDS test (truth 0.75 N): inside the 90 % interval and within the
    papers' ±10 %; the posterior is wider than with the time constants fixed at the truth."""
    from cassini_bayes.inference.thrust import fit_thrust

    sc, ev = fsds
    post = fit_thrust(jax.random.key(1), [ev], sc.prior, mode="mean", robust=False,
                      settings=_settings())
    f = post.idata.posterior["F"].values.ravel()
    q05, q95 = np.quantile(f, [0.05, 0.95])
    assert q05 < 0.75 < q95
    assert abs(f.mean() - 0.75) / 0.75 < 0.10
    assert post.diagnostics.divergences <= DIVERGENCES_MAX


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1])
def test_first_order_valve_thrust_covers_truth(seed):
    """A valve outside the papers' profile family as the manufacturer's ranges state it: no
    delay, rise = fall = 45 ms (``biasing_day028_first_order``, F = 0.699 N), robust model,
    inertia from the model's prior. F's 90 % interval covers the truth and the sampler mixes.
    Measured (2 × 300 + 300): seeds 0, 1 gave F −0.13 %, −0.21 % (sd 0.33 %, 0.31 %: 0.4 and
    0.7 sd), τr 44.4, 42.3 ms. |error| < 1.645 sd is what coverage asks; at 0.7 sd measured the
    margin holds across CPUs."""
    from cassini_bayes.inference.runner import SamplerSettings
    from cassini_bayes.inference.thrust import fit_thrust
    from cassini_bayes.simulate import load_scenario, simulate

    sc = load_scenario("experiments/scenarios/biasing_day028_first_order.toml")
    r = simulate(jax.random.key(seed), sc)
    post = fit_thrust(jax.random.key(1), [(r.telemetry, r.pulses)], sc.prior,
                      settings=SamplerSettings(chains=2, warmup=300, draws=300,
                                               chain_method="sequential"))
    f = post.idata.posterior["F"].values.ravel()
    q05, q95 = np.quantile(f, [0.05, 0.95])
    assert q05 < 0.699 < q95
    assert_mixed(post.diagnostics, ess_bulk_min=150)


@pytest.mark.slow
def test_unfired_thrusters_are_prior_dominated(fsds):
    """Only Y2, Y4 fire in the FSDS test: the other six keep their prior (contraction ≈ 0)."""
    from cassini_bayes.inference.thrust import THRUST_PRIOR_LOG_SD, fit_thrust

    sc, ev = fsds
    post = fit_thrust(jax.random.key(2), [ev], sc.prior, mode="thruster", robust=False,
                      settings=_settings())
    assert list(post.problem.fired) == [False] * 5 + [True, False, True]
    f_all = post.idata.posterior["F"]
    for name in ("Z1", "Z2", "Z3", "Z4", "Y1", "Y3"):
        sd = np.log(f_all.sel(thruster=name).values.ravel()).std()
        # prior sd of log F is 0.3; the sd of ~1600 draws is within ±15 % of it (≫ 3σ)
        assert 1.0 - sd / THRUST_PRIOR_LOG_SD == pytest.approx(0.0, abs=0.15)
    for name in ("Y2", "Y4"):
        f = f_all.sel(thruster=name).values.ravel()
        assert f.std() < 0.1 * THRUST_PRIOR_LOG_SD * f.mean()
        assert abs(f.mean() - 0.75) / 0.75 < 0.10


@pytest.mark.slow
def test_pooled_events_learn_tau_fall_better(days):
    """Two Table 2 events of different pulse mixes constrain τf better than one, and the pooled
    thrust lies within 4 posterior sd of the truth (a calibrated posterior fails that with
    probability 6e-5)."""
    from cassini_bayes.inference.thrust import fit_thrust

    (sc, ev1), (_, ev2) = days
    one = fit_thrust(jax.random.key(3), [ev1], sc.prior, robust=False, settings=_settings())
    both = fit_thrust(jax.random.key(3), [ev1, ev2], sc.prior, robust=False,
                      settings=_settings())
    sd_one = float(one.idata.posterior["tau_fall"].std())
    sd_both = float(both.idata.posterior["tau_fall"].std())
    assert sd_both < sd_one
    f = both.idata.posterior["F"].values.ravel()
    assert abs(f.mean() - 0.699) < 4.0 * f.std()


@pytest.mark.slow
def test_default_settings_converge(fsds):
    """Default sampler settings (4 × 1000 + 1000) converge on fsds_biasing."""
    from cassini_bayes.inference.runner import SamplerSettings
    from cassini_bayes.inference.thrust import fit_thrust

    sc, ev = fsds
    post = fit_thrust(jax.random.key(4), [ev], sc.prior, robust=False, settings=SamplerSettings())
    d = post.diagnostics
    assert_mixed(d)


# --------------------------------------------------------------------------------------------
# Robust model (nuisance parameters)
# --------------------------------------------------------------------------------------------

@pytest.mark.parametrize("wheel_errors", ["per_wheel", "common"])
def test_robust_columns_torque_and_wheel_scale(wheel_errors):
    """The external-torque columns are (t − t0)·1, the torque-rate columns ½ (t − t0)²·1, and the
    wheel-scale columns are −J_k ρ_k g_k per wheel (common: one column −H_w): the linear terms of
    the predicted Eq 17 left side (module docstring)."""
    from cassini_bayes.inference.nuisance import nuisance_layout
    from cassini_bayes.inference.thrust.columns import nuisance_columns
    from cassini_bayes.spacecraft import load_spacecraft

    sc = load_spacecraft("cassini_post_probe")
    layout = nuisance_layout(sc, 2, ("RWA1", "RWA2"), wheel_errors=wheel_errors,
                             torque_rate=True)
    t = np.linspace(10.0, 20.0, 11)
    per_wheel = {"RWA1": np.linspace(0.0, 5.0, 11), "RWA2": np.linspace(1.0, -2.0, 11)}
    h = sum(per_wheel[n][:, None] * sc.wheel(n).axis for n in per_wheel)
    cols = nuisance_columns(layout, 1, t, np.zeros((11, 3)), np.asarray(sc.inertia), h,
                            per_wheel)
    tq = layout.slices["body_torque"].start + 3
    np.testing.assert_allclose(cols[:, :, tq:tq + 3], (t - 10.0)[:, None, None] * np.eye(3))
    tr = layout.slices["torque_rate"].start + 3
    np.testing.assert_allclose(cols[:, :, tr:tr + 3],
                               0.5 * (t - 10.0)[:, None, None]**2 * np.eye(3))
    assert not cols[:, :, tr - 3:tr].any()
    wheel = cols[:, :, layout.slices["wheel_inertia"]]
    if wheel_errors == "per_wheel":
        for k, n in enumerate(("RWA1", "RWA2")):
            np.testing.assert_allclose(wheel[:, :, k], -per_wheel[n][:, None] * sc.wheel(n).axis)
    np.testing.assert_allclose(wheel.sum(-1), -h, atol=1e-12)
    # the other event's bias and torque columns are zero
    assert not cols[:, :, 0:3].any()
    assert not cols[:, :, tq - 3:tq].any()


def test_reported_draws_carry_the_common_wheel_scale():
    """With the inertia sampled the likelihood holds the wheels at the model file's common scale
    ``u``; the fit reports each draw's thrusts, inertia and torques times ``1 + u``, ``u`` from
    the draw's wheel block (its prior), and leaves the rest (gyro bias, time constants) alone. A
    problem with the inertia fixed keeps its draws."""
    import arviz as az

    from cassini_bayes.inference.nuisance import nuisance_layout
    from cassini_bayes.inference.thrust.fit import _at_common_scale

    sc = load_spacecraft("espa_bus")
    lay = nuisance_layout(sc, 1, tuple(w.name for w in sc.wheels), torque_rate=True)
    rng = np.random.default_rng(3)
    nu = rng.normal(size=(2 * 2000, lay.size)) * lay.sd
    post = {"F": np.full((2, 2000, 8), 0.7), "Ixx": np.full((2, 2000), 25.0),
            "tau_rise": np.full((2, 2000), 0.02), "T_body": np.full((2, 2000, 1, 3), 1e-5),
            "gyro_bias": np.full((2, 2000, 1, 3), 1e-6)}

    def reported(scale_free):
        idata = az.from_dict(posterior={k: v.copy() for k, v in post.items()})
        _at_common_scale(idata, SimpleNamespace(scale_free=scale_free, layout=lay, names=("F",)),
                         nu)
        return idata.posterior

    out = reported(True)
    u = nu[:, lay.wheel_block] @ lay.common_scale_weights
    np.testing.assert_allclose(out["F"].values[..., 3].ravel(), 0.7 * (1 + u), rtol=1e-12)
    np.testing.assert_allclose(out["Ixx"].values.ravel(), 25.0 * (1 + u), rtol=1e-12)
    np.testing.assert_allclose(out["T_body"].values[..., 0, 2].ravel(), 1e-5 * (1 + u),
                               rtol=1e-12)
    assert out["F"].dims == ("chain", "draw", "F_dim_0")
    for name in ("tau_rise", "gyro_bias"):
        np.testing.assert_array_equal(out[name].values, post[name])
    # u has the prior of the wheels' common scale (four wheels: √(0.5² + 0.5²/4) %), to 5 %
    assert np.std(u) == pytest.approx(lay.common_scale_sd, rel=0.05)
    assert lay.common_scale_sd == pytest.approx(0.005 * np.sqrt(1.25), rel=1e-9)
    np.testing.assert_array_equal(reported(False)["F"].values, post["F"])


@pytest.mark.slow
def test_robust_model_covers_what_the_idealised_misses():
    """Robust against idealised on a Table 2 event whose true wheels are 1 % heavier than the model
    file says and whose spacecraft feels 20 µN m: the idealised posterior of F excludes the truth
    (it is ~1 % off with a ~0.15 % sd), the robust one covers it; 99 % intervals. Fixed keys; a
    calibrated robust posterior misses with probability 1 % (a 2-sd wheel-scale error makes the
    idealised miss certain). With the inertia sampled (the default since the fixed inertia was
    found to bias F) the robust 90 % interval sits at the edge (measured [0.6860, 0.6985], z ≈ 1.7:
    the 1 % common error is 2 prior sd), hence 99 %.
    The robust model keeps its default 10 ms time-tag term although this scenario's tags are
    exact (measured: 0 divergences, R-hat 1.006, F in [0.6967, 0.7018] N). The idealised fit of
    this mis-specified event does not mix either (measured: 104 divergences, R-hat 1.13 at
    4 × 400, worst τr): a second symptom of the same misfit, so only the robust fit's mixing is
    asserted."""
    import tomllib

    from cassini_bayes.inference.thrust import fit_thrust
    from cassini_bayes.simulate.scenario import scenario_from_dict, scenario_path

    d = tomllib.loads(scenario_path("biasing_day028").read_text())
    d["truth"]["wheel_inertia_scale"] = 1.01
    d["truth"]["external_torque_body_nm"] = [1.2e-5, -1.0e-5, 1.2e-5]
    sc = scenario_from_dict(d)
    r = simulate_event(sc)
    found = {}
    for robust in (False, True):
        # the truth is one common wheel scale: the common-scale robust model (a 1 % common error
        # is 2 sd of its 0.5 % prior, 3.5 sd of the 0.29 % common part of the per-wheel prior)
        post = fit_thrust(jax.random.key(5), [r], sc.prior, robust=robust, settings=_settings(),
                          wheel_errors="common")
        f = post.idata.posterior["F"].values.ravel()
        found[robust] = np.quantile(f, [0.005, 0.995])
        if robust:
            assert post.diagnostics.divergences <= DIVERGENCES_MAX
    lo, hi = found[False]
    assert not lo <= 0.699 <= hi, found
    lo, hi = found[True]
    assert lo <= 0.699 <= hi, found


def simulate_event(sc):
    from cassini_bayes.simulate import simulate

    r = simulate(jax.random.key(13), sc)
    return r.telemetry, r.pulses


@pytest.mark.slow
def test_inertia_off_its_prediction_reaches_f_only_when_fixed():
    """A Table 2 event whose true moments are 3 % above the model file's prediction (0.3 of
    their ±10 % prior sd). The robust model's default samples the inertia from that prior and
    covers ``F``; held at the prediction (``inertia="fixed"``, the papers' practice) ``F`` is
    biased by the ``I Δω`` the pulses put into the body rates. Measured (2 × 200, key 5):
    sampled F 0.7002 ± 0.0036 N (z = +0.3, inertia back within 0.2 % of the truth), fixed
    0.6804 ± 0.0016 N (z = −11.6). Margins: sampled |z| < 3 (a calibrated posterior fails 0.3 %),
    within 1 %; fixed |z| > 5."""
    import tomllib

    from cassini_bayes.inference.thrust import fit_thrust
    from cassini_bayes.physics.momentum import INERTIA_NAMES, inertia_vector
    from cassini_bayes.simulate.scenario import scenario_from_dict, scenario_path

    d = tomllib.loads(scenario_path("biasing_day028").read_text())
    pred = np.asarray(inertia_vector(scenario_from_dict(d).prior.inertia))
    truth = pred * np.r_[1.03, 1.03, 1.03, 1.0, 1.0, 1.0]
    d["truth"]["inertia"] = dict(zip(INERTIA_NAMES, map(float, truth)))
    sc = scenario_from_dict(d)
    ev = simulate_event(sc)
    z = {}
    for inertia in (None, "fixed"):
        post = fit_thrust(jax.random.key(5), [ev], sc.prior, inertia=inertia,
                          settings=_settings())
        f = post.idata.posterior["F"].values.ravel()
        z[inertia] = (f.mean() - 0.699) / f.std()
        if inertia is None:
            assert_mixed(post.diagnostics)
            assert abs(f.mean() / 0.699 - 1) < 0.01
            ixx = post.idata.posterior["Ixx"].values.ravel()
            assert abs(ixx.mean() / truth[0] - 1) < 0.02, ixx.mean()
    assert abs(z[None]) < 3 and abs(z["fixed"]) > 5, z


def test_thrusters_that_cannot_torque_the_data_are_refused():
    """Feldman & Lee Eq 16/17: an event's momentum change lies in the span of its fired
    thrusters' torques. The FSDS event fitted with a model whose Y thrusters push along −Z (so
    no fired thruster torques about Z) is refused, naming the axis and the thrusters; the true
    model passes."""
    import dataclasses

    from cassini_bayes.inference.thrust.data import _check_torque_span
    from cassini_bayes.simulate import load_scenario, simulate

    sc = load_scenario("fsds_biasing")
    r = simulate(jax.random.key(31), sc)
    good = sc.prior
    _check_torque_span(r.telemetry, r.pulses, good, good.inertia)   # the data's model: fine
    bent = tuple(dataclasses.replace(t, direction=np.array([0.0, 0.0, -1.0]))
                 if t.name.startswith("Y") else t for t in good.thrusters)
    bad = dataclasses.replace(good, thrusters=bent)
    with pytest.raises(InputError, match=r"about body axis \[.*\] .* which the fired thrusters "
                                         r".*Y.* cannot torque") as e:
        prepare_thrust([(r.telemetry, r.pulses)], bad)
    assert "\n" not in str(e.value)
