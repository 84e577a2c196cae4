"""Modules of one idea and functions a reader can hold (issue 30): no module of the package over
500 lines and no function over 80, so that growth shows up as a failing test, not as drift."""

from __future__ import annotations

import ast
from pathlib import Path

import cassini_bayes

PACKAGE = Path(cassini_bayes.__file__).parent
MODULE_LINES = 500
FUNCTION_LINES = 80


def _sizes(path: Path):
    """``(name, lines)`` of the module and of each function in it, decorators excluded."""
    text = path.read_text(encoding="utf-8")
    yield "<module>", text.count("\n")
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            yield node.name, node.end_lineno - node.lineno + 1


def test_the_size_rule_sees_a_long_function(tmp_path):
    long = tmp_path / "long.py"
    long.write_text("def f():\n" + "    x = 1\n" * FUNCTION_LINES)
    assert dict(_sizes(long))["f"] > FUNCTION_LINES


def test_no_module_or_function_is_too_long():
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for name, lines in _sizes(path):
            limit = MODULE_LINES if name == "<module>" else FUNCTION_LINES
            if lines > limit:
                found.append(f"{path.relative_to(PACKAGE.parent)}: {name}: {lines} > {limit}")
    assert not found, "split these (one idea a module, a screen a function):\n" + "\n".join(found)
