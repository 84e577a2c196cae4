"""Sensitivity of the inertia estimate to neglected effects (cassini_bayes.inference.sensitivity).

The linearised shifts are checked against refits: injecting an effect at one prior sd along each
of its components and refitting the model that ignores it (Laplace mode of ``prepare_inertia``)
moves ``π`` by ``K e_j sd_j``; the root-sum-square over components must equal the reported shift.
Tolerance: 10 % of the shift plus 0.2 posterior sd (the refits also re-estimate the noise levels,
which the linearisation holds fixed; what matters is the shift in units of the posterior sd, and
that is reproduced to a fifth of an sd).
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import jax
import numpy as np
import pytest

from cassini_bayes.inference.inertia import prepare_inertia
from cassini_bayes.inference.sensitivity import linear_sensitivity, sensitivity_block
from cassini_bayes.physics.momentum import INERTIA_NAMES
from cassini_bayes.report.sensitivity import sensitivity_section
from cassini_bayes.spacecraft import load_spacecraft
from slews import H0, TORQUE, make_slews

KEY = jax.random.key(11)


@pytest.fixture(scope="module")
def sc():
    sc = load_spacecraft("cassini_2000_03_15")
    return replace(sc, knowledge=replace(sc.knowledge, gyro_bias_sd_rad_s=3e-6))


def prep(tel, sc, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return prepare_inertia([tel], sc, **kw)


@pytest.fixture(scope="module")
def base(sc):
    return prep(make_slews(KEY, sc), sc, torque=False)


def test_effects_and_modelled_flags(base, sc):
    s = base.sensitivity
    assert s.effects == ("external_torque", "gyro_bias", "gyro_scale", "wheel_inertia",
                         "wheel_inertia_common", "wheel_axes", "body_torque")
    assert not s.modelled.any()  # torque=False, idealised
    robust = prep(make_slews(KEY, sc), sc, robust=True).sensitivity
    assert robust.modelled.all()


def test_common_wheel_inertia_shift_is_the_scale(sc):
    """Wheel inertias (1 + c) J ignored ⇒ the fit returns π/(1 + c): shift = π × sd_c."""
    base = prep(make_slews(KEY, sc), sc, torque=False, wheel_errors="common")
    k = base.sensitivity.effects.index("wheel_inertia")
    np.testing.assert_allclose(base.sensitivity.shift[k],
                               np.abs(base.laplace_mean) * sc.knowledge.wheel_inertia_sd_frac,
                               rtol=0.02)


def test_per_wheel_inertia_shift_matches_refits(base, sc):
    """One wheel's spin inertia off by one prior sd at a time (the others exact), refitted with
    the model file's: the root-sum-square of the moves is the reported per-wheel shift (it
    reaches the products too: the wheels sit on a cone)."""
    sd = sc.knowledge.wheel_inertia_sd_frac
    moves = []
    for j in range(3):   # make_slews drives RWA1-3
        wheels = tuple(replace(w, inertia=w.inertia * (1 + sd)) if i == j else w
                       for i, w in enumerate(sc.wheels))
        moved = make_slews(KEY, replace(sc, wheels=wheels))
        moves.append(prep(moved, sc, torque=False).laplace_mean - base.laplace_mean)
    rss = np.sqrt(np.sum(np.square(moves), 0))
    k = base.sensitivity.effects.index("wheel_inertia")
    want = base.sensitivity.shift[k]
    assert np.all(np.abs(rss - want) <= 0.1 * want + 0.2 * base.laplace_sd), (rss, want)
    assert np.all(want[3:] > 3 * base.laplace_sd[3:]), want   # products: many sd


def test_gyro_bias_shift_matches_refits(base, sc):
    sd = sc.knowledge.gyro_bias_sd_rad_s
    tel = make_slews(KEY, sc)
    moves = []
    for j in range(3):
        b = np.zeros(3)
        b[j] = sd
        moved = replace(tel, omega=np.asarray(tel.omega) + b)
        moves.append(prep(moved, sc, torque=False).laplace_mean - base.laplace_mean)
    rss = np.sqrt(np.sum(np.square(moves), 0))
    k = base.sensitivity.effects.index("gyro_bias")
    want = base.sensitivity.shift[k]
    assert np.all(np.abs(rss - want) <= 0.1 * want + 0.2 * base.laplace_sd), (rss, want)


def test_external_torque_shift_matches_refits(base, sc):
    moves = []
    for j in range(3):
        tq = np.array(TORQUE, float)
        tq[j] += sc.knowledge.torque_sd_nm
        moved = make_slews(KEY, sc, h0=H0, torque=tq)
        moves.append(prep(moved, sc, torque=False).laplace_mean - base.laplace_mean)
    rss = np.sqrt(np.sum(np.square(moves), 0))
    k = base.sensitivity.effects.index("external_torque")
    want = base.sensitivity.shift[k]
    assert np.all(np.abs(rss - want) <= 0.1 * want + 0.2 * base.laplace_sd), (rss, want)


def test_linear_sensitivity_by_hand():
    """Two parameters, one effect: y = a x + ν; the mode of a with ν ignored moves by
    −(F_aa + P_a)⁻¹ F_aν ν."""
    x = np.array([1.0, 2.0, 3.0])
    cols = np.stack([x, np.ones(3)], 1)                      # (a, ν)
    info = np.zeros((7, 7))
    info[np.ix_([0, 6], [0, 6])] = cols.T @ cols
    prec = np.r_[np.full(6, 1e-6), 1.0]
    sd = np.r_[np.full(6, 1e3), 0.1]
    s = linear_sensitivity(info, prec, sd, np.arange(6), {"nu": [6]})
    assert s.shift[0, 0] == pytest.approx(6.0 / (14.0 + 1e-6) * 0.1)
    assert not s.modelled[0]


def test_summary_block_and_report_section(base):
    post_sd = {n: 2.0 for n in INERTIA_NAMES}
    block = sensitivity_block(base.sensitivity, post_sd)
    assert set(block) == set(base.sensitivity.effects)
    e = block["wheel_inertia"]["parameters"]["Ixx"]
    assert e["shift_in_sd"] == pytest.approx(e["shift"] / 2.0)
    html = sensitivity_section({"sensitivity": block})
    assert "Sensitivity to neglected effects" in str(html)
    assert sensitivity_section({}) is None


def test_posterior_sensitivity_is_the_regression_slope_at_prior_scale():
    """y = 2 x1 − 3 x2 + independent noise over the draws: pinning (x1, x2) at a prior-size
    error (sd 0.1, 0.2) moves y by √((2·0.1)² + (3·0.2)²); an unrelated group moves it ~0."""
    from cassini_bayes.inference.sensitivity import posterior_sensitivity

    rng = np.random.default_rng(0)
    x = rng.normal(size=(20000, 2))
    z = rng.normal(size=(20000, 1))
    y = 2.0 * x[:, 0] - 3.0 * x[:, 1] + rng.normal(size=20000)
    block = posterior_sensitivity({"F": y}, {"wheel_inertia": (x, np.array([0.1, 0.2])),
                                             "gyro_bias": (z, np.array([1.0]))}, {"F": "N"})
    entry = block["wheel_inertia"]["parameters"]["F"]
    assert entry["units"] == "N" and block["wheel_inertia"]["modelled"]
    # slope error ~ 1/√20000 ≈ 0.007 per coefficient: 1 % tolerance is > 5σ
    assert entry["shift"] == pytest.approx(np.hypot(0.2, 0.6), rel=0.01)
    assert entry["shift_in_sd"] == pytest.approx(np.hypot(0.2, 0.6) / y.std(ddof=1), rel=0.01)
    assert block["gyro_bias"]["parameters"]["F"]["shift"] < 0.03
