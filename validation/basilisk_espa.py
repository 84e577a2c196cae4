"""Basilisk (AVS Lab) flies any spacecraft model file's scenarios; cassini_bayes fits them.

The second part of the Basilisk cross-check (the first, Cassini's three cases, is
``basilisk_crosscheck.py``, whose plant, recorder and sensor model this module reuses). Here the
spacecraft is built from ``--model`` (default ``models/espa_bus.toml``: four pyramid wheels) with
truths the file does not know, and Basilisk flies the ``[[slew]]`` entries of package scenario
files under an RWA attitude controller that knows only the model file:

* ``slews``       a scenario's slews (default ``experiments/scenarios/slews_espa_bus.toml``)
                  -> ``fit inertia``;
* ``wheel-axis``  Brown §III.C's RWA calibration of one wheel (default
                  ``experiments/scenarios/wheel_axis_espa_bus.toml``, RW2 at 3000 rpm, four slew
                  pairs) -> ``fit wheel-axis --wheel RW2 --method rwa`` (windows detected);
* ``bias``        a wheel-biasing event under RCS dead-band control (the model's thrusters,
                  Basilisk's ramp model) -> ``check --pulses`` and ``fit thrust``;
* ``plan``        ``cassini-bayes plan inertia`` within a limits file, then its written
                  ``scenario.toml`` flown in Basilisk -> ``fit inertia`` at the default sampler,
                  and the achieved posterior sd against the plan's prediction, per parameter.

Run with the Basilisk venv (see validation/README.md)::

    /work/bskvenv/bin/python validation/basilisk_espa.py --out runs/basilisk_espa

This script is not part of the test suite.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

from Basilisk.utilities import RigidBodyKinematics as rbk

sys.path.insert(0, str(Path(__file__).resolve().parent))
import basilisk_crosscheck as bx  # noqa: E402  (the plant, recorder and CLI helpers)

import cassini_bayes  # noqa: E402
from cassini_bayes.spacecraft import load_spacecraft, tilted_axis  # noqa: E402

ROOT = bx.ROOT
RPM = bx.RPM
NAMES6 = bx.NAMES6

# True departures from the model file, relative to the file's own magnitudes (the fits start
# from the file): moments a few per cent off, products off by a fraction of the file's product
# knowledge, per-wheel spin inertias within ±0.8 %, one wheel's axis 1° off, an inertial torque
# a few per cent of the file's torque knowledge, a gyro bias and scale factor inside the file's
# gyro knowledge. Chosen as the package's own scenario wheel_axis_espa_bus (its inertia 27.3,
# 22.6, 20.4, products +0.14 kg m^2 each, RW2 tilted (0.8, −0.6)°) to make the two comparable.
MOMENT_SCALE = np.array([1.034, 0.978, 1.036])
PRODUCT_OFFSET_FRAC = np.array([0.28, 0.28, 0.28])      # × poi_uncertainty (Ixy, Ixz, Iyz)
WHEEL_SCALE = (1.008, 0.994, 1.005, 0.992)              # cycled over the model's wheels
TILT_DEG = (0.8, -0.6)                                   # along wheel_tilt_basis, 1.0° in all
TORQUE_FRAC = np.array([0.04, -0.03, 0.02])              # × torque_knowledge.sd_nm, inertial
GYRO_BIAS_FRAC = np.array([0.6, -0.4, 0.8])              # × gyro.bias_sd_rad_s
GYRO_SCALE_FRAC = np.array([0.4, -0.6, 0.2])             # × gyro.scale_factor_sd


# ----------------------------------------------------------------------------------------------
# truth

class Truth:
    """The spacecraft Basilisk flies: the model file with the departures above."""

    def __init__(self, model, tilted_wheel: str, tilt_deg=TILT_DEG):
        self.model = model
        self.tilt_deg = tuple(float(v) for v in tilt_deg)
        i = np.array(model.inertia, dtype=float)
        i[np.diag_indices(3)] *= MOMENT_SCALE
        for (r, c), f in zip(((0, 1), (0, 2), (1, 2)), PRODUCT_OFFSET_FRAC):
            i[r, c] += f * model.poi_uncertainty
            i[c, r] = i[r, c]
        self.inertia = i
        self.tilted_wheel = model.wheel(tilted_wheel).name
        self.wheels = {}
        for k, w in enumerate(model.wheels):
            axis = np.asarray(w.axis, float)
            if w.name == self.tilted_wheel:
                axis = tilted_axis(axis, np.radians(self.tilt_deg))
            self.wheels[w.name] = (axis, w.inertia * WHEEL_SCALE[k % len(WHEEL_SCALE)])
        ga = np.asarray(model.wheel(tilted_wheel).axis, float)
        ta = self.wheels[self.tilted_wheel][0]
        self.tilt_angle_deg = float(np.degrees(np.arccos(np.clip(ga @ ta / np.linalg.norm(ga),
                                                                 -1, 1))))
        self.torque_n = TORQUE_FRAC * model.knowledge.torque_sd_nm
        self.gyro_bias = GYRO_BIAS_FRAC * model.knowledge.gyro_bias_sd_rad_s
        self.gyro_scale = GYRO_SCALE_FRAC * model.knowledge.gyro_scale_factor_sd

    def as_dict(self) -> dict:
        return {"inertia": bx.inertia_dict(self.inertia),
                "wheel_inertia": {n: js for n, (_, js) in self.wheels.items()},
                "wheel_axis": {n: a.tolist() for n, (a, _) in self.wheels.items()},
                "tilted_wheel": self.tilted_wheel, "tilt_angle_deg": self.tilt_angle_deg,
                "external_torque_inertial_nm": self.torque_n.tolist(),
                "gyro_bias_rad_s": self.gyro_bias.tolist(),
                "gyro_scale_factor": self.gyro_scale.tolist()}


# ----------------------------------------------------------------------------------------------
# the commanded attitude and the RWA controller (the package's, written again on Basilisk's
# DCMs: cassini_bayes.simulate.controllers.command_profile and rwa_wheel_torques)

def slew_profile(tau, angle, rate, acc):
    """Angle, rate, acceleration (rad, rad/s, rad/s^2) of one trapezoidal or triangular slew."""
    sgn, big = np.sign(angle), abs(angle)
    ta = rate / acc
    if acc * ta * ta >= big:
        ta, tc = np.sqrt(big / acc), 0.0
    else:
        tc = (big - acc * ta * ta) / rate
    wpk = acc * ta
    if tau <= 0:
        return 0.0, 0.0, 0.0
    if tau < ta:
        return sgn * 0.5 * acc * tau**2, sgn * acc * tau, sgn * acc
    if tau < ta + tc:
        return sgn * (0.5 * acc * ta**2 + wpk * (tau - ta)), sgn * wpk, 0.0
    if tau < 2 * ta + tc:
        d = 2 * ta + tc - tau
        return sgn * (big - 0.5 * acc * d**2), sgn * acc * d, -sgn * acc
    return sgn * big, 0.0, 0.0


def command(t, c_r0n, slews):
    """Commanded DCM [RN], rate and acceleration (in R) of sequential eigen-axis slews.

    Slew j turns the commanded frame about its own axis e_j, later slews on the left:
    ``[RN] = Π_j R(e_j θ_j(t)) [R0N]`` (the package's ``q_cmd = Π rotvec(e_j θ_j) ⊗ q0``); the
    commanded rate and acceleration are ``e_j θ̇_j`` and ``e_j θ̈_j`` of the slew that is running.
    """
    c = c_r0n
    w = np.zeros(3)
    a = np.zeros(3)
    for t0, e, ang, rate, acc in slews:
        th, dth, ddth = slew_profile(t - t0, ang, rate, acc)
        if th != 0.0:
            c = rbk.PRV2C(th * e) @ c
        w += dth * e
        a += ddth * e
    return c, w, a


def read_scenario(path: Path) -> dict:
    """What Basilisk flies from a package scenario TOML: run, initial, controller, slews, noise."""
    s = tomllib.loads(Path(path).read_text())
    slews = [(float(x["t_start_s"]), np.asarray(x["axis"], float) / np.linalg.norm(x["axis"]),
              np.radians(float(x["angle_deg"])), 1e-3 * float(x["rate_mrad_s"]),
              1e-3 * float(x["accel_mrad_s2"])) for x in s.get("slew", [])]
    noise = s.get("noise", {})
    return {"name": s.get("name", Path(path).stem), "duration_s": float(s["run"]["duration_s"]),
            "dt_s": float(s["run"].get("dt_s", 0.1)),
            "sample_period_s": float(s["run"].get("sample_period_s", 1.0)),
            "wheels_on": list(s["initial"]["wheels_on"]), "q0": list(s["initial"]["q"]),
            "wheel_rpm": dict(s["initial"].get("wheel_rpm", {})),
            "bandwidth": float(s.get("rwa_controller", {}).get("bandwidth_rad_s", 0.3)),
            "damping": float(s.get("rwa_controller", {}).get("damping", 0.7)),
            "slews": slews,
            "noise": {"gyro_rad_s": float(noise.get("gyro_rad_s", 5e-6)),
                      "star_tracker_rad": float(noise.get("star_tracker_rad", 3e-5)),
                      "tach_rpm": float(noise.get("tach_noise_rpm", 0.5)),
                      "tach_quantum_rpm": float(noise.get("tach_quantum_rpm", 0.0))}}


def fly(truth: Truth, scen: dict, out: Path, seed: int, case: str) -> dict:
    """Fly a scenario's slews in Basilisk with all its wheels in RWA control; write the files.

    The controller is Feldman & Lee §III's PD with rate/acceleration feed-forward and the
    gyroscopic term ``ω × (I ω + H_RWA)``, the file's inertia, wheel inertias and axes (the
    truth's are not known to it), pseudo-inverse allocation, torques clipped to the file's
    ``max_torque_nm`` and no torque that would drive a wheel past ``max_speed_rpm``.
    Basilisk's dynamics step is half the scenario's control step; telemetry at its sample period.
    """
    model = truth.model
    names = [model.wheel(n).name for n in scen["wheels_on"]]
    wheels = [(n, truth.wheels[n][0], truth.wheels[n][1], float(scen["wheel_rpm"].get(n, 0.0)))
              for n in names]
    g_file = np.array([model.wheel(n).axis for n in names], float).T       # 3 x k, believed
    g_pinv = np.linalg.pinv(g_file)
    j_file = np.array([model.wheel(n).inertia for n in names])
    u_max = np.array([model.wheel(n).max_torque_nm for n in names])
    rho_max = np.array([model.wheel(n).max_speed_rpm / RPM for n in names])
    i_ctrl = np.asarray(model.inertia, float)
    kp, kd = scen["bandwidth"] ** 2, 2.0 * scen["damping"] * scen["bandwidth"]
    q0 = scen["q0"]                                    # package order, scalar last
    sigma0 = rbk.EP2MRP([q0[3], q0[0], q0[1], q0[2]])
    c_r0n = rbk.MRP2C(sigma0)
    dt_ctrl, dt_tel, duration = scen["dt_s"], scen["sample_period_s"], scen["duration_s"]
    plant = bx.Plant(truth.inertia, wheels, dt_ctrl / 2.0, sigma0, [0.0, 0.0, 0.0],
                     mass_kg=model.mass if np.isfinite(model.mass) else 100.0, tag=model.name)
    rec = bx.Recorder([n.lower() for n in names], seed, noise=scen["noise"],
                      gyro_bias=truth.gyro_bias, gyro_scale=truth.gyro_scale)
    n_steps = int(round(duration / dt_ctrl))
    tel_every = int(round(dt_tel / dt_ctrl))
    u_peak, rho_peak = 0.0, 0.0
    for k in range(n_steps):
        t = k * dt_ctrl
        sigma, omega, rho = plant.state()
        if k % tel_every == 0:
            rec.sample(t, sigma, omega, rho)
        c_rn, w_cmd, a_cmd = command(t, c_r0n, scen["slews"])
        c_br = rbk.MRP2C(sigma) @ c_rn.T
        theta = np.asarray(rbk.C2PRV(c_br))            # body relative to the command, rad
        wdot = c_br @ a_cmd - kp * theta - kd * (omega - c_br @ w_cmd)
        h_rwa = g_file @ (j_file * rho)
        # Feldman & Lee (2006) §III: T_c = I dω/dt + ω × (I ω + H_RWA); wheels absorb −T_c
        t_c = i_ctrl @ wdot + np.cross(omega, i_ctrl @ omega + h_rwa)
        u = np.clip(-(g_pinv @ t_c), -u_max, u_max)
        u = np.where((np.abs(rho) >= rho_max) & (u * rho > 0), 0.0, u)
        u_peak = max(u_peak, float(np.max(np.abs(u) / u_max)))
        rho_peak = max(rho_peak, float(np.max(np.abs(rho) / rho_max)))
        plant.step((k + 1) * dt_ctrl, u, truth.torque_n)
    sigma, omega, rho = plant.state()
    rec.sample(n_steps * dt_ctrl, sigma, omega, rho)
    out.mkdir(parents=True, exist_ok=True)
    rec.write(out / "telemetry.csv")
    tr = np.array(rec.truth_rows)
    body_rate_peak = float(np.max(np.linalg.norm(tr[:, 5:8], axis=1)))
    result = {"case": case, "scenario": scen["name"], "model": model.name, **truth.as_dict(),
              "wheels_on": names, "n_slews": len(scen["slews"]), "duration_s": duration,
              "noise": scen["noise"], "peak_body_rate_mrad_s": 1e3 * body_rate_peak,
              "peak_torque_fraction": u_peak, "peak_wheel_speed_fraction": rho_peak,
              "momentum_check_nms": bx.plant_momentum_check(plant, rec, truth.inertia, wheels),
              "convention_check": bx.check_convention(rec.sigmas)}
    (out / "truth.json").write_text(json.dumps(result, indent=2))
    return result


# Wheel-biasing event: the wheels spun from rest to these fractions of their speed limit by a
# motor torque of BIAS_TORQUE_FRAC of its limit while RCS pulses hold the attitude (a momentum
# change of about 0.6 of one wheel's capacity on the ESPA bus).
BIAS_TARGET_FRAC = (-0.42, -0.17, 0.08, -0.25)
BIAS_TORQUE_FRAC = 0.1
# True steady thrust / the file's, per thruster (cycled over the model's thrusters): ±4 %, the
# spread of the package's scenario pulses_espa_bus. The true centre of mass is 1 cm from the
# file's (m, true minus the file's; the offset of models/espa_bus_com_offset.toml, 2 × the ESPA
# file's sd_m): Basilisk's thruster positions are taken from the true centre of mass.
F_SCALES = (1.03, 0.97, 1.04, 0.96, 0.98, 1.02, 0.965, 1.035)
COM_OFFSET_M = (0.006, -0.008, 0.0)


def fly_bias(truth: Truth, out: Path, seed: int, noise: dict, dt_tel: float = 1.0) -> dict:
    """A wheel-biasing event under a dead-band RCS controller, in the files ``fit thrust`` reads.

    Thrusters from the model's ``[[thruster]]`` entries, steady thrust ``F_SCALES`` × the file's,
    at the file's positions taken from the true centre of mass (``COM_OFFSET_M`` off the file's),
    telemetry every ``dt_tel`` s (a multiple of the 0.125 s control step), Basilisk ramp tables
    at the file's ``[pulse]`` constants (Basilisk's own on/off model, see
    ``basilisk_crosscheck.ramp_tables``). Controller per axis: ``s = θ + τ ω`` against a
    dead-band, the thruster pair whose torque lies best along the axis (``thruster_pairs`` on the
    file's moment matrix), widths in 1/8 s from 125 ms, a minimum off-time; the dead-band and
    ``τ`` are set from one minimum pulse's rate kick on the file's inertia, so it does not chatter.
    """
    model = truth.model
    names = [w.name for w in model.wheels]
    wheels = [(n, truth.wheels[n][0], truth.wheels[n][1], 0.0) for n in names]
    rho_max = np.array([model.wheel(n).max_speed_rpm / RPM for n in names])
    targets = np.array([BIAS_TARGET_FRAC[k % 4] for k in range(len(names))]) * rho_max
    u_bias = BIAS_TORQUE_FRAC * np.array([model.wheel(n).max_torque_nm for n in names])
    qm = model.moment_matrix * np.asarray(model.thrust_per_thruster)[None, :]     # N m per thruster
    pairs = bx.thruster_pairs(qm)
    i_ctrl = np.asarray(model.inertia, float)
    # rate kick of one 125 ms pair on each axis (rad/s), from the file: sets dead-band and τ
    kick = max(np.abs(np.linalg.solve(i_ctrl, qm[:, list(pairs[(ax, 1)])].sum(1) * 0.125))[ax]
               for ax in range(3))
    rate_gain, deadband = 1.5, 1.5 * 1.5 * kick           # τ kick < 2 × dead-band: no chatter
    width_gain, wmax, min_off, quantum = 0.5 / deadband, 0.375, 1.0, 0.125
    taus = {"tau_delay": model.pulse.tau_delay, "tau_rise": model.pulse.tau_rise,
            "tau_fall": model.pulse.tau_fall}
    scales = np.array([F_SCALES[k % len(F_SCALES)] for k in range(len(model.thrusters))])
    f_true = scales * np.asarray(model.thrust_per_thruster)
    cfgs = [bx.thruster_configs(model, f, taus, COM_OFFSET_M)[k] for k, f in enumerate(f_true)]
    duration, dt_ctrl, dt_dyn, t_bias = 360.0, 0.125, 0.002, 60.0
    q0 = (0.05, -0.1, 0.2, 0.9733961166965892)
    sigma0 = rbk.EP2MRP([q0[3], q0[0], q0[1], q0[2]])
    c0 = rbk.MRP2C(sigma0)
    plant = bx.Plant(truth.inertia, wheels, dt_dyn, sigma0, [0.0, 0.0, 0.0], thrusters=cfgs,
                     mass_kg=model.mass if np.isfinite(model.mass) else 100.0, tag=model.name)
    rec = bx.Recorder([n.lower() for n in names], seed, noise=noise, gyro_bias=truth.gyro_bias,
                      gyro_scale=truth.gyro_scale)
    tnames = model.thruster_names
    pulses, busy_until = [], 0.0
    n_steps, tel_every = int(round(duration / dt_ctrl)), int(round(dt_tel / dt_ctrl))
    for k in range(n_steps):
        t = k * dt_ctrl
        sigma, omega, rho = plant.state()
        if k % tel_every == 0:
            rec.sample(t, sigma, omega, rho)
        u = np.where((t >= t_bias) & (np.abs(rho) < np.abs(targets)), u_bias * np.sign(targets),
                     0.0)
        fire = None
        if t >= busy_until:
            err = np.asarray(rbk.C2PRV(rbk.MRP2C(sigma) @ c0.T)) + rate_gain * omega
            widths = np.zeros(len(tnames))
            for ax in range(3):
                excess = abs(err[ax]) - deadband
                if excess > 0:
                    wdt = np.clip(np.ceil(width_gain * excess / quantum) * quantum, quantum, wmax)
                    for j in pairs[(ax, -int(np.sign(err[ax])))]:
                        widths[j] = max(widths[j], wdt)
            if widths.any():
                fire = widths
                pulses += [(t, tnames[j], widths[j]) for j in range(len(tnames)) if widths[j] > 0]
                busy_until = t + widths.max() + min_off
        plant.step((k + 1) * dt_ctrl, u, truth.torque_n, fire)
    sigma, omega, rho = plant.state()
    rec.sample(n_steps * dt_ctrl, sigma, omega, rho)
    out.mkdir(parents=True, exist_ok=True)
    rec.write(out / "telemetry.csv")
    bx.write_pulses(out / "pulses.csv", pulses)
    delivered = {}                                  # impulse per newton by commanded width, s
    for j, recd in enumerate(plant.thr_logs):
        f = np.array(recd.thrustForce)
        tt = np.array(recd.times()) * 1e-9
        for t_on, name, width in pulses:
            if name == tnames[j]:
                m = (tt > t_on) & (tt <= t_on + width + 1.0)
                delivered.setdefault(f"{width:.3f}", []).append(
                    float(np.sum(f[m]) * dt_dyn / f_true[j]))
    info = {"case": "bias", "model": model.name, **truth.as_dict(),
            "F_n": dict(zip(tnames, f_true.tolist())), "com_offset_m": list(COM_OFFSET_M),
            "sample_period_s": dt_tel,
            "pulses_per_thruster": {n: sum(p[1] == n for p in pulses) for n in tnames},
            **taus, "tau_note": "Basilisk ramp-table constants (delay + first-order rise/decay),"
            " not Feldman & Lee's §V profile; Basilisk skips the table's delay",
            "wheel_targets_rpm": (targets * RPM).tolist(), "n_pulses": len(pulses),
            "deadband_rad": deadband, "rate_gain_s": rate_gain,
            "impulse_per_newton_by_width": {w: {"count": len(v), "basilisk_s": float(np.mean(v))}
                                            for w, v in sorted(delivered.items())},
            "convention_check": bx.check_convention(rec.sigmas),
            "momentum_check_note": "thrusters fire: momentum not conserved, no check"}
    (out / "truth.json").write_text(json.dumps(info, indent=2))
    return info


# ----------------------------------------------------------------------------------------------
# fits and tables

def inertia_budget(model):
    """±1 % of each moment (Feldman & Lee §VI), the file's product knowledge for the products."""
    def budget(name, true):
        if name in ("Ixx", "Iyy", "Izz"):
            return 0.01 * abs(true), "1 % (moment)"
        return model.poi_uncertainty, "poi_uncertainty"
    return budget


def axis_row(summary, true_axis, file_axis):
    """Angle from the posterior mean axis to the true one, its 90 % cone and the file's offset."""
    mean = np.asarray(summary["direction"]["mean"], float)
    mean /= np.linalg.norm(mean)
    ang = float(np.degrees(np.arccos(np.clip(mean @ np.asarray(true_axis), -1, 1))))
    f = np.asarray(file_axis, float) / np.linalg.norm(file_axis)
    d = summary["diagnostics"]
    cone = summary["direction"]["cone_deg"]["90"]
    return {"error_deg": ang, "cone90_deg": cone, "covered": ang <= cone,
            "within_0p5_deg": ang <= 0.5,
            "file_to_truth_deg": float(np.degrees(np.arccos(np.clip(f @ true_axis, -1, 1)))),
            "divergences": d.get("divergences"), "max_r_hat": d.get("max_r_hat"),
            "min_ess_bulk": d.get("min_ess_bulk"), "converged": d.get("converged"),
            "adequacy_ok": summary.get("adequacy", {}).get("ok"),
            "windows": summary.get("windows")}


def sd_comparison(plan_summary, fit_dir: Path, model, wheels_on):
    """Achieved posterior sd over the plan's predicted sd, for every site of the robust fit.

    The fit's draws (``posterior.nc``) are reduced with the planner's own site order and labels
    (``cassini_bayes.plan.inertia.fitted_site_sd`` / ``site_labels``, as
    ``benchmarks/plan_prediction.py`` does), so the two columns name the same quantity.
    """
    import arviz as az

    from cassini_bayes.plan.inertia import fitted_site_sd, inertia_model, site_labels

    im = inertia_model(model, wheels_on)
    post = az.from_netcdf(fit_dir / "posterior.nc").posterior
    got = dict(zip(site_labels(im), fitted_site_sd(im, post)))
    pred = plan_summary["plan"]["sites"]
    rows = []
    for name, p in pred.items():
        if name not in got or not p.get("sd"):
            continue
        ratio = float(got[name]) / p["sd"]
        rows.append({"param": name, "predicted_sd": p["sd"], "achieved_sd": float(got[name]),
                     "prior_sd": p.get("prior_sd"), "ratio": ratio,
                     "within_25pct": abs(ratio - 1.0) <= 0.25})
    return rows


def scenario_at_truth(plan_scenario: Path, truth: Truth, model_path: Path, out: Path) -> Path:
    """The plan's scenario with the truth Basilisk flies written into it, for ``plan evaluate``.

    The plan predicts at the model file (its ``[truth]`` is the file); this copy carries the
    Basilisk truth in the package's scenario keys (``[truth] inertia``, ``wheel_inertia_errors``,
    ``wheel_axis_tilt_deg``, ``external_torque_inertial_nm``; ``[noise]`` gyro bias and scale),
    so the same prediction is made at the point the fit is linearised about.
    """
    import tomli_w

    s = tomllib.loads(Path(plan_scenario).read_text())
    model = truth.model
    tr = s.setdefault("truth", {})
    tr["model"] = str(Path(model_path).resolve())
    s.setdefault("prior", {})["model"] = str(Path(model_path).resolve())
    tr["inertia"] = {k: float(v) for k, v in bx.inertia_dict(truth.inertia).items()}
    tr["wheel_inertia_errors"] = [WHEEL_SCALE[k % len(WHEEL_SCALE)] - 1.0
                                  for k in range(len(model.wheels))]
    tr["wheel_axis_tilt_deg"] = {truth.tilted_wheel: list(truth.tilt_deg)}
    tr["external_torque_inertial_nm"] = truth.torque_n.tolist()
    s["noise"]["gyro_bias_rad_s"] = truth.gyro_bias.tolist()
    s["noise"]["gyro_scale_factor"] = truth.gyro_scale.tolist()
    s["name"] = f"{s.get('name', 'plan')}_at_basilisk_truth"
    out.write_text(tomli_w.dumps(s))
    return out


def compare_with_plan(plan_dir: Path, scen_path: Path, fit: Path, d: Path, truth: Truth,
                      model_path: Path, wheels_on, log) -> dict:
    """The plan case's table: achieved sd against the plan's prediction and the same at the truth.

    The prediction at the Basilisk truth (``plan evaluate`` on :func:`scenario_at_truth`)
    separates the linearisation point (the truth is a few per cent and 1° from the file) from
    the approximation.
    """
    plan_s = json.loads((plan_dir / "summary.json").read_text())
    rows = sd_comparison(plan_s, fit, truth.model, wheels_on)
    rc, text = bx.cli("plan", "evaluate",
                      scenario_at_truth(scen_path, truth, model_path, d / "scenario_at_truth.toml"),
                      "--out", d / "plan_at_truth", "--force", log=log)
    if rc == 0:
        at = json.loads((d / "plan_at_truth" / "summary.json").read_text())
        by = {r["param"]: r for r in rows}
        for name, p in at["prediction"]["sites"].items():
            if name in by and p.get("sd"):
                by[name]["predicted_sd_at_truth"] = p["sd"]
                by[name]["ratio_at_truth"] = by[name]["achieved_sd"] / p["sd"]
    else:
        print(f"[plan] plan evaluate at the truth exit {rc}: {text[-500:]}")
    n_ok = sum(r["within_25pct"] for r in rows)
    print(f"   achieved posterior sd / plan's predicted sd: {n_ok}/{len(rows)} sites within ±25 %")
    for r in rows:
        print(f"   {r['param']:>18} predicted {r['predicted_sd']:.4g} achieved "
              f"{r['achieved_sd']:.4g} ratio {r['ratio']:.3f} "
              f"{'ok' if r['within_25pct'] else 'OUTSIDE ±25 %'}; predicted at the truth: ratio "
              f"{r.get('ratio_at_truth', float('nan')):.3f}")
    return {"plan_vs_achieved": rows, "plan_slews": plan_s["slews"]}


def thrust_rows(summary: dict, info: dict) -> list:
    """Estimate vs Basilisk's truth for every thrust entry ``fit thrust --mode thruster`` reports.

    Entries: ``F[<name>]`` of each identified thruster, ``F_combination[<label>]`` of each
    identified combination (truth ``Σ w F_true``, the design's weights in newtons) and the
    centre-of-mass offset ``com_x/y/z`` (truth ``COM_OFFSET_M``). The time constants are not
    entries: Basilisk's ramp (delay skipped, first-order rise and decay) is not Feldman & Lee's
    §V profile, so it has no true ``τ`` of the fit's model.
    """
    params, design = summary["parameters"], summary.get("thrust_design") or {}
    f_true = info["F_n"]
    entries = [(f"F[{n}]", f_true[n], "thrust") for n in design.get("identified", [])]
    entries += [(f"F_combination[{c['label']}]",
                 sum(w * f_true[n] for n, w in c["weights"].items()), "combination")
                for c in design.get("combinations", [])]
    entries += [(n, v, "com") for n, v in zip(("com_x", "com_y", "com_z"), info["com_offset_m"])]
    rows = []
    for name, true, kind in entries:
        p = params.get(name)
        if p is None:
            continue
        err = p["mean"] - true
        row = {"param": name, "kind": kind, "truth": true, "mean": p["mean"], "sd": p["sd"],
               "q05": p["q05"], "q95": p["q95"], "covered": p["q05"] <= true <= p["q95"],
               "error": err, "r_hat": p.get("r_hat"), "contraction": p.get("contraction")}
        if kind != "com":
            row["rel_error_pct"] = 100.0 * err / true
            row["within_3pct"] = abs(err) <= 0.03 * abs(true)
        rows.append(row)
    return rows


def run_bias_case(truth: Truth, d: Path, a, log) -> dict:
    """Fly the biasing event, ``check`` its files, fit ``fit thrust --mode thruster`` on them
    (sampler ``--bias-sampler``, default the CLI's) and compare with Basilisk's truth."""
    t1 = time.time()
    info = fly_bias(truth, d, a.seed, read_scenario(a.slews_scenario)["noise"], a.bias_period)
    print(f"[bias] Basilisk flew a biasing event ({info['n_pulses']} pulses "
          f"{info['pulses_per_thruster']}, dead-band {1e3 * info['deadband_rad']:.1f} mrad, "
          f"telemetry every {a.bias_period:g} s) in {time.time() - t1:.0f} s; impulse per "
          f"newton by width: " + ", ".join(f"{w} s x{v['count']}: {v['basilisk_s']:.4f} s"
                                          for w, v in info["impulse_per_newton_by_width"].items()))
    files = [d / "telemetry.csv", "--pulses", d / "pulses.csv", "--spacecraft", a.model]
    rc, text = bx.cli("check", *files, log=log)
    print(f"[bias] check exit {rc}" + ("" if rc == 0 else f": {text[-800:]}"))
    res = {"truth": info, "check_exit": rc}
    if a.no_fit:
        return res
    t1 = time.time()
    rc, text = bx.cli("fit", "thrust", "--telemetry", *files, "--mode", "thruster", "--out",
                      d / "fit", *a.bias_sampler.split(), "--seed", a.seed, "--force", log=log)
    res.update(fit_exit=rc, fit_wall_s=time.time() - t1,
               fit_command_sampler=a.bias_sampler or "CLI defaults")
    print(f"[bias] fit thrust --mode thruster exit {rc} ({res['fit_wall_s']:.0f} s)")
    if not (d / "fit" / "summary.json").exists():
        print(text[-2000:])
        return res
    s = json.loads((d / "fit" / "summary.json").read_text())
    rows = thrust_rows(s, info)
    dg = s["diagnostics"]
    res.update(rows=rows, diagnostics=dg, adequacy=s.get("adequacy"),
               thrust_design=s.get("thrust_design"), warnings=s.get("warnings"),
               tau={k: s["parameters"].get(k) for k in ("tau_delay", "tau_rise", "tau_fall")},
               nuisance=s.get("nuisance"),
               coverage=float(np.mean([r["covered"] for r in rows])) if rows else None,
               max_abs_thrust_error_pct=max((abs(r["rel_error_pct"]) for r in rows
                                             if "rel_error_pct" in r), default=None))
    td = s.get("thrust_design") or {}
    print(f"\n== fit thrust --mode thruster (Basilisk ESPA bias, {a.bias_period:g} s telemetry)\n"
          f"   design: rank {td.get('rank')} of {td.get('parameters')}, identified "
          f"{td.get('identified')}, combinations {[c['label'] for c in td.get('combinations', [])]}"
          f", not fired {td.get('not_fired')}, com contraction {td.get('com_contraction')}")
    for r in rows:
        e = (f"{r['rel_error_pct']:+.2f} %" if "rel_error_pct" in r
             else f"{1e3 * r['error']:+.2f} mm")
        print(f"   {r['param']:>34} truth {r['truth']:.5g} mean {r['mean']:.5g} sd {r['sd']:.3g} "
              f"error {e} covered {r['covered']} r_hat {r['r_hat']}")
    print(f"   coverage {res['coverage']}; max |thrust error| {res['max_abs_thrust_error_pct']} %; "
          f"divergences {dg.get('divergences')}, max r_hat {dg.get('max_r_hat')}, converged "
          f"{dg.get('converged')}; adequacy ok {(s.get('adequacy') or {}).get('ok')}")
    return res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=ROOT / "runs" / "basilisk_espa")
    ap.add_argument("--model", type=Path, default=ROOT / "models" / "espa_bus.toml")
    ap.add_argument("--cases", default="slews,wheel-axis,plan")
    ap.add_argument("--slews-scenario", type=Path,
                    default=ROOT / "experiments" / "scenarios" / "slews_espa_bus.toml")
    ap.add_argument("--axis-scenario", type=Path,
                    default=ROOT / "experiments" / "scenarios" / "wheel_axis_espa_bus.toml")
    ap.add_argument("--wheel", default="RW2", help="the wheel whose axis is 1° off and fitted")
    ap.add_argument("--tilt-deg", default=",".join(f"{v:g}" for v in TILT_DEG),
                    help="the --wheel's true tilt along wheel_tilt_basis (deg, 'u1,u2'); the "
                    "bias case's thrust fit holds the axes to the file's axis_sd_deg, so fly it "
                    "inside that knowledge (e.g. 0.16,-0.12: 0.2° on the ESPA bus)")
    ap.add_argument("--limits", type=Path,
                    default=ROOT / "experiments" / "limits" / "espa_bus.toml")
    ap.add_argument("--plan", type=Path, default=None,
                    help="an existing `plan inertia` run directory (default: plan now)")
    ap.add_argument("--plan-args", default="",
                    help="extra arguments of `plan inertia` (default none: its own defaults)")
    ap.add_argument("--chains", type=int, default=2)
    ap.add_argument("--warmup", type=int, default=500)
    ap.add_argument("--draws", type=int, default=1000)
    ap.add_argument("--plan-sampler", default="",
                    help="sampler arguments of the plan case's fit (default: the CLI's defaults)")
    ap.add_argument("--bias-sampler", default="",
                    help="sampler arguments of the bias case's fit (default: the CLI's defaults)")
    ap.add_argument("--bias-period", type=float, default=1.0,
                    help="telemetry sample period of the bias case (s, a multiple of 0.125)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--no-fit", action="store_true", help="simulate and check only")
    a = ap.parse_args(argv)
    model = load_spacecraft(a.model)
    truth = Truth(model, a.wheel, [float(v) for v in a.tilt_deg.split(",")])
    print(f"cassini_bayes {cassini_bayes.__version__}; model {model.name}; truth: "
          f"{json.dumps(bx.inertia_dict(truth.inertia))}; {truth.tilted_wheel} "
          f"{truth.tilt_angle_deg:.3f}° off the file")
    log, results = [], {}
    sampler = bx.sampler_args(a)
    for case, d, t0 in bx.cases(a, results, log):
        if case == "plan":
            plan_dir = a.plan or (a.out / "plan_run")
            if a.plan is None:
                rc, text = bx.cli("plan", "inertia", "--spacecraft", a.model, "--limits",
                                  a.limits, "--out", plan_dir, *a.plan_args.split(), "--force",
                                  log=log)
                print(f"[plan] plan inertia exit {rc} ({time.time() - t0:.0f} s)")
                if rc != 0:
                    print(text[-2000:])
                    continue
            scen_path = plan_dir / "scenario.toml"
        elif case == "bias":
            results[case] = run_bias_case(truth, d, a, log)
            continue
        else:
            scen_path = a.slews_scenario if case == "slews" else a.axis_scenario
        scen = read_scenario(scen_path)
        t1 = time.time()
        info = fly(truth, scen, d, a.seed, case)
        print(f"[{case}] Basilisk flew {scen_path} ({info['n_slews']} slews, "
              f"{info['duration_s']:.0f} s) in {time.time() - t1:.0f} s; convention check "
              f"{info['convention_check']:.1e}; momentum check {info['momentum_check_nms']:.1e} "
              f"N m s; peak body rate {info['peak_body_rate_mrad_s']:.2f} mrad/s, torque "
              f"{info['peak_torque_fraction']:.2f}, wheel speed "
              f"{info['peak_wheel_speed_fraction']:.2f} of the limits")
        rc, text = bx.cli("check", d / "telemetry.csv", "--spacecraft", a.model, log=log)
        print(f"[{case}] check exit {rc}")
        if rc != 0:
            print(text[-1500:])
        if a.no_fit:
            continue
        fit = d / "fit"
        t1 = time.time()
        if case == "wheel-axis":
            rc, text = bx.cli("fit", "wheel-axis", d / "telemetry.csv", "--spacecraft", a.model,
                              "--wheel", truth.tilted_wheel, "--method", "rwa", "--out", fit,
                              *sampler, log=log)
        else:
            smp = sampler if case == "slews" else [*a.plan_sampler.split(), "--seed", a.seed,
                                                   "--force"]
            rc, text = bx.cli("fit", "inertia", "--telemetry", d / "telemetry.csv",
                              "--spacecraft", a.model, "--out", fit, *smp, log=log)
        print(f"[{case}] fit exit {rc} ({time.time() - t1:.0f} s)")
        if not (fit / "summary.json").exists():
            print(text[-2000:])
            continue
        s = json.loads((fit / "summary.json").read_text())
        res = {"truth": info, "diagnostics": s["diagnostics"], "adequacy": s.get("adequacy")}
        if case == "wheel-axis":
            row = axis_row(s, truth.wheels[truth.tilted_wheel][0],
                           model.wheel(truth.tilted_wheel).axis)
            res["axis"] = row
            print(f"\n== fit wheel-axis --wheel {truth.tilted_wheel} --method rwa (Basilisk)\n"
                  f"   angle to truth {row['error_deg']:.3f}° (file {row['file_to_truth_deg']:.3f}°"
                  f" off), 90 % cone {row['cone90_deg']:.3f}°, covered {row['covered']}, "
                  f"≤ 0.5° {row['within_0p5_deg']}; divergences {row['divergences']}, max r_hat "
                  f"{row['max_r_hat']:.3f}, min ESS {row['min_ess_bulk']:.0f}, adequacy ok "
                  f"{row['adequacy_ok']}; windows {row['windows']}")
        else:
            rows = bx.param_rows(s, bx.inertia_dict(truth.inertia), inertia_budget(model))
            for r in rows:
                r["rel_error"] = r["error"] / abs(r["truth"])
            res["rows"] = rows
            res["coverage"] = float(np.mean([r["covered"] for r in rows]))
            bx.print_rows(f"fit inertia (Basilisk, {scen['name']})", rows, s)
            print("   moments' error: " + ", ".join(f"{r['param']} {100 * r['rel_error']:+.2f} %"
                                                   for r in rows[:3])
                  + f"; 90 % coverage {res['coverage']:.2f}")
            if case == "plan":
                res.update(compare_with_plan(plan_dir, scen_path, fit, d, truth, a.model,
                                             info["wheels_on"], log))
        results[case] = res


if __name__ == "__main__":
    cassini_bayes.setup_jax()
    main()
