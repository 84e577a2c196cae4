"""Project-level checks: layering contract, README/CI agreement, the CLI shell."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_layers_import_contract():
    """frames/physics/simulate/estimators/telemetry/spacecraft import no NumPyro, ArviZ,
    matplotlib or CLI code (import-linter contracts in pyproject.toml)."""
    exe = Path(sys.executable).with_name("lint-imports")
    proc = subprocess.run([str(exe)], cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_code_passes_the_linter():
    """pycodestyle errors and warnings and pyflakes (ruff's E, F, W; line length 100,
    pyproject's [tool.ruff]) over the package and the tests: no line past 100, no unused name."""
    proc = subprocess.run([sys.executable, "-m", "ruff", "check", "--select", "E,F,W",
                           "--output-format", "concise", "cassini_bayes", "tests"],
                          cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_ci_runs_exactly_the_readme_test_command():
    readme = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```bash\n(.*?)\n```", readme, re.S)
    test_cmd = next(b for b in blocks if "pytest" in b)
    ci = (ROOT / ".ci" / "run").read_text()
    assert test_cmd.strip() in ci


def test_version_and_help(run_cli):
    code, out, _ = run_cli("--version")
    assert code == 0 and out.strip() == "cassini-bayes 0.1.0"
    code, out, _ = run_cli("--help")
    assert code == 0 and "fit" in out
