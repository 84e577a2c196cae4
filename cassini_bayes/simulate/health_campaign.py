"""Thruster-health campaigns: many wheel-biasing events over mission time (docs/health.md).

A campaign TOML names an event template (a scenario TOML, e.g. ``health_event.toml``) and says how
the events differ::

    name, description, seed, event = "health_event.toml"   (relative to the campaign file,
                  else a shipped scenario's name)
    [campaign]    n_events, span_days, date_jitter (0..1 of the mean spacing),
                  wheel_rpm = [lo, hi] (each wheel's biasing target: |rpm| uniform, random sign),
                  thrust_n (nominal true thrust, N)
    [errors]      thrust_offset_frac (per campaign and thruster, uniform on ±),
                  thrust_scatter_frac (per event and thruster: sd of a uniform scatter),
                  tau_scatter_frac (per event: sd of a uniform scatter of each time constant),
                  inertia_error_frac (per campaign: sd of each principal moment's error),
                  wheel_inertia_error_sd (per campaign and wheel: sd of the spin-inertia error)
    [degradation] thrusters = ["Z3", "Z4"], fraction (0..1 lost), day (after the first event)

:func:`campaign_events` turns a campaign and a seed into the event scenarios and their dates; the
errors are drawn here, independently of what the health model assumes (its scatter is Gaussian,
these are uniform; the inertia errors are shared by all events, as in flight).
"""

from __future__ import annotations

import copy
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cassini_bayes._toml import read_toml
from cassini_bayes.errors import InputError
from cassini_bayes.physics.impulse import THRUSTER_NAMES
from cassini_bayes.simulate.scenario import Scenario, scenario_from_dict, scenario_path

__all__ = ["Campaign", "CampaignEvent", "load_campaign", "campaign_events"]

_SQRT3 = np.sqrt(3.0)


@dataclass(frozen=True)
class Campaign:
    """A parsed campaign TOML (see the module docstring; fractions are of the thrust, days are
    after the first event)."""

    name: str
    description: str
    seed: int
    source: str
    event_template: dict
    event_source: str
    n_events: int
    span_days: float
    date_jitter: float
    wheel_rpm: tuple[float, float]
    thrust_n: float
    thrust_offset_frac: float
    thrust_scatter_frac: float
    tau_scatter_frac: float
    inertia_error_frac: float
    wheel_inertia_error_sd: float
    degraded: tuple[int, ...] = ()
    degradation_fraction: float = 0.0
    degradation_day: float | None = None


@dataclass(frozen=True)
class CampaignEvent:
    """One event: its date (days after the first event), scenario and true thrusts (8,), N."""

    date_days: float
    scenario: Scenario
    thrust_n: np.ndarray


def _num(table: dict, key: str, src: str, lo: float, hi: float, default=None) -> float:
    v = table.get(key, default)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not lo <= v <= hi:
        raise InputError(f"'{key}' must be a number in [{lo}, {hi}], got {v!r}", path=src)
    return float(v)


def load_campaign(path: str | os.PathLike) -> Campaign:
    """Read a campaign TOML (a path, or the stem of a shipped one, e.g. ``health_control``)."""
    p = scenario_path(path, "campaign")
    d = read_toml(p, "campaign", "experiments/scenarios/")
    src = str(p)
    if "campaign" not in d and "run" in d:
        raise InputError("a scenario file, not a thruster-health campaign: simulate it with "
                         "'cassini-bayes simulate FILE --out DIR'", path=src)
    allowed = {"name", "description", "seed", "event", "campaign", "errors", "degradation"}
    for key in d:
        if key not in allowed:
            raise InputError(f"unknown key '{key}'; allowed: {', '.join(sorted(allowed))}",
                             path=src)
    if "campaign" not in d or "event" not in d:
        raise InputError("a campaign needs 'event = \"TEMPLATE.toml\"' and a [campaign] table",
                         path=src)
    ev = Path(str(d["event"]))
    ev = p.parent / ev if not ev.is_absolute() and (p.parent / ev).exists() else ev
    template = read_toml(scenario_path(ev, "event scenario"), "event scenario",
                         "experiments/scenarios/")
    c, e = d["campaign"], d.get("errors", {})
    seed = d.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**63:
        raise InputError(f"'seed' must be an integer in 0 .. 2**63 - 1 (as --seed), got "
                         f"{seed!r}", path=src)
    rpm = c.get("wheel_rpm", [300.0, 900.0])
    if not (isinstance(rpm, list) and len(rpm) == 2 and 0 <= rpm[0] <= rpm[1] <= 3000):
        raise InputError("'campaign.wheel_rpm' must be [lo, hi] rpm with 0 <= lo <= hi <= 3000",
                         path=src)
    n = int(_num(c, "n_events", src, 2, 1000))
    kw = {}
    if "degradation" in d:
        g = d["degradation"]
        names = [str(x).upper() for x in g.get("thrusters", [])]
        if not names or any(x not in THRUSTER_NAMES for x in names):
            raise InputError(f"'degradation.thrusters' must list thrusters of "
                             f"{', '.join(THRUSTER_NAMES)}, got {g.get('thrusters')!r}", path=src)
        kw = {"degraded": tuple(THRUSTER_NAMES.index(x) for x in names),
              "degradation_fraction": _num(g, "fraction", src, 0.0, 0.9),
              "degradation_day": _num(g, "day", src, 0.0, 1e5)}
    return Campaign(
        name=str(d.get("name", p.stem)), description=str(d.get("description", "")), seed=seed,
        source=src, event_template=template, event_source=str(ev), n_events=n,
        span_days=_num(c, "span_days", src, 1.0, 1e5), date_jitter=_num(c, "date_jitter", src,
                                                                         0.0, 1.0, 0.0),
        wheel_rpm=(float(rpm[0]), float(rpm[1])),
        thrust_n=_num(c, "thrust_n", src, 0.01, 10.0, 0.699),
        thrust_offset_frac=_num(e, "thrust_offset_frac", src, 0.0, 0.3, 0.0),
        thrust_scatter_frac=_num(e, "thrust_scatter_frac", src, 0.0, 0.1, 0.0),
        tau_scatter_frac=_num(e, "tau_scatter_frac", src, 0.0, 0.3, 0.0),
        inertia_error_frac=_num(e, "inertia_error_frac", src, 0.0, 0.1, 0.0),
        wheel_inertia_error_sd=_num(e, "wheel_inertia_error_sd", src, 0.0, 0.03, 0.0), **kw)


def _uniform(rng, sd: float, size=None):
    """Uniform draws with standard deviation ``sd`` (on ``±√3 sd``)."""
    return rng.uniform(-_SQRT3 * sd, _SQRT3 * sd, size)


def campaign_events(campaign: Campaign, seed: int) -> list[CampaignEvent]:
    """The campaign's events for ``seed``: dates, scenarios (each with its own simulation seed)
    and true thrusts. The same seed gives the same events."""
    c = campaign
    rng = np.random.default_rng([seed, 17])
    spacing = c.span_days / max(c.n_events - 1, 1)
    dates = spacing * np.arange(c.n_events) + _uniform(rng, c.date_jitter * spacing / (2 * _SQRT3),
                                                       c.n_events)
    dates = np.sort(np.clip(dates, 0.0, c.span_days))
    dates -= dates[0]                                           # the first calibration is day 0
    offset = 1.0 + rng.uniform(-c.thrust_offset_frac, c.thrust_offset_frac, 8)
    tmpl = c.event_template
    truth0 = scenario_from_dict(tmpl, c.event_source)
    i0 = np.asarray(truth0.truth.inertia)
    # principal moments scaled, products of inertia kept (a mass-property error shared by all)
    scale = 1.0 + c.inertia_error_frac * rng.standard_normal(3)
    inertia = {"Ixx": i0[0, 0] * scale[0], "Iyy": i0[1, 1] * scale[1],
               "Izz": i0[2, 2] * scale[2], "Ixy": i0[0, 1], "Ixz": i0[0, 2], "Iyz": i0[1, 2]}
    wheel_err = np.clip(c.wheel_inertia_error_sd * rng.standard_normal(len(truth0.wheels_on)),
                        -0.09, 0.09)
    tau0 = np.array([truth0.truth.pulse.tau_delay, truth0.truth.pulse.tau_rise,
                     truth0.truth.pulse.tau_fall])
    sim_seeds = rng.integers(0, 2**31, c.n_events)
    events = []
    for k, day in enumerate(dates):
        d = copy.deepcopy(tmpl)
        thrust = c.thrust_n * offset * (1.0 + _uniform(rng, c.thrust_scatter_frac, 8))
        if c.degraded and day >= c.degradation_day:
            thrust[list(c.degraded)] *= 1.0 - c.degradation_fraction
        tau = tau0 * (1.0 + _uniform(rng, c.tau_scatter_frac, 3))
        d["name"] = f"{c.name}_event{k:03d}"
        d["seed"] = int(sim_seeds[k])
        tr = d.setdefault("truth", {})
        tr.update({"thrust_n": [float(x) for x in thrust], "tau_delay_s": float(tau[0]),
                   "tau_rise_s": float(tau[1]), "tau_fall_s": float(tau[2]),
                   "inertia": {kk: float(v) for kk, v in inertia.items()},
                   "wheel_inertia_errors": [float(x) for x in wheel_err]})
        for ramp in d.get("wheel_ramp", []):
            ramp["target_rpm"] = float(rng.choice([-1.0, 1.0]) * rng.uniform(*c.wheel_rpm))
        events.append(CampaignEvent(float(day), scenario_from_dict(d, c.event_source), thrust))
    return events
