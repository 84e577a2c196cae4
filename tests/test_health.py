"""Thruster health over many biasing events: the per-event summary, the exact
change-point model, the campaign simulator, ``fit health`` / ``simulate-health``, and the SBC glue.

Every random draw has a fixed seed, so each test is deterministic: its "false-failure rate" is 0
for this code, and the margins below say how far from its threshold each assertion sits (so a
harmless change of the random stream would not flip it). The statistical claims (detection delay,
control false alarms, coverage over seeds) are measured by ``benchmarks/health_campaign.py``
(docs/health.md), not here. Observed against the thresholds: detection P(Z3 or Z4 down)
0.99996 (> 0.99), before the change ≤ 2e-7 (< 0.01); control at every look ≤ 1.4e-4 (< 0.02);
the would-be-wrong models ≤ 4e-5 (< 0.05); the simulated event's |z| ≤ 0.13 (< 3) and thrusts
within 0.14 % (1-2 % allowed).
"""

from __future__ import annotations

import json
import textwrap
import tomllib

import numpy as np
import pytest
from scipy import stats

from cassini_bayes.cli import main
from cassini_bayes.errors import InputError
from cassini_bayes.inference.health import HealthPrior, event_summary, health_posterior
from cassini_bayes.inference.health.changepoint import SCATTER_GRID
from health_data import synthetic_events
from pages import first_table

Z3_Z4 = [2, 3]
CHANNELS = ("F[Z1]", "F[Z2]", "F[Z3]", "F[Z4]", "F_combination[0.5 F[Y1] + 0.5 F[Y3]]",
            "F_combination[0.5 F[Y2] + 0.5 F[Y4]]")
"""Cassini's six channels as the health fit finds them from its events' firings."""


# --- the change-point model --------------------------------------------------------------------


def test_detects_a_seven_percent_drop_and_dates_it():
    t, y, s = synthetic_events(1, drop=0.07)
    post = health_posterior(t, y, s)
    p = post.p_down(Z3_Z4, 0.05)
    assert post.p_change > 0.999
    assert p[-1] > 0.99                        # threshold 0.95
    assert np.all(p[t < 200.0] < 0.01)         # nothing before the change (threshold 0.05)
    lo, hi = post.change_date_interval(0.9)
    before, after = t[t < 200.0].max(), t[t >= 200.0].min()
    assert before - 1e-9 <= lo < hi <= after + 1e-9   # within the gap around the true date
    # the untouched channels keep their thrust
    for k in (0, 1, 4, 5):
        assert post.p_down([k], 0.05)[-1] < 0.01


def test_control_stays_quiet_at_every_event():
    t, y, s = synthetic_events(2)
    for n in range(3, t.size + 1):
        post = health_posterior(t[:n], y[:n], s[:n])
        assert post.p_down(Z3_Z4, 0.05)[-1] < 0.02      # threshold 0.05
    assert post.p_change < 0.05


def test_the_assertions_can_fail():
    """The detection test's checks would catch a model that misses the drop: the same data
    with the step on Z1/Z2 instead gives no Z3/Z4 alarm, and the pooled-baseline-only reading
    (no change allowed, p_change → 0) gives none either."""
    t, y, s = synthetic_events(1, drop=0.07, channels=(0, 1))
    assert health_posterior(t, y, s).p_down(Z3_Z4, 0.05)[-1] < 0.05
    t, y, s = synthetic_events(1, drop=0.07)
    assert health_posterior(t, y, s, HealthPrior(p_change=1e-12)).p_down(Z3_Z4, 0.05)[-1] < 0.05


def test_evidence_matches_brute_force():
    """``log_evidence`` equals the Gaussian integral done directly (dense covariance), for
    three events and one channel, summed over intervals and scatter levels."""
    t = np.array([0.0, 10.0, 30.0])
    y = np.log(0.699) + np.array([[0.01], [-0.02], [-0.08]])
    s = np.array([[0.02], [0.01], [0.03]])
    pr = HealthPrior(p_change=0.3, p_channel=0.6, step_sd=0.1, baseline_sd=0.5)
    post = health_posterior(t, y, s, pr)
    yc = y[:, 0] - np.log(0.699)
    g = SCATTER_GRID.size
    base = pr.baseline_sd ** 2 * np.ones((3, 3))

    def marginal(step):  # log p(y | step pattern), the scatter level marginalised
        return np.logaddexp.reduce([stats.multivariate_normal(
            np.zeros(3), base + step + np.diag(s[:, 0] ** 2 + sig ** 2)).logpdf(yc)
            for sig in SCATTER_GRID]) - np.log(g)

    k0 = marginal(np.zeros((3, 3)))
    terms = [np.log1p(-pr.p_change) + k0]
    for j, w in enumerate(np.diff(t) / (t[-1] - t[0])):
        x = (t >= t[j + 1]).astype(float)
        k1 = marginal(pr.step_sd ** 2 * np.outer(x, x))
        # the channel steps (slab, p_channel) or not (spike)
        terms.append(np.log(pr.p_change * w) + np.logaddexp(np.log1p(-pr.p_channel) + k0,
                                                            np.log(pr.p_channel) + k1))
    assert post.log_evidence == pytest.approx(np.logaddexp.reduce(terms), abs=1e-9)


def test_missing_channels_and_bad_inputs():
    t, y, s = synthetic_events(3)
    y[:, 4] = np.nan                                     # Y13 never identified
    post = health_posterior(t, y, s)
    assert np.all(np.isfinite(post.p_down([4], 0.05)))
    # an unobserved channel stays at its prior: no certainty either way
    assert post.p_down([4], 0.05)[-1] < 0.05
    with pytest.raises(InputError, match="at least 2 events"):
        health_posterior(t[:1], y[:1], s[:1])
    with pytest.raises(InputError, match="p_change"):
        health_posterior(t, y, s, HealthPrior(p_change=1.0))


def test_draws_agree_with_the_exact_probabilities():
    t, y, s = synthetic_events(4, drop=0.07)
    post = health_posterior(t, y, s)
    dr = post.draws(np.random.default_rng(0), 4000)
    exact = post.p_down([2], 0.05)[-1]
    mc = np.mean(dr["change"] & (dr["d"][:, 2] < np.log(0.95)))
    assert mc == pytest.approx(exact, abs=4 * np.sqrt(exact * (1 - exact) / 4000) + 1e-3)


# --- the per-event summary on simulated events -------------------------------------------------


def _event(**truth):
    from cassini_bayes.api import simulate_scenario
    from cassini_bayes.simulate import scenario_from_dict
    from cassini_bayes.simulate.scenario import scenario_path

    d = tomllib.loads(scenario_path("health_event").read_text())
    d["truth"].update(truth)
    for ramp, rpm in zip(d["wheel_ramp"], (640.0, -720.0, 500.0)):
        ramp["target_rpm"] = rpm
    return simulate_scenario(scenario_from_dict(d), seed=11)


@pytest.fixture(scope="module")
def split_event():
    """Y1 5 % strong, Y3 5 % weak: the pair mean is nominal."""
    f = [0.699] * 8
    f[4], f[6] = 0.699 * 1.05, 0.699 * 0.95
    return _event(thrust_n=f), f


def test_summary_recovers_the_thrust(split_event):
    sim, f = split_event
    sm = event_summary(sim.telemetry, sim.pulses, sim.prior)
    truth = np.log([f[0], f[1], f[2], f[3], (f[4] + f[6]) / 2, (f[5] + f[7]) / 2])
    ok = sm.observed
    assert ok.sum() >= 4
    z = (sm.log_thrust[ok] - truth[ok]) / np.sqrt(np.diag(sm.cov)[ok])
    assert np.all(np.abs(z) < 3.0)            # seed fixed; observed max |z| well below


def test_y_pair_split_is_not_reported(split_event):
    """Rank deficiency of Feldman & Lee Eqs 20-21: only pair means are summarised; a ±5 % split
    inside a pair neither shows as a change of the pair nor leaks into the Z channels."""
    sim, f = split_event
    sm = event_summary(sim.telemetry, sim.pulses, sim.prior)
    assert sm.channels.names == CHANNELS
    fired = [k for k in (4, 5) if sm.observed[k]]
    assert fired
    for k in fired:
        assert np.exp(sm.log_thrust[k]) == pytest.approx(0.699, rel=0.01)
    z_ok = sm.observed[:4]
    assert np.allclose(sm.thrust_n[:4][z_ok], 0.699, rtol=0.02)


def test_left_out_pulses_and_channels_are_warnings(split_event):
    """Issue 28: every input a fit leaves out is a warning. Pulses acting entirely outside an
    event's telemetry are dropped with a PulsesDroppedWarning (the summary is the one without
    them); a channel that fired but is not reported (too few pulses, or a thrust estimate that is
    not positive) is one line per channel of ``fit health``'s summary.json warnings."""
    from cassini_bayes.inference.health.summary import (EventSummary, HealthChannels,
                                                        left_out_channels)
    from cassini_bayes.telemetry import PulseLog, PulsesDroppedWarning

    sim, _ = split_event
    p, end = sim.pulses, float(sim.telemetry.t[-1])
    beyond = PulseLog(np.r_[p.t_on, end + 10.0, end + 20.0], np.r_[p.thruster, 0, 0],
                      np.r_[p.width, 0.25, 0.25], "pulses.csv")
    with pytest.warns(PulsesDroppedWarning, match="pulses.csv: 2 of .* outside"):
        sm = event_summary(sim.telemetry, beyond, sim.prior)
    np.testing.assert_array_equal(sm.n_pulses, event_summary(sim.telemetry, p,
                                                             sim.prior).n_pulses)

    def summary(n_z1, f_z1):
        y = np.full(6, np.log(0.7))
        y[0] = np.log(f_z1) if n_z1 >= 3 and f_z1 > 0 else np.nan
        return EventSummary(y, np.eye(6), np.r_[f_z1, np.full(5, 0.7)],
                            np.r_[n_z1, np.full(5, 4)], np.ones(3), sm.channels)

    events = [summary(4, 0.7), summary(2, 0.7), summary(5, -0.1), summary(0, np.nan)]
    lines = left_out_channels(events, [0.0, 10.0, 20.0, 30.0])
    assert sm.channels == HealthChannels(("Z1", "Z2", "Z3", "Z4", "Y1", "Y2", "Y3", "Y4"),
                                         ((0,), (1,), (2,), (3,), (4, 6), (5, 7)), CHANNELS)
    assert lines == ["channel F[Z1] is left out of 2 of the 3 events in which it fired (fewer "
                     "than 3 pulses, or a thrust estimate that is not positive): days 10, 20"]
    assert left_out_channels(events[:1], [0.0]) == []


# --- campaign files, simulator and CLI ---------------------------------------------------------


def test_campaign_events_are_reproducible_and_degrade_on_the_date():
    from cassini_bayes.simulate.health_campaign import campaign_events, load_campaign

    camp = load_campaign("health_degradation")
    a, b = campaign_events(camp, 5), campaign_events(camp, 5)
    assert [e.date_days for e in a] == [e.date_days for e in b]
    assert len(a) == camp.n_events >= 30
    assert a[-1].date_days - a[0].date_days > 600     # two years
    pre = np.array([e.thrust_n for e in a if e.date_days < camp.degradation_day])
    post = np.array([e.thrust_n for e in a if e.date_days >= camp.degradation_day])
    ratio = post.mean(axis=0) / pre.mean(axis=0)
    assert ratio[2] == pytest.approx(0.93, abs=0.01) and ratio[3] == pytest.approx(0.93, abs=0.01)
    assert ratio[0] == pytest.approx(1.0, abs=0.01)
    ctl = campaign_events(load_campaign("health_control"), 5)
    assert np.allclose([e.date_days for e in ctl], [e.date_days for e in a])


def test_campaign_file_errors(tmp_path):
    from cassini_bayes.simulate.health_campaign import load_campaign

    p = tmp_path / "c.toml"
    p.write_text('event = "health_event.toml"\n[campaign]\nn_events = 4\nspan_days = 10\n'
                 '[degradation]\nthrusters = ["Z9"]\nfraction = 0.1\nday = 5\n')
    with pytest.raises(InputError, match="degradation.thrusters"):
        load_campaign(p)
    p.write_text('event = "health_event.toml"\nbogus = 1\n[campaign]\nn_events = 4\n')
    with pytest.raises(InputError, match="unknown key 'bogus'"):
        load_campaign(p)


def test_scenario_and_campaign_files_are_told_apart():
    """The campaign files sit beside the scenarios: each loader names the other command."""
    from cassini_bayes.simulate import load_scenario
    from cassini_bayes.simulate.health_campaign import load_campaign

    with pytest.raises(InputError, match="campaign file, not a scenario.*simulate-health"):
        load_scenario("health_control")
    with pytest.raises(InputError, match="scenario file, not a thruster-health campaign"):
        load_campaign("slews_post_probe")


def test_cli_end_to_end(tmp_path, capsys):
    camp = tmp_path / "tiny.toml"
    camp.write_text(textwrap.dedent(f"""\
        name = "tiny"
        seed = 3
        event = "{(tmp_path / 'ev.toml').as_posix()}"
        [campaign]
        n_events = 5
        span_days = 100.0
        [degradation]
        thrusters = ["Z3", "Z4"]
        fraction = 0.07
        day = 50.0
        """))
    from cassini_bayes.simulate.scenario import scenario_path

    ev = scenario_path("health_event").read_text().replace("duration_s = 120.0",
                                                           "duration_s = 60.0")
    (tmp_path / "ev.toml").write_text(ev)
    runs, out = tmp_path / "runs", tmp_path / "fit"
    assert main(["simulate-health", str(camp), "--out", str(runs)]) == 0
    assert (runs / "events.csv").is_file() and (runs / "event_004" / "pulses.csv").is_file()
    assert main(["fit", "health", str(runs), "--spacecraft", "cassini_post_probe",
                 "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["n_events"] == 5 and set(s["channels"]) == set(CHANNELS)
    assert set(s["p_down_last"]) == {"any"} and 0.0 <= s["p_down_last"]["any"] <= 1.0
    assert s["channels"][CHANNELS[4]]["weights"] == {"Y1": 0.5, "Y3": 0.5}
    for name in ("health.csv", "thrust_bands.csv", "config.toml", "health.png", "report.html"):
        assert (out / name).is_file()
    # the page opens with the answer: a row per channel, its unit, P(down) and the verdict
    headers, rows = first_table((out / "report.html").read_text())
    assert headers[:2] == ["channel", "unit"] and headers[-1] == "verdict"
    assert "P(more than 5% down)" in headers and "model file (N)" in headers
    assert [r[0] for r in rows] == list(CHANNELS)
    assert {r[-1] for r in rows} <= {"healthy", "DOWN", "undecided"}
    header = (out / "health.csv").read_text().splitlines()[0]
    assert "p_down_any" in header and "thrust_F[Y1]_n" not in header
    # a second run into the same folder needs --force, and then works
    assert main(["fit", "health", str(runs), "--spacecraft", "cassini_post_probe",
                 "--out", str(out)]) == 2
    assert main(["fit", "health", str(runs / "events.csv"), "--spacecraft",
                 "cassini_post_probe", "--out", str(out), "--force"]) == 0
    # a broken event list is one error line, exit 2
    bad = tmp_path / "bad.csv"
    bad.write_text("date,telemetry\n0,x.csv\n")
    capsys.readouterr()
    assert main(["fit", "health", str(bad), "--spacecraft", "cassini_post_probe",
                 "--out", str(tmp_path / "x")]) == 2
    assert "date_days, telemetry, pulses" in capsys.readouterr().err


# --- SBC glue ----------------------------------------------------------------------------------


def test_sbc_glue_runs():
    from cassini_bayes.analysis.health_sbc import (calibration_table, changepoint_sbc,
                                                   leak_sbc)

    t, _, s = synthetic_events(5, n=8)
    res = changepoint_sbc(0, 12, t, s, n_draws=19, channels=CHANNELS)
    assert res.ranks.shape == (12, 19) and res.ranks.max() <= 19      # 6 × (b, d, sigma), tau
    assert res.names[:3] == ("b[F[Z1]]", "d[F[Z1]]", "sigma[F[Z1]]")
    lk = leak_sbc(0, 12, hours=1.0)
    assert lk.prob.shape == (12, 9) and np.allclose(lk.prob.sum(axis=1), 1.0)
    rows = calibration_table(lk.p_leak, lk.leak)
    assert sum(r["n"] for r in rows) == 12
