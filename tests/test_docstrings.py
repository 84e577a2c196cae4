"""Docstrings state rules, not measurement history (issue 30): no docstring of the package holds
a number followed by "measured", "was" or "before", or "on N open-world". Measured numbers go
to ``docs/`` (with the command that made them) and to commit bodies."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import cassini_bayes

PACKAGE = Path(cassini_bayes.__file__).parent
HISTORY = re.compile(
    r"\d[\d.,]*(?:e[+-]?\d+)?\s*(?:%|[A-Za-zµ°²/]{1,6})?\s+(?:measured|was|before)\b"
    r"|\bon \d+ open-world", re.IGNORECASE)
"""A number (with at most one short unit) followed by a word of history, or a campaign size."""


def _docstrings(tree: ast.Module):
    """``(name, text)`` of every module, class and function docstring and of every string
    literal that documents an assignment (``X = 1`` then ``\"\"\"...\"\"\"``)."""
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            doc = ast.get_docstring(node, clean=False)
            if doc:
                yield getattr(node, "name", "<module>"), doc
            body = node.body
            for a, b in zip(body, body[1:]):
                if (isinstance(a, (ast.Assign, ast.AnnAssign)) and isinstance(b, ast.Expr)
                        and isinstance(b.value, ast.Constant) and isinstance(b.value.value, str)):
                    target = a.targets[0] if isinstance(a, ast.Assign) else a.target
                    yield ast.unparse(target), b.value.value


def test_the_pattern_finds_history_and_passes_rules():
    for history in ("R-hat 1.05 before this parameterisation", "38-54 ms measured on a simulator",
                    "0.9984-1.0000 on 160 open-world campaigns", "the bound 0.3 was too tight"):
        assert HISTORY.search(history), history
    for rule in ("how the paper obtained Eq 8", "within 4 se of the mean", "a 3 % error"):
        assert not HISTORY.search(rule), rule


def test_no_docstring_quotes_a_measurement_history():
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for name, doc in _docstrings(ast.parse(path.read_text(encoding="utf-8"))):
            found += [f"{path.relative_to(PACKAGE.parent)}: {name}: {m.group(0)!r}"
                      for m in HISTORY.finditer(doc)]
    assert not found, "measurement history in docstrings (move it to docs/):\n" + "\n".join(found)
