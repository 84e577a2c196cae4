"""The package ships its data: a wheel built from the project holds every spacecraft model,
experiment file and scenario, and an installed wheel finds them from any working directory.

The wheel is built offline from a copy of the sources (``pip wheel --no-build-isolation
--no-index``, the ``[dev]`` extra's setuptools and wheel): about 3 s, plus ~5 s per import of the
package in a subprocess.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from cassini_bayes._paths import DATA_DIR
from cassini_bayes.experiments._reproduce import discover_experiments

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = sorted(p.relative_to(DATA_DIR.parent).as_posix() for p in DATA_DIR.rglob("*.toml"))


def test_clone_links_the_root_folders_to_the_package_data():
    """``models/`` and ``experiments/`` at the root of a clone are the package's data folders,
    so the paths the README and the docs use name the files an installed package reads."""
    for name in ("models", "experiments"):
        assert (ROOT / name).resolve() == (DATA_DIR / name).resolve()
    assert {"data/models/cassini_post_probe.toml", "data/experiments/impulse_ratio.toml",
            "data/experiments/scenarios/slews_post_probe.toml",
            "data/experiments/scenarios/sbc/sbc_thrust_biasing.toml"} <= set(SHIPPED)


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """A wheel built offline from a copy of the sources (the clone stays untouched)."""
    tmp = tmp_path_factory.mktemp("wheel")
    src = tmp / "src"
    src.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    shutil.copytree(ROOT / "cassini_bayes", src / "cassini_bayes",
                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    proc = subprocess.run([sys.executable, "-m", "pip", "wheel", str(src), "--no-deps",
                           "--no-build-isolation", "--no-index", "-q", "-w", str(tmp / "dist")],
                          capture_output=True, text=True)
    assert proc.returncode == 0, ("building the wheel needs the [dev] extra's setuptools>=68 and "
                                  "wheel (pip install -e '.[dev]'):\n" + proc.stdout + proc.stderr)
    (whl,) = (tmp / "dist").glob("cassini_bayes-*.whl")
    return whl


def test_wheel_holds_every_model_experiment_and_scenario(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    missing = [f for f in SHIPPED if f"cassini_bayes/{f}" not in names]
    assert not missing, f"not in the wheel: {missing}"
    assert len(SHIPPED) >= 5 + 7 + 20 + 3   # models, experiments, scenarios, SBC scenarios
    assert not any(n.startswith(("models/", "experiments/")) for n in names)


_CHECK = """
import sys
from pathlib import Path
import cassini_bayes
from cassini_bayes import _paths
from cassini_bayes.analysis.sbc_models import THRUST_SCENARIO
from cassini_bayes.experiments._reproduce import discover_experiments
from cassini_bayes.simulate import load_scenario
from cassini_bayes.spacecraft import load_spacecraft

# imported from where the test put it, not from the clone
assert Path(cassini_bayes.__file__).resolve().parents[1] == Path(sys.argv[1]).resolve(), \
    cassini_bayes.__file__
assert _paths.MODELS_DIR.is_dir(), _paths.MODELS_DIR
load_spacecraft("cassini_post_probe")
sc = load_scenario("slews_post_probe")          # its model = "models/..." is shipped data
assert Path(sc.prior_model_path).is_file(), sc.prior_model_path
assert load_scenario(THRUST_SCENARIO).name == "sbc_thrust_biasing"
found, skipped = discover_experiments()
assert not skipped, skipped
print(len(found))
"""


def _run_check(tmp_path: Path, pythonpath: Path) -> str:
    """Run :data:`_CHECK` in an empty working directory with ``pythonpath`` first on the path."""
    cwd = tmp_path / "empty"
    cwd.mkdir()
    env = {**os.environ, "PYTHONPATH": str(pythonpath)}
    proc = subprocess.run([sys.executable, "-c", _CHECK, str(pythonpath)], cwd=cwd, env=env,
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc.stdout.strip()


def test_installed_wheel_finds_its_data_from_any_directory(wheel, tmp_path):
    """The wheel installed into a fresh folder (not the clone) loads a shipped model, a scenario
    naming ``models/…`` and an SBC default scenario, and finds every experiment the clone has."""
    site = tmp_path / "site"
    proc = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--no-index",
                           "-q", "--target", str(site), str(wheel)], capture_output=True,
                          text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert _run_check(tmp_path, site) == str(len(discover_experiments()[0]))


def test_zip_imported_package_extracts_its_data(wheel, tmp_path):
    """Imported straight from the wheel (a zip: ``importlib.resources`` gives no real folder),
    the data are extracted once to a temporary directory and read from there."""
    assert _run_check(tmp_path, wheel) == str(len(discover_experiments()[0]))
