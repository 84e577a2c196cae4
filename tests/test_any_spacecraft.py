"""Any spacecraft, not only Cassini: model files with other wheels and thrusters, files whose
columns follow the model, the simulator flying any wheel set within its limits, and the
least-squares baseline on any wheel set."""

from __future__ import annotations

import jax
import numpy as np
import pytest
import tomli_w

from cassini_bayes.errors import InputError
from cassini_bayes.simulate import scenario_from_dict, simulate
from cassini_bayes.spacecraft import load_spacecraft, spacecraft_from_dict
from cassini_bayes.telemetry import (RPM_TO_RAD_S, read_pulses, read_telemetry, write_telemetry)

S3 = 1.0 / np.sqrt(3.0)


def _model(tmp_path, wheels, name="bus", thrusters=(), **extra) -> str:
    """A model file with ``wheels`` [(name, axis, extra keys)] and optional thrusters."""
    d = {"name": name,
         "inertia": {"Ixx": 25.0, "Iyy": 22.0, "Izz": 18.0, "Ixy": -0.4, "Ixz": 0.3,
                     "Iyz": -0.2, "poi_uncertainty": 0.5},
         "wheel": [{"name": n, "axis": list(a), "inertia": 2.4e-3, **kw} for n, a, kw in wheels],
         **({"thruster": list(thrusters)} if thrusters else {}), **extra}
    path = tmp_path / f"{name}.toml"
    path.write_text(tomli_w.dumps(d))
    return str(path)


PYRAMID = [(f"RW{k + 1}", (sx * S3, sy * S3, S3), {})
           for k, (sx, sy) in enumerate(((1, 1), (-1, 1), (-1, -1), (1, -1)))]


def _slews(model: str, wheels_on, *, duration=360.0, rpm=800.0, **truth) -> dict:
    """Three RWA slews (X, Y, Z) of the model, 1 s telemetry, mild noise."""
    return {"name": "slews", "seed": 3,
            "run": {"duration_s": duration, "dt_s": 0.1, "sample_period_s": 1.0,
                    "control": "rwa"},
            "truth": {"model": model,
                      "inertia": {"Ixx": 26.0, "Iyy": 21.5, "Izz": 18.6, "Ixy": -0.3,
                                  "Ixz": 0.45, "Iyz": -0.1}, **truth},
            "prior": {"model": model},
            "initial": {"wheels_on": list(wheels_on),
                        "wheel_rpm": {n: rpm * (-1) ** k for k, n in enumerate(wheels_on)}},
            "rwa_controller": {"bandwidth_rad_s": 0.3, "damping": 0.7},
            "slew": [{"t_start_s": t0, "axis": axis, "angle_deg": 20.0, "rate_mrad_s": 15.0,
                      "accel_mrad_s2": 1.0}
                     for t0, axis in ((20.0, [1.0, 0.0, 0.0]), (130.0, [0.0, 1.0, 0.0]),
                                      (240.0, [0.0, 0.0, 1.0]))],
            "noise": {"gyro_rad_s": 5e-6, "star_tracker_rad": 3e-5, "tach_noise_rpm": 0.5,
                      "tach_quantum_rpm": 0.1}}


@pytest.fixture(scope="module")
def five_wheels(tmp_path_factory):
    """A pyramid plus a fifth wheel along +Z named RWA5: simulated slews, written and read."""
    tmp = tmp_path_factory.mktemp("five")
    model = _model(tmp, [*PYRAMID, ("RWA5", (0.0, 0.0, 1.0), {})], name="five")
    s = scenario_from_dict(_slews(model, ["RW1", "RW2", "RW3", "RW4", "RWA5"]))
    run = simulate(jax.random.key(0), s)
    path = tmp / "telemetry.csv"
    write_telemetry(path, run.telemetry)
    return model, path, run


def test_a_five_wheel_model_writes_and_reads_its_own_columns(five_wheels):
    model, path, run = five_wheels
    header = path.read_text().splitlines()[0].split(",")
    assert header[8:] == ["rw1", "rw2", "rw3", "rw4", "rwa5"]
    sc = load_spacecraft(model)
    tel = read_telemetry(path, spacecraft=sc)
    assert tel.wheel_names == sc.wheel_names and tel.thruster_names == ()
    np.testing.assert_allclose(tel.wheel_rates, run.telemetry.wheel_rates, rtol=1e-12)
    from cassini_bayes.api import check_telemetry

    c = check_telemetry(path, spacecraft=model)   # wheel units by momentum conservation
    assert [w.name for w in c.wheels] == list(sc.wheel_names)
    assert c.momentum.alignment > 0.999 and 0.9 < c.momentum.scale < 1.1


def test_columns_the_model_lacks_name_both(five_wheels, tmp_path):
    model, path, _ = five_wheels
    with pytest.raises(InputError) as e:      # no model: Cassini's columns
        read_telemetry(path)
    msg = str(e.value)
    assert "unknown column 'rw1'" in msg and "Cassini's layout" in msg
    assert "rwa1 rwa2 rwa3 rwa4" in msg
    assert "--spacecraft" in msg and "\n" not in msg
    four = _model(tmp_path, PYRAMID, name="four")
    with pytest.raises(InputError) as e:      # another model: names its wheels
        read_telemetry(path, spacecraft=load_spacecraft(four))
    msg = str(e.value)
    assert "unknown column 'rwa5'" in msg and "'four'" in msg and "rw1 rw2 rw3 rw4" in msg


def test_thrusters_follow_the_model(tmp_path):
    thr = [{"name": "A1", "position": [0.3, 0.3, -0.4], "direction": [0.0, 0.0, 1.0], "F": 1.0},
           {"name": "A2", "position": [-0.3, -0.3, -0.4], "direction": [0.0, 0.0, 1.0],
            "F": 1.0}]
    sc = load_spacecraft(_model(tmp_path, PYRAMID, name="thr", thrusters=thr))
    lines = ["t,q1,q2,q3,q4,wx,wy,wz,rw1,on_A1,on_A2", "0,0,0,0,1,0,0,0,800,0,0",
             "1,0,0,0,1,0,0,0,800,0.1,0", "2,0,0,0,1,0,0,0,800,0.1,0.2"]
    p = tmp_path / "t.csv"
    p.write_text("\n".join(lines) + "\n")
    tel = read_telemetry(p, spacecraft=sc)
    assert tel.thruster_names == ("A1", "A2") and tel.on_times.shape == (3, 2)
    log = tmp_path / "p.csv"
    log.write_text("t_on,thruster,width\n0.5,a1,0.1\n1.2,A2,0.2\n")
    assert read_pulses(log, spacecraft=sc).names == ["A1", "A2"]
    log.write_text("t_on,thruster,width\n0.5,Z1,0.1\n")
    with pytest.raises(InputError, match="unknown thruster 'Z1'; the thrusters of the spacecraft "
                                         "model 'thr' are A1 A2"):
        read_pulses(log, spacecraft=sc)
    p.write_text("\n".join(lines).replace("on_A2", "on_B2") + "\n")
    with pytest.raises(InputError, match="'on_B2' is the on-time of no thruster .*on_A1 on_A2"):
        read_telemetry(p, spacecraft=sc)


def test_a_model_without_thrusters_refuses_thruster_files(tmp_path):
    sc = load_spacecraft(_model(tmp_path, PYRAMID, name="none"))
    log = tmp_path / "p.csv"
    log.write_text("t_on,thruster,width\n0.5,Z1,0.1\n")
    with pytest.raises(InputError, match="the spacecraft model 'none' has no thrusters"):
        read_pulses(log, spacecraft=sc)
    p = tmp_path / "t.csv"
    p.write_text("t,q1,q2,q3,q4,wx,wy,wz,rw1,on_Z1\n0,0,0,0,1,0,0,0,800,0\n"
                 "1,0,0,0,1,0,0,0,800,0\n")
    with pytest.raises(InputError, match="'on_Z1' is the on-time of no thruster .*none: it has "
                                         "no thrusters"):
        read_telemetry(p, spacecraft=sc)
    from cassini_bayes.api import fit_thrust

    with pytest.raises(InputError, match="fit thrust needs thrusters, but the spacecraft model "
                                         "'none' has none"):
        fit_thrust(p, log, sc)


def test_in_memory_telemetry_must_name_the_models_wheels(five_wheels):
    """A Telemetry with Cassini's default wheel names given to a fit of another spacecraft is
    refused before any work, naming the wheel and the model's wheels."""
    from cassini_bayes.api import fit_inertia
    from cassini_bayes.telemetry import Telemetry

    model, _, run = five_wheels
    tel = run.telemetry
    cassini_named = Telemetry(tel.t, tel.q, tel.omega, tel.wheel_rates[:, :4], source="mem")
    with pytest.raises(InputError, match="wheel RWA1 .* is not a wheel of the spacecraft model "
                                         "'five', whose wheels are RW1, RW2, RW3, RW4, RWA5"):
        fit_inertia(cassini_named, model)


def test_baseline_on_three_wheels(tmp_path):
    """The least-squares baseline of a three-wheel model (it had looked for RWA4): Feldman & Lee
    Eq 11 on noisy slews recovers the moments within 1 %."""
    from cassini_bayes.estimators.baseline import fit_inertia_baseline

    three = [("RWX", (1.0, 0.0, 0.0), {}), ("RWY", (0.0, 1.0, 0.0), {}),
             ("RWZ", (0.0, 0.0, 1.0), {})]
    model = _model(tmp_path, three, name="three")
    s = scenario_from_dict(_slews(model, ["RWX", "RWY", "RWZ"], rpm=1500.0))
    run = simulate(jax.random.key(0), s)
    write_telemetry(tmp_path / "t.csv", run.telemetry)
    sc = load_spacecraft(model)
    tel = read_telemetry(tmp_path / "t.csv", spacecraft=sc)
    fit = fit_inertia_baseline([tel], sc, method="all_axes")
    truth = np.diag(s.truth.inertia)
    assert np.max(np.abs(np.diag(fit.inertia) / truth - 1)) < 0.01


def test_wheel_limits_hold_in_the_simulator(tmp_path):
    """The model's max_torque_nm and max_speed_rpm bound the wheels: a slew that asks for more
    torque is torque-limited (the wheels' momentum changes no faster than the limit), and a
    wheel at its speed limit is not driven beyond it (the attitude error grows instead)."""
    limited = [(n, a, {"max_torque_nm": 0.004, "max_speed_rpm": 1000.0}) for n, a, _ in PYRAMID]
    model = _model(tmp_path, limited, name="limited")
    run = simulate(jax.random.key(0), scenario_from_dict(
        _slews(model, ["RW1", "RW2", "RW3", "RW4"], rpm=700.0)))
    axes = np.array([a for _, a, _ in PYRAMID])

    def motor_torque(r):      # N m: change of each wheel's axial momentum J (ρ + g·ω) per second
        h = 2.4e-3 * (np.asarray(r.truth.wheel_rates) + np.asarray(r.truth.omega) @ axes.T)
        return np.abs(np.diff(h, axis=0))

    rho = np.asarray(run.truth.wheel_rates)
    assert motor_torque(run).max() <= 0.004 * (1 + 1e-9)
    # at the limit the motor stops; the rate relative to the body still moves with g·ω (15 mrad/s
    # is 0.14 rpm) and by the last 0.1 s step of torque
    assert 990.0 < np.abs(rho).max() / RPM_TO_RAD_S < 1000.0 * 1.005
    free = simulate(jax.random.key(0), scenario_from_dict(
        _slews(_model(tmp_path, PYRAMID, name="free"), ["RW1", "RW2", "RW3", "RW4"], rpm=700.0)))
    assert motor_torque(free).max() > 0.006
    assert (np.abs(run.arrays.pointing_error).max()
            > 3 * np.abs(free.arrays.pointing_error).max())


def test_shipped_models_of_other_spacecraft():
    bus, cube = load_spacecraft("espa_bus"), load_spacecraft("cubesat_12u")
    assert bus.wheel_names == ("RW1", "RW2", "RW3", "RW4") and len(bus.thrusters) == 8
    assert np.linalg.matrix_rank(bus.moment_matrix) == 3 and not bus.eq16_layout
    assert cube.thrusters == () and cube.wheel_names == ("RWX", "RWY", "RWZ", "RWS")
    for sc in (bus, cube):
        again = spacecraft_from_dict(sc.to_dict())
        np.testing.assert_array_equal(again.moment_matrix, sc.moment_matrix)


def test_the_cubesat_check_sees_its_gyro_bias_and_no_thrusters(tmp_path, run_cli):
    """The CubeSat's one-minute rests: the gyro-bias windows follow the file (60-s windows had
    left fewer than five quiet ones, and the check said nothing), and the estimate of its MEMS
    turn-on bias lies within 4 standard errors of the truth on every axis (the scenario's seed;
    with 9 degrees of freedom beyond 4 se is 0.3 % per axis). ``check`` says the model has no
    thrusters instead of asking for a pulse log."""
    from cassini_bayes.api import simulate_scenario
    from cassini_bayes.consistency import gyro_bias_estimate

    sim = simulate_scenario("slews_cubesat_12u")
    est = gyro_bias_estimate(sim.telemetry)
    truth = np.asarray(sim.result.scenario.noise.gyro_bias_rad_s)
    assert est is not None and est.window_s < 60.0
    assert np.all(np.abs(est.bias - truth) < 4 * est.se), (est, truth)
    path = tmp_path / "cube.csv"
    write_telemetry(path, sim.telemetry)
    code, out, err = run_cli("check", path, "--spacecraft", "cubesat_12u")
    assert code == 0, err
    assert "Thrusters: none in the spacecraft model" in out and "--pulses" not in out
