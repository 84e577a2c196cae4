"""The test suite's own layout (issue 30): a helper shared by test modules lives in a helper module
of tests/ (``helpers.py``, ``slews.py``, ``run_dirs.py``, …) or a fixture, never in another test
module, so that running or editing one test file never runs or changes another's module code."""

from __future__ import annotations

import ast
from pathlib import Path

TESTS = Path(__file__).parent


def _test_modules_imported(tree: ast.AST) -> list[str]:
    """The ``test_*`` modules that ``tree`` imports, at any depth (not package submodules)."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [a.name for a in node.names if a.name.startswith("test_")]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            if node.module.split(".")[0].startswith("test_"):
                found.append(node.module)
    return found


def test_the_checker_finds_every_import_of_a_test_module():
    """The checker above finds each form of import of a test module, and only those."""
    src = ("import os\nimport test_a\nimport pkg.test_b as b\nfrom test_c import x\n"
           "from helpers import y\ndef f():\n    from test_d import z\n")
    assert _test_modules_imported(ast.parse(src)) == ["test_a", "test_c", "test_d"]


def test_no_test_or_helper_module_imports_a_test_module():
    offenders = {p.name: _test_modules_imported(ast.parse(p.read_text(), str(p)))
                 for p in sorted(TESTS.glob("*.py"))}
    offenders = {k: v for k, v in offenders.items() if v}
    assert not offenders, f"move the shared helpers into a tests/ helper module: {offenders}"
