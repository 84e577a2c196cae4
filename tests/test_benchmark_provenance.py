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
