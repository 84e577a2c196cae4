"""The pins hold on another instruction set: XLA emits other code for an older ISA (no AVX-512,
no AVX2), the draws then differ in their last bits and NUTS follows another path, exactly as on
a CPU of another family. The pinned inertia fit, simulated and fitted in a fresh process under
``--xla_cpu_max_isa=SSE4_2``, must match ``tests/data/fit_pins.json`` by its stated tolerances
(exact where no sampler touches a number, a multiple of the MCSE where one does).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import arviz as az

from fit_pins import PINS, assert_within_tolerance, numbers

_SCRIPT = """
import sys
from pathlib import Path
sys.path.insert(0, {tests!r})
import arviz as az

from fit_pins import cli_args, write_inputs
from cassini_bayes.cli import main
files = write_inputs("inertia", Path({tmp!r}) / "inputs")
sys.exit(main(cli_args("inertia", files, Path({tmp!r}) / "run")))
"""


def test_pinned_inertia_fit_holds_under_another_instruction_set(tmp_path):
    flags = os.environ.get("XLA_FLAGS", "") + " --xla_cpu_max_isa=SSE4_2"
    env = {**os.environ, "XLA_FLAGS": flags.strip()}
    script = _SCRIPT.format(tests=str(Path(__file__).parent), tmp=str(tmp_path))
    proc = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                          text=True, timeout=900)
    assert proc.returncode in (0, 3), proc.stderr[-2000:]
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    pins = json.loads(PINS.read_text())
    idata = az.from_netcdf(tmp_path / "run" / "posterior.nc")
    assert_within_tolerance(pins["inertia"], numbers(summary), "inertia under SSE4_2",
                            idata=idata)
