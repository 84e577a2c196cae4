"""Optional ``[gyro]``, ``[wheel_knowledge]`` and ``[telemetry_knowledge]`` sections of a
spacecraft model (priors of the robust models' nuisance parameters): defaults, values read, bad
values rejected clearly."""

from __future__ import annotations

import pytest

from cassini_bayes._paths import MODELS_DIR
from cassini_bayes.errors import InputError
from cassini_bayes.spacecraft import Knowledge, load_spacecraft, spacecraft_from_dict

GOOD = (MODELS_DIR / "cassini_post_probe.toml").read_text()


def _write(tmp_path, text):
    p = tmp_path / "sc.toml"
    p.write_text(text)
    return p


def test_defaults_when_absent():
    assert load_spacecraft("cassini_post_probe").knowledge == Knowledge()


def test_sections_are_read(tmp_path):
    text = GOOD + ("\n[gyro]\nbias_sd_rad_s = 1e-6\nscale_factor_sd = 2e-4\n"
                   "\n[wheel_knowledge]\ninertia_sd_frac = 0.01\naxis_sd_deg = 0.5\n"
                   "common_inertia_sd_frac = 0.002\n"
                   "\n[torque_knowledge]\nsd_nm = 3e-5\nrate_sd_nm_per_h = 1e-5\n"
                   "\n[telemetry_knowledge]\ntime_tag_sd_s = 0.02\n")
    k = load_spacecraft(_write(tmp_path, text)).knowledge
    assert k == Knowledge(1e-6, 2e-4, 0.01, 0.5, 0.02, wheel_common_inertia_sd_frac=0.002,
                         torque_sd_nm=3e-5, torque_rate_sd_nm_per_h=1e-5)


def test_partial_section_keeps_other_defaults(tmp_path):
    k = load_spacecraft(_write(tmp_path, GOOD + "\n[gyro]\nbias_sd_rad_s = 0.0\n")).knowledge
    assert k.gyro_bias_sd_rad_s == 0.0
    assert k.gyro_scale_factor_sd == Knowledge().gyro_scale_factor_sd


def test_round_trip_through_dict():
    sc = load_spacecraft("fsds")
    assert spacecraft_from_dict(sc.to_dict()).knowledge == sc.knowledge


@pytest.mark.parametrize("extra, needle", [
    ("[gyro]\nbias_sd = 1e-6\n", "gyro.bias_sd"),
    ("[gyro]\nbias_sd_rad_s = -1e-6\n", ">= 0"),
    ("[gyro]\nscale_factor_sd = 'big'\n", "finite number"),
    ("[wheel_knowledge]\ninertia_sd_frac = 5.0\n", "fraction"),
    ("[wheel_knowledge]\naxis_sd_deg = 45.0\n", "degrees"),
    ("[wheel_knowledge]\naxes = 1.0\n", "wheel_knowledge.axes"),
    ("[telemetry_knowledge]\ntime_tag_sd_s = 5.0\n", "seconds"),
    ("[wheel_knowledge]\ncommon_inertia_sd_frac = 0.7\n", "common_inertia_sd_frac.*fraction"),
    ("[torque_knowledge]\nsd_nm = 15.0\n", "torque_knowledge.sd_nm.*N m"),
    ("[torque_knowledge]\nrate_sd_nm_per_h = -1e-6\n", ">= 0"),
])
def test_bad_values_are_one_line_errors(tmp_path, extra, needle):
    with pytest.raises(InputError, match=needle):
        load_spacecraft(_write(tmp_path, GOOD + "\n" + extra))
