"""Residual of the least-squares thruster estimators at the simulator's truth, noise-free: what
the leak monitor's residual momentum (Lee Eq 10) and the thrust-health regression (Feldman & Lee
Eq 17) miss of a flight they should describe exactly.

A scenario is flown with every sensor error off and sampled at its telemetry period (and, for
the simulator's own floor, at its integration step). The spacecraft model is the truth's: its
inertia, thrusts, time constants and centre of mass. Printed per axis as rms over the gyro
noise ``σ_ω √diag(I I)``:

* ``leak``: :func:`~cassini_bayes.inference.leak.leak_inputs`' residual ``R`` less its
  least-squares offset and slope (the monitor's offset and external torque);
* ``health``: the health design's residual ``v − X f`` at the true thrusts
  (:func:`~cassini_bayes.inference.health.summary.event_design`), and the weighted least-squares
  estimate's offset from the true thrusts in white-noise sd (the sd of the weighted estimate
  with the residual levels at the gyro noise): what the noise-free event moves a fit by.

Each with the rate-step correction's second-order terms
(:func:`~cassini_bayes.estimators.leak.rate_step_second_order`, ``second``), without them (that
term taken off again, ``first``) and, for the health regression, with no rate-step correction at
all (the design's columns without their rate steps, ``none``)::

    python benchmarks/leak_health_residual_at_truth.py biasing_espa_bus [--json out.json]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys

import numpy as np

import cassini_bayes
from cassini_bayes.files import write_text


def flight(name: str, sample_period_s: float | None = None):
    """(telemetry, pulse log, truth spacecraft model, gyro sd rad/s) of the scenario ``name``
    flown noise-free and without its leak (if any), sampled every ``sample_period_s`` (default
    its own)."""
    import jax

    from cassini_bayes.simulate import load_scenario, simulate
    from cassini_bayes.simulate.scenario import Noise

    s = load_scenario(name)
    gyro = float(s.noise.gyro_rad_s)
    s = dataclasses.replace(s, noise=Noise(), leak=None)
    if sample_period_s:
        s = dataclasses.replace(s, sample_period_s=sample_period_s)
    sim = simulate(jax.random.key(0), s)
    truth = s.truth
    thrust = np.asarray(s.thrust_n, float)
    sc = dataclasses.replace(truth, thrusters=tuple(
        dataclasses.replace(th, thrust_n=float(f)) for th, f in zip(truth.thrusters, thrust)))
    return sim.telemetry, sim.pulses, sc, gyro


def measure(name: str, sample_period_s: float | None = None, health: bool = True) -> dict:
    """The leak and health residuals at the truth of scenario ``name`` (module docstring), with
    the second-order terms (``second``) and without them (``first``)."""
    from cassini_bayes.estimators.baseline import wheel_momentum
    from cassini_bayes.estimators.leak import rate_step_second_order
    from cassini_bayes.inference.health.summary import event_design, weighted_fit
    from cassini_bayes.inference.leak import leak_inputs

    tel, pulses, sc, gyro = flight(name, sample_period_s)
    noise = gyro * np.sqrt(np.diag(sc.inertia @ sc.inertia))
    p = sc.pulse
    second = rate_step_second_order(
        tel.t, tel.omega, sc.inertia, wheel_momentum(tel, sc),
        (pulses.t_on, pulses.thruster, pulses.width), (p.tau_delay, p.tau_rise, p.tau_fall),
        sc.moment_matrix * sc.thrust_per_thruster[None, :])
    r2 = leak_inputs(tel, pulses, sc).residual
    # the monitor's own nuisances: an offset and a constant external torque
    basis = np.c_[np.ones(tel.t.size), tel.t - tel.t[0]]
    if not health:
        out = {}
        for label, r in (("first", r2 - second), ("second", r2)):
            r = r - basis @ np.linalg.lstsq(basis, r, rcond=None)[0]
            out[label] = {"leak_rms_over_noise": (np.sqrt((r**2).mean(0)) / noise).tolist()}
        return out
    des = event_design(tel, pulses, sc)
    # the true thrusts in the design's coordinates (channel means, splits): exact least squares
    # of the thrusters' angular impulse on the columns without their rate steps
    x0 = np.stack([sum(vec[None, :] * des.j[:, s:s + 1] for s, vec in col)
                   for col in des.channels.columns(des.q)], -1)[:, :, des.fired]
    target = np.einsum("as,ts,s->ta", des.q, des.j, sc.thrust_per_thruster)
    f_true = np.linalg.lstsq(x0.reshape(-1, x0.shape[-1]), target.ravel(), rcond=None)[0]
    w = 1.0 / noise**2
    xw = des.x * np.sqrt(w)[None, :, None]
    sd = np.sqrt(np.diag(np.linalg.inv(np.einsum("tap,taq->pq", xw, xw))))
    out = {}
    for label, r, v, x in (("none", None, des.v - second, x0),
                           ("first", r2 - second, des.v - second, des.x),
                           ("second", r2, des.v, des.x)):
        e = v - np.einsum("tap,p->ta", x, f_true)
        e = e - e.mean(0)
        off = (weighted_fit(x, v, w)[0] - f_true) / sd
        out[label] = {"health_rms_over_noise": (np.sqrt((e**2).mean(0)) / noise).tolist(),
                      "health_offset_in_white_sd": off.tolist(),
                      "health_offset_max_abs": float(np.max(np.abs(off)))}
        if r is not None:       # the monitor's residual always carries the first order
            r = r - basis @ np.linalg.lstsq(basis, r, rcond=None)[0]
            out[label]["leak_rms_over_noise"] = (np.sqrt((r**2).mean(0)) / noise).tolist()
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scenarios", nargs="+")
    ap.add_argument("--fine", action="store_true",
                    help="also sample at the integration step (the simulator's floor)")
    ap.add_argument("--leak-only", action="store_true",
                    help="the leak monitor's residual only (a stretch with an external torque, "
                         "which the health regression does not model)")
    ap.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    if a.json:
        from _provenance import start

        start(a.json, vars(a), argv, replace=True)
    from cassini_bayes.simulate import load_scenario

    out = []
    for name in a.scenarios:
        step = load_scenario(name).dt_s
        periods = [None] + ([step] if a.fine else [])
        for period in periods:
            row = {"scenario": name, "sample_period_s": period, "package": cassini_bayes.__file__,
                   **measure(name, period, not a.leak_only)}
            out.append(row)
            at = "" if period is None else f", every {step:g} s"
            for label in ("first", "second") if a.leak_only else ("none", "first", "second"):
                m = row[label]
                print(f"{name} [{label} order{at}]: rms/noise leak "
                      + " ".join(f"{v:.3g}" for v in m.get("leak_rms_over_noise", []))
                      + ("" if a.leak_only else
                         "; health " + " ".join(f"{v:.3g}" for v in m["health_rms_over_noise"])
                         + f"; health estimate - truth max {m['health_offset_max_abs']:.2f} "
                         "white sd"))
    if a.json:
        write_text(a.json, json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    cassini_bayes.setup_jax()
    sys.exit(main())
