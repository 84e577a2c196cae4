"""Residuals of the thrust likelihood at Basilisk's truth, on a ``basilisk_espa.py --cases bias``
run: is what the fit sees at the true parameters only the sensor noise?

Feldman & Lee Eq 17 at the truth Basilisk flew (``truth.json``): the true inertia, wheel axes and
spin inertias in place of the model file's, the gyro's true bias and scale factor taken out of
the measured rates, the true thrusts, centre-of-mass offset and ramp. Basilisk's ramp (the delay
skipped, first-order rise from the command, first-order decay from the off command) is Feldman &
Lee §V's profile at ``τd = 0`` (``cassini_bayes.physics.pulse.thrust_profile``), so the
likelihood's pulse model is exact there. The true inertial torque's impulse is taken out with the
measured attitude. What remains should be white sensor noise: ``σ_ω I`` and ``σ_ρ J g`` per
sample (the likelihood's ``B``), plus the gyro noise's random walk through ``ΔG``.

Prints, per axis: the residual rms, the per-sample noise sd ``sqrt(diag B)``, the same without
the rate-step correction (``jump_area``), the rms of its second-order terms
(``physics/rate_step_moments.py``) over that sd, and the rms of the residual's increments over
intervals in which a pulse fires against quiet ones. Also the residuals' least-squares
projection on the thrusts and the centre of mass (what a fit with the other parameters at the
truth would move them by), with and without the second-order terms. Needs only this package
(not Basilisk):

    python validation/bias_residuals.py runs/bskbias_dt0.5_s1/bias [--json out.json]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

import jax
import numpy as np

import cassini_bayes
from cassini_bayes.frames import dcm
from cassini_bayes.inference.thrust.data import prepare_thrust
from cassini_bayes.inference.thrust.likelihood import impulse_residuals
from cassini_bayes.physics.momentum import inertia_vector
from cassini_bayes.spacecraft import load_spacecraft
from cassini_bayes.telemetry import read_pulses, read_telemetry

ROOT = Path(__file__).resolve().parents[1]
NOISE = {"gyro_rad_s": 5e-6, "tach_rpm": 0.5, "tach_quantum_rpm": 0.1}   # slews_espa_bus [noise]


def true_spacecraft(model, truth: dict):
    """The model file with Basilisk's true inertia, wheel axes and spin inertias."""
    i = truth["inertia"]
    inertia = np.array([[i["Ixx"], i["Ixy"], i["Ixz"]], [i["Ixy"], i["Iyy"], i["Iyz"]],
                        [i["Ixz"], i["Iyz"], i["Izz"]]])
    wheels = tuple(dataclasses.replace(w, axis=np.asarray(truth["wheel_axis"][w.name], float),
                                       inertia=float(truth["wheel_inertia"][w.name]))
                   for w in model.wheels)
    return dataclasses.replace(model, inertia=inertia, wheels=wheels)


def corrected_telemetry(tel, truth: dict):
    """The measured rates with the true gyro bias and scale factor taken out."""
    b = np.asarray(truth["gyro_bias_rad_s"], float)
    s = np.asarray(truth["gyro_scale_factor"], float)
    return dataclasses.replace(tel, omega=(np.asarray(tel.omega) - b) / (1.0 + s))


def torque_impulse(tel, torque_inertial) -> np.ndarray:
    """(n, 3) N m s: ``∫ A(q) T_N dt`` (trapezoid), the inertial torque's body-axis impulse."""
    tb = np.asarray(dcm(np.asarray(tel.q))) @ np.asarray(torque_inertial, float)
    t = np.asarray(tel.t)
    inc = 0.5 * (tb[1:] + tb[:-1]) * np.diff(t)[:, None]
    return np.vstack([np.zeros((1, 3)), np.cumsum(inc, 0)])


def offset_free(r: np.ndarray) -> np.ndarray:
    return r - r.mean(0)


def common_scale_profile(r, inertia, wheel_cov, sigma0, ks=(-0.01, -0.005, 0.0, 0.005, 0.01)):
    """The white-noise log-likelihood of Eq 17's residuals ``r`` (n, 3) under the common scale
    ``1 + k`` of thrust, inertia and wheel inertias that Eq 17 cannot see (``r → (1 + k) r``),
    with the noise covariance as the thrust likelihood builds it: ``σ_ω² I I`` scaled with the
    inertia, ``σ_ρ² Σ J² g gᵀ`` at the file's wheel inertias (not scaled), and the gyro data's
    Jacobian ``|det I|`` per sample; maximised over ``σ_ω``, ``σ_ρ`` at each ``k``. Flat in
    ``k``: the noise model gives the scale no information."""
    from scipy.optimize import minimize

    n = r.shape[0]
    ii = inertia @ inertia

    def nll(log_s, k):
        s = np.exp(log_s)
        b = (1 + k) ** 2 * s[0] ** 2 * ii + s[1] ** 2 * wheel_cov
        _, logdet = np.linalg.slogdet(b)
        quad = (1 + k) ** 2 * np.einsum("ij,jk,ik->", r, np.linalg.inv(b), r)
        return 0.5 * n * logdet + 0.5 * quad - 3 * (n - 1) * np.log1p(k)

    out = {}
    for k in ks:
        res = minimize(nll, np.log(sigma0), args=(k,), method="Nelder-Mead",
                       options={"xatol": 1e-8, "fatol": 1e-6, "maxiter": 2000})
        out[f"{k:+.3f}"] = {"loglik": -float(res.fun), "sigma": np.exp(res.x).tolist()}
    base = out[f"{0.0:+.3f}"]["loglik"]
    for v in out.values():
        v["delta"] = v["loglik"] - base
    return out


def analyse(run: Path, model_path: Path) -> dict:
    truth = json.loads((run / "truth.json").read_text())
    model = load_spacecraft(model_path)
    sc = true_spacecraft(model, truth)
    tel = corrected_telemetry(read_telemetry(run / "telemetry.csv", spacecraft=sc), truth)
    log = read_pulses(run / "pulses.csv", spacecraft=sc)
    problem = prepare_thrust([(tel, log)], sc, mode="thruster")
    names = list(problem.thrusters)
    f_true = np.array([truth["F_n"][n] for n in names])
    com = np.asarray(truth["com_offset_m"], float)
    tau = (0.0, truth["tau_rise"], truth["tau_fall"])      # Basilisk's ramp: F&L §V at τd = 0
    sd_rho = np.hypot(NOISE["tach_rpm"], NOISE["tach_quantum_rpm"] / np.sqrt(12)) * np.pi / 30
    sigma = np.array([[NOISE["gyro_rad_s"], sd_rho]])
    pi = np.asarray(inertia_vector(sc.inertia))
    n = int(problem.n_samples[0])
    ext = torque_impulse(tel, truth["external_torque_inertial_nm"])[:n]

    def resid(prob, thrust=f_true, c=com, tau_=tau):
        r = impulse_residuals(prob, thrust, tau_, sigma, pi=pi, com=c)[0, :n]
        return offset_free(r - ext)

    r = resid(problem)
    ev = problem.data.events
    bare = problem._replace(data=problem.data._replace(events=ev._replace(
        omega_mid=jax.numpy.zeros_like(ev.omega_mid), h_mid=jax.numpy.zeros_like(ev.h_mid))))
    r_bare = resid(bare)
    # the second-order rate-step terms (physics/rate_step_moments.py) off: every input zero
    first_only = problem._replace(data=problem.data._replace(events=ev._replace(
        d_omega=jax.numpy.zeros_like(ev.d_omega), d_h=jax.numpy.zeros_like(ev.d_h),
        step_moments=jax.numpy.zeros_like(ev.step_moments),
        step_pairs=ev.step_pairs._replace(value=jax.numpy.zeros_like(ev.step_pairs.value)))))
    r_second = r - resid(first_only)
    wheel_cov = np.asarray(ev.wheel_cov[0])
    b = NOISE["gyro_rad_s"] ** 2 * sc.inertia @ sc.inertia + sd_rho ** 2 * wheel_cov
    noise_sd = np.sqrt(np.diag(b))
    t = np.asarray(tel.t)[:n]
    slot = np.searchsorted(t, np.asarray(log.t_on))
    fired = np.zeros(n - 1, bool)
    fired[slot[(slot >= 1) & (slot < n)] - 1] = True
    d = np.diff(r, axis=0)
    inc_ratio = np.sqrt(np.mean(d[fired] ** 2, 0) / np.mean(d[~fired] ** 2, 0))

    def lsq(prob):
        """Linearised least squares of the residuals on (F, com) with the rest at the truth,
        weighted by the per-sample noise: what the data would move them by, and its cov."""
        r0, cols, eps = resid(prob), [], 1e-4
        for k in range(len(names)):
            f = f_true.copy()
            f[k] += eps
            cols.append((resid(prob, thrust=f) - r0).ravel() / eps)
        for k in range(3):
            c = com.copy()
            c[k] += eps
            cols.append((resid(prob, c=c) - r0).ravel() / eps)
        w = np.tile(1.0 / noise_sd, n)
        a = -np.stack(cols, 1) * w[:, None]
        return np.linalg.lstsq(a, r0.ravel() * w, rcond=None)[0], np.linalg.inv(a.T @ a)

    def per_entry(v):
        return {**{f"F[{nm}]_pct": 100 * v[k] / f_true[k] for k, nm in enumerate(names)},
                **{f"com_{ax}_mm": 1e3 * v[len(names) + k] for k, ax in enumerate("xyz")}}

    step, cov = lsq(problem)
    step_first, _ = lsq(first_only)
    out = {"common_scale_profile": common_scale_profile(r, sc.inertia, wheel_cov, sigma[0]),
           "run": str(run), "package": cassini_bayes.__file__, "n_samples": n,
           "sample_period_s": float(np.median(np.diff(t))), "n_pulses": int(np.size(log.t_on)),
           "residual_rms_nms": np.sqrt(np.mean(r ** 2, 0)).tolist(),
           "noise_sd_nms": noise_sd.tolist(),
           "rms_over_noise": (np.sqrt(np.mean(r ** 2, 0)) / noise_sd).tolist(),
           "residual_rms_without_step_correction_nms":
               np.sqrt(np.mean(r_bare ** 2, 0)).tolist(),
           "fired_over_quiet_increment_rms": inc_ratio.tolist(),
           "second_order_rms_over_noise":
               (np.sqrt(np.mean(r_second ** 2, 0)) / noise_sd).tolist(),
           "lsq_shift_at_truth": per_entry(step),
           "lsq_shift_at_truth_without_second_order": per_entry(step_first),
           "lsq_sd_white": per_entry(np.sqrt(np.diag(cov)))}
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+", type=Path, help="bias case directories (truth.json …)")
    ap.add_argument("--model", type=Path, default=ROOT / "models" / "espa_bus.toml")
    ap.add_argument("--json", type=Path, default=None)
    a = ap.parse_args(argv)
    res = [analyse(r, a.model) for r in a.runs]
    for o in res:
        print(f"\n{o['run']}: {o['n_samples']} samples every {o['sample_period_s']:g} s, "
              f"{o['n_pulses']} pulses")
        for k in ("residual_rms_nms", "noise_sd_nms", "rms_over_noise",
                  "residual_rms_without_step_correction_nms", "second_order_rms_over_noise",
                  "fired_over_quiet_increment_rms"):
            print(f"  {k:>42}: " + ", ".join(f"{v:.3g}" for v in o[k]))
        print("  common-scale profile log-likelihood (k: Δ): " + ", ".join(
            f"{k} {v['delta']:+.2f}" for k, v in o["common_scale_profile"].items()))
        sd = o["lsq_sd_white"]
        print("  least-squares shift at the truth (white noise; sd): " + ", ".join(
            f"{k} {v:+.2f} ({sd[k]:.2f})" for k, v in o["lsq_shift_at_truth"].items()))
        print("  the same without the second-order rate-step terms: " + ", ".join(
            f"{k} {v:+.2f}" for k, v in o["lsq_shift_at_truth_without_second_order"].items()))
    if a.json:
        a.json.write_text(json.dumps(res, indent=2))


if __name__ == "__main__":
    cassini_bayes.setup_jax()
    sys.exit(main())
