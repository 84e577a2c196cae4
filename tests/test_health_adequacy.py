"""The adequacy verdict of ``fit health`` (:mod:`cassini_bayes.inference.health.adequacy`).

Every random draw has a fixed seed, so each test is deterministic; the margins below say how
far from its threshold each assertion sits. The statistical claims (false-alarm rate on correctly
specified campaigns, power against the Pre-SOI model) are measured by
``benchmarks/verdict_false_alarms.py health`` (docs/health.md), not here.
"""

from __future__ import annotations

import numpy as np
import pytest

from cassini_bayes.inference.health import HealthPrior, event_summary, health_posterior
from cassini_bayes.inference.health.adequacy import (InertiaProbe, held_out_events,
                                                     inertia_conflict, inertia_probe,
                                                     predictive_cdf)
from cassini_bayes.inference.health.changepoint import SCATTER_GRID
from health_data import synthetic_events

LABELS = [f"event_{k:03d}" for k in range(40)]
NAMES = ["F[Z1]", "F[Z2]", "F[Z3]", "F[Z4]", "F_combination[0.5 F[Y1] + 0.5 F[Y3]]",
         "F_combination[0.5 F[Y2] + 0.5 F[Y4]]"]


def _probes(shift: np.ndarray, sd: np.ndarray) -> list[InertiaProbe]:
    return [InertiaProbe(s, d, np.zeros(3), np.full(3, 0.01)) for s, d in zip(shift, sd)]


def test_inertia_conflict_ignores_a_shared_shift_and_names_an_odd_event():
    """A thrust change that every event shares (a common inertia scale, absorbed by the health
    model's baseline) is no conflict, however large; one event whose change differs by 8 of its
    own sd beyond the others' is, and is named."""
    rng = np.random.default_rng(0)
    sd = np.full((10, 6), 0.01)
    shift = 0.05 + 0.002 * rng.standard_normal((10, 6))           # shared 5 %, scatter 0.2 sd
    shift[:, 5] = np.nan                                            # a channel no event reports
    c = inertia_conflict(_probes(shift, sd), LABELS, NAMES)
    assert c.ok and c.statistic < 1.0                               # observed 0.45
    shift[6, 2] += 0.08
    c = inertia_conflict(_probes(shift, sd), LABELS, NAMES)
    assert not c.ok and c.statistic > 6.0 and c.parameter == "event_006 F[Z3]"
    assert inertia_conflict(_probes(np.full((3, 6), np.nan), sd[:3]), LABELS,
                            NAMES).statistic is None


def test_predictive_cdf_matches_exact_draws():
    """The closed-form posterior predictive of a new event (mixture over no change, the change
    intervals — the one holding the date split by the fraction before it —, step or not, and
    the scatter grid) against 6000 exact draws of the posterior plus the event's noise: within
    0.025 (4 binomial sd at 6000 draws) at five points of each of two channels and three
    dates (one before, one inside, one after the change interval)."""
    t, y, s = synthetic_events(1, drop=0.07)
    post = health_posterior(t, y, s)
    rng = np.random.default_rng(3)
    dr = post.draws(rng, 6000)
    se = 0.01
    for date in (100.0, 0.5 * (t[t < 200].max() + t[t >= 200].min()), 300.0):
        after = np.where(dr["change"], dr["tau"] <= date, False)
        for k in (0, 2):
            mean = dr["b"][:, k] + dr["d"][:, k] * after
            ynew = mean + np.sqrt(dr["sigma"][:, k] ** 2 + se ** 2) * rng.standard_normal(mean.size)
            for q in (0.05, 0.25, 0.5, 0.75, 0.95):
                x = float(np.quantile(ynew, q))
                assert predictive_cdf(post, date, x, se, k) == pytest.approx(q, abs=0.025)


def test_held_out_passes_a_clean_campaign_and_names_an_outlier():
    """Each event against the change-point posterior of the others: the synthetic campaigns of
    tests/health_data.py (a 7 % drop, and none) pass (observed 0.0; threshold 4); one event
    moved by 12 times its sd plus the largest scatter level fails, and is named; two events: not
    applicable."""
    prior = HealthPrior()
    for drop in (0.07, 0.0):
        t, y, s = synthetic_events(1, drop=drop)
        assert held_out_events(t, y, s, prior, LABELS, NAMES).statistic < 2.0
    t, y, s = synthetic_events(1, drop=0.07)
    y[5, 4] += 12 * np.hypot(s[5, 4], SCATTER_GRID[-1])
    c = held_out_events(t, y, s, prior, LABELS, NAMES)
    assert not c.ok and c.statistic > 4.0 and c.parameter == f"event_005 {NAMES[4]}"
    assert held_out_events(t[:2], y[:2], s[:2], prior, LABELS, NAMES).statistic is None


@pytest.fixture(scope="module")
def one_event():
    from cassini_bayes.api import simulate_scenario

    return simulate_scenario("health_event", seed=4)


def test_inertia_probe_measures_the_moments_and_a_wrong_model_fails(one_event):
    """One simulated event (Post-Probe truth): with its own model the event's principal moments
    agree with the model's within 1 % (observed ≤ 0.8 %) and the thrusts barely move under them;
    with the Pre-SOI model (the deliberately wrong one, moments 19-32 % high) the event measures
    the truth's ratios to it, Iyy and Izz −24.3 % and −21.0 % within 2 points (observed −23.1,
    −21.1; Ixx −23 % against −15.9 %: the three moment columns also take up the products'
    difference, Ixz 115 against −12 kg m²) and the Z3 thrust moves by 4.2 of the event's own sd
    (asserted > 3 and > 10× the Post-Probe model's largest, 0.12)."""
    from cassini_bayes.spacecraft import load_spacecraft

    tel, pulses = one_event.telemetry, one_event.pulses
    right = load_spacecraft("cassini_post_probe")
    wrong = load_spacecraft("cassini_pre_soi")
    pr = inertia_probe(tel, pulses, right, event_summary(tel, pulses, right))
    assert np.all(np.abs(pr.moments) < 0.01)
    ok = np.isfinite(pr.shift)
    assert ok[:4].sum() >= 2 and np.all(np.abs(pr.shift[ok]) / pr.own_sd[ok] < 0.5)
    pw = inertia_probe(tel, pulses, wrong, event_summary(tel, pulses, wrong))
    truth_ratio = np.diag(right.inertia) / np.diag(wrong.inertia) - 1.0
    assert pw.moments[1:] == pytest.approx(truth_ratio[1:], abs=0.02)
    assert np.all(pw.moments < -0.1)
    z = np.abs(pw.shift) / pw.own_sd
    z_right = np.abs(pr.shift) / pr.own_sd
    assert np.nanmax(z[:4]) > max(3.0, 10 * np.nanmax(z_right))


def test_an_event_without_body_motion_gives_no_probe(tmp_path):
    """A biasing record whose body rates are exactly zero cannot tell the moments from the
    thrusts: the probe is NaN (no error), and a verdict of such events only is not applicable."""
    from cassini_bayes.spacecraft import load_spacecraft
    from cassini_bayes.telemetry import RPM_TO_RAD_S, PulseLog, Telemetry, cumulative_on_times

    t = np.arange(0.0, 200.0, 0.5)
    t_on = np.arange(20.0, 180.0, 10.0)
    log = PulseLog(t_on, np.tile([0, 2], t_on.size // 2), np.full(t_on.size, 0.25))
    rates = np.full((t.size, 4), np.nan)
    rates[:, :3] = np.linspace(0.0, 1.0, t.size)[:, None] * np.array([100.0, -200.0, 150.0]) \
        * RPM_TO_RAD_S
    tel = Telemetry(t, np.tile([0.0, 0.0, 0.0, 1.0], (t.size, 1)), np.zeros((t.size, 3)), rates,
                    on_times=cumulative_on_times(log, t))
    sc = load_spacecraft("cassini_post_probe")
    pr = inertia_probe(tel, log, sc, event_summary(tel, log, sc))
    assert np.all(np.isnan(pr.shift)) and np.all(np.isnan(pr.moments))
    assert inertia_conflict([pr, pr], LABELS, NAMES).statistic is None
