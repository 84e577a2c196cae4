"""The robust thrust fit's density along the common-scale ridge.

Scaling the inertia, every thrust and every wheel's spin inertia by one factor leaves a biasing
event's rates and wheel speeds unchanged (Feldman & Lee Eq 17 is homogeneous in them), so only
the wheels' spin-inertia prior may tell that factor. The fit holds the wheels at the model
file's common scale in its likelihood and draws the common scale from its prior
(``ThrustProblem.scale_free``); its density must then put the inertia and thrusts where those
wheels do: moving ``F`` and ``I`` together, its maximum at the truth and its width well inside
the prior of the common scale that the fit adds (``benchmarks/thrust_scale_ridge.py``, whose
``ridge`` this calls; docs/planning.md). Deterministic: no sampling.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

PEAK_SHARE = 0.05
"""Largest offset of the density's maximum from the truth, a share of the common scale's prior
sd: a tilt that large would move every reported inertia and thrust by a twentieth of it."""


def _ridge(case: str) -> tuple[float, float, float]:
    """``(sd, peak offset, the common scale's prior sd)`` of the scale from the fit's density."""
    spec = importlib.util.spec_from_file_location(
        "thrust_scale_ridge", Path(__file__).parents[1] / "benchmarks" / "thrust_scale_ridge.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    r = bench.ridge(case)
    return r["rows"][0]["sd"], r["rows"][0]["peak_offset"], r["prior_sd"]


def test_cassini_density_holds_the_scale_at_the_wheels():
    """Day 028: the maximum at the truth, the width a third of the common scale's prior or
    less (the event weighs the inertia and thrust against the wheels)."""
    sd, peak, prior_sd = _ridge("biasing_day028:mean")
    assert sd < prior_sd / 3 and abs(peak) < PEAK_SHARE * prior_sd


@pytest.mark.slow
def test_espa_density_holds_the_scale_at_the_wheels():
    """The ESPA bus, whose tachometers add as much momentum noise as its gyro: the same."""
    sd, peak, prior_sd = _ridge("biasing_espa_bus:thruster")
    assert sd < prior_sd / 3 and abs(peak) < PEAK_SHARE * prior_sd
