"""The same spacecraft at a fraction of its size gives the same verdicts and the same relative
posterior: no threshold or prior scale is in one spacecraft's absolute units
(docs/model_file.md, "Thresholds relative to the spacecraft").

A shipped model and scenario are scaled by ``s``: the inertia, its products' knowledge, the
wheels' spin inertias and motor-torque limits, the thrust, the external torques and the model
file's ``[torque_knowledge]`` all by ``s``. The same manoeuvre is flown (the controller's
inertia is the model's, so its torques scale too), so the rates, the attitude and every sensor
noise (gyro, star tracker, tachometers: rates and angles) stay as they are, while every momentum
and torque is ``s`` times the original. Simulated with the same key, both files must then give

* ``check``: the same physics verdicts and statistics (momenta divided by ``s``), the same quiet
  periods and idle wheels;
* ``fit inertia`` (robust): the same deterministic part to rounding (the Laplace mean and sd of
  each inertia entry divided by ``s``, the information ratios, the priors: ``H_0`` and ``T_N``
  prior sd and the nuisance priors ``s`` times the original where they are momenta or torques),
  the same adequacy and convergence verdicts, and posterior means and sds over ``s`` equal within
  Monte Carlo error. The chains do not stay together: the scaled sufficient statistics differ in
  the last bits and NUTS trajectories amplify that, so the sampled numbers agree as two seeds do.

Tolerances: deterministic numbers at rtol 1e-6 (they agree to ~1e-11; a threshold or prior put
back in absolute units moves them by 1e-4 or more); sampled means within 5 combined Monte Carlo
standard errors and sds within 5 combined MCSE of the sd (a false failure ~1e-6 per number if the
MCSE estimates hold; 12 numbers).
"""

from __future__ import annotations


import numpy as np
import pytest
import tomli_w

import cassini_bayes as cb
from cassini_bayes.names import INERTIA_NAMES
from cassini_bayes.simulate import scenario_from_dict
from scaled import scaled_model, scaled_scenario

RTOL = 1e-6
K_MCSE = 5.0

# (model, scenario, scale, sampler settings); the CubeSat cannot shrink: its scaled wheels would
# fall below the model file's smallest spin inertia (docs/limits.md)
CASES = [
    pytest.param(("cassini_post_probe", "slews_post_probe", 1e-4,
                  {"chains": 2, "warmup": 100, "draws": 100}), id="cassini-1e-4"),
    pytest.param(("espa_bus", "slews_espa_bus", 1e-2,
                  {"chains": 4, "warmup": 500, "draws": 500}), id="espa-1e-2",
                 marks=pytest.mark.slow),
]


@pytest.fixture(scope="module", params=CASES)
def pair(request, tmp_path_factory):
    """Per scale (1 and ``s``): the model path, the telemetry, ``check``'s result and the fit."""
    model, scenario, s, settings = request.param
    tmp = tmp_path_factory.mktemp("scaled")
    out = {"s": s}
    for scale in (1.0, s):
        path = tmp / f"{model}_{scale:g}.toml"
        path.write_text(tomli_w.dumps(scaled_model(model, scale)))
        sc = scenario_from_dict(scaled_scenario(scenario, scale, str(path)), f"{scenario}")
        tel = cb.simulate_scenario(sc, seed=11).telemetry
        check = cb.check_telemetry(tel, spacecraft=str(path))
        fit = cb.fit_inertia(tel, str(path), seed=5, **settings)
        out[scale] = {"path": path, "model": cb.load_spacecraft(path), "tel": tel,
                      "check": check, "fit": fit}
    return out


def _close(a, b, what: str, rtol: float = RTOL) -> None:
    np.testing.assert_allclose(np.asarray(a, float), np.asarray(b, float), rtol=rtol,
                               atol=0.0, err_msg=what)


def test_the_scaled_spacecraft_flies_the_same_manoeuvre(pair):
    """Rates and attitude agree to rounding: the scaling is the one intended."""
    s = pair["s"]
    a, b = pair[1.0], pair[s]
    assert b["model"].momentum_capacity_nms == pytest.approx(s * a["model"].momentum_capacity_nms,
                                                             rel=1e-12)
    np.testing.assert_allclose(b["tel"].omega, a["tel"].omega, rtol=0, atol=1e-12)
    np.testing.assert_allclose(b["tel"].q, a["tel"].q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.nan_to_num(b["tel"].wheel_rates),
                               np.nan_to_num(a["tel"].wheel_rates), rtol=0, atol=1e-9)


def test_check_gives_the_same_verdicts(pair):
    s = pair["s"]
    a, b = pair[1.0]["check"], pair[s]["check"]
    assert b.physics == a.physics
    assert b.quiet == a.quiet
    assert [w.idle for w in b.wheels] == [w.idle for w in a.wheels]
    assert b.notes == a.notes
    _close(b.attitude.alignment, a.attitude.alignment, "attitude alignment")
    ma, mb = a.momentum, b.momentum
    _close([mb.scale, mb.alignment], [ma.scale, ma.alignment], "momentum scale, alignment")
    xa, xb = ma.axes, mb.axes
    assert xb.judged == xa.judged
    _close([xb.alignment, xb.conditioning], [xa.alignment, xa.conditioning], "free axes")
    _close([xb.swing_nms / s, xb.noise_nms / s], [xa.swing_nms, xa.noise_nms], "swing, noise")
    for name in xa.vectors:
        _close(xb.vectors[name], xa.vectors[name], f"{name}'s momentum per rad/s / J", 1e-5)


def _damaged(tel) -> dict:
    """Damaged copies of ``tel`` that the free-axis momentum balance refuses: the first wheel's
    tachometer halving its scale mid-record, and (where a wheel crosses zero) one reporting
    |rpm| without direction."""
    from dataclasses import replace

    rates = np.array(tel.wheel_rates)
    halved = rates.copy()
    halved[tel.t > 0.5 * (tel.t[0] + tel.t[-1]), 0] *= 0.5
    out = {"scale halves": replace(tel, wheel_rates=halved)}
    crossing = [j for j in range(rates.shape[1])
                if np.any(rates[:, j] < 0) and np.any(rates[:, j] > 0)]
    if crossing:
        unsigned = rates.copy()
        unsigned[:, crossing[0]] = np.abs(unsigned[:, crossing[0]])
        out["unsigned"] = replace(tel, wheel_rates=unsigned)
    return out


def test_check_refuses_the_same_damaged_files(pair):
    """The free-axis balance is judged where the body swings by 100 × the momentum noise: both
    scales refuse the same damaged files in the same words and numbers."""
    from cassini_bayes.errors import InputError

    messages: dict[float, dict[str, str]] = {}
    for scale in (1.0, pair["s"]):
        messages[scale] = {}
        for what, tel in _damaged(pair[scale]["tel"]).items():
            with pytest.raises(InputError, match="do not balance the body's") as err:
                cb.check_telemetry(tel, spacecraft=str(pair[scale]["path"]))
            messages[scale][what] = str(err.value)
    assert messages[pair["s"]] == messages[1.0]


def test_the_priors_scale(pair):
    """``H_0``, ``T_N`` and the robust torques' prior sd are ``s`` times the original; the gyro,
    wheel-scale and tilt priors (rates, fractions, angles) are the same."""
    s = pair["s"]
    pa, pb = pair[1.0]["fit"].posterior.problem, pair[s]["fit"].posterior.problem
    _close(pb.prior.mean / s, pa.prior.mean, "prior mean")
    _close(pb.prior.sd / s, pa.prior.sd, "prior sd")
    _close(pb.prior.file_sd / s, pa.prior.file_sd, "H_0 and T_N prior sd")
    la, lb = pa.layout, pb.layout
    torques = np.zeros(la.size, bool)
    for effect in la.torque_effects:
        torques[la.slices[effect]] = True
    _close(lb.sd[torques] / s, la.sd[torques], "robust torque priors")
    _close(lb.sd[~torques], la.sd[~torques], "gyro, wheel-scale and tilt priors")


def test_fit_gives_the_same_relative_posterior(pair):
    s = pair["s"]
    fa, fb = pair[1.0]["fit"], pair[s]["fit"]
    pa, pb = fa.posterior.problem, fb.posterior.problem
    _close(pb.laplace_mean / s, pa.laplace_mean, "Laplace mean / s")
    _close(pb.laplace_sd / s, pa.laplace_sd, "Laplace sd / s")
    _close(pb.information_ratio, pa.information_ratio, "information ratio", 1e-5)
    assert pb.weak_directions == pa.weak_directions
    _close(pb.noise_eb, pa.noise_eb, "empirical-Bayes noise levels (rates, angles)")
    sa, sb = fa.summary(), fb.summary()
    assert sb["diagnostics"]["converged"] == sa["diagnostics"]["converged"]
    assert sb["adequacy"]["ok"] == sa["adequacy"]["ok"]
    assert ({k: c["ok"] for k, c in sb["adequacy"]["checks"].items()}
            == {k: c["ok"] for k, c in sa["adequacy"]["checks"].items()})
    for name in INERTIA_NAMES:
        xa = fa.idata.posterior[name].values
        xb = fb.idata.posterior[name].values / s
        # ArviZ as the package loads it (tests/conftest.py): without numba, whose
        # mcse(method="sd") kernel fails under NumPy 2
        import arviz as az

        mc_mean = np.hypot(*(np.asarray(az.mcse(x, method="mean")).reshape(()) for x in (xa, xb)))
        mc_sd = np.hypot(*(np.asarray(az.mcse(x, method="sd")).reshape(()) for x in (xa, xb)))
        assert abs(xb.mean() - xa.mean()) <= K_MCSE * mc_mean, (name, xa.mean(), xb.mean())
        assert abs(xb.std() - xa.std()) <= K_MCSE * mc_sd, (name, xa.std(), xb.std())


@pytest.fixture(scope="module")
def leak_pair(tmp_path_factory):
    """Cassini's leak scenario (10 % of Z1 from 600 s, cut to 20 min) flown at its size and at
    1e-4 of it (true thrusts scaled too): per scale the monitor's inputs."""
    from cassini_bayes.inference.leak import leak_inputs

    tmp = tmp_path_factory.mktemp("scaled_leak")
    out = {}
    for scale in (1.0, 1e-4):
        path = tmp / f"cassini_post_probe_{scale:g}.toml"
        path.write_text(tomli_w.dumps(scaled_model("cassini_post_probe", scale)))
        d = scaled_scenario("leak_cruise", scale, str(path))
        d["truth"]["thrust_n"] = [f * scale for f in d["truth"]["thrust_n"]]
        d["run"]["duration_s"] = 1200.0
        sim = cb.simulate_scenario(scenario_from_dict(d, "leak_cruise"), seed=11)
        out[scale] = leak_inputs(sim.telemetry, sim.pulses, cb.load_spacecraft(path))
    return out


def test_leak_monitor_gives_the_same_answer(leak_pair):
    """The Bayesian leak monitor at 1e-4 of Cassini: the residual, its offset prior and noise
    floor 1e-4 times the original, every probability at every check, the fraction, its interval
    and the onset the same (rtol 1e-6; they agree to 1e-14 and 1e-10). The noise floor of
    1e-6 N m s put back (the scaled residual's noise is ~7e-7 N m s) moves the fraction's sd by
    27 %: the test can fail. (The offset prior's scale barely matters: 10 N m s instead of the
    wheels' capacity moves the probabilities by 7e-12.)"""
    import dataclasses

    from cassini_bayes.inference.leak import leak_posterior

    a, b = leak_pair[1.0], leak_pair[1e-4]
    np.testing.assert_allclose(b.residual / 1e-4, a.residual, rtol=0,
                               atol=1e-6 * np.max(np.abs(a.residual)))
    _close(b.offset_sd_nms / 1e-4, a.offset_sd_nms, "offset prior sd / s")
    _close(b.noise_floor_nms / 1e-4, a.noise_floor_nms, "noise floor / s")
    pa, pb = leak_posterior(a), leak_posterior(b)
    assert pa.thruster == pb.thruster == "Z1"
    assert pa.detection_time_s == pb.detection_time_s
    np.testing.assert_allclose(pb.prob, pa.prob, rtol=0, atol=RTOL)
    _close([pb.fraction_mean, pb.fraction_sd, *pb.fraction_interval, pb.onset_s],
           [pa.fraction_mean, pa.fraction_sd, *pa.fraction_interval, pa.onset_s],
           "fraction, its sd and interval, onset")
    _close(pb.noise_sd_nms / 1e-4, pa.noise_sd_nms, "noise level / s")
    old = leak_posterior(dataclasses.replace(b, noise_floor_nms=1e-6))
    assert abs(old.fraction_sd - pa.fraction_sd) > 100 * RTOL * pa.fraction_sd
