"""Spacecraft models: the shipped files load, carry the papers' numbers, and bad files fail clearly."""

from __future__ import annotations

import numpy as np
import pytest

from cassini_bayes._paths import MODELS_DIR
from cassini_bayes.errors import InputError
from cassini_bayes.spacecraft import CASSINI_WHEEL_AXES, load_spacecraft

SHIPPED = sorted(p.stem for p in MODELS_DIR.glob("*.toml"))

# Feldman & Lee (2006) Eq 1 and Table 1 predictions, kg m^2: (Ixx, Iyy, Izz, Ixy, Ixz, Iyz)
PREDICTIONS = {
    "cassini_2000_03_15": (8810.8, 8157.3, 4721.8, -136.8, 115.3, 156.4),
    "cassini_pre_soi": (8802, 8155, 4715, -137, 115, 156),
    "cassini_post_prm": (7589, 6948, 4449, -138, 151, 150),
    "cassini_post_probe": (7403, 6174, 3727, -129, -12, 147),
    "fsds": (7375.02, 6061.58, 3829.70, -136.58, 6.23, 180.26),  # Feldman & Lee §V
}


def test_every_paper_model_is_shipped():
    assert set(PREDICTIONS) <= set(SHIPPED)


@pytest.mark.parametrize("name", sorted(PREDICTIONS))
def test_model_numbers(name):
    sc = load_spacecraft(name)
    i = sc.inertia
    got = (i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2])
    np.testing.assert_allclose(got, PREDICTIONS[name], rtol=0, atol=1e-9)
    assert sc.moi_uncertainty == 0.10 and sc.poi_uncertainty == 75.0
    # Feldman & Lee App. A: the fixed wheels are the columns of T.
    np.testing.assert_allclose(sc.wheel_axes[:3], CASSINI_WHEEL_AXES, atol=1e-9)
    assert [w.name for w in sc.wheels] == ["RWA1", "RWA2", "RWA3", "RWA4"]
    assert (sc.thrusters.Lx, sc.thrusters.Ly, sc.thrusters.Lzy, sc.thrusters.Lzz) == (
        1.234, 1.580, 2.880, 3.019)


def test_fsds_wheel_inertias():
    # Feldman & Lee §V: 0.161, 0.160, 0.161 kg m^2
    np.testing.assert_allclose(load_spacecraft("fsds").wheel_inertias[:3], [0.161, 0.160, 0.161])


def _write(tmp_path, text):
    p = tmp_path / "sc.toml"
    p.write_text(text)
    return p


GOOD = (MODELS_DIR / "cassini_post_probe.toml").read_text()


@pytest.mark.parametrize(
    "edit, needle",
    [
        (lambda s: s.replace("Ixx = 7403", "Ixx = -7403"), "positive"),
        (lambda s: s.replace("Ixx = 7403", "Ixx = 20000"), "triangle"),
        (lambda s: s.replace("Ixx = 7403", "Ixxx = 7403"), "inertia.Ixxx"),
        (lambda s: s.replace("Ixx = 7403\n", ""), "inertia.Ixx"),
        (lambda s: s.replace("inertia = 0.161", "inertia = -0.161", 1), "wheel[0].inertia"),
        (lambda s: s.replace("0.816496580928", "0.9", 1), "unit vector"),
        (lambda s: s.replace("Lx = 1.234", "Lx = \"a\""), "thrusters.Lx"),
        (lambda s: s.replace("tau_rise_range = [0.015, 0.025]", "tau_rise_range = [0.025, 0.015]"),
         "pulse.tau_rise_range"),
        (lambda s: s + "\n[extra]\nx = 1\n", "unknown key 'extra'"),
        (lambda s: s.replace("[inertia]", "[inertia"), "not valid TOML"),
    ],
)
def test_bad_model_files_give_one_line_errors(tmp_path, edit, needle):
    p = _write(tmp_path, edit(GOOD))
    with pytest.raises(InputError) as e:
        load_spacecraft(p)
    msg = str(e.value)
    assert needle in msg and "\n" not in msg and str(p) in msg


def test_missing_model_names_what_to_do():
    with pytest.raises(InputError, match="models/"):
        load_spacecraft("no_such_model")


def test_round_trip_through_dict():
    from cassini_bayes.spacecraft import spacecraft_from_dict

    sc = load_spacecraft("cassini_post_prm")
    again = spacecraft_from_dict(sc.to_dict())
    np.testing.assert_array_equal(again.inertia, sc.inertia)
    np.testing.assert_allclose(again.wheel_axes, sc.wheel_axes, rtol=0, atol=1e-15)
    assert again.pulse == sc.pulse
