"""benchmarks/_provenance.py: every campaign's records carry a manifest of what made them."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def provenance():
    spec = importlib.util.spec_from_file_location("_provenance",
                                                  ROOT / "benchmarks" / "_provenance.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_manifest_written_extended_and_guarded(tmp_path, provenance):
    out = tmp_path / "c.jsonl"
    opts = {"chains": 4, "off": ["drift"], "widen": 1.5}
    provenance.start(out, opts, ["--seeds", "2"])
    man = json.loads(provenance.manifest_path(out).read_text())
    assert man["records"] == "c.jsonl" and man["options"] == opts
    run = man["runs"][0]
    assert run["command"].endswith("--seeds 2") and run["versions"]["jax"]
    assert run["commit"] is None or len(run["commit"].split("+")[0]) == 40
    out.write_text("{}\n")                       # a record appended, then resumed
    provenance.start(out, opts, ["--seeds", "4"])
    assert len(json.loads(provenance.manifest_path(out).read_text())["runs"]) == 2
    with pytest.raises(SystemExit, match="other options"):
        provenance.start(out, {**opts, "chains": 2}, [])
    orphan = tmp_path / "old.jsonl"
    orphan.write_text("{}\n")
    with pytest.raises(SystemExit, match="without a manifest"):
        provenance.start(orphan, opts, [])


def test_manifest_replaced_for_rewritten_records_and_inside_run_directories(tmp_path,
                                                                            provenance):
    out = tmp_path / "r.json"
    out.write_text("{}\n")                       # a one-shot benchmark's old records
    provenance.start(out, {"json": out, "seeds": 2}, ["--json", str(out)], replace=True)
    provenance.start(out, {"json": out, "seeds": 3}, [], replace=True)
    man = json.loads(provenance.manifest_path(out).read_text())
    assert man["options"] == {"json": str(out), "seeds": 3} and len(man["runs"]) == 1
    run_dir = tmp_path / "sbc" / "health"
    run_dir.mkdir(parents=True)
    provenance.start(run_dir, {"reps": 4}, [], replace=True)
    assert provenance.manifest_path(run_dir) == run_dir / "manifest.json"
    assert json.loads((run_dir / "manifest.json").read_text())["records"] == "."
