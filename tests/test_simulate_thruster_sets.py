"""The RCS dead-band controller flies any model: thruster sets chosen from the geometry
(:func:`~cassini_bayes.simulate.controllers.thruster_sets`), the papers' pairs on Cassini, the
ESPA bus's sets, the one-line refusals, and the ESPA bus's wheel-biasing event (dead-band held,
pulse log and momentum bookkeeping against the geometry). The ESPA bus's RCS spin-axis fit at the
default settings is slow."""

from __future__ import annotations

import json
from dataclasses import replace

import jax
import numpy as np
import pytest

from cassini_bayes.errors import InputError
from cassini_bayes.frames import dcm
from cassini_bayes.physics.momentum import inertia_matrix, inertial_momentum, wheel_momentum_body
from cassini_bayes.physics.pulse import pulse_impulse
from cassini_bayes.simulate import load_scenario, scenario_from_dict, simulate
from cassini_bayes.simulate.controllers import thruster_sets
from cassini_bayes.spacecraft import Thruster, load_spacecraft

# Feldman & Lee (2006) §II: the Z-facing thrusters turn about X and Y, the Y-facing couples about
# Z: {Y2, Y4} for +Z, {Y1, Y3} for −Z (Eq 16's thrusters Z1 … Y4).
PAPER_SETS = {(0, 0): ("Z3", "Z4"), (0, 1): ("Z1", "Z2"), (1, 0): ("Z1", "Z4"),
              (1, 1): ("Z2", "Z3"), (2, 0): ("Y2", "Y4"), (2, 1): ("Y1", "Y3")}
ESPA_SETS = {(0, 0): ("A1", "A2", "F3", "F4"), (0, 1): ("A3", "A4", "F1", "F2"),
             (1, 0): ("A2", "A3", "F1", "F4"), (1, 1): ("A1", "A4", "F2", "F3"),
             (2, 0): ("A1", "A3", "F2", "F4"), (2, 1): ("A2", "A4", "F1", "F3")}


def _named(sc, masks) -> dict:
    return {(ax, j): tuple(n for n, on in zip(sc.thruster_names, masks[ax, j]) if on)
            for ax in range(3) for j in range(2)}


def _torques(sc, masks) -> np.ndarray:
    """(3, 2, 3) torque of each set at the nominal thrusts, N m."""
    return np.einsum("ajm,im->aji", masks, sc.moment_matrix * sc.thrust_per_thruster)


@pytest.mark.parametrize("model", ["cassini_post_probe", "cassini_pre_soi", "cassini_post_prm",
                                   "cassini_2000_03_15", "fsds"])
def test_cassini_sets_are_the_papers_pairs(model):
    """Every Cassini model file: exactly Feldman & Lee's pairs, each a pure torque about its axis
    with the right sign (the + and − sets, 12 thrusters in all)."""
    sc = load_spacecraft(model)
    masks = thruster_sets(sc)
    assert _named(sc, masks) == PAPER_SETS
    tau = _torques(sc, masks)
    for ax in range(3):
        for j, sign in enumerate((1, -1)):
            assert sign * tau[ax, j, ax] > 1.0
            assert np.all(np.abs(np.delete(tau[ax, j], ax)) < 1e-12)
    assert masks.sum() == 12


def test_cassini_sets_survive_a_centre_of_mass_offset_and_a_backup_branch():
    """A centre of mass 5 cm off and eight branch-B copies listed after branch A: still the
    papers' pairs, on branch A only (the backups never fire)."""
    sc = load_spacecraft("cassini_post_probe")
    sc = replace(sc, com_m=np.array([0.05, -0.05, 0.05]),
                 thrusters=sc.thrusters + tuple(replace(t, name=t.name + "B", branch="B")
                                                for t in sc.thrusters))
    masks = thruster_sets(sc)
    assert masks.shape == (3, 2, 16) and not masks[:, :, 8:].any()
    assert {k: v for k, v in _named(sc, masks).items()} == PAPER_SETS


def test_espa_sets_turn_mostly_about_their_axis():
    """ESPA bus: X and Y by four thrusters whose axial forces cancel (1.159 N m, net force
    0.732 N), Z by the force-free couples (0.439 N m); the off-axis torque is zero by the
    layout's symmetry (≤ 1e-12 of the on-axis torque) and stays below 1 % with the model's
    centre of mass 1 cm off (the prior the controller flies)."""
    sc = load_spacecraft("espa_bus")
    masks = thruster_sets(sc)
    assert _named(sc, masks) == ESPA_SETS
    for com, tol in ((np.zeros(3), 1e-12), (np.array([0.006, -0.004, 0.007]), 0.01)):
        tau = _torques(replace(sc, com_m=com), masks)
        for ax in range(3):
            for j, sign in enumerate((1, -1)):
                on = sign * tau[ax, j, ax]
                assert on == pytest.approx(1.159 if ax < 2 else 0.439, rel=0.01)
                assert np.linalg.norm(np.delete(tau[ax, j], ax)) <= tol * on


@pytest.mark.parametrize("model, cm", [("cassini_post_probe", 0.05), ("espa_bus", 0.02)])
def test_sets_survive_thruster_misalignments(model, cm):
    """Twenty draws of every thruster's direction tilted by ~3° and its position moved by ``cm``
    per axis (Feldman & Lee: Cassini's thrusters are aligned to ~1°): the same sets every time
    (fixed generator: deterministic)."""
    sc = load_spacecraft(model)
    ref = thruster_sets(sc)
    rng = np.random.default_rng(3)
    for _ in range(20):
        moved = []
        for t in sc.thrusters:
            d = t.direction + np.radians(3.0) * rng.normal(size=3) / np.sqrt(2)
            moved.append(replace(t, direction=d / np.linalg.norm(d),
                                 position=t.position + cm * rng.normal(size=3)))
        np.testing.assert_array_equal(thruster_sets(replace(sc, thrusters=tuple(moved))), ref)


def _through_com(sc):
    """Every thruster pushing along its own position vector: no torque about anything."""
    return replace(sc, com_m=np.zeros(3), thrusters=tuple(
        replace(t, direction=t.position / np.linalg.norm(t.position)) for t in sc.thrusters))


@pytest.mark.parametrize("edit, axis", [
    (_through_com, "+X"),
    # Cassini without its Y-facing thrusters: nothing turns it about Z
    (lambda sc: replace(sc, thrusters=sc.thrusters[:4]), "+Z"),
    # one thruster only: its torque is not about one body axis
    (lambda sc: replace(sc, thrusters=(Thruster("T1", np.array([0.3, 0.3, -0.4]),
                                                np.array([0.0, 0.0, 1.0])),)), "+X"),
])
def test_no_usable_set_is_a_one_line_error(edit, axis):
    sc = edit(load_spacecraft("cassini_post_probe"))
    with pytest.raises(InputError) as e:
        thruster_sets(sc)
    msg = str(e.value)
    assert "\n" not in msg and "'cassini-post-probe'" in msg and f"about {axis}" in msg


def _bias_dict(model: str, **truth) -> dict:
    return {"name": "t", "seed": 1,
            "run": {"duration_s": 20.0, "dt_s": 0.125, "sample_period_s": 1.0, "control": "rcs"},
            "truth": {"model": model, **truth}, "prior": {"model": model},
            "initial": {"wheels_on": ["RW1", "RW2", "RW3", "RW4"]}}


def test_scenario_refusals_are_one_line():
    """RCS control of a model without thrusters, or whose thrusters cannot turn it, and a centre
    of mass moved on a model without thrusters: one line naming the key and the model."""
    d = _bias_dict("models/cubesat_12u.toml")
    d["initial"] = {"wheels_on": ["RWX", "RWY", "RWZ", "RWS"]}
    with pytest.raises(InputError, match=r"'run.control' = \"rcs\" needs thrusters; the truth "
                                         r"model 'cubesat-12u' has none"):
        scenario_from_dict(d, "s.toml")
    d["run"]["control"] = "rwa"
    d["truth"]["center_of_mass_offset_m"] = [0.01, 0.0, 0.0]
    with pytest.raises(InputError, match="center_of_mass_offset_m' moves the centre of mass"):
        scenario_from_dict(d, "s.toml")


def test_truth_centre_of_mass_offset_moves_the_true_torques():
    """``[truth] center_of_mass_offset_m``: the truth's moment matrix is Eq 16's about the moved
    centre, ``Q' = Q − [e×] D``; the prior keeps the model file's."""
    e = np.array([0.006, -0.004, 0.007])
    s = scenario_from_dict(_bias_dict("models/espa_bus.toml", center_of_mass_offset_m=list(e)))
    d = np.stack([t.direction for t in s.truth.thrusters], 1)
    np.testing.assert_allclose(s.truth.moment_matrix,
                               s.prior.moment_matrix - np.cross(e[:, None], d, axis=0),
                               atol=1e-15)
    np.testing.assert_array_equal(s.prior.com_m, np.zeros(3))


# --- the ESPA bus's wheel-biasing event --------------------------------------------------------

@pytest.fixture(scope="module")
def espa_biasing():
    s = load_scenario("biasing_espa_bus")
    return simulate(jax.random.key(s.seed), s)


def test_espa_biasing_holds_its_dead_band(espa_biasing):
    """Four wheels biased to ±4000 rpm under RCS control: every axis stays inside its 10 mrad
    dead-band, every wheel reaches its target, all six sets fire (each thruster several dozen
    times), only whole sets fire at once, and the on-time columns equal the pulse log."""
    r = espa_biasing
    s, a = r.scenario, r.arrays
    err = np.abs(np.asarray(a.pointing_error)).max(0)
    assert np.all(err <= np.asarray(s.rcs.deadband_rad)), err
    rpm = np.asarray(a.wheel_rates)[-1] * 60 / (2 * np.pi)
    np.testing.assert_allclose(rpm, [4000.0, -4000.0, 4000.0, -4000.0], atol=0.1)
    masks = thruster_sets(s.prior).reshape(6, -1).astype(bool)
    fired = np.asarray(a.pulse_units)[np.asarray(a.pulse_units).any(1)] > 0
    for row in fired:                                     # each firing is a union of sets
        whole = [m for m in masks if (row & m).sum() == m.sum()]
        assert np.array_equal(np.any(whole, axis=0), row)
    assert all(((fired & m).sum(1) == 4).sum() >= 10 for m in masks)
    assert set(r.pulses.names) == set(s.truth.thruster_names)
    assert r.telemetry.thruster_names == s.truth.thruster_names
    on = np.bincount(r.pulses.thruster, r.pulses.width, len(s.truth.thrusters))
    np.testing.assert_allclose(r.telemetry.on_times[-1], on, atol=1e-9)


def test_espa_biasing_momentum_bookkeeping(espa_biasing):
    """The pulse log and the truth's per-thruster thrusts account for the momentum: each pulse's
    closed-form impulse (Feldman & Lee §V) sums to the simulated thruster impulse (1e-6), the
    body impulse is ``Q`` (true centre of mass) times it (1e-9), and over each wheel's spin-up
    the inertial momentum change equals ``Σ Aᵀ(q) Q_s F_s g(w)`` over its pulses to 0.2 % (the
    attitude interpolated from the 1 s samples to mid-pulse; measured 0.05-0.13 %), less than
    half what the model file's ``Q`` leaves (the true centre of mass is 1 cm off: 0.3-0.5 %)."""
    r = espa_biasing
    s, a, p, pl = r.scenario, r.arrays, r.params, r.pulses
    f = np.asarray(p.thrust_n)
    g = np.asarray(pulse_impulse(pl.width, *np.asarray(p.tau_s))) * f[pl.thruster]
    per = np.bincount(pl.thruster, g, len(f))
    np.testing.assert_allclose(np.asarray(a.thruster_impulse)[-1], per, rtol=1e-6)
    np.testing.assert_allclose(np.asarray(a.impulse_body)[-1], s.truth.moment_matrix @ per,
                               rtol=1e-9, atol=1e-12)
    t = np.asarray(a.t)
    hw = wheel_momentum_body(np.asarray(a.wheel_rates), np.asarray(p.wheel_axes),
                             np.asarray(p.wheel_inertias))
    h = np.asarray(inertial_momentum(np.asarray(a.q), np.asarray(a.omega),
                                     np.asarray(inertia_matrix(p.inertia)), hw))
    q_mid = np.stack([np.interp(pl.t_on + 0.08, t, c) for c in np.asarray(a.q).T], 1)
    at = np.swapaxes(np.asarray(dcm(q_mid / np.linalg.norm(q_mid, axis=1)[:, None])), 1, 2)
    for lo, hi in ((55, 155), (155, 255), (255, 355), (355, 480)):
        i, j = np.searchsorted(t, (lo, hi))
        sel = (pl.t_on >= lo) & (pl.t_on < hi)
        dh = h[j] - h[i]
        for q, tol in ((s.truth.moment_matrix, 2e-3), (s.prior.moment_matrix, None)):
            body = (q[:, pl.thruster[sel]] * g[sel]).T
            miss = np.linalg.norm(dh - np.einsum("nij,nj->i", at[sel], body))
            if tol is not None:
                assert miss <= tol * np.linalg.norm(dh), (lo, miss)
                true_miss = miss
            else:
                assert miss > 2 * true_miss, (lo, miss, true_miss)


# --- the ESPA bus's RCS spin-axis calibration --------------------------------------------------

@pytest.mark.slow
def test_espa_wheel_axis_by_the_rcs_method(tmp_path):
    """Issue 29's acceptance for the RCS method (Brown §III.B) on the ESPA bus's RW2, with the
    inertia calibrated first from ``slews_espa_bus`` (Brown's budget assumes a flight-calibrated
    inertia; the truth is a few per cent off the model file's): at the default settings (4 × 1000
    draws, robust model, windows detected) the mean axis lies within 0.5° of the truth (measured
    0.10°; with the model file's inertia knowledge alone 1.39°, inside its 8.3° cone: the
    deliberately weaker model fails the tolerance), converged, adequacy passing."""
    import cassini_bayes as cb
    from cassini_bayes.telemetry import write_telemetry

    def telemetry(name):
        s = load_scenario(name)
        path = tmp_path / f"{name}.csv"
        write_telemetry(path, simulate(jax.random.key(s.seed), s).telemetry)
        return s, path

    _, slews = telemetry("slews_espa_bus")
    inertia = cb.fit_inertia(slews, "espa_bus", seed=0)
    s, csv = telemetry("wheel_axis_espa_bus_rcs")
    res = cb.fit_wheel_axis(csv, "espa_bus", wheel="RW2", method="rcs",
                            inertia_posterior=inertia, seed=0)
    summ = json.loads(json.dumps(res.summary()))
    m = np.asarray(summ["direction"]["mean"], float)
    truth = s.truth.wheel("RW2").axis
    err = float(np.degrees(np.arccos(np.clip(m @ truth / np.linalg.norm(m), -1.0, 1.0))))
    assert err < 0.5, err
    d = summ["diagnostics"]
    assert d["divergences"] == 0 and d["max_r_hat"] <= 1.01 and d["converged"], d
    assert summ["adequacy"]["ok"], summ["adequacy"]
