"""One small fit per model, run through the CLI, and its summary.json numbers pinned.

``tests/data/fit_pins.json`` was recorded with this module (``python tests/fit_pins.py``) on the
code *before* the fit logic moved out of the CLI into :mod:`cassini_bayes.api`;
``tests/test_api.py`` runs the same fits through the CLI and through the public API and requires
the same numbers (1e-9 relative). Re-record only for a deliberate change of the numbers, and say
why in the commit.

Inputs come from the shipped scenarios (``simulate`` with a fixed key), the sampler is tiny.
"""

from __future__ import annotations

import json
import math
import re
import sys
from pathlib import Path

PINS = Path(__file__).parent / "data" / "fit_pins.json"
SMALL = {"chains": 2, "warmup": 150, "draws": 150}

# model -> (scenario, simulation key, spacecraft model, extra CLI options, seed)
RECIPES = {
    "inertia": ("slew_2000_03_15", 21, "models/cassini_2000_03_15.toml", [], 3),
    "thrust": ("fsds_biasing", 31, "models/fsds.toml", [], 4),
    "rwa4": ("rwa4_rcs", 32, "models/cassini_pre_soi.toml",
             ["--method", "rcs", "--prior", "cone"], 5),
}


def write_inputs(model: str, folder: Path) -> dict[str, Path]:
    """Simulate the model's scenario into ``folder``: ``{"telemetry": csv, "pulses": csv?}``."""
    import jax

    from cassini_bayes.simulate import load_scenario, simulate
    from cassini_bayes.telemetry import write_pulses, write_telemetry

    scenario, sim_key = RECIPES[model][:2]
    r = simulate(jax.random.key(sim_key), load_scenario(scenario))
    folder.mkdir(parents=True, exist_ok=True)
    files = {"telemetry": folder / "telemetry.csv"}
    write_telemetry(files["telemetry"], r.telemetry, force=True)
    if r.pulses is not None and model == "thrust":
        files["pulses"] = folder / "pulses.csv"
        write_pulses(files["pulses"], r.pulses, force=True)
    return files


def cli_args(model: str, files: dict[str, Path], out: Path) -> list[str]:
    """``cassini-bayes fit MODEL ...`` arguments of the pinned run."""
    _, _, spacecraft, extra, seed = RECIPES[model]
    args = ["fit", model, "--telemetry", str(files["telemetry"])]
    if "pulses" in files:
        args += ["--pulses", str(files["pulses"])]
    args += ["--spacecraft", spacecraft, "--out", str(out), "--seed", str(seed), *extra]
    for k, v in SMALL.items():
        args += [f"--{k}", str(v)]
    return args


def numbers(summary: dict) -> dict:
    """The summary without what legitimately differs between runs (warning lines name paths)."""
    return {k: v for k, v in summary.items() if k != "warnings"}


def assert_same(a, b, where: str = "summary", rtol: float = 1e-9) -> None:
    """Equal structure, equal strings (but for directories)/ints/bools, floats within ``rtol``
    relative."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), f"{where}: keys {set(a) ^ set(b)}"
        for k in a:
            assert_same(a[k], b[k], f"{where}.{k}", rtol)
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), f"{where}: lengths differ"
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{where}[{i}]", rtol)
    elif isinstance(a, float) and not isinstance(b, bool) and isinstance(b, (int, float)):
        assert math.isclose(a, b, rel_tol=rtol, abs_tol=1e-300), f"{where}: {a!r} != {b!r}"
    elif isinstance(a, str):  # messages name the input files: compare their names only
        assert _no_dirs(a) == _no_dirs(b), f"{where}: {a!r} != {b!r}"
    else:
        assert a == b, f"{where}: {a!r} != {b!r}"


def _no_dirs(text) -> str:
    return re.sub(r"\S*/", "", text) if isinstance(text, str) else text


def record() -> None:  # pragma: no cover - run by hand
    import os
    import tempfile

    os.environ.setdefault("XLA_FLAGS", "--xla_force_host_platform_device_count=4")
    import cassini_bayes  # noqa: F401  (64-bit)
    from cassini_bayes.cli import main

    pins = {}
    with tempfile.TemporaryDirectory() as tmp:
        for model in RECIPES:
            files = write_inputs(model, Path(tmp) / model)
            out = Path(tmp) / f"{model}-run"
            code = main(cli_args(model, files, out))
            assert code in (0, 3), f"{model}: exit {code}"
            pins[model] = numbers(json.loads((out / "summary.json").read_text()))
            print(model, "recorded", file=sys.stderr)
    PINS.parent.mkdir(exist_ok=True)
    PINS.write_text(json.dumps(pins, indent=1) + "\n")


if __name__ == "__main__":  # pragma: no cover
    record()
