"""A regular telemetry clock (inference/thrust/clock.py): the labels on their grid, the grid's
offset and period errors as nuisance columns of the robust thrust fit."""

from dataclasses import replace

import jax.numpy as jnp
import numpy as np
import pytest

from cassini_bayes.errors import InputError
from cassini_bayes.estimators.leak import interval_means
from cassini_bayes.inference.thrust.clock import clock_columns, clock_grid
from cassini_bayes.inference.thrust.likelihood import (jump_area, pulse_layout,
                                                       thruster_impulse)
from cassini_bayes.physics.impulse import impulse_lhs, rate_step_correction

TAU = (0.005, 0.020, 0.065)
M = 4


def _labels(n=400, sd=0.01, seed=0):
    """True times on a 0.5-s clock from 100 s with samples 50-59 missing, and labels carrying
    white errors of sd ``sd``."""
    rng = np.random.default_rng(seed)
    t = 100.0 + 0.5 * np.delete(np.arange(n + 10), np.arange(50, 60))
    return t, t + sd * rng.standard_normal(n)


def test_the_grid_is_the_labels_least_squares_line():
    """Through a gap of ten samples the grid keeps each sample's place: its error from the true
    times is the offset and period error the grid states, within 4 of their sds (a false
    failure below 1e-4), and the scatter is the labels' sd within 15 % (n = 400: the estimate's
    relative sd is 3.5 %, 4 sds)."""
    t, labels = _labels()
    g = clock_grid(labels)
    err = g.t - t
    period, offset = np.polyfit(g.index, err, 1)
    assert np.allclose(err, offset + period * g.index, rtol=0, atol=1e-12)   # a straight line
    assert abs(offset) < 4 * g.offset_sd_s and abs(period) < 4 * g.period_sd_s
    assert g.scatter_s == pytest.approx(0.01, rel=0.15)
    assert g.offset_sd_s == pytest.approx(g.scatter_s / np.sqrt(t.size))
    assert g.period_sd_s == pytest.approx(g.scatter_s / np.sqrt(np.sum(g.index**2)))
    assert clock_grid(labels, sd_s=0.02).offset_sd_s == pytest.approx(0.02 / np.sqrt(t.size))
    d = g.to_dict()
    assert d["period_s"] == pytest.approx(0.5, abs=1e-4) and d["scatter_s"] == g.scatter_s


def test_labels_off_a_regular_clock_are_a_one_line_error():
    t, labels = _labels(sd=0.0)
    labels[123] += 0.2
    with pytest.raises(InputError, match=r"tel.csv: the sample labelled t = 166.7 s is 19. ms "
                                         r"off .*regular_clock"):
        clock_grid(labels, "tel.csv")
    with pytest.raises(InputError, match="3 or more samples"):
        clock_grid(t[:2])


def _event(n=40, seed=0):
    """Rates that step at a few samples, a large wheel momentum, four thrusters, on a 1-s
    clock (the pulses' commands between samples)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n, dtype=float)
    omega = 1e-3 * np.cumsum(rng.normal(size=(n, 3)) * (rng.random((n, 1)) < 0.3), 0)
    h = np.array([20.0, -5.0, 3.0]) + 0.01 * rng.normal(size=(n, 3))
    t_on = np.sort(rng.uniform(1.0, n - 3.0, 12)).round(3)
    pulses = (t_on, rng.integers(0, M, 12), rng.uniform(0.05, 0.4, 12))
    return t, omega, h, pulses, rng.normal(size=(3, M)), np.diag([300.0, 250.0, 200.0])


def _residual(t, omega, h, pulses, q_f, inertia):
    """Eq 17's left minus right side (3, n), everything rebuilt from the sample times ``t``."""
    t_on, thr, width = pulses
    lay = pulse_layout(t, t_on, thr, width, np.searchsorted(t, t_on), 3, M)
    mid = [np.asarray(interval_means(x[None]))[0] for x in (omega, h)]
    left = (impulse_lhs(jnp.asarray(t), omega, inertia, h)
            + rate_step_correction(inertia, jump_area(lay, q_f, *TAU), *mid).T)
    return np.asarray(left.T - thruster_impulse(lay, q_f, *TAU))


def test_the_columns_are_the_residuals_change_with_the_clock():
    """Every sample moved by ``a + b (i − ī)`` (a = 1e-6 s, b = 1e-8 s per sample; no sample
    crosses a command) changes the residual rebuilt from the moved times by ``a col_a +
    b col_b`` to first order: within 1e-4 of the change."""
    t, omega, h, pulses, q_f, inertia = _event()
    t_on, thr, width = pulses
    lay = pulse_layout(t, t_on, thr, width, np.searchsorted(t, t_on), 3, M)
    mid = [np.asarray(interval_means(x[None]))[0] for x in (omega, h)]
    grid = clock_grid(t, sd_s=0.01)
    cols = clock_columns(t, omega, h, lay, inertia, q_f, TAU, *mid, grid)
    a, b = 1e-6, 1e-8
    moved = t + a + b * grid.index
    change = _residual(moved, omega, h, pulses, q_f, inertia) - _residual(t, omega, h, pulses,
                                                                          q_f, inertia)
    predicted = a * cols[0] + b * cols[1]
    assert np.max(np.abs(change)) > 0
    assert np.max(np.abs(change - predicted)) < 1e-4 * np.max(np.abs(change))


@pytest.fixture(scope="module")
def espa_clock():
    """The single-width ESPA biasing event flown with 10-ms tags on a regular clock, and its
    robust problem where the model file states the clock regular."""
    import tomllib
    import tempfile
    from pathlib import Path

    import cassini_bayes as cb
    from cassini_bayes.files import toml_text
    from cassini_bayes.inference.thrust.data import prepare_thrust
    from cassini_bayes.simulate.scenario import scenario_path

    d = tomllib.loads(scenario_path("biasing_espa_bus").read_text())
    d["noise"]["time_tag_jitter_s"] = 0.01
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "espa.toml"
        path.write_text(toml_text(d))
        sim = cb.simulate_scenario(path, seed=1)
    prior = replace(sim.prior, knowledge=replace(sim.prior.knowledge, regular_clock=True))
    return sim, prepare_thrust([(sim.telemetry, sim.pulses)], prior, mode="thruster",
                               robust=True, flex="off")


def test_a_regular_clock_replaces_the_white_tags_by_the_grids_errors(espa_clock):
    """The labels go on their grid (its scatter the flown 10 ms within 15 %), the white tag
    terms and their learned scale are gone, and the grid's two errors are integrated out with
    the sds it states; they are not drawn as sites."""
    sim, problem = espa_clock
    (grid,) = problem.clock
    assert grid.scatter_s == pytest.approx(0.01, rel=0.15)
    t = np.asarray(problem.data.events.t[0])[:sim.telemetry.n]
    assert np.allclose(t, grid.t) and np.ptp(np.diff(t)) < 1e-9
    assert problem.data.tag_sd is None
    assert "time_tag_steps" not in problem.layout.slices
    sl = problem.layout.slices["clock"]
    assert np.allclose(problem.layout.sd[sl], [grid.offset_sd_s, grid.period_sd_s])
    assert "clock" not in problem.layout.sites
    cols = np.asarray(problem.data.events.nu_cols[0])[sl]
    assert np.all(np.linalg.norm(cols.reshape(2, -1), axis=1) > 0)


def test_the_model_file_states_the_clock(tmp_path):
    from cassini_bayes._paths import MODELS_DIR
    from cassini_bayes.spacecraft import load_spacecraft, spacecraft_from_dict

    text = (MODELS_DIR / "espa_bus.toml").read_text()
    path = tmp_path / "sc.toml"
    path.write_text(text + "\n[telemetry_knowledge]\nregular_clock = true\n")
    sc = load_spacecraft(path)
    assert sc.knowledge.regular_clock
    assert spacecraft_from_dict(sc.to_dict()).knowledge.regular_clock
    assert not load_spacecraft("espa_bus").knowledge.regular_clock
    path.write_text(text + "\n[telemetry_knowledge]\nregular_clock = 1\n")
    with pytest.raises(InputError, match="regular_clock.*true or false"):
        load_spacecraft(path)


def test_a_plan_states_the_grids_errors_at_the_model_files_tag_sd():
    """Noise-free labels have no scatter; the plan's prediction takes the grid's errors at the
    model file's ``time_tag_sd_s`` instead (10 ms for the ESPA bus)."""
    from cassini_bayes.plan.thrust import noise_free_problem
    from cassini_bayes.simulate import load_scenario

    s = load_scenario("biasing_espa_bus")
    prior = replace(s.prior, knowledge=replace(s.prior.knowledge, regular_clock=True))
    _, problem, _ = noise_free_problem(replace(s, prior=prior), "thruster")
    (grid,) = problem.clock
    n = grid.t.size
    assert grid.offset_sd_s == pytest.approx(0.01 / np.sqrt(n))
    assert np.allclose(problem.layout.sd[problem.layout.slices["clock"]],
                       [0.01 / np.sqrt(n), 0.01 / np.sqrt(np.sum(grid.index**2))])
