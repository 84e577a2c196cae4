"""Quiet-period detection, slew splitting and ``T0:T1`` parsing on a synthetic series."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from cassini_bayes.errors import InputError
from cassini_bayes.telemetry import RPM_TO_RAD_S, PulseLog, Telemetry, with_on_times
from cassini_bayes.windows import (
    WindowClampWarning,
    clamp_window,
    parse_window,
    quiet_mask,
    quiet_periods,
    slew_windows,
    split_slews,
)

DT = 0.5  # s


def _series(seed: int = 0) -> tuple[Telemetry, list[tuple[float, float]]]:
    """Three quiet stretches separated by two wheel slews, with realistic noise.

    0-300 s quiet; 300-400 s slew (wheel ramps 600 → 1400 rpm, |ω| up to 2 mrad/s);
    400-900 s quiet; 900-1000 s slew back; 1000-1300 s quiet. Noise: 1e-5 rad/s on ω,
    0.2 rpm on the wheels. Known quiet periods shrink by the 10 s moving window (5 s per side).
    """
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 1300.0 + DT / 2, DT)
    n = t.size
    up = np.clip((t - 300.0) / 100.0, 0, 1) - np.clip((t - 900.0) / 100.0, 0, 1)
    rpm = 600.0 + 800.0 * up
    slewing = ((t > 300) & (t < 400)) | ((t > 900) & (t < 1000))
    wz = np.where(slewing, 2e-3 * np.sin(np.pi * ((t - 300.0) % 600.0) / 100.0), 0.0)
    w = np.stack([np.zeros(n), np.zeros(n), wz], 1) + rng.normal(0, 1e-5, (n, 3))
    ang = np.concatenate([[0.0], np.cumsum(0.5 * (wz[1:] + wz[:-1]) * DT)])
    q = np.stack([np.zeros(n), np.zeros(n), np.sin(ang / 2), np.cos(ang / 2)], 1)
    rates = np.stack([rpm, -rpm, np.full(n, 300.0), np.full(n, np.nan)], 1)
    rates[:, :3] += rng.normal(0, 0.2, (n, 3))
    tel = Telemetry(t, q, w, rates * RPM_TO_RAD_S, source="synthetic")
    return tel, [(0.0, 300.0), (400.0, 900.0), (1000.0, 1300.0)]


@pytest.fixture(scope="module")
def series():
    return _series()


def test_quiet_periods_found(series):
    tel, truth = series
    found = quiet_periods(tel, min_duration_s=60.0)
    assert len(found) == 3
    for (a, b), (ta, tb) in zip(found, truth):
        # inside the true quiet stretch, eroded by at most the 5 s half-window plus 2 s of the
        # slew's gentle start (wheel change below 2 rpm)
        assert ta <= a <= ta + 8.0 if ta > 0 else a == 0.0
        assert tb - 8.0 <= b <= tb if tb < 1300 else b == 1300.0
    assert slew_windows(found) == [(found[0][1], found[1][0]), (found[1][1], found[2][0])]


def test_coarse_sampling_still_sees_a_wheel_ramp():
    """At 0.1 Hz (10 s steps) half the 10-s window rounds to no sample; every sample is still
    compared with its neighbours, so the wheel ramps (800 rpm in 100 s) stay out of the quiet
    periods (they had been swallowed: the RWA4 axis came out at its antipode)."""
    tel, truth = _series()
    coarse = tel.slice(0.0, 1300.0)
    keep = np.arange(0, coarse.n, int(10.0 / DT))
    coarse = Telemetry(coarse.t[keep], coarse.q[keep], coarse.omega[keep],
                       coarse.wheel_rates[keep], source="coarse")
    found = quiet_periods(coarse, min_duration_s=60.0)
    assert len(found) == 3
    for (a, b), (ta, tb) in zip(found, truth):
        assert ta <= a and b <= tb


def test_min_duration_and_thresholds(series):
    tel, _ = series
    assert len(quiet_periods(tel, min_duration_s=400.0)) == 1  # only the 500 s middle one
    # tolerances below the file's own noise (0.2 rpm, 1e-5 rad/s) are raised to 8 sd of it
    found = quiet_periods(tel, min_duration_s=60.0)
    assert quiet_periods(tel, min_duration_s=60.0, wheel_tol_rpm=0.01) == found
    assert quiet_periods(tel, min_duration_s=60.0, rate_max=1e-6) == found
    everything = quiet_periods(tel, min_duration_s=60.0, rate_max=1.0, wheel_tol_rpm=1e4)
    assert everything == [(0.0, 1300.0)]


def test_coarse_sensors_are_quiet_at_rest():
    """A CubeSat's MEMS gyro (3e-4 rad/s) and 1-rpm hall sensors (2 rpm noise, whole-rpm steps)
    at rest: the tolerances rise to 8 sd of the file's own noise, so the three rests are found
    and the slews are not."""
    tel, truth = _series()
    rng = np.random.default_rng(3)
    rates = np.round(tel.wheel_rates / RPM_TO_RAD_S + rng.normal(0, 2.0, tel.wheel_rates.shape))
    coarse = Telemetry(tel.t, tel.q, tel.omega + rng.normal(0, 3e-4, tel.omega.shape),
                       rates * RPM_TO_RAD_S, source="coarse")
    found = quiet_periods(coarse, min_duration_s=60.0)
    assert len(found) == 3
    for (a, b), (ta, tb) in zip(found, truth):
        assert ta <= a and b <= tb


def test_thruster_pulse_breaks_a_quiet_period(series):
    tel, _ = series
    log = PulseLog(np.array([600.05]), np.array([5]), np.array([0.05]))
    found = quiet_periods(with_on_times(tel, log), min_duration_s=60.0)
    assert len(found) == 4
    assert found[1][1] < 600.05 < found[2][0]
    assert found[2][0] - found[1][1] <= 12.0  # only the pulse's 10 s neighbourhood is lost


def test_off_wheel_is_ignored_and_mask_shape(series):
    tel, _ = series
    mask = quiet_mask(tel)
    assert mask.shape == tel.t.shape and mask.dtype == bool
    assert mask[0] and not mask[np.searchsorted(tel.t, 350.0)]


def test_split_slews(series):
    tel, _ = series
    parts = split_slews(tel, margin_s=30.0)
    assert len(parts) == 2
    for part, (a, b) in zip(parts, [(300.0, 400.0), (900.0, 1000.0)]):
        assert a - 40.0 <= part.t[0] <= a - 25.0
        assert b + 25.0 <= part.t[-1] <= b + 40.0
        assert np.ptp(part.wheel_rate("RWA1")) > 700 * RPM_TO_RAD_S  # the whole ramp is inside
    whole = split_slews(tel, margin_s=None)
    assert whole[0].t[0] == 0.0


def test_parse_window():
    t = np.arange(0.0, 1000.0, 1.0)
    assert parse_window("120:540") == (120.0, 540.0)
    assert parse_window(" 1.5e2 : 6e2 ", t) == (150.0, 600.0)
    assert parse_window(":600", t) == (0.0, 600.0)
    assert parse_window("900:", t) == (900.0, 999.0)
    bad = {
        "120-540": "expected T0:T1",
        "a:b": "expected T0:T1",
        "540:120": "start 540 s is not before end 120 s",
        "100:100": "is not before",
        "-5:100": r"outside the data \(0 to 999 s\)",
        "900:1200": "outside the data",
        "10.2:10.8": r"holds 0 sample\(s\)",
    }
    for text, needle in bad.items():
        with pytest.raises(InputError, match=needle) as info:
            parse_window(text, t, option="window-a")
        assert f"--window-a '{text}'" in str(info.value)
    with pytest.raises(InputError, match="give both ends"):
        parse_window(":600")


def test_window_a_few_ms_past_the_data_is_clamped_with_a_warning():
    """An end up to half a median sample period past the data (here 2 ms past, 1-s samples) is
    moved onto the data with one WindowClampWarning; 0.6 s past (more than half a period) stays
    an error."""
    t = np.arange(0.0, 1000.0, 1.0) + 0.001          # jittered: first sample at 1 ms
    with pytest.warns(WindowClampWarning, match=r"--window-b '900:999\.003'.*clamped to "
                                                r"900:999\.001 s"):
        assert parse_window("900:999.003", t, option="window-b") == (900.0, 999.001)
    with pytest.warns(WindowClampWarning, match="clamped to 0.001:600 s"):
        assert parse_window("0:600", t) == (0.001, 600.0)
    with pytest.raises(InputError, match="outside the data"):
        parse_window("900:999.61", t)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert clamp_window((1.0, 999.001), t, "w") == (1.0, 999.001)


def _coast(k: float) -> Telemetry:
    """The synthetic series with the wheels held steady and the slews' body rates times ``k``
    (sensor noise unchanged): only the body-rate rule can tell a slew from a rest."""
    tel, _ = _series()
    rates = np.asarray(tel.wheel_rates, float).copy()
    rates[:, :2] = rates[:1, :2] + np.random.default_rng(4).normal(0, 0.2 * RPM_TO_RAD_S,
                                                                    rates[:, :2].shape)
    noise = tel.omega - np.where(np.abs(tel.omega) > 5e-5, tel.omega, 0.0)
    signal = tel.omega - noise
    return Telemetry(tel.t, tel.q, k * signal + noise, rates, source=f"coast x{k:g}")


def test_quiet_rate_is_relative_to_the_files_slews():
    """A spacecraft slewing 30 times faster (60 mrad/s, the same noise) has the same quiet
    periods under the default rule (a third of the file's top rate), to within a sample; the old
    absolute 1 mrad/s moves every edge of the fast file by ~10 s (the slews' sine ramps cross it
    earlier), so the test can fail."""
    slow, fast = _coast(1.0), _coast(30.0)
    a, b = quiet_periods(slow, min_duration_s=60.0), quiet_periods(fast, min_duration_s=60.0)
    assert len(a) == len(b) == 3
    np.testing.assert_allclose(np.ravel(a), np.ravel(b), atol=DT + 1e-9)
    old = quiet_periods(fast, min_duration_s=60.0, rate_max=1e-3)
    assert np.max(np.abs(np.ravel(old) - np.ravel(a))) > 5.0


def test_free_drift_is_quiet_without_a_rate_rule():
    """``rate_max=inf`` (Brown's RCS Time B: a free drift) keeps only the wheel and thruster
    rules: with steady wheels the whole file is one quiet period."""
    assert quiet_periods(_coast(30.0), min_duration_s=60.0, rate_max=np.inf) == [(0.0, 1300.0)]


@pytest.mark.parametrize("scenario, model, wheel, s", [
    ("rwa4_rcs", "cassini_pre_soi", "RWA4", 1e-4),
    ("wheel_axis_espa_bus_rcs", "espa_bus", "RW2", 1e-2),   # 1e-4 puts its wheels below 1e-6 kg m²
])
def test_rcs_windows_detected_and_scale_free(scenario, model, wheel, s, tmp_path):
    """Brown's RCS-method Time A / Time B are detected on Cassini (the windows the flight-data
    audit and the pinned fit use: 0-417 s and 723-1237 s) and on the ESPA bus, whose Time B
    drifts at 22 mrad/s, beyond any Cassini-sized rate rule (1 mrad/s finds no Time B); and
    the same spacecraft scaled by ``s`` in inertia, wheel inertias and torques (the same
    manoeuvre, tests/scaled.py) gives the same windows."""
    import tomli_w
    from scaled import scaled_model, scaled_scenario

    import cassini_bayes as cb
    from cassini_bayes.inference.rwa4 import detect_windows
    from cassini_bayes.simulate import scenario_from_dict

    found = []
    for scale in (1.0, s):
        path = tmp_path / f"{model}_{scale:g}.toml"
        path.write_text(tomli_w.dumps(scaled_model(model, scale)))
        sc = scenario_from_dict(scaled_scenario(scenario, scale, str(path)), scenario)
        tel = cb.simulate_scenario(sc, seed=sc.seed).telemetry
        found.append(detect_windows(tel, "rcs", wheel=wheel))
    assert found[0] == found[1]
    (a, b), = found[0]
    if wheel == "RWA4":
        assert (a, b) == ((0.0, 417.0), (723.0, 1237.0))
    else:
        assert 30.0 <= a[1] - a[0] and a[1] < 62.0            # before the spin-up at 62 s
        assert 73.0 < b[0] <= 85.0 and b[1] >= 110.0           # after it, holding 85-110 s
        assert len(quiet_periods(tel, min_duration_s=30.0, rate_max=1e-3)) < 2


@pytest.mark.parametrize("glitch", ["wheel step", "gyro spike"])
def test_a_rest_split_by_a_glitch_is_paired_once(glitch):
    """A wheel-rate step or one gyro spike inside the middle rest splits it in two quiet periods;
    the RWA method's rests join them (the longer piece), so Time A and Time B keep a slew between
    them. Without the join the first pair would be two pieces of one rest."""
    from cassini_bayes.inference.rwa4 import detect_windows
    from cassini_bayes.windows import joined_rests

    tel, _ = _series(seed=3)
    t = np.asarray(tel.t)
    if glitch == "wheel step":
        rates = np.array(tel.wheel_rates)
        rates[(t >= 640.0) & (t < 646.0), 0] += 30.0 * RPM_TO_RAD_S
        tel = Telemetry(t, tel.q, tel.omega, rates, source="synthetic")
    else:
        omega = np.array(tel.omega)
        omega[t == 640.0, 2] = 5e-3
        tel = Telemetry(t, tel.q, omega, tel.wheel_rates, source="synthetic")
    quiet = quiet_periods(tel, min_duration_s=60.0)
    assert len(quiet) == 4 and 630.0 < quiet[1][1] < quiet[2][0] < 660.0
    rests = joined_rests(tel, quiet)
    assert rests == [quiet[0], quiet[2], quiet[3]]       # 640-900 s is the longer piece
    assert detect_windows(tel, "rwa") == [(quiet[0], quiet[2])]
    clean, _ = _series(seed=3)
    quiet = quiet_periods(clean, min_duration_s=60.0)
    assert joined_rests(clean, quiet) == quiet           # slews between: nothing joined
