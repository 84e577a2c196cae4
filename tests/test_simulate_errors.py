"""Simulator real-world error effects not covered elsewhere: telemetry time-tag jitter and the
flexible/slosh mode (hybrid coordinates, :class:`cassini_bayes.simulate.scenario.FlexMode`)."""

from __future__ import annotations

import jax
import numpy as np
import pytest

from cassini_bayes.errors import InputError
from cassini_bayes.physics.momentum import inertia_matrix
from cassini_bayes.simulate import (noise_params, scenario_from_dict, simulate, simulate_batch,
                                    truth_params)

DELTA_Z = 37.0          # kg^½ m about Z: δᵀ I⁻¹ δ ≈ 0.37 of the Post-Probe Izz (a strong mode)


def _drift_dict(duration=300.0, flex=None, jitter=0.0):
    """RCS control, dead-bands too wide to fire, one open-loop Y pulse pair at 10 s (a kick)."""
    d = {
        "name": "flex_drift", "seed": 1,
        "run": {"duration_s": duration, "dt_s": 0.125, "sample_period_s": 0.5, "control": "rcs"},
        "truth": {"model": "models/cassini_post_probe.toml"},
        "prior": {"model": "models/cassini_post_probe.toml"},
        "initial": {"wheels_on": ["RWA1", "RWA2", "RWA3"],
                    "wheel_rpm": {"RWA1": 300.0, "RWA2": -200.0, "RWA3": 100.0}},
        "rcs_controller": {"deadband_mrad": [1000.0, 1000.0, 1000.0]},
        "pulse": [{"t_on_s": 10.0, "thruster": "Y1", "width_s": 0.75},
                  {"t_on_s": 10.0, "thruster": "Y3", "width_s": 0.75}],
        "noise": {"gyro_rad_s": 1e-6, "star_tracker_rad": 5e-5, "tach_quantum_rpm": 0.1,
                  "time_tag_jitter_s": jitter},
    }
    if flex is not None:
        d["flex_mode"] = flex
    return d


MODE = {"freq_hz": 0.05, "damping": 0.0, "coupling": [0.0, 0.0, DELTA_Z]}


@pytest.fixture(scope="module")
def flex_run():
    return simulate(jax.random.key(0), scenario_from_dict(_drift_dict(flex=MODE)))


@pytest.fixture(scope="module")
def rigid_run():
    return simulate(jax.random.key(0), scenario_from_dict(_drift_dict()))


def test_effects_off_by_default(rigid_run):
    s = rigid_run.scenario
    assert s.flex is None and s.noise.time_tag_jitter_s == 0.0
    a = rigid_run.arrays
    np.testing.assert_array_equal(a.t_meas, a.t)
    np.testing.assert_array_equal(a.flex_eta, 0.0)
    np.testing.assert_array_equal(rigid_run.telemetry.t, rigid_run.truth.t)


def test_time_tag_jitter_level_and_only_the_tags_change(rigid_run):
    s = scenario_from_dict(_drift_dict(jitter=0.02))
    assert float(noise_params(s).time_tag_jitter_s) == 0.02
    r = simulate(jax.random.key(0), s)
    err = r.telemetry.t - r.truth.t
    # 601 draws: the sample sd is within 10 % of 0.02 s unless a 2.4-sigma event (~2 %)
    assert abs(np.std(err) / 0.02 - 1.0) < 0.1
    assert abs(np.mean(err)) < 4 * 0.02 / np.sqrt(err.size)
    assert np.all(np.diff(r.telemetry.t) > 0)
    np.testing.assert_array_equal(r.truth.t, rigid_run.truth.t)
    # values are those at the true times, with the same noise as without jitter
    np.testing.assert_array_equal(r.telemetry.omega, rigid_run.telemetry.omega)
    np.testing.assert_array_equal(r.telemetry.q, rigid_run.telemetry.q)


def test_flex_mode_rings_at_the_coupled_frequency(flex_run):
    """Undamped mode excited by the Y-pulse kick: η oscillates at Ω / √(1 − δᵀ I⁻¹ δ) (the body
    recoils while the mode swings), not at the cantilevered Ω."""
    a, s = flex_run.arrays, flex_run.scenario
    t, eta = np.asarray(a.t), np.asarray(a.flex_eta)
    assert np.max(np.abs(eta)) > 0
    delta = np.asarray(s.flex.coupling)
    share = delta @ np.linalg.solve(np.asarray(inertia_matrix(truth_params(s).inertia)), delta)
    f_free = s.flex.freq_hz / np.sqrt(1.0 - share)
    m = t > 20.0
    x = eta[m] - np.mean(eta[m])
    ups = np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]
    tz = t[m][ups] - x[ups] * (t[m][ups + 1] - t[m][ups]) / (x[ups + 1] - x[ups])
    f_meas = (ups.size - 1) / (tz[-1] - tz[0])
    # the integrator's phase error at Ω dt ≈ 0.05 is ~1e-4; 0.5 % separates Ω from Ω_free by 50x
    assert f_meas == pytest.approx(f_free, rel=5e-3)
    assert abs(f_meas / s.flex.freq_hz - 1.0) > 0.2


def test_flex_mode_keeps_momentum_and_shakes_the_rates(flex_run, rigid_run):
    a = flex_run.arrays
    h = np.asarray(a.h_inertial)
    # total momentum changes only by the thruster impulse (the mode is internal)
    np.testing.assert_allclose(h - h[0], np.asarray(a.impulse_inertial), atol=1e-12)
    # the hub's Z rate carries the mode's recoil: δ η̇ / Izz-ish, absent in the rigid run
    dw = np.asarray(a.omega)[:, 2] - np.asarray(rigid_run.arrays.omega)[:, 2]
    assert np.max(np.abs(dw)) > 1e-6
    assert flex_run.telemetry.wheel_rates.shape == rigid_run.telemetry.wheel_rates.shape


def test_flex_mode_damps():
    mode = {**MODE, "damping": 0.05}
    r = simulate(jax.random.key(0), scenario_from_dict(_drift_dict(flex=mode)))
    t, eta = np.asarray(r.arrays.t), np.asarray(r.arrays.flex_eta)
    early = np.max(np.abs(eta[(t > 20) & (t < 60)]))
    late = np.max(np.abs(eta[t > 260]))
    # envelope exp(−ζ Ω_free Δt) over ~220 s: ~1e-3 (upper bound 2e-2 leaves room for the phase)
    assert late < 0.02 * early


def test_batch_with_mode_and_jitter_matches_single():
    s = scenario_from_dict(_drift_dict(duration=60.0, flex=MODE, jitter=0.01))
    keys = jax.random.split(jax.random.key(3), 3)
    batch = simulate_batch(keys, s)
    one = simulate(keys[1], s)
    np.testing.assert_allclose(np.asarray(batch.flex_eta[1]), one.arrays.flex_eta, atol=1e-12)
    np.testing.assert_allclose(np.asarray(batch.t_meas[1]), one.telemetry.t, atol=1e-12)
    # a batched truth with the mode's parameters varied per replicate runs too
    tp = truth_params(s)
    tiled = jax.tree.map(lambda x: np.broadcast_to(np.asarray(x), (3,) + np.shape(x)), tp)
    tiled = tiled._replace(flex_freq_rad_s=np.array([0.2, 0.3, 0.4]))
    out = simulate_batch(keys, s, tiled)
    assert np.all(np.isfinite(np.asarray(out.flex_eta)))
    assert not np.allclose(out.flex_eta[0], out.flex_eta[2])


@pytest.mark.parametrize("section, value, needle", [
    ("noise", {"time_tag_jitter_s": 0.1}, "noise.time_tag_jitter_s"),
    ("noise", {"time_tag_jitter_s": -0.01}, "noise.time_tag_jitter_s"),
    ("flex_mode", {"freq_hz": 2.0, "damping": 0.01, "coupling": [1.0, 0, 0]}, "flex_mode.freq_hz"),
    ("flex_mode", {"freq_hz": 0.1, "damping": 1.5, "coupling": [1.0, 0, 0]}, "flex_mode.damping"),
    ("flex_mode", {"freq_hz": 0.1, "damping": 0.0, "coupling": [0, 0, 60.0]},
     "flex_mode.coupling"),
    ("flex_mode", {"freq_hz": 0.1, "damping": 0.0, "coupling": [0, 0, 0]}, "flex_mode.coupling"),
    ("flex_mode", {"freq_hz": 0.1, "coupling": [1.0, 0, 0]}, "flex_mode.damping"),
    ("flex_mode", {"freq_hz": 0.1, "damping": 0.0, "coupling": [1, 0, 0], "mass": 3},
     "flex_mode.mass"),
])
def test_bad_values_are_one_line_errors(section, value, needle):
    d = _drift_dict()
    d[section] = {**d.get(section, {}), **value}
    with pytest.raises(InputError) as e:
        scenario_from_dict(d, "bad.toml")
    assert needle in str(e.value) and "\n" not in str(e.value)


# ---- per-wheel spin-inertia errors -------------------------------------------------------

def _wheel_truth(**keys):
    d = _drift_dict(duration=20.0)
    d["truth"].update(keys)
    return scenario_from_dict(d)


def test_per_wheel_inertia_errors_fixed_and_drawn():
    """True J_k = scale × (1 + e_k) × the model file's; absent keys change nothing; the drawn
    errors are independent per wheel, fixed by the scenario's seed, and add to the fixed ones."""
    base = _wheel_truth()
    assert base.wheel_inertia_errors == () and base.wheel_inertia_scale == 1.0
    np.testing.assert_array_equal(base.truth.wheel_inertias, base.prior.wheel_inertias)
    e = [0.008, -0.006, 0.010, -0.007]
    s = _wheel_truth(wheel_inertia_errors=e, wheel_inertia_scale=1.002)
    np.testing.assert_allclose(s.truth.wheel_inertias,
                               1.002 * (1 + np.array(e)) * s.prior.wheel_inertias, rtol=1e-15)
    assert s.wheel_inertia_errors == tuple(e)
    d1 = _wheel_truth(wheel_inertia_error_sd=0.005).wheel_inertia_errors
    assert d1 == _wheel_truth(wheel_inertia_error_sd=0.005).wheel_inertia_errors   # seeded
    assert len(set(d1)) == 4 and all(0 < abs(x) < 0.03 for x in d1)   # 6 sd: never by chance
    both = _wheel_truth(wheel_inertia_error_sd=0.005, wheel_inertia_errors=e)
    np.testing.assert_allclose(both.wheel_inertia_errors, np.array(d1) + e, rtol=1e-14)
    other = scenario_from_dict({**_drift_dict(duration=20.0), "seed": 2,
                                "truth": {"model": "models/cassini_post_probe.toml",
                                          "wheel_inertia_error_sd": 0.005}})
    assert other.wheel_inertia_errors != d1


def test_per_wheel_inertia_errors_in_truth_json_and_in_the_run():
    """truth.json records each wheel's true spin inertia and its error; the run uses them (the
    inertial momentum of the true model is conserved between pulses)."""
    from cassini_bayes.api import truth_document

    e = [0.008, -0.006, 0.010, -0.007]
    s = _wheel_truth(wheel_inertia_errors=e)
    doc = truth_document(simulate(jax.random.key(0), s), 0)
    np.testing.assert_allclose([w["inertia_error_frac"] for w in doc["wheels"]], e, rtol=1e-12)
    np.testing.assert_allclose([w["inertia_kgm2"] for w in doc["wheels"]],
                               (1 + np.array(e)) * s.prior.wheel_inertias, rtol=1e-12)
    assert doc["wheel_inertia_errors"] == e and doc["wheel_inertia_scale"] == 1.0
    np.testing.assert_allclose(np.asarray(truth_params(s).wheel_inertias)[:3],
                               s.truth.wheel_inertias[:3], rtol=1e-15)


@pytest.mark.parametrize("keys, needle", [
    ({"wheel_inertia_errors": [0.01, 0.0, 0.0]}, "wheel_inertia_errors"),
    ({"wheel_inertia_errors": [0.2, 0.0, 0.0, 0.0]}, "small fraction"),
    ({"wheel_inertia_error_sd": -0.01}, "wheel_inertia_error_sd"),
])
def test_bad_wheel_inertia_errors_are_one_line_errors(keys, needle):
    with pytest.raises(InputError, match=needle):
        _wheel_truth(**keys)
