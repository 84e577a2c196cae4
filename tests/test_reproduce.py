"""``cassini-bayes reproduce --quick``: one page, every experiment, every figure embedded."""

from __future__ import annotations

import json
import re
import shutil
import tomllib

import pytest

from cassini_bayes._paths import EXPERIMENTS_DIR
from cassini_bayes.analysis.paper_facts import PAPER_FACTS
from cassini_bayes.experiments import discover_experiments, registered_kinds


@pytest.fixture(scope="module")
def reproduced(tmp_path_factory):
    from cassini_bayes.cli import main

    out = tmp_path_factory.mktemp("reproduce") / "out"
    code = main(["reproduce", "--out", str(out), "--quick"])
    return code, out


def test_reproduce_quick_writes_one_page_with_every_experiment(reproduced):
    code, out = reproduced
    assert code == 0
    page = (out / "report.html").read_text()
    expected = [p.stem for p in sorted(EXPERIMENTS_DIR.glob("*.toml"))
                if tomllib.loads(p.read_text()).get("kind") in registered_kinds()]
    assert {"impulse_ratio", "mass_property_mc"} <= set(expected)
    for name in expected:
        assert f'id="exp-{name}"' in page, name
        assert f'href="{name}/report.html"' in page
        assert (out / name / "report.html").exists() and (out / name / "results.json").exists()


def test_every_figure_is_embedded_and_nothing_external(reproduced):
    _, out = reproduced
    page = (out / "report.html").read_text()
    summary = json.loads((out / "results.json").read_text())
    n_figures = sum(len(json.loads((out / e["name"] / "results.json").read_text())["figures"])
                    for e in summary["experiments"] if e["ok"])
    srcs = re.findall(r'<img src="([^"]*)"', page)
    assert len(srcs) == n_figures > 0
    assert all(s.startswith("data:image/png;base64,") for s in srcs)
    hrefs = re.findall(r'href="([^"]*)"', page)
    assert all(h.startswith("#") or not re.match(r"[a-z]+:", h) for h in hrefs)  # relative only
    assert "<script" not in page and "<link" not in page


def test_paper_values_beside_ours(reproduced):
    _, out = reproduced
    page = (out / "report.html").read_text()
    summary = json.loads((out / "results.json").read_text())
    ids = {c["fact_id"] for c in summary["checks"] if c["fact_id"]}
    for fid in ("R_125ms_tf65", "R_250ms_tf65", "R_125ms_tf40", "R_fsds_mix", "F_fsds_corrected",
                "rwa4_mass_property_deg", "rwa4_rcs_total_deg"):
        assert fid in ids
    for printed in ("1.395", "1.198", "1.195", "1.3406", "0.731", "≤ 1.5 deg", "&lt; 3 deg"):
        assert printed in page
    for c in summary["checks"]:
        if c["fact_id"] in {"R_125ms_tf65", "R_250ms_tf65", "R_125ms_tf40", "R_fsds_mix",
                            "F_fsds_corrected", "fsds_mix_on_time_s"}:
            assert c["passed"] is True, c
    assert set(summary["uncovered_facts"]) == {f.id for f in PAPER_FACTS} - ids


def test_existing_out_is_refused(reproduced, run_cli):
    _, out = reproduced
    code, _, err = run_cli("reproduce", "--out", out, "--quick")
    assert code == 2 and "--force" in err and len(err.strip().splitlines()) == 1


def test_files_of_unregistered_kinds_are_skipped_and_listed(tmp_path):
    exp_dir = tmp_path / "experiments"
    exp_dir.mkdir()
    shutil.copy(EXPERIMENTS_DIR / "impulse_ratio.toml", exp_dir)
    (exp_dir / "later.toml").write_text('kind = "not_registered_yet"\n')
    found, skipped = discover_experiments(exp_dir)
    assert [e.name for e in found] == ["impulse_ratio"]
    assert skipped and "not_registered_yet" in skipped[0][1]
    from cassini_bayes.experiments import reproduce

    result = reproduce(tmp_path / "out", quick=True, experiments_dir=exp_dir)
    page = (tmp_path / "out" / "report.html").read_text()
    assert "later.toml" in page and result.skipped and not result.failed


def test_bad_key_in_a_registered_experiment_fails_before_running(tmp_path, run_cli):
    exp_dir = tmp_path / "experiments"
    exp_dir.mkdir()
    (exp_dir / "bad.toml").write_text('kind = "impulse_ratio"\n[settings]\ngrid = 3\n')
    code, _, err = run_cli("reproduce", "--out", tmp_path / "out", "--quick",
                           "--experiments", exp_dir)
    assert code == 2 and "settings.grid" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_full_reproduce_runs_every_experiment(tmp_path):
    """The README's main job at its full settings (quick mode skips paths such as the RWA
    flight test); about 2.5 min on two cores."""
    from cassini_bayes.cli import main

    assert main(["reproduce", "--out", str(tmp_path / "out")]) == 0
    results = json.loads((tmp_path / "out" / "results.json").read_text())
    assert not [e["name"] for e in results["experiments"] if not e["ok"]]
