"""Helpers shared by test modules (imported as ``from helpers import …``; tests/ is on the path).

Statistical helpers state their tolerance; the tests that call them state the false-failure
rate of their whole set of checks.
"""

from __future__ import annotations

import numpy as np


def assert_standard_normal(z: np.ndarray) -> None:
    """Columns of ``z`` (draws × components) are independent N(0, 1): each mean within 4 se
    (se = 1/√draws), each sd within 10 % of 1, the largest |correlation| within 4.5 se."""
    se = 1.0 / np.sqrt(z.shape[0])
    assert np.all(np.abs(z.mean(0)) < 4 * se), z.mean(0)
    np.testing.assert_allclose(z.std(0), 1.0, rtol=0.10)
    corr = np.corrcoef(z, rowvar=False) - np.eye(z.shape[1])
    assert np.abs(corr).max() < 4.5 * se


def nuisance_columns(d: list[dict], common: list[float]) -> dict[str, list]:
    """Robust-model truths ``d`` (one dict per draw) as columns per nuisance effect, in the
    effects' own units: the per-wheel scales with the shared scale ``common`` split off
    (``c_k = d_k + c_s``); the inertial torque only where the truths carry it."""
    cols = {"gyro_bias": [x["gyro_bias"] for x in d], "gyro_scale": [x["gyro_scale"] for x in d],
            "wheel_inertia": [x["wheel_scale"] - c for x, c in zip(d, common)],
            "wheel_inertia_common": [[c] for c in common],
            "wheel_axes": [np.ravel(x["wheel_tilt"]) for x in d],
            "body_torque": [x["T_body"] for x in d], "torque_rate": [x["T_N_rate"] for x in d]}
    if "T_inertial" in d[0]:
        cols["inertial_torque"] = [x["T_inertial"] for x in d]
    return cols


def assert_gyro_errors_recovered(w: np.ndarray, wm: np.ndarray, scale, bias) -> None:
    """Per axis the least-squares fit of ``ω_meas − ω = s ω + b`` recovers the drawn ``scale``
    and ``bias`` (3,) within 5 of its own standard errors (false-failure rate < 1e-5 a check)."""
    for j in range(3):
        x = np.c_[w[:, j], np.ones(len(w))]
        coef, res, *_ = np.linalg.lstsq(x, wm[:, j] - w[:, j], rcond=None)
        se = np.sqrt(np.diag(np.linalg.inv(x.T @ x) * res[0] / (len(w) - 2)))
        assert abs(coef[0] - scale[j]) < 5 * se[0]
        assert abs(coef[1] - bias[j]) < 5 * se[1]


def campaign_sbc(res, alpha_family: float = 0.01):
    """The SBC verdicts of a finished campaign ``res`` (its ranks, draws and truths)."""
    from cassini_bayes.analysis import sbc

    return sbc.sbc_result(res.names, res.rank, res.n_draws, alpha_family=alpha_family,
                          draws={n: res.draws[:, j] for j, n in enumerate(res.names)},
                          truth={n: res.truth[:, j] for j, n in enumerate(res.names)})


def replicate_of(arrays, i: int):
    """Replicate ``i`` of batched simulator output (a pytree of arrays), as NumPy."""
    import jax

    return jax.tree.map(lambda a: np.asarray(a[i]), arrays)
