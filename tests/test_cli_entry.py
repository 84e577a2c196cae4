"""The console script's start-up: Dask stays unimported unless the command asks for it."""

from __future__ import annotations

import subprocess
import sys

import pytest

_PROBE = """
import sys
from cassini_bayes.cli import _hide_dask
_hide_dask(sys.argv[1:])
import numpy as np, xarray as xr
ds = xr.Dataset({"a": (("chain", "draw"), np.zeros((2, 3)))})
ds.to_netcdf(sys.argv[-1], engine="h5netcdf")
loaded = sorted(m for m in ("dask", "dask.array", "distributed") if sys.modules.get(m) is not None)
import importlib.util
print(loaded, importlib.util.find_spec("dask") is not None)
"""


@pytest.mark.parametrize("argv, importable", [
    (["fit", "inertia", "--telemetry", "x.csv"], False),
    (["report", "dask-runs/a"], False),
    (["sbc", "thrust", "--executor", "dask"], True),
    (["sbc", "thrust", "--executor=dask"], True),
])
def test_dask_hidden_unless_asked_for(tmp_path, argv, importable):
    """A fit writes its netCDF file without importing Dask; ``--executor dask`` keeps it."""
    pytest.importorskip("dask")
    out = subprocess.run([sys.executable, "-c", _PROBE, *argv, str(tmp_path / "p.nc")],
                         capture_output=True, text=True, check=True)
    assert (tmp_path / "p.nc").stat().st_size > 0
    if importable:
        assert out.stdout.strip().endswith("True"), out.stderr
    else:
        assert out.stdout.strip() == "[] False", out.stderr
