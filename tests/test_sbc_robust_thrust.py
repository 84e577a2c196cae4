"""SBC of the default robust thrust model (``cassini-bayes sbc thrust --set robust=true``).

The adapter (cassini_bayes.analysis.sbc_models._thrust_robust) draws every parameter of the robust
thrust fit from that fit's prior and flies it; these tests check the options and the ranked
names, that the draws follow the prior the fit states (thrust, centre of mass, time constants,
inertia, the nuisance in the layout ``prepare_thrust`` builds), that the draws reach the
simulator (thrusts, centre of mass, body torque, gyro errors, time tags), and, slow, the
plumbing of a tiny campaign through the command line and the detection of a wrong thrust. The
campaigns themselves are in docs/sbc/thrust_robust*/.
"""

from __future__ import annotations

import json

import jax
import numpy as np
import pytest

from cassini_bayes.analysis.sbc_models import THRUST_SCENARIO, ModelSpec, build_model
from cassini_bayes.analysis.sbc_models._thrust_robust import (
    THRUST_ESPA_SCENARIO,
    robust_thrust_truth,
    simulate_robust_thrust,
)
from cassini_bayes.errors import InputError
from cassini_bayes.simulate.scenario import load_scenario

N_DRAWS = 1000


def test_options_and_ranked_names():
    names = build_model(ModelSpec.make("thrust", robust=True)).parameter_names
    assert names[:4] == ("F", "tau_delay", "tau_rise", "tau_fall")
    assert names[4:10] == ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")
    assert names[10:] == ("gyro_scale[x]", "gyro_scale[y]", "gyro_scale[z]", "gyro_bias[x]",
                          "gyro_bias[y]", "gyro_bias[z]", "wheel_scale[RWA1]",
                          "wheel_scale[RWA2]", "wheel_scale[RWA3]", "time_tag_sd")
    small = build_model(ModelSpec.make("thrust", robust=True, rank_inertia=False,
                                       rank_nuisance=False))
    assert small.parameter_names == ("F", "tau_delay", "tau_rise", "tau_fall")
    with pytest.raises(InputError, match="mode='single'"):
        build_model(ModelSpec.make("thrust", robust=True, mode="single"))
    with pytest.raises(InputError, match="bogus"):
        build_model(ModelSpec.make("thrust", robust=True, bogus=1))
    with pytest.raises(InputError, match="mode"):      # the idealised adapter has no mode
        build_model(ModelSpec.make("thrust", mode="thruster"))


def _z(x, mean, sd):
    return (np.asarray(x) - mean) / sd


@pytest.mark.parametrize("mode", ["mean", "thruster"])
def test_truth_follows_the_fits_prior(mode):
    """1000 draws against the prior the fit states, each component standardised: ``log F``
    about the model's (per-thruster) nominal with sd THRUST_PRIOR_LOG_SD, the centre of mass with
    ``[center_of_mass] sd_m`` (mode ``thruster``), ``log τr``, ``log τf`` by the ``[pulse]``
    prior, ``τd/σ_d`` half-normal (mean √(2/π)), the inertia whitened by its Gaussian's Cholesky
    factor, the nuisance by the ``nu_sd`` of the layout ``prepare_thrust`` builds for the
    scenario's running wheels (sorted, as it sorts them), and the time tags' sd by the inverse
    of ``tag_log_scale`` about the stated sd. Per component the mean within 4 se
    (se = 1/√1000) and the sd within 10 % (sd of a sample sd ≈ 2.2 %: 4.5 se); up to 49
    components × 2 checks at ≥ 4 se: false-failure rate below 0.5 %. A wrong sd, a missing wheel
    or a thrust about the wrong nominal fails."""
    from cassini_bayes.inference.inertia.knowledge import inertia_prior_gaussian
    from cassini_bayes.inference.nuisance import nuisance_layout
    from cassini_bayes.inference.thrust import THRUST_PRIOR_LOG_SD, tau_prior
    from cassini_bayes.inference.thrust.prior import tag_log_scale

    path = THRUST_SCENARIO if mode == "mean" else THRUST_ESPA_SCENARIO
    sc = load_scenario(path)
    sp = sc.prior
    wheels = tuple(sorted(n for n, on in zip(sc.wheel_names, sc.wheels_on) if on))
    d = [robust_thrust_truth(k, sp, wheels, mode)
         for k in jax.random.split(jax.random.key(3), N_DRAWS)]
    layout = nuisance_layout(sp, 1, wheels, torque_rate=True)
    assert d[0]["wheels"] == wheels == layout.wheels
    f_pred = sp.thrust_per_thruster if mode == "thruster" else np.array([sp.thrust])
    cols = [_z(np.log([x["thrust"] for x in d]), np.log(f_pred), THRUST_PRIOR_LOG_SD)]
    if mode == "thruster":
        cols.append(_z([x["com"] for x in d], 0.0, sp.com_sd_m))
        assert np.allclose([x["thrust_n"] for x in d], [x["thrust"] for x in d])
    else:
        assert np.allclose([x["thrust_n"] for x in d], [np.full(8, x["thrust"][0]) for x in d])
        assert not np.any([x["com"] for x in d])
    tp = tau_prior(sp)
    tau = np.array([x["tau"] for x in d])
    cols.append(_z(np.log(tau[:, 1:]), tp.log_mean, tp.log_sd))
    g = inertia_prior_gaussian(sp)
    chol = np.linalg.cholesky(np.asarray(g.cov) + 1e-9 * np.eye(6))
    cols.append(np.linalg.solve(chol, (np.array([x["inertia"] for x in d]) - g.mean).T).T)
    common = np.array([x["wheel_scale_common"] for x in d])
    nu = np.concatenate([np.array([x["gyro_bias"] for x in d]),
                         np.array([x["gyro_scale"] for x in d]),
                         np.array([x["wheel_scale"] for x in d]) - common[:, None],
                         common[:, None],
                         np.array([np.ravel(x["wheel_tilt"]) for x in d]),
                         np.array([x["T_body"] for x in d]),
                         np.array([x["T_N_rate"] for x in d])], 1)
    assert nu.shape[1] == layout.size
    cols.append(nu / layout.sd)
    grid = np.linspace(-8.0, 8.0, 16001)
    log_scale = np.log(np.array([x["time_tag_sd"] for x in d]) / sp.knowledge.time_tag_sd_s)
    cols.append(np.interp(log_scale, np.asarray(tag_log_scale(grid)), grid)[:, None])
    z = np.concatenate(cols, 1)
    se = 1.0 / np.sqrt(N_DRAWS)
    assert np.all(np.abs(z.mean(0)) < 4 * se), z.mean(0)
    np.testing.assert_allclose(z.std(0), 1.0, rtol=0.10)
    half = tau[:, 0] / tp.delay_scale
    assert np.all(half >= 0) and abs(half.mean() - np.sqrt(2 / np.pi)) < 4 * 0.6 * se


def test_truth_reaches_the_simulator():
    """Two ESPA-bus replicates (per-thruster mode): at the last sample the body-axis impulse of
    the body-fixed torques is ``Q(δ) · (each thruster's impulse) + T_body t`` with the drawn
    thrusts' impulses, centre-of-mass offset ``δ`` (``Q(δ)_s = (r_s − e − δ) × d_s``) and body
    torque, to 1e-6 of its size (without ``δ`` it is off by more than 1e-5); each thruster's
    impulse is its drawn thrust times the pulse log's accumulated pulse impulses at the drawn
    time constants (Feldman & Lee §V); the inertial momentum gains ``½ Ṫ t²`` beside that
    impulse, ``Ṫ`` the drawn torque rate in inertial axes (to 1e-6 of the impulse); the recorded
    sample times are jittered with the drawn time-tag sd (sample sd within 25 % over 81 samples,
    ~3 se)."""
    from helpers import replicate_of
    from cassini_bayes.frames import dcm_body_to_inertial
    from cassini_bayes.physics.pulse import pulse_impulse_until
    from cassini_bayes.simulate.run import pulse_log
    from cassini_bayes.spacecraft import moment_matrix

    sc = load_scenario(THRUST_ESPA_SCENARIO)
    keys = jax.random.split(jax.random.key(5), 4)
    drawn, arrays = simulate_robust_thrust(keys[:2], keys[2:], sc, "thruster")
    for i, d in enumerate(drawn):
        again = robust_thrust_truth(keys[i], sc.prior, ("RW1", "RW2", "RW3", "RW4"), "thruster")
        assert np.array_equal(again["thrust"], d["thrust"]) and np.any(d["com"])
        a = replicate_of(arrays, i)
        imp = a.thruster_impulse[-1]
        t_end = a.t[-1] - a.t[0]
        q = moment_matrix(sc.prior.thrusters, sc.prior.com_m + d["com"])
        want = q @ imp + d["T_body"] * t_end
        scale = np.abs(want).max()
        np.testing.assert_allclose(a.impulse_body[-1], want, atol=1e-6 * scale)
        q0 = moment_matrix(sc.prior.thrusters, sc.prior.com_m)
        assert np.abs(q0 @ imp + d["T_body"] * t_end - a.impulse_body[-1]).max() > 1e-5 * scale
        log = pulse_log(a, sc)
        per_pulse = np.asarray(pulse_impulse_until(a.t[-1] - log.t_on, log.width, *d["tau"]))
        np.testing.assert_allclose(imp, np.bincount(log.thruster, per_pulse, minlength=8)
                                   * d["thrust"], rtol=1e-6, atol=1e-9)
        drift = (a.h_inertial[-1] - a.h_inertial[0] - a.impulse_inertial[-1]
                 + a.impulse_inertial[0])
        rate = np.asarray(dcm_body_to_inertial(np.asarray(sc.q0))) @ d["T_N_rate"]
        np.testing.assert_allclose(drift, 0.5 * rate * (a.t[-1]**2 - a.t[0]**2),
                                   atol=1e-6 * scale)
        jitter = np.std(a.t_meas - a.t)
        assert abs(jitter / d["time_tag_sd"] - 1.0) < 0.25


@pytest.mark.slow
def test_tiny_campaign_through_the_cli(run_cli, tmp_path):
    """``cassini-bayes sbc thrust --set robust=true -n 2`` with a tiny sampler (Cassini, mode
    mean): exit 0, 20 ranked parameters (``time_tag_sd`` the last), no failure, the options
    recorded (90 s at load ~13 on the 2-core machine, most of it compiling the simulator and
    the sampler)."""
    out = tmp_path / "sbc"
    code, _, stderr = run_cli("sbc", "thrust", "-n", 2, "--batch", 2, "--seed", 3,
                              "--set", "robust=true", "--set", "num_warmup=60",
                              "--set", "num_draws=30", "--out", out)
    assert code == 0, stderr
    s = json.loads((out / "summary.json").read_text())
    assert s["replicates"] == 2 and s["failures"] == 0 and len(s["parameters"]) == 20
    assert s["settings"]["robust"] is True and s["settings"]["mode"] == "mean"


@pytest.mark.slow
def test_robust_sbc_detects_a_wrong_thrust(tmp_path):
    """The simulator flies 1.1 × the drawn thrust (``thrust_factor``) while the truth recorded is
    the drawn one: ``F``'s posterior (about 0.6 % wide, the wheel scale's prior) sits ~10 % above
    the truth. Eight Cassini replicates (seed 6, one batch; ~6 min on the loaded 2-core machine)
    fail the ECDF statistic at family-wise 1 % (measured once: every F rank 0 of 200, ECDF
    p 3.3e-4 against the per-parameter 5.3e-4, 95 % intervals covering 0 of 8). For a calibrated
    model the test fails at most 1 % of the time."""
    from cassini_bayes.analysis import sbc
    from cassini_bayes.analysis.campaign import run_campaign

    spec = ModelSpec.make("thrust", robust=True, thrust_factor=1.1)
    res = run_campaign(spec, 8, tmp_path, seed=6, batch_size=8)
    out = sbc.sbc_result(res.names, res.rank, res.n_draws, alpha_family=0.01,
                         draws={n: res.draws[:, j] for j, n in enumerate(res.names)},
                         truth={n: res.truth[:, j] for j, n in enumerate(res.names)})
    assert res.failed.sum() == 0
    assert out.parameters["F"].ecdf.p_value < out.alpha
    assert not out.passed("ecdf")
