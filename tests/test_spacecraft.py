"""Spacecraft models: the shipped files load, carry the papers' numbers, and bad files fail
clearly."""

from __future__ import annotations

import numpy as np
import pytest

from cassini_bayes._paths import MODELS_DIR
from cassini_bayes.errors import InputError
from cassini_bayes.spacecraft import (CASSINI_WHEEL_AXES, eq16_thrusters, load_spacecraft,
                                      spacecraft_from_dict)

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
    assert sc.eq16 == (1.234, 1.580, 2.880, 3.019) and sc.eq16_layout
    assert sc.thruster_names == ("Z1", "Z2", "Z3", "Z4", "Y1", "Y2", "Y3", "Y4")
    assert sc.articulated_wheels == ("RWA4",)   # Brown §I: re-articulated about +Z


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
    with pytest.raises(InputError, match="no shipped spacecraft model of that name "
                                         r"\(shipped: cassini_2000_03_15"):
        load_spacecraft("no_such_model")


def test_round_trip_through_dict():
    sc = load_spacecraft("cassini_post_prm")
    again = spacecraft_from_dict(sc.to_dict())
    np.testing.assert_array_equal(again.inertia, sc.inertia)
    np.testing.assert_allclose(again.wheel_axes, sc.wheel_axes, rtol=0, atol=1e-15)
    assert again.pulse == sc.pulse
    np.testing.assert_array_equal(again.moment_matrix, sc.moment_matrix)
    assert again.eq16 == sc.eq16 and "thrusters" in again.to_dict()   # written back as shorthand
    assert again.articulated_wheels == ("RWA4",)


def test_a_wheels_quiet_tolerance_is_read_and_written_back():
    """``[[wheel]] quiet_tol_rpm``: 2 rpm where the file gives none (and not written back),
    the file's own otherwise (docs/model_file.md, "A wheel's quiet tolerance")."""
    from cassini_bayes.spacecraft import QUIET_WHEEL_TOL_RPM

    d = _bus()
    assert all(w.quiet_tol_rpm == QUIET_WHEEL_TOL_RPM == 2.0
               for w in spacecraft_from_dict(d).wheels)
    assert "quiet_tol_rpm" not in spacecraft_from_dict(d).to_dict()["wheel"][0]
    d["wheel"][1]["quiet_tol_rpm"] = 0.25
    sc = spacecraft_from_dict(d)
    assert [w.quiet_tol_rpm for w in sc.wheels][:2] == [2.0, 0.25]
    again = spacecraft_from_dict(sc.to_dict())
    assert [w.quiet_tol_rpm for w in again.wheels][:2] == [2.0, 0.25]


def test_eq16_shorthand_expands_to_the_papers_moment_matrix():
    """Feldman & Lee Eq 16 as printed, entry by entry, with a centre-of-mass offset ``e``: the
    ``[thrusters]`` shorthand's eight ``[[thruster]]`` entries give exactly this ``Q``."""
    lx, ly, lzy, lzz = 1.234, 1.580, 2.880, 3.019
    ex, ey, ez = 0.011, -0.023, 0.037
    printed = np.array([
        [-(ly - ey), -(ly - ey), ly + ey, ly + ey, lzy - ez, lzy - ez, -(lzy - ez), -(lzy - ez)],
        [lx - ex, -(lx + ex), -(lx + ex), lx - ex, 0, 0, 0, 0],
        [0, 0, 0, 0, -(lx - ex), lx + ex, -lx - ex, lx - ex]])
    d = load_spacecraft("cassini_post_probe").to_dict()
    d["thrusters"]["com"] = [ex, ey, ez]
    sc = spacecraft_from_dict(d)
    np.testing.assert_allclose(sc.moment_matrix, printed, rtol=0, atol=1e-12)
    # the same eight thrusters written out as [[thruster]] entries: the same Q, not Eq 16's form
    del d["thrusters"]
    d["thruster"] = [{"name": s.name, "position": s.position.tolist(),
                      "direction": s.direction.tolist()} for s in eq16_thrusters(lx, ly, lzy, lzz)]
    d["center_of_mass"] = {"offset_m": [ex, ey, ez]}
    long = spacecraft_from_dict(d)
    np.testing.assert_allclose(long.moment_matrix, printed, rtol=0, atol=1e-12)
    assert long.eq16 is None and long.eq16_layout and long.thrust == sc.thrust


def _bus(**extra) -> dict:
    """A minimal non-Cassini model: three orthogonal wheels, two thrusters."""
    d = {"name": "bus", "inertia": {"Ixx": 25.0, "Iyy": 22.0, "Izz": 18.0, "Ixy": 0.4,
                                     "Ixz": -0.2, "Iyz": 0.3, "moi_uncertainty": 0.1},
         "wheel": [{"name": n, "axis": a, "inertia": 2e-3}
                   for n, a in (("rw1", [1, 0, 0]), ("rw2", [0, 1, 0]), ("rw3", [0, 0, 1]))],
         "thruster": [{"name": "T1", "position": [0.3, 0.3, -0.4], "direction": [0, 0, 1],
                       "F": 1.0},
                      {"name": "T2", "position": [-0.3, -0.3, -0.4], "direction": [0, 0, 1],
                       "F": 1.1, "branch": "A"}]}
    d.update(extra)
    return d


def test_any_spacecraft_from_thruster_entries():
    sc = spacecraft_from_dict(_bus())
    assert sc.wheel_names == ("RW1", "RW2", "RW3") and sc.thruster_names == ("T1", "T2")
    np.testing.assert_array_equal(sc.moment_matrix[:, 0], np.cross([0.3, 0.3, -0.4], [0, 0, 1]))
    np.testing.assert_allclose(sc.thrust_per_thruster, [1.0, 1.1])
    assert sc.thrust == pytest.approx(1.05) and not sc.eq16_layout
    assert sc.com_sd_m == pytest.approx(0.01 * np.linalg.norm([0.3, 0.3, -0.4]))
    assert sc.poi_uncertainty == pytest.approx(0.25)      # 1 % of the largest moment
    again = spacecraft_from_dict(sc.to_dict())
    np.testing.assert_array_equal(again.moment_matrix, sc.moment_matrix)
    assert again.thruster_names == sc.thruster_names
    assert again.com_sd_m == sc.com_sd_m and again.thrust == sc.thrust


def test_spacecraft_without_thrusters():
    d = _bus()
    del d["thruster"]
    sc = spacecraft_from_dict(d)
    assert sc.thrusters == () and sc.moment_matrix.shape == (3, 0) and np.isnan(sc.thrust)
    assert "pulse" not in sc.to_dict() and "thrust" not in sc.to_dict()
    with pytest.raises(InputError, match="fit thrust needs thrusters"):
        sc.require_thrusters("fit thrust")
    for section in ("pulse", "thrust"):
        with pytest.raises(InputError, match=rf"\[{section}\] describes thrusters"):
            spacecraft_from_dict({**d, section: {}})


@pytest.mark.parametrize("edit, needle", [
    (lambda d: d["thruster"][0].update(direction=[0, 0, 0]), "'thruster[0].direction' of "
     "thruster T1 is zero"),
    (lambda d: d["thruster"][1].update(direction=[0, 0, 2]), "'thruster[1].direction' of "
     "thruster T2 must be a unit vector"),
    (lambda d: d["wheel"][2].update(axis=[0, 0, 0.9]), "'wheel[2].axis' of wheel RW3 must be a "
     "unit vector"),
    (lambda d: d["wheel"][2].update(name="Rw1"), "two wheels are named 'RW1'"),
    (lambda d: d["thruster"][1].update(name="t1"), "two thrusters are named 't1'"),
    (lambda d: d["thruster"][1].pop("F"), "thruster T2 has no thrust"),
    (lambda d: d["thruster"][0].pop("position"), "'thruster[0].position' (thruster T1)"),
    (lambda d: d["wheel"][0].update(name="wx"), "'wheel[0].name' = 'wx'"),
    (lambda d: d["wheel"][0].update(name="rw 1"), "'wheel[0].name' = 'rw 1'"),
    (lambda d: d["wheel"][0].update(max_speed_rpm=-1), "wheel[0].max_speed_rpm"),
    (lambda d: d["wheel"][0].update(articulated="yes"), "wheel[0].articulated"),
    (lambda d: d["wheel"][1].update(quiet_tol_rpm=0), "'wheel[1].quiet_tol_rpm' = 0 rpm"),
    (lambda d: d.update(thrusters={"Lx": 1, "Ly": 1, "Lzy": 1, "Lzz": 1}), "give the thrusters "
     "once"),
    (lambda d: d.update(center_of_mass={"sd_m": -0.1}), "center_of_mass.sd_m"),
])
def test_bad_entries_name_the_entry(edit, needle):
    d = _bus()
    edit(d)
    with pytest.raises(InputError) as e:
        spacecraft_from_dict(d, "bus.toml")
    msg = str(e.value)
    assert needle in msg and "\n" not in msg and "bus.toml" in msg
