"""Physics checks of the inputs (cassini_bayes.consistency): each mistake is refused with its cause,
clean data from every scenario family pass.

Data: one simulated run per scenario family (slews, biasing event, FSDS biasing, RWA4 by RCS and
by RWA, and a ``_real`` variant with every real-world error on), cut where long; corrupted copies
of them. The statistics and their margins (measured on the full scenario files with
``cassini-bayes simulate``, every file in experiments/scenarios/, see docs/input_checks.md):

* attitude vs rates: the declared reading's alignment with ∫ω dt is ≥ 0.988 on clean data; the
  misfit ratio ``(1 − c_declared)/(1 − c_best other)`` is ≤ 0.013 clean and ≥ 28 for a
  scalar-first, conjugated or both-wrong file (threshold 5); body-rate scale 0.99–1.03 clean,
  0.0174–0.0181 for deg/s (accepted 0.5–2);
* wheel units: the wheel-momentum scale κ is 0.993–1.032 clean and 9.48–9.86 for rad/s columns
  (accepted 0.324–3.09, the geometric midpoints), alignment ≥ 0.962 (needed ≥ 0.9);
* wheel axes (a free momentum vector per wheel, judged where the design's conditioning is
  ≥ 0.1: slews 0.30–0.47, biasing events 0.02–0.05): ≤ 2.1° from the model's axes on clean
  open-world files (benchmarks/input_check_margins.py), 178–180° for a flipped sign, 88–92°
  for swapped columns on Cassini's orthogonal wheels (threshold 30°);
* pulse log vs on_*: largest per-sample difference ≤ 0.018 s clean against a slack of one
  pulse (≥ 0.125 s); doubled widths differ by the whole total (seconds);
* excitation: second/first eigenvalue of Σ ω ωᵀ dt ≥ 0.35 on the shipped slews (post-PRM: X and
  Y equal, Z small: 1.0), 2.6e-6 for X-only slews (threshold 1e-3).
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import replace

import jax
import numpy as np
import pytest

from cassini_bayes import consistency as cons
from cassini_bayes.consistency._attitude import ALIGN_GOOD
from cassini_bayes._paths import SCENARIOS_DIR
from cassini_bayes.errors import InputError, UnidentifiableError, command_line
from cassini_bayes.simulate import load_scenario, scenario_from_dict, simulate
from cassini_bayes.simulate.controllers import slew_duration
from cassini_bayes.spacecraft import load_spacecraft
from cassini_bayes.telemetry import RPM_TO_RAD_S, PulseLog, Telemetry, write_telemetry
from kinematics import slew_segments, wheels_for_conserved_momentum

FAMILIES = ["slews_post_prm", "slew_2000_03_15_real", "biasing_day028", "fsds_biasing",
            "rwa4_rcs", "rwa4_rwa"]
CUT_S = 1800.0  # long scenarios are cut here (slews that would not finish are dropped)


def _scenario(name: str):
    """The scenario, cut to CUT_S when longer (as tests/test_scenarios.py does)."""
    d = tomllib.loads((SCENARIOS_DIR / f"{name}.toml").read_text())
    if d["run"]["duration_s"] <= CUT_S:
        return scenario_from_dict(d, name)
    d["run"]["duration_s"] = CUT_S
    d["slew"] = [s for s in d.get("slew", []) if s["t_start_s"] + slew_duration(
        np.deg2rad(s["angle_deg"]), s["rate_mrad_s"] * 1e-3, s["accel_mrad_s2"] * 1e-3)
        <= CUT_S]
    return scenario_from_dict(d, f"{name}[:{CUT_S:g} s]")


def _prior(name: str):
    d = tomllib.loads((SCENARIOS_DIR / f"{name}.toml").read_text())
    return load_spacecraft(d["prior"]["model"].split("/")[-1].removesuffix(".toml"))


@pytest.fixture(scope="module")
def runs():
    out = {}
    for i, name in enumerate(FAMILIES):
        r = simulate(jax.random.key(100 + i), _scenario(name))
        tel = replace(r.telemetry, source=f"{name}.csv")
        log = None if r.pulses is None else replace(r.pulses, source=f"{name}_pulses.csv")
        out[name] = (tel, log, _prior(name))
    return out


def _scalar_first(tel):
    return replace(tel, q=np.roll(tel.q, 1, axis=1))


def _conjugated(tel):
    return replace(tel, q=tel.q * np.array([-1.0, -1.0, -1.0, 1.0]))


def _wheels_in_rad_s(tel):
    """The file's wheel columns hold rad/s; read as rpm they become ×2π/60 too small."""
    return replace(tel, wheel_rates=tel.wheel_rates * RPM_TO_RAD_S)


# --------------------------------------------------------------------------------------------
# Clean data pass, with margin


@pytest.mark.parametrize("name", FAMILIES)
def test_clean_scenario_families_pass(runs, name):
    tel, log, sc = runs[name]
    cons.check_telemetry_data(tel, sc, log)
    ag = cons.attitude_rate_agreement(tel)
    if ag is not None:  # fsds_biasing barely turns: not identifiable, skipped
        misfit = (1 - ag.alignment[0]) / (1 - ag.alignment[1:].max())
        assert ag.alignment[0] > 0.97 and misfit < 0.05 and 0.9 < ag.scale < 1.1
    on = tel.on_times
    fit = cons.wheel_momentum_scale(tel, sc, on)
    assert fit.alignment > 0.93 and 0.9 < fit.scale < 1.1


def test_not_identifiable_says_nothing():
    """No rotation, no wheel change: every check is skipped, nothing is raised."""
    n = 300
    rates = np.full((n, 4), np.nan)
    rates[:, :3] = 400.0 * RPM_TO_RAD_S
    tel = Telemetry(np.arange(float(n)), np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)),
                    1e-7 * np.ones((n, 3)), rates)
    assert cons.attitude_rate_agreement(tel) is None
    cons.check_telemetry_data(tel, load_spacecraft("cassini_post_prm"))


# --------------------------------------------------------------------------------------------
# Quaternion convention and body-rate units


@pytest.mark.parametrize("name", ["slews_post_prm", "biasing_day028", "rwa4_rcs", "rwa4_rwa"])
@pytest.mark.parametrize("corrupt, cause", [
    (_scalar_first, "looks scalar-first (q4 first)"),
    (_conjugated, "looks conjugated (body → inertial)"),
    (lambda t: _scalar_first(_conjugated(t)), "looks scalar-first and conjugated"),
])
def test_quaternion_convention_refused(runs, name, corrupt, cause):
    tel = runs[name][0]
    with pytest.raises(InputError, match=re.escape(cause)) as e:
        cons.check_telemetry_data(corrupt(tel))
    assert str(e.value).startswith(f"{name}.csv: columns q1..q4:")
    assert "\n" not in str(e.value)


def test_single_axis_turn_names_every_fitting_reading(runs):
    """One slew about body Y from near the identity: three readings fit a conjugated file."""
    tel = runs["slew_2000_03_15_real"][0]              # cut: its first slew only
    with pytest.raises(InputError, match=r"does not follow the format's convention but fits "
                                         r"the body rates read as scalar-first \(1.00\) or "
                                         r"conjugated \(1.00\) or scalar-first and conjugated"):
        cons.check_attitude_rates(_conjugated(tel))


@pytest.mark.parametrize("name", ["slews_post_prm", "rwa4_rcs"])
def test_body_rates_in_deg_s_refused(runs, name):
    tel = runs[name][0]
    with pytest.raises(InputError, match=r"look like deg/s: divide by 57\.2958"):
        cons.check_attitude_rates(replace(tel, omega=np.degrees(tel.omega)))


def test_rates_unrelated_to_attitude_refused(runs):
    tel = runs["slews_post_prm"][0]
    shuffled = np.random.default_rng(0).permutation(tel.omega)
    with pytest.raises(InputError, match="body rates and attitude are inconsistent"):
        cons.check_attitude_rates(replace(tel, omega=shuffled))


# --------------------------------------------------------------------------------------------
# Wheel units by momentum conservation


@pytest.mark.parametrize("name", ["slews_post_prm", "slew_2000_03_15_real", "biasing_day028",
                                  "fsds_biasing", "rwa4_rcs", "rwa4_rwa"])
def test_wheel_rates_in_rad_s_refused(runs, name):
    tel, log, sc = runs[name]
    bad = _wheels_in_rad_s(tel)
    fit = cons.wheel_momentum_scale(bad, sc)
    assert 8.5 < fit.scale < 10.5                      # 60/(2π) = 9.55
    with pytest.raises(InputError, match=r"wheel rates look like rad/s, the file format wants "
                                         r"rpm; multiply by 60/\(2\*pi\)"):
        cons.check_telemetry_data(bad, sc, log)


def test_unlogged_firings_skip_the_wheel_check(runs):
    """Without on-times the biasing event's thruster firings break the balance: no verdict."""
    tel, _, sc = runs["biasing_day028"]
    bare = replace(_wheels_in_rad_s(tel), on_times=None)
    fit = cons.wheel_momentum_scale(bare, sc)
    assert fit.alignment < cons.MOMENTUM_ALIGN_MIN
    cons.check_wheel_units(bare, sc)


def _edit_wheel(tel, name: str, edit):
    """``tel`` with one wheel's column replaced by ``edit(rates, column index)``."""
    rates = np.array(tel.wheel_rates, float)
    edit(rates, tel.wheel_names.index(name))
    return replace(tel, wheel_rates=rates)


def _flipped(tel, name):
    return _edit_wheel(tel, name, lambda r, i: r.__setitem__((slice(None), i), -r[:, i]))


def _swapped(tel, a, b):
    i, j = tel.wheel_names.index(a), tel.wheel_names.index(b)
    rates = np.array(tel.wheel_rates, float)
    rates[:, [i, j]] = rates[:, [j, i]]
    return replace(tel, wheel_rates=rates)


def _one_in_rad_s(tel, name):
    return _edit_wheel(tel, name, lambda r, i: r.__setitem__((slice(None), i),
                                                             r[:, i] * RPM_TO_RAD_S))


def test_clean_wheel_axes_lie_along_the_model(runs):
    """Slews about several axes separate the wheels: each free momentum vector lies along its
    model axis (≤ 2.1° on 320 open-world files against 30°) at scale 1 (within ±10 %)."""
    tel, log, sc = runs["slews_post_prm"]
    axes = cons.wheel_momentum_scale(tel, sc).axes
    assert axes.judged and axes.conditioning > 2 * cons.AXES_CONDITION_MIN
    for n in axes.vectors:
        assert axes.angle_deg(n, sc.wheel(n).axis) < 3.0
        assert 0.9 < axes.scale(n) < 1.1


def test_flipped_wheel_sign_refused(runs):
    tel, log, sc = runs["slews_post_prm"]
    with pytest.raises(InputError, match=r"column rwa2: momentum is conserved only with rwa2's "
                                         r"momentum 1[78]\d° from RWA2's axis .*its sign looks "
                                         r"flipped; negate the column"):
        cons.check_telemetry_data(_flipped(tel, "RWA2"), sc, log)


def test_swapped_wheel_columns_refused(runs):
    tel, log, sc = runs["slews_post_prm"]
    with pytest.raises(InputError, match=r"column rwa2: .* 9\d° from RWA2's axis .*, [0-5]° from "
                                         r"RWA3's: it looks like RWA3's rates; check the column "
                                         r"order"):
        cons.check_telemetry_data(_swapped(tel, "RWA2", "RWA3"), sc, log)


def test_one_wheel_in_rad_s_refused(runs):
    """One column in rad/s breaks the common scale's balance (no verdict there); the free-axis
    balance names the column."""
    tel, log, sc = runs["slews_post_prm"]
    with pytest.raises(InputError, match=r"column rwa3: wheel rates look like rad/s"):
        cons.check_telemetry_data(_one_in_rad_s(tel, "RWA3"), sc, log)
    # the same balance from a model whose RWA3 spin inertia is a tenth: the message says so too
    wheels = tuple(replace(w, inertia=w.inertia / 10) if w.name == "RWA3" else w
                   for w in sc.wheels)
    with pytest.raises(InputError, match=r"column rwa3: .* or the model's RWA3 spin inertia "
                                         r"0\.01\d* kg m\^2 is \d+(\.\d+)?x too small"):
        cons.check_telemetry_data(tel, replace(sc, wheels=wheels), log)


def test_an_idle_wheel_written_as_zero_is_as_off(runs):
    """RWA4 written as 0 rpm (or tachometer noise about 0) instead of left empty: it carries no
    momentum, so it is not a wheel of the balance. It had entered as a free wheel with all-zero
    columns, the balance became rank-deficient, and the sign check was skipped (the flight-data
    audit: a flipped RWA2 then fitted Ixx 235 kg m² with exit 0)."""
    tel, log, sc = runs["slews_post_prm"]
    k = tel.wheel_names.index("RWA4")
    noise = np.random.default_rng(3).normal(0.0, 0.3, tel.n).round(1) * RPM_TO_RAD_S
    for idle in (np.zeros(tel.n), noise):
        zero = _edit_wheel(tel, "RWA4", lambda r, i: r.__setitem__((slice(None), i), idle))
        assert not zero.active_mask()[k] and "RWA4" not in zero.active_wheels()
        cons.check_telemetry_data(zero, sc, log)
        with pytest.raises(InputError, match="column rwa2: .* its sign looks flipped"):
            cons.check_telemetry_data(_flipped(zero, "RWA2"), sc, log)
    # a wheel through zero speed, and one holding a constant speed, are wheels
    through = _edit_wheel(tel, "RWA4", lambda r, i: r.__setitem__(
        (slice(None), i), np.linspace(-50.0, 50.0, tel.n) * RPM_TO_RAD_S))
    assert through.active_mask()[k]


def test_an_unsigned_tachometer_is_refused_in_a_file_without_thrusters(runs):
    """A wheel reported as |rpm| through a zero crossing stays near its axis (9° in the audit), so
    the axis check passes; but with no thruster firing the momenta must balance, and the free-axis
    balance falls from ≥ 0.998 (every correct slew file) to 0.96 (the audit's file: Iyy −29 % fitted
    with exit 0). Refused, naming the wheel that touches zero without crossing it; a file with
    thruster firings (on_* columns) is left to the fit."""
    tel, log, sc = runs["slews_post_prm"]
    crossing = [n for n in tel.active_wheels()
                if np.nanmin(tel.wheel_rate(n)) < 0 < np.nanmax(tel.wheel_rate(n))]
    assert crossing, "the cut slews must take some wheel through zero"
    name = crossing[0]
    unsigned = _edit_wheel(tel, name, lambda r, i: r.__setitem__((slice(None), i), np.abs(r[:, i])))
    axes = cons.wheel_momentum_scale(tel, sc).axes
    assert tel.on_times is None and axes.alignment >= 0.998 and axes.swing_nms > 5.0
    with pytest.raises(InputError, match=rf"do not balance the body's even with a free axis "
                                         rf"per wheel \(alignment 0\.\d+; .*{name.lower()} stays "
                                         r"on one side of 0 rpm yet reaches"):
        cons.check_telemetry_data(unsigned, sc, log)


def test_a_wheel_still_between_firings_is_not_judged():
    """A wheel that hardly moves between firings (the ESPA biasing event spins its wheels up in
    turn while the thrusters fire) leaves its free vector to the noise: a correct column must not
    be refused. The shipped event passes; only determined wheels are judged, and a wheel off its
    axis is never among them; `check` names those left out; a judged wheel flipped is refused.
    Which wheel stays still follows the closed-loop pulse train, so no wheel is named."""
    import cassini_bayes as cb
    from cassini_bayes.api import check_telemetry

    sim = cb.simulate_scenario("biasing_espa_bus", seed=0)
    sc = cb.load_spacecraft("espa_bus")
    cons.check_telemetry_data(sim.telemetry, sc, sim.pulses)
    axes = cons.wheel_momentum_scale(sim.telemetry, sc).axes
    angle_max = cons.axis_angle_max_deg(sc)
    judged = [n for n in axes.vectors if axes.determined(n, angle_max)]
    assert judged
    for n in axes.vectors:
        if axes.angle_deg(n, sc.wheel(n).axis) > angle_max:
            assert n not in judged, n
    line = check_telemetry(sim.telemetry, pulses=sim.pulses, spacecraft=sc).physics
    left_out = len(judged) < len(axes.vectors)
    assert ("not checked (too little motion between firings" in line) == left_out, line
    with pytest.raises(InputError, match=rf"column {judged[0].lower()}: .* from "
                                         rf"{judged[0]}'s axis"):
        cons.check_telemetry_data(_flipped(sim.telemetry, judged[0]), sc, sim.pulses)


def test_wheels_moving_together_are_not_judged(runs):
    """A biasing event's wheels change together: the free vectors are not separable
    (conditioning 0.02–0.05), so swapped columns pass, and `check` says they were not checked."""
    from cassini_bayes.api import check_telemetry

    tel, log, sc = runs["biasing_day028"]
    bad = _swapped(tel, "RWA1", "RWA2")
    axes = cons.wheel_momentum_scale(bad, sc, tel.on_times).axes
    assert axes.conditioning < cons.AXES_CONDITION_MIN and not axes.judged
    cons.check_telemetry_data(bad, sc, log)
    line = check_telemetry(bad, pulses=log, spacecraft=sc).physics
    assert "wheel signs and column order not checked (the wheels' rates move together" in line
    clean = check_telemetry(*runs["slews_post_prm"][:1], spacecraft=sc).physics
    assert "each wheel's momentum along its axis in the model (within" in clean


# --------------------------------------------------------------------------------------------
# Pulse log vs on_* columns


@pytest.mark.parametrize("factor, pct", [(2.0, "+100 %"), (0.5, "-50 %")])
def test_pulse_widths_disagreeing_with_on_columns_refused(runs, factor, pct):
    tel, log, sc = runs["biasing_day028"]
    bad = PulseLog(log.t_on, log.thruster, log.width * factor, log.source)
    with pytest.raises(InputError, match=r"pulse log widths disagree with on_\w\d of "
                                         r"biasing_day028.csv by " + re.escape(pct)):
        cons.check_thrust_data([(tel, bad)], sc)


def test_pulse_log_of_another_thruster_refused(runs):
    tel, log, sc = runs["biasing_day028"]
    swapped = PulseLog(log.t_on, (log.thruster + 1) % 8, log.width, log.source)
    with pytest.raises(InputError, match="pulse log widths disagree with on_"):
        cons.check_pulses_match_on_times(tel, swapped)


# --------------------------------------------------------------------------------------------
# Identifiability for the fit asked for


def _one_axis_slews(axis):
    sc = load_spacecraft("cassini_2000_03_15")
    t, q, w = slew_segments([0.0, 0.0, 0.0, 1.0], [(axis, 0.6, 300.0), (axis, -0.5, 300.0)],
                            2.0, 100.0)
    rates, _ = wheels_for_conserved_momentum(t, q, w, sc.inertia, np.array([3.0, -2.0, 5.0]),
                                             sc.wheel_axes[:3], sc.wheel_inertias[:3])
    rng = np.random.default_rng(1)
    wheel = np.full((t.size, 4), np.nan)
    wheel[:, :3] = rates
    tel = Telemetry(t, q, w + 1e-6 * rng.standard_normal(w.shape), wheel, source="x.csv")
    return tel, sc


def test_one_axis_slews_unidentifiable():
    tel, sc = _one_axis_slews((1.0, 0.0, 0.0))
    with pytest.raises(UnidentifiableError, match=r"about body X only .* Iyy, Izz, Iyz cannot be "
                                                  r"learned .*add slews about other axes"):
        cons.check_inertia_data([tel], sc)
    tel, sc = _one_axis_slews((1.0, 1.0, 1.0))
    with pytest.raises(UnidentifiableError, match=r"only the three combinations I·e"):
        cons.check_inertia_data([tel], sc)


def test_two_files_about_two_axes_are_enough():
    tx, sc = _one_axis_slews((1.0, 0.0, 0.0))
    ty, _ = _one_axis_slews((0.0, 1.0, 0.0))
    cons.check_inertia_data([tx, ty], sc)


def test_rwa4_method_must_match_the_control(runs):
    tel_rcs, _, sc = runs["rwa4_rcs"]
    tel_rwa = runs["rwa4_rwa"][0]
    cons.check_rwa4_data(tel_rcs, sc, "rcs")
    cons.check_rwa4_data(tel_rwa, sc, "rwa")
    with pytest.raises(InputError, match="method='rwa' needs RWA slew pairs.*use method='rcs'"):
        cons.check_rwa4_data(tel_rcs, sc, "rwa")
    with pytest.raises(InputError, match="method='rcs' needs RCS-controlled data.*use "
                                         "method='rwa'"):
        cons.check_rwa4_data(tel_rwa, sc, "rcs")
    with command_line(), pytest.raises(InputError, match="--method rwa needs RWA slew pairs.*use "
                                                         "--method rcs"):
        cons.check_rwa4_data(tel_rcs, sc, "rwa")


# --------------------------------------------------------------------------------------------
# Through the CLI


def test_cli_refuses_wheel_rates_in_rad_s(runs, run_cli, tmp_path):
    """`check` and `fit inertia` exit 2 with one stderr line, no traceback, no run directory."""
    tel, _, sc = runs["slews_post_prm"]
    path = tmp_path / "slews_rad_s.csv"
    write_telemetry(path, _wheels_in_rad_s(tel))        # 300-400 rpm written as 31-42 rad/s
    model = "cassini_post_prm"
    code, _, err = run_cli("check", path, "--spacecraft", model)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert "wheel rates look like rad/s" in err and str(path) in err
    code, _, err = run_cli("fit", "inertia", "--telemetry", path, "--spacecraft", model,
                           "--out", tmp_path / "run")
    assert code == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert "wheel rates look like rad/s" in err
    assert not (tmp_path / "run").exists()
    write_telemetry(tmp_path / "ok.csv", tel)
    code, out, err = run_cli("check", tmp_path / "ok.csv", "--spacecraft", model)
    assert code == 0, err


# --------------------------------------------------------------------------------------------
# Every shipped scenario (slow: one full simulation each)


# scenarios whose wheels hold their speed (the attitude held on thrusters): no momentum moves
# between body and wheels, so the wheels' unit cannot be read from the data
WHEELS_AT_REST = {"leak_cruise", "leak_espa_bus"}


def _scenario_names() -> list[str]:
    """The shipped scenario files; the thruster-health campaign files beside them (a
    ``[campaign]`` table) are ``simulate-health`` inputs, not scenarios."""
    return sorted(p.stem for p in SCENARIOS_DIR.glob("*.toml")
                  if "campaign" not in tomllib.loads(p.read_text()))


@pytest.mark.slow
@pytest.mark.parametrize("name", _scenario_names())
def test_every_shipped_scenario_passes_and_its_corruptions_fail(name):
    r = simulate(jax.random.key(7), load_scenario(name))
    tel, log, sc = r.telemetry, r.pulses, _prior(name)
    cons.check_telemetry_data(tel, sc, log)
    agreement = cons.attitude_rate_agreement(tel)
    if agreement is not None:
        # the check names the right reading only where that reading aligns well itself (500 ms
        # rate steps between 1 s samples of biasing_espa_bus_mixed_widths: 0.898); otherwise it
        # still refuses the corrupted file as inconsistent
        named = agreement.alignment[0] >= ALIGN_GOOD
        match = "columns q1..q4: the quaternion looks" if named else "columns q1..q4"
        for bad in (_scalar_first(tel), _conjugated(tel)):
            with pytest.raises(InputError, match=match):
                cons.check_attitude_rates(bad)
    if name in WHEELS_AT_REST:
        # the balance does not fit (alignment 0.16 on leak_cruise), so the check says nothing
        fit = cons.wheel_momentum_scale(_wheels_in_rad_s(tel), sc)
        assert fit is None or fit.alignment < cons.MOMENTUM_ALIGN_MIN
        cons.check_telemetry_data(_wheels_in_rad_s(tel), sc, log)
        return
    with pytest.raises(InputError, match="wheel rates look like rad/s"):
        cons.check_telemetry_data(_wheels_in_rad_s(tel), sc, log)
    axes = cons.wheel_momentum_scale(tel, sc, tel.on_times).axes
    if axes is not None and axes.judged:     # slews about several axes: every wheel on its own
        known = list(axes.vectors)
        # one running wheel (wheel_axis_espa_bus_rcs): its flip may show first as the balance's
        # scale κ ≈ −1
        flip = "its sign looks flipped" + ("" if len(known) > 1 else r"|wheel momentum -[0-9.]+x")
        with pytest.raises(InputError, match=flip):
            cons.check_telemetry_data(_flipped(tel, known[0]), sc, log)
        if len(known) > 1:
            with pytest.raises(InputError, match="check the column order"):
                cons.check_telemetry_data(_swapped(tel, known[0], known[1]), sc, log)


def test_a_data_gap_at_a_slew_start_is_not_a_unit_error(runs):
    """A 300-s gap in the rows where a slew starts: no turning stretch spans the gap (the
    trapezoid ∫ω dt across it is a straight line through the slew's start). One such stretch had
    turned a correct file into "the body rates integrate to 0.444x …; check their unit"
    (flight-data audit); the file passes, and deg/s rates with the same gap are still refused."""
    tel, log, sc = runs["slews_post_prm"]
    rate = np.linalg.norm(tel.omega, axis=1)
    start = tel.t[np.argmax(rate > 0.2 * rate.max())]
    keep = (tel.t < start - 60.0) | (tel.t > start + 240.0)
    gap = replace(tel, t=tel.t[keep], q=tel.q[keep], omega=tel.omega[keep],
                  wheel_rates=tel.wheel_rates[keep],
                  on_times=None if tel.on_times is None else tel.on_times[keep])
    assert np.diff(gap.t).max() >= 300.0 - 1e-9
    ag = cons.check_attitude_rates(gap)
    assert ag.alignment[0] > 0.97 and 0.9 < ag.scale < 1.1
    with pytest.raises(InputError, match="they look like deg/s"):
        cons.check_attitude_rates(replace(gap, omega=np.degrees(gap.omega)))


def test_a_gyro_bias_beyond_the_models_knowledge_is_reported(runs):
    """Quiet 60-s windows show a constant gyro bias as ∫ω dt running ahead of the quaternions:
    clean slews give |b| within 1.1 prior sd on every shipped scenario (threshold 5 prior sd
    and 5 standard errors); 2e-5 rad/s (40 prior sd; the flight-data audit's RWA4 axis 0.71°
    off against a 0.18° cone, every adequacy check passing) is measured to 5 % and reported,
    by `check` too."""
    import warnings

    from cassini_bayes.api import check_telemetry

    tel, log, sc = runs["slews_post_prm"]
    sd = sc.knowledge.gyro_bias_sd_rad_s
    with warnings.catch_warnings():
        warnings.simplefilter("error", cons.GyroBiasWarning)
        clean = cons.check_gyro_bias(tel, sc)
    assert np.all(np.abs(clean.bias) < 3 * sd)
    b = np.array([2e-5, -2e-5, 1e-5])
    biased = replace(tel, omega=tel.omega + b)
    with pytest.warns(cons.GyroBiasWarning, match=r"columns wx wy wz carry a constant gyro bias "
                                                  r"of about x \+2e-05, y -2e-05, z \+1e-05 rad/s"):
        est = cons.check_gyro_bias(biased, sc)
    np.testing.assert_allclose(est.bias, b, atol=0.05 * 2e-5)
    notes = check_telemetry(biased, spacecraft=sc).notes
    assert any("widen bias_sd_rad_s in the spacecraft model" in n for n in notes)


def test_rates_that_turn_under_a_still_attitude_are_refused():
    """Constant quaternions beside body rates that integrate to 0.5 rad (the CLI audit's stale
    attitude columns: 52°) are refused; the same file with the rates at gyro-noise level is
    not (too little turn to judge)."""
    t = np.arange(0.0, 100.0, 0.5)
    q = np.tile([0.0, 0.0, 0.0, 1.0], (t.size, 1))
    w = np.zeros((t.size, 3))
    w[20:120, 0] = 0.01                                   # 0.5 rad about x
    rates = np.full((t.size, 4), np.nan)
    tel = Telemetry(t, q, w, rates, source="still.csv")
    with pytest.raises(InputError, match=r"still.csv: columns q1..q4 and wx wy wz: the body "
                                         r"rates integrate to a turn of 28.6°"):
        cons.check_attitude_rates(tel)
    quiet = Telemetry(t, q, np.full((t.size, 3), 1e-6), rates, source="quiet.csv")
    assert cons.check_attitude_rates(quiet) is None


def test_quantised_rates_are_found_and_coarse_ones_reported(runs):
    """A rate column on a lattice ``q k`` is found with its quantum; it is reported when the
    noise measured in it is below q/4 (undithered: the rounding error repeats while the rate
    holds its value) and q is at least 5e-4 of its excursion. The simulator's 0.1-rpm
    tachometers, dithered by 0.05 rpm of noise (measured noise 0.61 quanta, ≤ 0.05 % of the
    excursion), are found on every family and not reported; body rates rounded to 1 mrad/s (the
    fuzz's file: Ixx 6 sd low with exit 0) are, by ``check`` too; so are wheel rates rounded to
    1 rpm (0.06–0.09 % of a slew's excursion; they moved Iyz by 2.2–2.4 posterior sd)."""
    import warnings

    from cassini_bayes.api import check_telemetry

    for name, (tel, _, _) in runs.items():
        with warnings.catch_warnings():
            warnings.simplefilter("error", cons.QuantisedRatesWarning)
            found = cons.check_rate_quantisation(tel)
        assert [r.column for r in found] == [n.lower() for n in tel.active_wheels()], name
        for r in found:
            assert abs(r.quantum / RPM_TO_RAD_S - 0.1) < 1e-9 and not r.large, (name, r)
            assert r.noise > r.quantum / cons.QUANTUM_NOISE_RATIO, (name, r)
    tel, log, sc = runs["slews_post_prm"]
    body = replace(tel, omega=np.round(tel.omega / 1e-3) * 1e-3)
    with pytest.warns(cons.QuantisedRatesWarning,
                      match=r"slews_post_prm.csv: rates on a coarse lattice: wx 0.001 rad/s "
                            r"\(its measured noise 0 quanta, \d+ % of its excursion\); wy "):
        found = cons.check_rate_quantisation(body)
    assert [r.column for r in found if r.large] == ["wx", "wy"]   # wz (8 µrad/s) rounds to 0
    c = check_telemetry(body, spacecraft=sc)
    assert any("rates on a coarse lattice" in n for n in c.notes)
    assert {r.column for r in c.quanta} == {"wx", "wy", "rwa1", "rwa2", "rwa3"}
    wheels = replace(tel, wheel_rates=np.round(tel.wheel_rates / RPM_TO_RAD_S) * RPM_TO_RAD_S)
    with pytest.warns(cons.QuantisedRatesWarning, match=r"rwa1 1 rpm \(its measured noise 0 "):
        cons.check_rate_quantisation(wheels)
    # not reported: 1 rpm dithered by 0.5 rpm of noise before the rounding, and 0.3 rpm, below
    # 5e-4 of these slews' excursion (it moved the inertia by ≤ 0.6 posterior sd)
    rpm = tel.wheel_rates / RPM_TO_RAD_S
    dithered = np.round(rpm + np.random.default_rng(2).normal(0.0, 0.5, rpm.shape))
    for rounded in (dithered, np.round(rpm / 0.3) * 0.3):
        with warnings.catch_warnings():
            warnings.simplefilter("error", cons.QuantisedRatesWarning)
            found = cons.check_rate_quantisation(replace(tel, wheel_rates=rounded * RPM_TO_RAD_S))
        assert found and not any(r.large for r in found)


def test_rate_quantum_of_a_lattice():
    """The lattice spacing survives an offset, gaps between occupied levels and the rpm → rad/s
    conversion; two levels are a lattice; continuous values and a constant have none."""
    rng = np.random.default_rng(4)
    k = np.r_[0, 1, 2, 4, 7, rng.integers(-50, 50, 200)]
    assert cons.rate_quantum((0.25 + 3.0 * k) * RPM_TO_RAD_S) == pytest.approx(
        3.0 * RPM_TO_RAD_S, rel=1e-9)
    assert cons.rate_quantum(1e-3 * k) == pytest.approx(1e-3, rel=1e-9)
    assert cons.rate_quantum(rng.normal(size=1000)) is None
    assert cons.rate_quantum(np.full(50, 0.3)) is None
    assert cons.rate_quantum(np.r_[np.zeros(10), 0.3 * np.ones(10)]) == pytest.approx(0.3)
    assert cons.rate_quantum(np.r_[1e-3 * k, np.nan]) == pytest.approx(1e-3, rel=1e-9)
