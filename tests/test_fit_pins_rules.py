"""The pins' tolerances can fail: each rule of ``tests/fit_pins.py`` rejects a summary moved by
an error it exists to catch, and accepts one moved by less than its bound. No fit is run: the
pinned summaries are perturbed by hand."""

from __future__ import annotations

import copy
import json

import pytest
from fit_pins import PINS, assert_within_tolerance

PINNED = json.loads(PINS.read_text())
MODELS = ("inertia", "thrust", "rwa4")


def _moved(model: str, path: tuple, by) -> dict:
    """The pinned summary of ``model`` with the leaf at ``path`` replaced by ``by(leaf)``."""
    s = copy.deepcopy(PINNED[model]["summary"])
    node = s
    for k in path[:-1]:
        node = node[k]
    node[path[-1]] = by(node[path[-1]])
    return s


@pytest.mark.parametrize("model", MODELS)
def test_the_pin_matches_itself(model):
    assert_within_tolerance(PINNED[model], PINNED[model]["summary"], model)


@pytest.mark.parametrize("model", MODELS)
def test_a_mean_moved_by_a_posterior_sd_fails(model):
    """The mean's bound (7 MCSE of ~300 draws, 0.42-0.49 sd in the pins) is under a posterior
    sd for every parameter: a bug that moves an estimate by one sd is caught; half the bound
    is not."""
    params = PINNED[model]["summary"]["parameters"]
    rules = PINNED[model]["tolerance"]["parameters"]
    for name, p in params.items():
        assert rules[name]["mean"]["atol"] < p["sd"], name
        with pytest.raises(AssertionError, match=rf"parameters\.{name}\.mean"):
            assert_within_tolerance(PINNED[model], _moved(model, ("parameters", name, "mean"),
                                                          lambda v, d=p["sd"]: v + d), model)
        half = 0.5 * rules[name]["mean"]["atol"]
        assert_within_tolerance(PINNED[model], _moved(model, ("parameters", name, "mean"),
                                                      lambda v, d=half: v + d), model)


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("leaf, by", [
    (("diagnostics", "divergences"), lambda v: v + 10),
    (("diagnostics", "max_r_hat"), lambda v: 1.2),
    (("diagnostics", "min_ess_bulk"), lambda v: 5.0),
])
def test_a_sampler_that_stops_mixing_fails(model, leaf, by):
    with pytest.raises(AssertionError, match=r"diagnostics\."):
        assert_within_tolerance(PINNED[model], _moved(model, leaf, by), model)


@pytest.mark.parametrize("model", ["inertia", "rwa4"])
def test_a_least_squares_baseline_off_in_its_sixth_digit_fails(model):
    """The baseline is exact (no sampler touches it): 1e-6 relative is a change of the data or
    the estimator, not of the CPU."""
    name = next(iter(PINNED[model]["summary"]["baseline"]))
    with pytest.raises(AssertionError, match=rf"baseline\.{name}"):
        assert_within_tolerance(PINNED[model], _moved(model, ("baseline", name),
                                                      lambda v: v * (1 + 1e-6)), model)
