"""Regenerate the markdown tables of ``docs/`` from the records they summarise.

    python benchmarks/docs_tables.py           # rewrite every table block that differs
    python benchmarks/docs_tables.py --check   # exit 1, naming each block that differs
    python benchmarks/docs_tables.py --list    # every table: its heading, generated or by hand

A table block in a markdown file under ``docs/`` is, each marker on a line of its own,

    <!-- table: KIND RECORDS... -->
    | the table |
    <!-- /table -->

``KIND`` names a registered table kind (``_tables.KINDS``; the kinds are in ``_tables_*.py``)
and ``RECORDS`` are the records' paths, relative to the markdown file's folder (``A+B``: one
argument of several records, pooled where the kind pools; ``PATH@0-19``: those seeds only, where
the kind reads seeds); each record must have a manifest (``benchmarks/_provenance.py``), so a
table can always be traced to the run that made it. The text between the markers is the kind's
output and nothing else: a hand-edited cell fails ``--check`` (``tests/test_evidence.py``).
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
sys.path.insert(0, str(ROOT / "benchmarks"))

import _tables_adequacy  # noqa: E402,F401  (each module registers its kinds)
import _tables_budgets  # noqa: E402,F401
import _tables_coverage  # noqa: E402,F401
import _tables_evidence  # noqa: E402,F401
import _tables_leak  # noqa: E402,F401
import _tables_performance  # noqa: E402,F401
import _tables_planning  # noqa: E402,F401
import _tables_robust  # noqa: E402,F401
import _tables_sbc  # noqa: E402,F401
import _tables_validation  # noqa: E402,F401
from _provenance import manifest_path  # noqa: E402
from _tables import KINDS, Records  # noqa: E402

BLOCK = re.compile(r"^<!-- table: (?P<spec>[^\n]*?) -->\n(?P<body>.*?)^<!-- /table -->$",
                   re.DOTALL | re.MULTILINE)
TABLE_RULE = re.compile(r"^\|(\s*:?-+:?\s*\|)+\s*$")
OPEN, CLOSE = (re.compile(r"^<!-- table:", re.MULTILINE),
               re.compile(r"^<!-- /table -->$", re.MULTILINE))


def _rel(path: Path) -> str:
    try:
        return str(path.relative_to(ROOT))
    except ValueError:
        return str(path)


def _records(arg: str, folder: Path, where: str) -> Records:
    """A marker argument ``A+B@FIRST-LAST`` as :class:`Records`."""
    paths, _, seeds = arg.partition("@")
    rec = Records((folder / r).resolve() for r in paths.split("+"))
    if seeds:
        first, _, last = seeds.partition("-")
        if not (first.isdigit() and last.isdigit()):
            sys.exit(f"{where}: seeds {seeds!r} of {arg!r} are not FIRST-LAST; write e.g. @0-19")
        rec.seeds = range(int(first), int(last) + 1)
    return rec


def blocks(text: str, md: Path) -> list[tuple[re.Match, str, list[Records]]]:
    """Each table block of ``text``: the match, its kind and its arguments' records; exits
    with a one-line message naming ``md`` for an unknown kind, a missing record or one without
    a manifest."""
    out = []
    for m in BLOCK.finditer(text):
        line = text.count("\n", 0, m.start()) + 1
        name, *rel = shlex.split(m["spec"])
        where = f"{_rel(md)}:{line}"
        groups = [_records(arg, md.parent, where) for arg in rel]
        if name not in KINDS:
            sys.exit(f"{where}: unknown table kind {name!r}; known: {', '.join(sorted(KINDS))}")
        for p in (p for group in groups for p in group):
            if not p.exists():
                sys.exit(f"{where}: records {_rel(p)} not found")
            if not (manifest_path(p).exists() or (p.parent / "manifest.json").exists()):
                sys.exit(f"{where}: records {_rel(p)} have no manifest; write one "
                         "(benchmarks/_provenance.py)")
        out.append((m, name, groups))
    if len(OPEN.findall(text)) != len(out) or len(CLOSE.findall(text)) != len(out):
        sys.exit(f"{_rel(md)}: a table marker without its pair")
    return out


def inventory(text: str) -> list[tuple[int, str, str | None]]:
    """Each markdown table of ``text`` outside code fences: its first line, the heading it sits
    under and the marker spec that generates it (None: written by hand; docs/evidence.md)."""
    spans = [(m.start(), m.end(), m["spec"]) for m in BLOCK.finditer(text)]
    lines = text.split("\n")
    starts = [0]
    for line in lines:
        starts.append(starts[-1] + len(line) + 1)
    out, heading, fence = [], "", False
    for i, line in enumerate(lines):
        fence ^= line.startswith("```")
        if fence:
            continue
        if line.startswith("#"):
            heading = line.lstrip("#").strip()
        if (i and TABLE_RULE.match(line) and lines[i - 1].startswith("|")
                and not (i > 1 and lines[i - 2].startswith("|"))):
            out.append((i, heading, next((s for a, b, s in spans if a <= starts[i] < b), None)))
    return out


def render(md: Path) -> tuple[str, list[str]]:
    """The text of ``md`` with every table block regenerated, and the blocks that changed."""
    text = md.read_text(encoding="utf-8")
    pieces, changed, at = [], [], 0
    for m, name, groups in blocks(text, md):
        try:
            body = KINDS[name](groups) + "\n"
        except ValueError as e:
            line = text.count("\n", 0, m.start()) + 1
            sys.exit(f"{_rel(md)}:{line}: table {m['spec']!r}: {e}")
        if body != m["body"]:
            changed.append(f"{_rel(md)}:{text.count(chr(10), 0, m.start()) + 1}: "
                           f"table {m['spec']!r} differs from its records")
        pieces += [text[at:m.start("body")], body]
        at = m.end("body")
    return "".join(pieces) + text[at:], changed


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true",
                    help="change nothing; exit 1 if a table differs from its records")
    ap.add_argument("--list", action="store_true",
                    help="change nothing; print every table: file:line, heading, its kind or "
                    "'by hand'")
    ap.add_argument("--docs", type=Path, default=DOCS, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    differ = []
    for md in sorted(args.docs.rglob("*.md")):
        if args.list:
            for line, heading, spec in inventory(md.read_text(encoding="utf-8")):
                print(f"{_rel(md)}:{line}\t{heading}\t{spec.split()[0] if spec else 'by hand'}")
            continue
        text, changed = render(md)
        differ += changed
        if changed and not args.check:
            tmp = md.with_name(md.name + ".tmp")
            tmp.write_text(text, encoding="utf-8")
            os.replace(tmp, md)
    for line in differ:
        print(line if args.check else line.replace("differs from its records", "rewritten"))
    return 1 if differ and args.check else 0


if __name__ == "__main__":
    sys.exit(main())
