"""Evidence with provenance: every record under docs/ has a manifest, and the docs' tables are
what benchmarks/docs_tables.py makes of their records (issue 30)."""

from __future__ import annotations

import importlib.util
import json
import re
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
RECORD_SUFFIXES = (".json", ".jsonl", ".txt", ".csv", ".npz", ".nc")


@pytest.fixture(scope="module")
def docs_tables():
    spec = importlib.util.spec_from_file_location("docs_tables",
                                                  ROOT / "benchmarks" / "docs_tables.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _records(docs: Path) -> list[Path]:
    return sorted(p for p in docs.rglob("*") if p.is_file() and p.suffix in RECORD_SUFFIXES
                  and not p.name.endswith("manifest.json"))


def _manifest_of(record: Path) -> Path | None:
    for m in (record.with_name(record.name + ".manifest.json"), record.parent / "manifest.json"):
        if m.exists():
            return m
    return None


def test_every_record_under_docs_has_a_manifest():
    records = _records(DOCS)
    assert len(records) > 100                     # the walk found the records
    missing = [str(r.relative_to(ROOT)) for r in records if _manifest_of(r) is None]
    assert not missing, f"records without a manifest (benchmarks/_provenance.py): {missing}"


def test_every_manifest_names_its_records_and_runs():
    manifests = sorted(DOCS.rglob("*manifest.json"))
    assert manifests
    for m in manifests:
        man = json.loads(m.read_text(encoding="utf-8"))
        where = m.relative_to(ROOT)
        if m.name == "manifest.json":
            assert man["records"] == ".", where      # a run directory: the folder's files
        else:
            assert m.name == man["records"] + ".manifest.json", where
            assert (m.parent / man["records"]).exists(), f"{where}: its records are gone"
        assert "options" in man and man["runs"], where
        for run in man["runs"]:
            assert "command" in run and "commit" in run, where   # null where unknown


def test_docs_tables_regenerate_from_their_records(docs_tables, capsys):
    assert docs_tables.main(["--check"]) == 0, capsys.readouterr().out


def test_a_hand_edited_cell_or_a_record_without_manifest_fails(docs_tables, tmp_path, capsys):
    docs = tmp_path / "docs"
    shutil.copytree(DOCS / "sbc", docs / "sbc")
    assert docs_tables.main(["--check", "--docs", str(docs)]) == 0
    readme = docs / "sbc" / "thrust" / "README.md"
    text = readme.read_text(encoding="utf-8")
    cell = re.search(r"\| F \| (\d\.\d+) \|", text)             # F's χ² p, as generated
    edited = f"| F | {float(cell[1]) + 0.001:.3f} |"
    readme.write_text(text.replace(cell[0], edited), encoding="utf-8")
    assert docs_tables.main(["--check", "--docs", str(docs)]) == 1
    assert "docs/sbc/thrust/README.md" in capsys.readouterr().out
    assert docs_tables.main(["--docs", str(docs)]) == 0          # rewritten from the record
    assert readme.read_text(encoding="utf-8") == text
    (docs / "sbc" / "thrust" / "manifest.json").unlink()
    with pytest.raises(SystemExit, match="no manifest"):
        docs_tables.main(["--check", "--docs", str(docs)])


@pytest.mark.parametrize("block, message", [
    ("<!-- table: no_such_kind x.json -->\n| a |\n<!-- /table -->\n", "unknown table kind"),
    ("<!-- table: sbc missing.json -->\n| a |\n<!-- /table -->\n", "not found"),
    ("<!-- table: sbc x.json@first-last -->\n| a |\n<!-- /table -->\n", "FIRST-LAST"),
    ("<!-- table: sbc x.json -->\n| a |\n", "without its pair"),
])
def test_a_bad_table_marker_is_a_one_line_error(docs_tables, tmp_path, block, message):
    docs = tmp_path / "docs"
    docs.mkdir()
    (docs / "x.json").write_text("{}\n")
    (docs / "x.json.manifest.json").write_text("{}\n")
    (docs / "page.md").write_text("# A page\n\n" + block, encoding="utf-8")
    with pytest.raises(SystemExit, match=message):
        docs_tables.main(["--check", "--docs", str(docs)])


def test_list_names_every_table_generated_or_by_hand(docs_tables, tmp_path, capsys):
    docs = tmp_path / "docs"
    docs.mkdir()
    (docs / "page.md").write_text(
        "# Page\n\n| a | b |\n|---|---|\n| 1 | 2 |\n\n```\n| fenced |\n|---|\n```\n\n"
        "## Measured\n\n<!-- table: some_kind rec.json -->\n| c |\n|:-:|\n| 3 |\n"
        "<!-- /table -->\n\n| not a table: no rule |\n", encoding="utf-8")
    assert docs_tables.main(["--list", "--docs", str(docs)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split("\t") for line in lines] == [
        [f"{docs / 'page.md'}:3", "Page", "by hand"],
        [f"{docs / 'page.md'}:15", "Measured", "some_kind"]]


def test_every_table_in_the_docs_is_listed(docs_tables, capsys):
    assert docs_tables.main(["--list"]) == 0
    listed = [line.split("\t") for line in capsys.readouterr().out.splitlines()]
    generated = [kind for _, _, kind in listed if kind != "by hand"]
    assert len(listed) > 100 and len(generated) > 40
    assert set(generated) <= set(docs_tables.KINDS)
