"""Reading a scenario: the file, then its sections in a fixed order (each reader in
:mod:`._truth`, :mod:`._sections`, :mod:`._events`), into one :class:`Scenario`."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from cassini_bayes._paths import SCENARIOS_DIR, input_path
from cassini_bayes._toml import TomlTable, read_toml
from cassini_bayes.errors import InputError
from cassini_bayes.simulate.scenario._events import (read_deadbands, read_leak, read_pulses,
                                                     read_slews, read_wheel_ramps, read_windows)
from cassini_bayes.simulate.scenario._sections import (check_rcs_control, read_flex_mode,
                                                       read_initial, read_noise,
                                                       read_rcs_controller, read_run,
                                                       read_rwa_controller, read_seed)
from cassini_bayes.simulate.scenario._truth import read_prior, read_truth
from cassini_bayes.simulate.scenario._types import NUMBER_ABS_MAX, Scenario

_TOP_KEYS = {"name", "description", "seed", "run", "truth", "prior", "initial", "rwa_controller",
             "rcs_controller", "slew", "wheel_ramp", "deadband", "pulse", "noise", "window",
             "flex_mode", "leak"}


def scenario_path(name: str | os.PathLike, what: str = "scenario") -> Path:
    """Path of a scenario (or campaign): a file, or the bare name of one shipped under
    ``experiments/scenarios/`` (:func:`cassini_bayes._paths.input_path`, the rule of every file
    argument)."""
    return input_path(name, what, SCENARIOS_DIR)


def scenario_from_dict(d: dict[str, Any], src: str = "<scenario>") -> Scenario:
    """Build and validate a :class:`Scenario` from the TOML schema (as a dict).

    The sections are read in a fixed order, each after those it is checked against (the run
    before its events, the truth before the prior), so the first error in that order is the one
    reported.
    """
    top = TomlTable(d, "", src, _TOP_KEYS, number_max=NUMBER_ABS_MAX)
    seed = read_seed(top)
    run = read_run(top)
    truth = read_truth(top, seed)
    prior, prior_path = read_prior(top, truth.spacecraft)
    initial = read_initial(top, truth.spacecraft)
    rwa = read_rwa_controller(top, truth.spacecraft, prior, run.control, initial)
    rcs = read_rcs_controller(top)
    slews = read_slews(top, run)
    check_rcs_control(run, truth.spacecraft, prior)
    ramps = read_wheel_ramps(top, run, truth.spacecraft, initial)
    deadbands = read_deadbands(top, run)
    pulses = read_pulses(top, run, truth.spacecraft)
    noise = read_noise(top, run.sample_period_s)
    flex = read_flex_mode(top, truth.spacecraft.inertia, run.dt_s)
    windows = read_windows(top, run)
    leak = read_leak(top, run, truth.spacecraft)
    errors = truth.wheel_inertia_errors
    return Scenario(
        name=top.string("name", Path(src).stem), description=top.string("description", ""),
        source=src, seed=seed, duration_s=run.duration_s, dt_s=run.dt_s,
        sample_period_s=run.sample_period_s, control=run.control, truth=truth.spacecraft,
        thrust_n=tuple(float(x) for x in truth.thrust_n), prior=prior,
        wheels_on=tuple(initial.wheels_on), q0=tuple(initial.q / np.linalg.norm(initial.q)),
        rates0_rad_s=tuple(initial.rates_rad_s), wheel0_rad_s=tuple(initial.wheel_rad_s),
        rwa=rwa, rcs=rcs,
        external_torque_inertial_nm=tuple(truth.external_torque_inertial_nm),
        external_torque_body_nm=tuple(truth.external_torque_body_nm),
        external_torque_inertial_rate_nm_s=tuple(truth.external_torque_inertial_rate_nm_s),
        wheel_inertia_scale=truth.wheel_inertia_scale,
        wheel_inertia_errors=() if errors is None else tuple(float(x) for x in errors),
        slews=tuple(slews), wheel_ramps=tuple(ramps), deadbands=tuple(deadbands),
        pulses=tuple(pulses), noise=noise, flex=flex, windows=tuple(windows), leak=leak,
        truth_model_path=truth.model_path, prior_model_path=prior_path,
    )


def load_scenario(path: str | os.PathLike) -> Scenario:
    """Load a scenario TOML (a path, or the stem of a file under ``experiments/scenarios/``)."""
    p = scenario_path(path)
    d = read_toml(p, "scenario", "experiments/scenarios/")
    if "campaign" in d:
        raise InputError("a thruster-health campaign file, not a scenario: simulate it with "
                         "'cassini-bayes simulate-health FILE --out DIR'", path=str(p))
    return scenario_from_dict(d, str(p))
