"""The package's public surface: what ``import cassini_bayes`` shows, that the docs list it, and
that the type checker passes over the public API modules (``[tool.mypy]`` in pyproject.toml)."""

from __future__ import annotations

import inspect
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import cassini_bayes as cb

ROOT = Path(__file__).resolve().parents[1]


def test_dir_shows_the_public_names_only():
    """No helper (``importlib``, ``sys``, ``types``, ``_api``), imported module or subpackage
    is listed: ``dir`` is ``__all__`` and the module's dunders."""
    import cassini_bayes.cli  # noqa: F401  (binds many subpackages on the package)

    shown = {n for n in dir(cb) if not (n.startswith("__") and n.endswith("__"))}
    assert shown == set(cb.__all__) - {"__version__"}
    for name in cb.__all__:
        assert getattr(cb, name) is not None


def test_every_public_name_is_documented():
    """``docs/api.md`` names every entry of ``cassini_bayes.__all__`` (as ``name`` or
    ``name(…)``)."""
    text = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    missing = [n for n in cb.__all__
               if n != "__version__" and not re.search(rf"`{re.escape(n)}[`(]", text)]
    assert not missing, f"docs/api.md does not list {missing}"


def _unannotated(fn, qual: str) -> list[str]:
    sig = inspect.signature(inspect.unwrap(fn))
    out = [f"{qual}({p.name})" for p in sig.parameters.values()
           if p.name not in ("self", "cls") and p.annotation is inspect.Parameter.empty]
    if fn.__name__ != "__init__" and sig.return_annotation is inspect.Signature.empty:
        out.append(f"{qual} -> ?")
    return out


def test_every_public_function_is_fully_annotated():
    """Every function of ``cassini_bayes.__all__``, and every public method and property of its
    classes, annotates each argument and its return (the type checker then checks them)."""
    missing = []
    for name in cb.__all__:
        obj = getattr(cb, name)
        if inspect.isclass(obj):
            for key, member in vars(obj).items():
                fn = member.fget if isinstance(member, property) else member
                if ((key == "__init__" or not key.startswith("_")) and inspect.isfunction(fn)
                        and fn.__module__.startswith("cassini_bayes")):
                    missing += _unannotated(fn, f"{name}.{key}")
        elif callable(obj) and name != "__version__":
            missing += _unannotated(obj, name)
    assert not missing, missing


@pytest.mark.skipif(shutil.which("mypy", path=str(Path(sys.executable).parent)) is None
                    and not shutil.which("mypy"), reason="mypy not installed (the dev extra)")
def test_type_checker_passes_on_the_public_api():
    """mypy over the files of ``[tool.mypy]`` (the entry modules and the infrastructure layer),
    with the project's settings. Can fail: a wrong annotation there is reported."""
    proc = subprocess.run([sys.executable, "-m", "mypy"], cwd=ROOT, capture_output=True,
                          text=True, timeout=600, check=False)
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-2000:]


_USER_SCRIPT = """
import cassini_bayes as cb


def use(fit: cb.FitResult) -> float:
    tel = cb.read_telemetry("slew.csv")
    sc = cb.load_spacecraft("cassini_post_probe")
    again = cb.fit_inertia([tel], sc, seed=1, wheel_errors=WHEEL_ERRORS)
    return float(fit.idata.posterior["Ixx"].mean()) + again.summary()["seed"]
"""


@pytest.mark.skipif(shutil.which("mypy", path=str(Path(sys.executable).parent)) is None
                    and not shutil.which("mypy"), reason="mypy not installed (the dev extra)")
def test_a_users_script_is_type_checked_against_the_api(tmp_path):
    """The types reach a user: ``cassini_bayes``'s lazily loaded names are typed for checkers.
    A script using them passes, and the same script with a misspelt option fails."""
    def check(wheel_errors: str) -> subprocess.CompletedProcess:
        script = tmp_path / f"user_{len(wheel_errors)}.py"
        script.write_text(_USER_SCRIPT.replace("WHEEL_ERRORS", repr(wheel_errors)))
        return subprocess.run([sys.executable, "-m", "mypy", str(script)],
                              cwd=ROOT, capture_output=True, text=True, timeout=600,
                              check=False)

    ok = check("common")
    assert ok.returncode == 0, ok.stdout[-3000:]
    bad = check("commn")
    assert bad.returncode == 1 and "wheel_errors" in bad.stdout, bad.stdout[-3000:]
