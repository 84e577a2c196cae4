"""Impulse ratio R (Feldman & Lee 2006 §V): the paper's printed numbers and the grids."""

from __future__ import annotations

import numpy as np
import pytest

from cassini_bayes.analysis.impulse_ratio import (
    adjust_thrust,
    analyse_impulse_ratio,
    mix_ratio_grid,
    ratio_grid,
)
from cassini_bayes.analysis.paper_facts import TABLE2, fact
from cassini_bayes.physics.pulse import impulse_ratio


@pytest.fixture(scope="module")
def analysis():
    return analyse_impulse_ratio(grid_points=7)


def _printed(value, decimals):
    return round(float(value), decimals)


def test_single_pulse_ratios_match_paper(analysis):
    # Feldman & Lee (2006) §V: "For a 125-ms on-time command, the ratio is 1.395. For a 250-ms
    # on-time command, the ratio is 1.198." and "If ... τ_Decay is 40 ms, then R = 1.195".
    r = dict(zip(np.round(analysis.widths_s * 1e3).astype(int), analysis.ratio))
    r40 = dict(zip(np.round(analysis.widths_s * 1e3).astype(int), analysis.ratio_alt))
    assert _printed(r[125], 3) == 1.395
    assert _printed(r[250], 3) == 1.198
    assert _printed(r40[125], 3) == 1.195
    assert fact("R_125ms_tf65").passes(r[125]) and fact("R_250ms_tf65").passes(r[250])
    assert fact("R_125ms_tf40").passes(r40[125])


def test_fsds_mix_and_corrected_thrust_match_paper(analysis):
    # Feldman & Lee (2006) §V: 133×125 + 16×250 + 500 + 750 ms = 21.875 s; R = 1.3406;
    # 0.98 / 1.3406 ≈ 0.731 N.
    assert analysis.mix_on_time_s == pytest.approx(21.875, abs=1e-12)
    assert _printed(analysis.mix_ratio, 4) == 1.3406
    assert _printed(analysis.corrected_thrust_n, 3) == 0.731
    assert fact("F_fsds_corrected").passes(analysis.corrected_thrust_n)


def test_table2_adjusted_columns_match_paper(analysis):
    # Feldman & Lee (2006) Table 2: the adjusted columns are the first divided by R = 1.395 / 1.195
    np.testing.assert_array_equal(np.round(analysis.table2_adjusted_n, 3), TABLE2["tf65_n"])
    np.testing.assert_array_equal(np.round(analysis.table2_adjusted_alt_n, 3), TABLE2["tf40_n"])


def test_unrounded_ratio_moves_day28_by_one_in_the_last_digit():
    # Why the paper's procedure (divide by the printed R) is followed: 0.80 / 1.39462 = 0.5736.
    assert round(float(adjust_thrust(0.80, 1.3946196930540842)), 3) == 0.574
    assert round(float(adjust_thrust(0.80, 1.3946196930540842, decimals=3)), 3) == 0.573


def test_grids_agree_with_pointwise_evaluation(analysis):
    a = analysis
    g = ratio_grid(a.widths_s, a.tau_fall_grid_s, a.tau_rise_grid_s, a.tau_delay_s)
    assert g.shape == (len(a.widths_s), 7, 7)
    np.testing.assert_allclose(g, a.ratio_on_grid[:-1], rtol=1e-14)
    i, j = 3, 5
    for k, w in enumerate(a.widths_s):
        expect = float(impulse_ratio(w, a.tau_delay_s, a.tau_rise_grid_s[j], a.tau_fall_grid_s[i]))
        assert g[k, i, j] == pytest.approx(expect, rel=1e-14)
    m = mix_ratio_grid(a.mix_widths_s, a.mix_counts, a.tau_fall_grid_s, a.tau_rise_grid_s,
                       a.tau_delay_s)
    np.testing.assert_allclose(m, a.ratio_on_grid[-1], rtol=1e-14)


def test_ratio_grows_with_fall_time_and_shrinks_with_rise_time(analysis):
    g = analysis.ratio_on_grid
    assert np.all(np.diff(g, axis=1) > 0)   # longer tail, more impulse
    assert np.all(np.diff(g, axis=2) < 0)   # slower rise, less impulse
    assert np.all(g > 1.0)                  # τ_fall > τ_rise everywhere in the box


def test_to_dict_is_json_able(analysis):
    import json

    d = json.loads(json.dumps(analysis.to_dict()))
    assert d["fsds_mix"]["ratio"] == pytest.approx(1.34058, abs=1e-5)
    lo, hi = d["fsds_mix"]["corrected_thrust_range_n"]
    assert lo < d["fsds_mix"]["corrected_thrust_n"] < hi
