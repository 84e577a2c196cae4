"""Synthetic run directories of every fit kind (inertia, thrust, rwa4), shaped like the fit's
(docs/design.md §4.4): ArviZ InferenceData with posterior (4 chains), prior, sample_stats
(diverging, energy), observed_data and a ``residuals`` group, plus summary.json and config.toml.

The numbers are drawn from known normals, so a report's flags (weak identification, truth in the
90 % interval) have known answers.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import xarray as xr

__all__ = ["INERTIA", "make_run", "summary_stats"]

INERTIA = {"Ixx": 7403.0, "Iyy": 6174.0, "Izz": 3727.0, "Ixy": -129.0, "Ixz": -12.0, "Iyz": 147.0}
THRUSTERS = ["Z1", "Z2", "Z3", "Z4", "Y1", "Y2", "Y3", "Y4"]
TAUS = {"tau_delay": 0.005, "tau_rise": 0.020, "tau_fall": 0.065}


# The fits' adequacy block (cassini_bayes.inference.adequacy): one failed check for inertia.
_OK = {"statistic": 1.2, "threshold": 4.0, "ok": True, "parameter": "gyro_scale[x]"}
_NA = {"statistic": None, "threshold": 4.0, "ok": True, "note": "one event: nothing to hold out"}
ADEQUACY = {
    "inertia": {"ok": False, "checks": {
        "prior_data_conflict": {"statistic": 6.1, "threshold": 4.0, "ok": False,
                                "parameter": "wheel_scale"},
        "held_out": _OK, "residual_autocorrelation": {"statistic": 0.03, "threshold": 0.5,
                                                      "ok": True}}},
    "thrust": {"ok": True, "checks": {"prior_data_conflict": _OK, "held_out": _NA}},
    "rwa4": {"ok": True, "checks": {"prior_data_conflict": _OK}},
}


def summary_stats(x):
    """A summary.json parameter entry of the draws ``x``, with fixed, converged diagnostics."""
    x = np.asarray(x).ravel()
    q05, q50, q95 = np.quantile(x, [0.05, 0.5, 0.95])
    return {"mean": float(x.mean()), "sd": float(x.std(ddof=1)), "q05": float(q05),
            "q50": float(q50), "q95": float(q95), "r_hat": 1.0, "ess_bulk": 700.0,
            "ess_tail": 650.0}


def _draws(rng, chains, draws, spec):
    """{name: (mean, sd)} -> {name: (chains, draws)} normal draws."""
    return {k: m + s * rng.standard_normal((chains, draws)) for k, (m, s) in spec.items()}


def make_run(root: Path, kind: str, *, draws: int = 200, prior: bool = True,
             residuals: bool = True, energy: bool = True, seed: int = 0) -> Path:
    """Write a synthetic run directory of ``kind`` under ``root`` and return it."""
    import arviz as az

    rng = np.random.default_rng(seed)
    chains = 4
    run = root / f"{kind}-run"
    run.mkdir(parents=True)
    dims, coords = {}, {"axis": ["x", "y", "z"]}
    truth = None
    extra = {}
    extra_groups = {}
    file_idx = None
    if kind == "inertia":
        post_spec = {k: (v + 3.0, 8.0 if k[1] == k[2] else 4.0) for k, v in INERTIA.items()}
        prior_spec = {k: (v, 0.10 * v if k[1] == k[2] else 75.0) for k, v in INERTIA.items()}
        posterior = _draws(rng, chains, draws, post_spec)
        posterior["sigma_H"] = np.abs(0.002 + 1e-4 * rng.standard_normal((chains, draws)))
        posterior["H0"] = 5.0 + 0.01 * rng.standard_normal((chains, draws, 3))
        dims["H0"] = ["axis"]
        truth = dict(INERTIA)
        baseline = {k: v + 1.0 for k, v in INERTIA.items()}
        # two slew files concatenated along t, each on its own clock (as inference/inertia.py)
        t = np.concatenate([np.arange(0.0, 900.0, 2.0), np.arange(0.0, 600.0, 2.0)])
        file_idx = np.repeat([0, 1], [450, 300])
        res = 0.002 * rng.standard_normal((t.size, 3))
        extra_groups["constant_data"] = xr.Dataset(
            {"prior_sd": ("param", [prior_spec[k][1] for k in INERTIA]),
             "prior_mean": ("param", [prior_spec[k][0] for k in INERTIA])},
            coords={"param": list(INERTIA)})
    elif kind == "thrust":
        post_spec = {f"F_{s}": (0.74, 0.02) for s in THRUSTERS[:4]}
        # Y thrusters fire in pairs (Feldman & Lee Eqs 20-21): individually prior-dominated
        post_spec |= {f"F_{s}": (0.75, 0.19) for s in THRUSTERS[4:]}
        post_spec |= {k: (v, 0.1 * v) for k, v in TAUS.items()}
        prior_spec = {f"F_{s}": (0.75, 0.2) for s in THRUSTERS}
        prior_spec |= {k: (v, 0.3 * v) for k, v in TAUS.items()}
        posterior = _draws(rng, chains, draws, post_spec)
        posterior["sigma_J"] = np.abs(1e-3 + 1e-4 * rng.standard_normal((chains, draws)))
        truth = {f"F_{s}": 0.74 for s in THRUSTERS} | TAUS
        baseline = {f"F_{s}": 0.73 for s in THRUSTERS}
        t = np.sort(rng.uniform(0, 600, 40))
        res = 1e-3 * rng.standard_normal((t.size, 3))
        # the fit's per-pulse impulses (cassini_bayes.inference.thrust.pulses), N m s
        on = rng.choice([0.125, 0.25, 0.5], 30)
        pred = 0.75 * 3.0 * on * 1.3
        q = pred[:, None] * (1.0 + 0.01 * np.array([-1.645, 0.0, 1.645]))
        extra_groups["pulse_impulses"] = xr.Dataset(
            {"t": ("group", np.sort(rng.uniform(0, 600, 30))),
             "event": ("group", np.zeros(30, int)),
             "thrusters": ("group", np.array(["Y1+Y3"] * 30)),
             "n_pulses": ("group", np.full(30, 2)), "on_time": ("group", on),
             "measured": ("group", pred + 0.005 * rng.standard_normal(30)),
             "measured_sd": ("group", np.full(30, 0.005)),
             "predicted": (("group", "quantile"), q)},
            coords={"quantile": [0.05, 0.5, 0.95]})
    elif kind == "rwa4":
        u_true = np.array([0.05, 0.80, 0.597])
        u_true /= np.linalg.norm(u_true)
        x = u_true + np.radians(0.4) * rng.standard_normal((chains, draws, 3))
        u = x / np.linalg.norm(x, axis=-1, keepdims=True)
        posterior = {n: u[..., i] for i, n in enumerate(["u4_x", "u4_y", "u4_z"])}
        posterior["sigma_w"] = np.abs(1e-4 + 1e-5 * rng.standard_normal((chains, draws)))
        z = rng.standard_normal((1, 2000, 3))
        zu = z / np.linalg.norm(z, axis=-1, keepdims=True)
        prior_draws = {n: zu[..., i] for i, n in enumerate(["u4_x", "u4_y", "u4_z"])}
        truth = {"u4": u_true.tolist()}
        baseline = {"u4_x": float(u_true[0] + 0.004), "u4_y": float(u_true[1]),
                    "u4_z": float(u_true[2] - 0.003)}
        flat = u.reshape(-1, 3)
        m = flat.mean(0) / np.linalg.norm(flat.mean(0))
        ang = np.degrees(np.arccos(np.clip(flat @ m, -1, 1)))
        extra["direction"] = {"mean": m.tolist(), "cone_deg": {
            k: float(np.quantile(ang, int(k) / 100)) for k in ("50", "90", "95")}}
        t = np.arange(0.0, 300.0, 1.0)
        res = 1e-5 * rng.standard_normal((t.size, 3))
    else:  # pragma: no cover
        raise ValueError(kind)
    if kind != "rwa4":
        prior_draws = _draws(rng, 1, 1000, prior_spec)

    sample_stats = {"diverging": np.zeros((chains, draws), bool),
                    "tree_depth": np.full((chains, draws), 3)}
    if energy:
        sample_stats["energy"] = 10 + 2.0 * rng.standard_normal((chains, draws)).cumsum(1) * 0.1 \
            + rng.standard_normal((chains, draws))
    idata = az.from_dict(
        posterior=posterior,
        prior=prior_draws if prior else None,
        sample_stats=sample_stats,
        observed_data={"Gamma": rng.standard_normal((50, 3))},
        dims=dims | {"Gamma": ["t_obs", "axis"]},
        coords=coords,
    )
    if residuals:
        coords_r = {"t": t, "axis": ["x", "y", "z"]}
        data = {"residual": (("t", "axis"), res, {"units": "N m s"})}
        if file_idx is not None:
            coords_r["file"] = ("t", file_idx)
            data["residual_std"] = (("t", "axis"), res / 0.002,
                                    {"units": "1", "description": "whitened body residual"})
        extra_groups["residuals"] = xr.Dataset(data, coords=coords_r)
    if extra_groups:
        idata.add_groups(extra_groups)
    idata.to_netcdf(str(run / "posterior.nc"))

    names = [n for n in posterior if not n.startswith(("sigma", "H0"))]
    summary = {
        "kind": kind,
        "parameters": {n: summary_stats(posterior[n]) for n in names},
        "baseline": baseline,
        "diagnostics": {"divergences": 0, "max_r_hat": 1.003, "min_ess_bulk": 600.0,
                        "converged": True},
        "seed": seed,
        "version": "0.1.0",
        "truth": truth,
        "warnings": ["synthetic <test> run"],
        "adequacy": ADEQUACY[kind],
    } | extra
    (run / "summary.json").write_text(json.dumps(summary, indent=1))
    (run / "config.toml").write_text(
        f'kind = "{kind}"\nseed = {seed}\nversion = "0.1.0"\n'
        f"[sampler]\nchains = 4\ndraws = {draws}\n")
    return run
