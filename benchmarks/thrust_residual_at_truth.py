"""Residual of the thrust likelihood at the simulator's truth, noise-free: what the fit's model
misses of a flight it should describe exactly.

A scenario is flown with every sensor error off and sampled twice from one flight, at the
scenario's telemetry period and at its integration step; the per-thruster likelihood's residual
``V − Q (F ⊙ j)`` (Feldman & Lee Eq 17, offset removed) is evaluated at the true inertia, thrusts,
centre of mass and time constants. Printed per axis as rms over the gyro noise ``σ_ω √diag(I I)``:
the coarse sampling's residual (the simulator's error plus the fit's interval model's), the fine
one's (mostly the simulator's), and the coarse residual's least-squares shift of the thrusts and
the centre of mass, in white-noise sd (what a fit would be moved by)::

    python benchmarks/thrust_residual_at_truth.py biasing_espa_bus [--json out.json]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys

import jax
import numpy as np

import cassini_bayes
from cassini_bayes.files import write_text


def residuals(name: str, sample_period_s: float | None = None):
    """(residual (n, 3) N m s, noise sd (3,) N m s, function of (F, com) → residual) of the
    scenario ``name`` flown noise-free, sampled every ``sample_period_s`` (default its own)."""
    from cassini_bayes.inference.thrust.data import prepare_thrust
    from cassini_bayes.inference.thrust.likelihood import impulse_residuals
    from cassini_bayes.physics.momentum import inertia_vector
    from cassini_bayes.simulate import load_scenario, simulate
    from cassini_bayes.simulate.scenario import Noise

    s = load_scenario(name)
    gyro = float(s.noise.gyro_rad_s)
    s = dataclasses.replace(s, noise=Noise())
    if sample_period_s:
        s = dataclasses.replace(s, sample_period_s=sample_period_s)
    truth = s.truth
    sc = dataclasses.replace(s.prior, inertia=np.asarray(truth.inertia))
    sim = simulate(jax.random.key(0), s)
    sigma = np.array([[gyro, 1e-3]])
    problem = prepare_thrust([(sim.telemetry, sim.pulses)], sc, mode="thruster",
                             noise_hat=sigma)
    thrust = dict(zip(sc.thruster_names, np.asarray(s.thrust_n)))
    f0 = np.array([thrust[k] for k in problem.thrusters])
    com0 = np.asarray(truth.com_m) - np.asarray(sc.com_m)
    tau = (truth.pulse.tau_delay, truth.pulse.tau_rise, truth.pulse.tau_fall)
    pi, n = np.asarray(inertia_vector(sc.inertia)), int(problem.n_samples[0])

    def resid(f=f0, com=com0):
        r = impulse_residuals(problem, f, tau, sigma, pi=pi, com=com)[0, :n]
        return r - r.mean(0)

    noise = gyro * np.sqrt(np.diag(sc.inertia @ sc.inertia))
    return resid(), noise, resid, f0, com0, list(problem.thrusters)


def shift_in_sd(resid, noise, f0, com0, names) -> dict:
    """Least-squares shift of the thrusts and the centre of mass that the residual asks for,
    each over its white-noise sd (finite differences of the residual)."""
    r = (resid() / noise).ravel()
    cols = []
    for k in range(f0.size):
        f = f0.copy()
        f[k] *= 1.001
        cols.append((resid(f=f) / noise).ravel() - r)
    for k in range(3):
        c = com0.copy()
        c[k] += 1e-4
        cols.append((resid(com=c) / noise).ravel() - r)
    a = -np.stack(cols, 1)
    step, *_ = np.linalg.lstsq(a, r, rcond=None)
    sd = np.sqrt(np.diag(np.linalg.inv(a.T @ a)))
    labels = [f"F[{k}]" for k in names] + ["com_x", "com_y", "com_z"]
    return {k: float(v) for k, v in zip(labels, step / sd)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scenarios", nargs="+")
    ap.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    out = []
    for name in a.scenarios:
        from cassini_bayes.simulate import load_scenario

        step = load_scenario(name).dt_s
        coarse, noise, resid, f0, com0, names = residuals(name)
        fine, *_ = residuals(name, step)
        row = {"scenario": name, "package": cassini_bayes.__file__,
               "coarse_rms_over_noise": (np.sqrt((coarse**2).mean(0)) / noise).tolist(),
               "fine_rms_over_noise": (np.sqrt((fine**2).mean(0)) / noise).tolist(),
               "shift_in_white_sd": shift_in_sd(resid, noise, f0, com0, names)}
        out.append(row)
        print(f"{name}: rms/noise, telemetry period "
              + " ".join(f"{v:.3f}" for v in row["coarse_rms_over_noise"])
              + f"; every {step:g} s " + " ".join(f"{v:.3f}" for v in row["fine_rms_over_noise"]))
        print("  least-squares shift at the truth (white sd): " + ", ".join(
            f"{k} {v:+.2f}" for k, v in row["shift_in_white_sd"].items()))
    if a.json:
        write_text(a.json, json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    cassini_bayes.setup_jax()
    sys.exit(main())
