"""The time tags' terms of the robust thrust model (inference/thrust/time_tags.py)."""

import tempfile
from pathlib import Path

import jax.numpy as jnp
import numpy as np
import pytest

from cassini_bayes.estimators.leak import interval_means
from cassini_bayes.inference.thrust.likelihood import jump_area, pulse_layout, tag_expectation
from cassini_bayes.inference.thrust.time_tags import (TAG_NODES, TAG_VARIANCE_SHARE,
                                                      TagSensitivity, tag_sensitivity,
                                                      tag_step_columns, with_pre_command_rates,
                                                      with_tag_expectation)
from cassini_bayes.physics.impulse import impulse_lhs, rate_step_correction
from cassini_bayes.physics.pulse import thrust_profile

TAU = (0.005, 0.020, 0.065)
M = 4


def _event(n=40, seed=0):
    """Rates that step at a few samples (pulses), a large wheel momentum, four thrusters."""
    rng = np.random.default_rng(seed)
    t = np.arange(n, dtype=float) + 0.01 * rng.random(n)
    omega = 1e-3 * np.cumsum(rng.normal(size=(n, 3)) * (rng.random((n, 1)) < 0.3), 0)
    h = np.array([20.0, -5.0, 3.0]) + 0.01 * rng.normal(size=(n, 3))
    t_on = np.sort(rng.uniform(1.0, n - 3.0, 12))
    pulses = (t_on, rng.integers(0, M, 12), rng.uniform(0.05, 0.4, 12))
    q_f = rng.normal(size=(3, M))
    return t, omega, h, pulses, q_f, np.diag([300.0, 250.0, 200.0])


def _left_side(t, omega, h, pulses, q_f, inertia):
    """The model's left side of Eq 17 with its first-order rate-step correction, (n, 3),
    everything rebuilt from the tags ``t``."""
    t_on, thr, width = pulses
    slot = np.searchsorted(t, t_on)
    lay = pulse_layout(t, t_on, thr, width, slot, 3, M)
    mid = [np.asarray(interval_means(x[None]))[0] for x in (omega, h)]
    return np.asarray(impulse_lhs(jnp.asarray(t), omega, inertia, h)
                      + rate_step_correction(inertia, jump_area(lay, q_f, *TAU), *mid).T)


def _sensitivity(t, omega, h, pulses, q_f, inertia):
    t_on, thr, width = pulses
    lay = pulse_layout(t, t_on, thr, width, np.searchsorted(t, t_on), 3, M)
    mid = [np.asarray(interval_means(x[None]))[0] for x in (omega, h)]
    return tag_sensitivity(t, omega, h, lay, inertia, q_f, TAU, *mid)


def test_sensitivity_is_the_model_left_sides_change_with_the_tags():
    """Tags moved by δ (1e-7 s, no sample crossing a command) change the model's left side,
    rebuilt from the moved tags, by Σ δ_i (own at i + step after i) to first order: relative
    1e-4 of the change (the second order is δ/Δt ~ 1e-7 of it)."""
    t, omega, h, pulses, q_f, inertia = _event()
    sens = _sensitivity(t, omega, h, pulses, q_f, inertia)
    delta = 1e-7 * np.random.default_rng(1).normal(size=t.size)
    delta[0] = 0.0                                  # the first tag moves the offset only
    change = (_left_side(t + delta, omega, h, pulses, q_f, inertia)
              - _left_side(t, omega, h, pulses, q_f, inertia))
    later = np.tril(np.ones((t.size, t.size)), -1)  # [k, i] = 1 where k > i
    predicted = sens.own * delta[:, None] + later @ (sens.step * delta[:, None])
    np.testing.assert_allclose(predicted, change, atol=1e-4 * np.abs(change).max())


def test_without_pulses_the_step_is_the_trapezoids():
    """No pulse: the step at sample i is ½ (f_{i−1} − f_{i+1}), f = ω × (Iω + H) (Eq 15)."""
    t, omega, h, _, q_f, inertia = _event()
    none = (np.zeros(1), np.zeros(1, int), np.zeros(1))
    sens = _sensitivity(t, omega, h, none, q_f, inertia)
    f = np.cross(omega, omega @ inertia.T + h)
    np.testing.assert_allclose(sens.step[1:-1], 0.5 * (f[:-2] - f[2:]), rtol=1e-9, atol=1e-15)


def test_only_the_steps_that_matter_get_columns():
    """Steps kept largest first until the walk of the rest is below the share; none for a
    still spacecraft."""
    n = 50
    still = TagSensitivity(np.zeros((n, 3)), np.full((n, 3), 1e-9))
    assert tag_step_columns(still, np.ones(n), np.eye(3) * 1e-8, 0.01).shape[0] == 0
    rng = np.random.default_rng(2)
    sens = TagSensitivity(np.zeros((n, 3)), rng.normal(size=(n, 3)) * rng.random((n, 1))**4)
    b = np.eye(3) * 1e-4
    cols = tag_step_columns(sens, np.ones(n), b, 0.01)
    var = np.sort(0.01**2 * np.sum(sens.step[1:-1]**2, 1) / 1e-4)[::-1]
    p = cols.shape[0]
    assert 0 < p < n - 2
    assert var[p:].sum() <= TAG_VARIANCE_SHARE < var[p - 1:].sum()
    first = np.argmax(np.any(cols[0] != 0.0, 0))    # the column starts after its sample
    assert not cols[0][:, :first].any() and np.all(cols[0][:, first:] == cols[0][:, -1:])


def _layout_with_spread(t, pulses, sd):
    """One event's layout (stacked, E = 1) with every transient sample averaged over ``sd``."""
    t_on, thr, width = pulses
    lay = pulse_layout(t, t_on, thr, width, np.searchsorted(t, t_on), 3, M)
    x, w = np.polynomial.hermite_e.hermegauss(TAG_NODES)
    return lay._replace(tag_spread=np.full(lay.dt.shape, sd), tag_nodes=x,
                        tag_weights=w / w.sum())


def test_tag_expectation_is_the_rate_averaged_over_the_tag():
    """The quadrature against the thrust profile integrated over a dense grid of Normal tags
    (sd 10 ms, pulses of 50-400 ms): within 4 % of the largest change that averaging makes
    (the profile's jump at the delay slows Gauss–Hermite: 1.5 % at 11 nodes). The rate at the
    sample, which a first-order expansion takes, fails it."""
    t, _, _, pulses, _, _ = _event()
    sd = 0.01
    lay = _layout_with_spread(t, pulses, sd)
    got = np.asarray(tag_expectation(thrust_profile, lay, *TAU))
    grid = np.linspace(-6 * sd, 6 * sd, 4001)
    dens = np.exp(-0.5 * (grid / sd)**2)
    dens /= dens.sum()
    exact = np.asarray(thrust_profile(lay.dt[..., None] - grid, lay.width[:, None, None],
                                      *TAU)) @ dens
    at_sample = np.asarray(thrust_profile(lay.dt, lay.width[:, None], *TAU))
    change = np.abs(exact - at_sample).max()
    assert change > 0.1                              # the edges are within the tags' reach
    np.testing.assert_allclose(got, exact, atol=0.04 * change)
    t_on, thr, width = pulses
    plain = pulse_layout(t, t_on, thr, width, np.searchsorted(t, t_on), 3, M)  # one node at 0
    np.testing.assert_array_equal(tag_expectation(thrust_profile, plain, *TAU), at_sample)


def test_tag_expectation_is_kept_where_it_matters():
    """Pulses near a sample's time get the expectation; with tags much smaller than every
    edge's distance to a sample, or no stated tag error, the layout is unchanged."""
    t, _, _, pulses, q_f, _ = _event()
    t_on, thr, width = pulses
    lay = pulse_layout(t, t_on, thr, width, np.searchsorted(t, t_on), 3, M)
    stacked = type(lay)(*(np.asarray(x)[None] for x in lay))
    b = np.eye(3)[None] * 1e-8
    got = with_tag_expectation(stacked, q_f, TAU, b, 0.01)
    assert got.tag_nodes.shape == (1, TAG_NODES) and np.any(got.tag_spread > 0)
    assert with_tag_expectation(stacked, q_f, TAU, b, 0.0) is stacked
    assert with_tag_expectation(stacked, q_f, TAU, b, 1e-9) is stacked


def test_the_sample_before_a_command_gets_its_expected_rate():
    """A pulse commanded 4 ms after a sample (delay 5 ms, tags of 10 ms): that sample's rate is
    the profile averaged over its tag, against a dense grid of Normal tags (4 % of it); a pulse
    commanded 0.4 s after its sample adds nothing, nor does a stated tag sd of zero."""
    t = np.arange(10.0)
    t_on, thr, width = np.array([3.004, 6.4]), np.array([1, 2]), np.array([0.2, 0.2])
    lay = pulse_layout(t, t_on, thr, width, np.searchsorted(t, t_on), 3, M)
    stacked = type(lay)(*(np.asarray(x)[None] for x in lay))
    q_f, b = np.ones((3, M)), np.eye(3)[None] * 1e-10
    rates = np.zeros((1, M, t.size))
    sd = 0.01
    got = with_pre_command_rates(rates, stacked, q_f, TAU, b, sd)
    grid = np.linspace(-6 * sd, 6 * sd, 4001)
    dens = np.exp(-0.5 * (grid / sd)**2)
    exact = sd * float(np.asarray(thrust_profile(-0.004 - grid, 0.2, *TAU)) @ (dens / dens.sum()))
    assert exact > 0.05 * sd                 # a tag within reach puts the sample in the pulse
    np.testing.assert_allclose(got[0, 1, 3], exact, rtol=0.04)  # sample 3 s
    assert np.count_nonzero(got) == 1        # the pulse 0.4 s after its sample: out of reach
    assert with_pre_command_rates(rates, stacked, q_f, TAU, b, 0.0) is rates


def test_the_tag_scale_prior_is_split_at_the_stated_sd():
    """The stated sd is the prior median; the log scale falls with slope 1.5 below it and
    rises with slope 0.5 above (TAG_SCALE_LOG_SD), smoothly and monotonically."""
    from cassini_bayes.inference.thrust.prior import TAG_SCALE_LOG_SD, tag_log_scale

    z = np.linspace(-4.0, 4.0, 801)
    x = np.asarray(tag_log_scale(jnp.asarray(z)))
    assert x[400] == 0.0 and np.all(np.diff(x) > 0)
    assert (x[1] - x[0]) / 0.01 == pytest.approx(TAG_SCALE_LOG_SD[0], rel=0.01)
    assert (x[-1] - x[-2]) / 0.01 == pytest.approx(TAG_SCALE_LOG_SD[1], rel=0.01)


def test_the_learned_tag_sd_is_warned_of_above_the_prior_upper_tail():
    """The warning fires where the posterior median of ``time_tag_sd`` lies above the prior's
    95 % (about 2.5 × the statement), names the site and the statement, and is silent below it
    and where the site is absent."""
    from statistics import NormalDist

    import xarray as xr

    from cassini_bayes.inference.thrust.prior import (TAG_SCALE_WARN_MASS, tag_log_scale,
                                                      tag_scale_warning)

    stated = 0.010
    top = stated * float(np.exp(tag_log_scale(NormalDist().inv_cdf(1 - TAG_SCALE_WARN_MASS))))
    assert 2.0 * stated < top < 3.0 * stated

    def group(median_s):
        draws = median_s * np.exp(0.1 * np.random.default_rng(0).standard_normal((2, 201)))
        draws = draws * median_s / np.median(draws)
        return xr.Dataset({"time_tag_sd": (("chain", "draw"), draws)})

    assert tag_scale_warning(group(0.95 * top), stated) == []
    lines = tag_scale_warning(group(1.05 * top), stated)
    assert len(lines) == 1 and lines[0].startswith("time_tag_sd:")
    assert "10 ms" in lines[0] and "time_tag_sd_s" in lines[0]
    assert tag_scale_warning(xr.Dataset({"tau_rise": (("chain", "draw"), np.ones((2, 3)))}),
                             stated) == []


def _espa_problem(flown_s: float):
    """The robust per-thruster problem of the single-width ESPA biasing event, flown with time
    tags of sd ``flown_s`` and fitted at the model file's default 10 ms."""
    import tomllib

    import cassini_bayes as cb
    from cassini_bayes.files import toml_text
    from cassini_bayes.inference.thrust.data import prepare_thrust
    from cassini_bayes.simulate.scenario import scenario_path

    d = tomllib.loads(scenario_path("biasing_espa_bus").read_text())
    d["noise"]["time_tag_jitter_s"] = flown_s
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "espa.toml"
        path.write_text(toml_text(d))
        sim = cb.simulate_scenario(path, seed=1)
    assert sim.prior.knowledge.time_tag_sd_s == pytest.approx(0.01)
    return sim, prepare_thrust([(sim.telemetry, sim.pulses)], sim.prior, mode="thruster",
                               robust=True, flex="off")


@pytest.mark.parametrize("flown_s, low, high", [(0.0, 0.0, 0.1), (0.01, 0.6, 1.8)])
def test_the_tags_sd_is_learned_from_the_events(flown_s, low, high):
    """At the Laplace centre the time tags' sd over the stated 10 ms follows the tags flown:
    exact tags take it below 0.1 (seen 0.016), 10-ms tags to 0.6-1.8 (seen 1.28). A scale
    held at the stated sd (1) fails the first bound."""
    from cassini_bayes.inference.thrust.coords import physical

    _, problem = _espa_problem(flown_s)
    kw = problem.data
    assert kw.tag_sd is not None and kw.tag_walk.sum() > 0
    p = physical(kw.centre, kw, problem.n_f, problem.n_c, False)
    assert low < float(p.tag_scale) < high
