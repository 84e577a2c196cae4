"""One spin-inertia scale per wheel (robust models, ``wheel_errors="per_wheel"``) against the
earlier single common scale (``"common"``).

The wheels sit on a cone, not along the body axes, so wheels whose spin inertias are off by
different fractions tilt the wheel momentum: the products of inertia move by many posterior sd
(``docs/robust/per_wheel.md``). A common scale cannot absorb that; one scale per wheel can, and
the data learn the differences from slews about several axes while the common part stays at its
prior (Psiaki 2005). Data: the multi-axis slews of ``make_slews`` (tests/slews.py:
Y, X, Y, Z and a skew axis, wheels RWA1-3) whose true wheels are off by ``ERRORS``.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import jax
import numpy as np
import pytest

from cassini_bayes.errors import InputError
from cassini_bayes.inference.inertia import fit_inertia
from cassini_bayes.inference.nuisance import (nuisance_layout, robust_columns, wheel_scale_columns,
                                              without_common_scale)
from cassini_bayes.inference.runner import SamplerSettings
from cassini_bayes.physics.momentum import INERTIA_NAMES, inertia_vector
from cassini_bayes.spacecraft import load_spacecraft, spacecraft_from_dict
from margins import assert_mixed
from slews import TRUTH, make_slews

PI_TRUE = np.asarray(inertia_vector(TRUTH))
# Each wheel's true spin-inertia error (RWA1..RWA4; RWA4 is off in these slews): ±0.6-0.9 %,
# independent signs, each 1.2-1.8 prior sd of 0.5 %.
ERRORS = np.array([0.008, -0.009, 0.006, -0.007])
FIT = SamplerSettings(chains=4, warmup=300, draws=300)


@pytest.fixture(scope="module")
def sc():
    return load_spacecraft("cassini_2000_03_15")


def with_wheel_errors(sc, errors):
    return replace(sc, wheels=tuple(replace(w, inertia=w.inertia * (1 + e))
                                    for w, e in zip(sc.wheels, errors)))


# ---- layout and columns ------------------------------------------------------------------

def test_per_wheel_columns_sum_to_the_common_column(sc):
    """Column k = J_k ρ_k g_k (wheel k's momentum, body axes); their sum over wheels is the
    common model's one column H_w, and the shared scale c_s's column; every other column is the
    same in both layouts."""
    rng = np.random.default_rng(0)
    n, wheels = 50, ("RWA1", "RWA2", "RWA3")
    wheel_h = {w: rng.normal(size=n) for w in wheels}
    h_w = sum(wheel_h[w][:, None] * sc.wheel(w).axis for w in wheels)
    args = (np.asarray(sc.inertia), rng.normal(size=(n, 3)) * 1e-3, h_w, wheel_h,
            np.tile(np.eye(3), (n, 1, 1)), np.arange(n, dtype=float))
    per = nuisance_layout(sc, 2, wheels)
    common = nuisance_layout(sc, 2, wheels, wheel_errors="common")
    assert per.n_scales == 3 and common.n_scales == 1 and per.size == common.size + 3
    assert per.has_common and not common.has_common
    c_per = robust_columns(per, 1, *args)
    c_com = robust_columns(common, 1, *args)
    s_per, s_com = per.slices["wheel_inertia"], common.slices["wheel_inertia"]
    np.testing.assert_allclose(c_per[:, :, s_per].sum(-1), c_com[:, :, s_com.start], rtol=1e-12)
    np.testing.assert_allclose(c_com[:, :, s_com.start], h_w, rtol=0)
    np.testing.assert_allclose(c_per[:, :, per.slices["wheel_inertia_common"].start], h_w,
                               rtol=1e-12)
    for k, w in enumerate(wheels):
        np.testing.assert_allclose(c_per[:, :, s_per.start + k],
                                   wheel_h[w][:, None] * sc.wheel(w).axis, rtol=0)
    rest = [e for e in per.slices if e not in ("wheel_inertia", "wheel_inertia_common")]
    for e in rest:
        np.testing.assert_array_equal(c_per[:, :, per.slices[e]], c_com[:, :, common.slices[e]])
    # a wheel not running in the file has a zero column
    only = wheel_scale_columns(per, h_w, {"RWA2": wheel_h["RWA2"]})
    assert not only[:, :, [0, 2]].any() and only[:, :, 1].any()


def test_without_common_scale_keeps_the_deviations(sc):
    """The thrust fit's wheel block with the common scale taken out: no combination of its
    parameters moves every wheel alike any more (the shared scale's column is zero), and the
    deviations from the precision-weighted mean keep their columns, with that mean independent
    of them a priori (unequal knowledge: the weights are not the plain mean)."""
    rng = np.random.default_rng(1)
    n, wheels = 40, ("RWA1", "RWA2", "RWA3")
    knowledge = {"RWA1": 0.002, "RWA2": 0.005, "RWA3": 0.01}
    sc2 = replace(sc, wheels=tuple(replace(w, inertia_sd_frac=knowledge.get(w.name))
                                   for w in sc.wheels))
    lay = nuisance_layout(sc2, 1, wheels)
    wheel_h = {w: rng.normal(size=n) for w in wheels}
    h_w = sum(wheel_h[w][:, None] * sc.wheel(w).axis for w in wheels)
    cols = robust_columns(lay, 0, np.asarray(sc.inertia), rng.normal(size=(n, 3)) * 1e-3, h_w,
                          wheel_h, np.tile(np.eye(3), (n, 1, 1)), np.arange(n, dtype=float))
    out = without_common_scale(cols, lay)
    blk = lay.wheel_block
    w = lay.common_scale_weights
    prec = 1.0 / np.array(list(knowledge.values()))**2
    np.testing.assert_allclose(w, np.r_[prec / prec.sum(), 1.0], rtol=1e-12)
    scale = np.abs(cols[..., blk]).max()
    np.testing.assert_allclose(out[..., blk.stop - 1], 0.0, atol=1e-14 * scale)   # c_s: none
    np.testing.assert_allclose(out[..., blk][..., :3].sum(-1), 0.0, atol=1e-14 * scale)
    d = rng.normal(size=3)
    e = d - w[:3] @ d                     # the deviations from the weighted mean
    np.testing.assert_allclose(out[..., blk][..., :3] @ d, cols[..., blk][..., :3] @ e,
                               atol=1e-12)
    sd = np.asarray(lay.sd)[blk][:3]
    np.testing.assert_allclose((np.eye(3) - w[:3][None, :]) @ (sd**2 * w[:3]), 0.0, atol=1e-18)
    assert lay.common_scale_sd == pytest.approx(np.sqrt(0.005**2 + 1.0 / prec.sum()), rel=1e-12)
    rest = np.setdiff1d(np.arange(lay.size), np.arange(lay.size)[blk])
    np.testing.assert_array_equal(out[..., rest], cols[..., rest])


def test_prior_sd_per_wheel_from_the_model_file(sc):
    """[wheel_knowledge] inertia_sd_frac for every wheel, overridden per [[wheel]]; the common
    model keeps the one [wheel_knowledge] value; a bad override is a one-line error."""
    d = sc.to_dict()
    d["wheel_knowledge"]["inertia_sd_frac"] = 0.004
    d["wheel"][1]["inertia_sd_frac"] = 0.002
    sc2 = spacecraft_from_dict(d)
    assert sc2.wheel("RWA2").inertia_sd_frac == 0.002 and sc2.wheel("RWA1").inertia_sd_frac is None
    again = spacecraft_from_dict(sc2.to_dict())   # config.toml round trip
    assert again.wheel("RWA2").inertia_sd_frac == 0.002
    assert again.wheel("RWA1").inertia_sd_frac is None
    lay = nuisance_layout(sc2, 1, ("RWA1", "RWA2", "RWA3"))
    np.testing.assert_array_equal(lay.sd[lay.slices["wheel_inertia"]], [0.004, 0.002, 0.004])
    com = nuisance_layout(sc2, 1, ("RWA1", "RWA2", "RWA3"), wheel_errors="common")
    np.testing.assert_array_equal(com.sd[com.slices["wheel_inertia"]], [0.004])
    d["wheel"][1]["inertia_sd_frac"] = 0.7
    with pytest.raises(InputError, match=r"wheel\[1\]\.inertia_sd_frac"):
        spacecraft_from_dict(d, "m.toml")
    with pytest.raises(InputError, match="per_wheel"):
        nuisance_layout(sc, 1, ("RWA1",), wheel_errors="each")


# ---- acceptance: per-wheel errors on multi-axis slews -------------------------------------

@pytest.fixture(scope="module")
def fits(sc):
    """The robust posterior of both wheel models on the same slews (true wheels off by
    ``ERRORS``, the fit given the model file's spin inertias)."""
    tel = make_slews(jax.random.key(11), with_wheel_errors(sc, ERRORS))
    out = {}
    for model in ("per_wheel", "common"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out[model] = fit_inertia(jax.random.key(0), [tel], sc, robust=True,
                                     wheel_errors=model, settings=FIT, prior_draws=100)
    return out


def _z_and_intervals(post, level):
    p = post.idata.posterior
    z, inside = [], []
    for i, n in enumerate(INERTIA_NAMES):
        x = p[n].values.ravel()
        lo, hi = np.quantile(x, [(1 - level) / 2, (1 + level) / 2])
        z.append((x.mean() - PI_TRUE[i]) / x.std())
        inside.append(lo <= PI_TRUE[i] <= hi)
    return np.array(z), np.array(inside)


def test_per_wheel_model_covers_every_entry(fits):
    """Every 90 % interval of the per-wheel model covers the truth (measured: |z| ≤ 0.63, the
    edge being 1.645; the common part of ERRORS, +0.17 %, is 0.6 sd of its prior), converged."""
    post = fits["per_wheel"]
    d = post.diagnostics
    assert_mixed(d)
    z, inside = _z_and_intervals(post, 0.90)
    assert inside.all(), z
    assert np.all(np.abs(z) < 1.3), z


def test_common_scale_model_misses_the_products(fits):
    """The common-scale model cannot absorb wheels off by different fractions: the products of
    inertia miss by many sd (measured: Ixy +10.9, Ixz −22.8, Iyz −18.3 sd; outside the 99 %
    intervals, whose edge is 2.58 sd) while it converges just as well."""
    post = fits["common"]
    d = post.diagnostics
    assert_mixed(d)
    z, inside = _z_and_intervals(post, 0.99)
    assert not inside[3:].all(), z
    assert np.max(np.abs(z[3:])) > 8.0, z


def test_per_wheel_scales_recover_the_differences(fits, sc):
    """The posterior wheel scales minus their mean match the true differences (the common part
    stays at its prior, mean ≈ 0): within 3 posterior sd of the difference (measured ≤ 0.46 sd)."""
    p = fits["per_wheel"].idata.posterior
    scales = p["wheel_scale"].values.reshape(-1, 3)
    diff = scales - scales.mean(-1, keepdims=True)
    true = ERRORS[:3] - ERRORS[:3].mean()
    assert np.all(np.abs(diff.mean(0) - true) < 3 * diff.std(0)), (diff.mean(0), true)
    assert list(p["wheel_scale"]["wheel"].values) == ["RWA1", "RWA2", "RWA3"]


def _cli_base(tmp_path, sc):
    from cassini_bayes.telemetry import write_telemetry

    csv = tmp_path / "slew.csv"
    write_telemetry(csv, make_slews(jax.random.key(11), sc))
    return ["fit", "inertia", "--telemetry", csv, "--spacecraft", "cassini_2000_03_15"]


def test_cli_bad_wheel_errors_is_one_line(tmp_path, run_cli, sc):
    base = _cli_base(tmp_path, sc)
    code, _, err = run_cli(*base, "--out", tmp_path / "bad", "--wheel-errors", "each")
    assert code == 2 and "--wheel-errors" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "bad").exists()
    # the idealised model has no wheel errors: both given is a contradiction, not a no-op
    code, _, err = run_cli(*base, "--out", tmp_path / "bad", "--idealised", "--wheel-errors",
                           "common")
    assert code == 2 and "the idealised model has no wheel errors" in err
    assert not (tmp_path / "bad").exists()


@pytest.mark.slow
def test_cli_wheel_errors_option(tmp_path, run_cli, sc):
    """``--wheel-errors common`` reaches the fit and is recorded in config.toml's options and
    summary.json (about 70 s on the shared machine: a full run directory with its report)."""
    import json
    import tomllib

    base = _cli_base(tmp_path, sc)
    out = tmp_path / "run"
    code, _, err = run_cli(*base, "--out", out, "--wheel-errors", "common", "--chains", "2",
                           "--warmup", "100", "--draws", "100")
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["model"] == "robust" and summary["wheel_errors"] == "common"
    assert tomllib.loads((out / "config.toml").read_text())["options"]["wheel_errors"] == "common"
    import arviz as az

    post = az.from_netcdf(out / "posterior.nc").posterior
    assert post["wheel_scale"].dims == ("chain", "draw")   # one common scale
