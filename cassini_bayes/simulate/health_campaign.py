"""Thruster-health campaigns: many wheel-biasing events over mission time (docs/health.md).

A campaign TOML names an event template (a scenario TOML, e.g. ``health_event.toml``) and says how
the events differ::

    name, description, seed, event = "health_event.toml"   (relative to the campaign file,
                  else a shipped scenario's name)
    [campaign]    n_events, span_days, date_jitter (0..1 of the mean spacing),
                  wheel_rpm = [lo, hi] (each wheel's biasing target: |rpm| uniform, random sign;
                  at most the model's wheel speed limit), thrust_n (nominal true thrust of every
                  thruster, N; default each thruster's own in the event's truth model)
    [errors]      thrust_offset_frac (per campaign and thruster, uniform on ±),
                  thrust_scatter_frac (per event and thruster: sd of a uniform scatter),
                  tau_scatter_frac (per event: sd of a uniform scatter of each time constant),
                  inertia_error_frac (per campaign: sd of each principal moment's error),
                  wheel_inertia_error_sd (per campaign and wheel: sd of the spin-inertia error)
    [degradation] thrusters = names of the truth model's thrusters (e.g. ["Z3", "Z4"]),
                  fraction (0..1 lost), day (after the first event)

The file is read through :class:`~cassini_bayes._toml.TomlTable` (every key checked, every error
naming the file and the key); any spacecraft model with thrusters flies it.

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

from cassini_bayes._toml import TomlTable, read_toml
from cassini_bayes.errors import InputError
from cassini_bayes.spacecraft import WHEEL_SPEED_NOMINAL_RPM
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
    thrust_n: np.ndarray
    thrust_offset_frac: float
    thrust_scatter_frac: float
    tau_scatter_frac: float
    inertia_error_frac: float
    wheel_inertia_error_sd: float
    degraded: tuple[int, ...] = ()
    degradation_fraction: float = 0.0
    degradation_day: float | None = None
    thrusters: tuple[str, ...] = ()


@dataclass(frozen=True)
class CampaignEvent:
    """One event: its date (days after the first event), scenario and true thrusts (M,), N
    (the truth model's thrusters in order)."""

    date_days: float
    scenario: Scenario
    thrust_n: np.ndarray


_ALLOWED = {"name", "description", "seed", "event", "campaign", "errors", "degradation"}
_CAMPAIGN_KEYS = {"n_events", "span_days", "date_jitter", "wheel_rpm", "thrust_n"}
_ERROR_KEYS = {"thrust_offset_frac", "thrust_scatter_frac", "tau_scatter_frac",
               "inertia_error_frac", "wheel_inertia_error_sd"}
_DEGRADATION_KEYS = {"thrusters", "fraction", "day"}


def load_campaign(path: str | os.PathLike) -> Campaign:
    """Read a campaign TOML (a path, or the stem of a shipped one, e.g. ``health_control``)."""
    p = scenario_path(path, "campaign")
    d = read_toml(p, "campaign", "experiments/scenarios/")
    src = str(p)
    if "campaign" not in d and "run" in d:
        raise InputError("a scenario file, not a thruster-health campaign: simulate it with "
                         "'cassini-bayes simulate FILE --out DIR'", path=src)
    top = TomlTable(d, "", src, _ALLOWED)
    if "campaign" not in d or "event" not in d:
        raise InputError("a campaign needs 'event = \"TEMPLATE.toml\"' and a [campaign] table",
                         path=src)
    ev = Path(top.string("event"))
    ev = p.parent / ev if not ev.is_absolute() and (p.parent / ev).exists() else ev
    template = read_toml(scenario_path(ev, "event scenario"), "event scenario",
                         "experiments/scenarios/")
    truth0 = scenario_from_dict(template, str(ev))
    model = truth0.truth
    names = model.thruster_names
    if not names:
        raise InputError(f"the event's truth model {model.name!r} has no thrusters; a health "
                         "campaign's events are biasing events", path=src)
    c = top.sub("campaign", _CAMPAIGN_KEYS, required=True)
    e = top.sub("errors", _ERROR_KEYS)
    seed = d.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**63:
        raise InputError(f"'seed' must be an integer in 0 .. 2**63 - 1 (as --seed), got "
                         f"{seed!r}", path=src)
    top_rpm = min(w.max_speed_rpm if np.isfinite(w.max_speed_rpm) else WHEEL_SPEED_NOMINAL_RPM
                  for w in model.wheels)
    rpm = c.table.get("wheel_rpm", [300.0, 900.0])
    if not (isinstance(rpm, list) and len(rpm) == 2
            and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in rpm)
            and 0 <= rpm[0] <= rpm[1] <= top_rpm):
        raise c.err("wheel_rpm", f"must be [lo, hi] rpm with 0 <= lo <= hi <= {top_rpm:g} (the "
                                 f"truth model's wheel speed limit), got {rpm!r}")
    n = int(c.in_range("n_events", lo=2, hi=1000, open_lo=False))
    if c.has("thrust_n"):
        thrust = np.full(len(names), c.in_range("thrust_n", lo=0.0, unit="N"))
    else:
        thrust = model.thrust_per_thruster
    kw = {}
    if "degradation" in d:
        g = top.sub("degradation", _DEGRADATION_KEYS)
        want = g.table.get("thrusters", [])
        upper = [x.upper() for x in names]
        if (not isinstance(want, list) or not want
                or any(str(x).upper() not in upper for x in want)):
            raise g.err("thrusters", f"must list thrusters of the truth model {model.name!r} "
                                     f"({', '.join(names)}), got {want!r}")
        kw = {"degraded": tuple(upper.index(str(x).upper()) for x in want),
              "degradation_fraction": g.in_range("fraction", lo=0.0, hi=0.9, open_lo=False),
              "degradation_day": g.in_range("day", lo=0.0, hi=1e5, open_lo=False, unit="d")}
    return Campaign(
        name=top.string("name", p.stem), description=top.string("description", ""), seed=seed,
        source=src, event_template=template, event_source=str(ev), n_events=n,
        span_days=c.in_range("span_days", lo=1.0, hi=1e5, open_lo=False, unit="d"),
        date_jitter=c.in_range("date_jitter", 0.0, lo=0.0, hi=1.0, open_lo=False),
        wheel_rpm=(float(rpm[0]), float(rpm[1])), thrust_n=thrust,
        thrust_offset_frac=e.in_range("thrust_offset_frac", 0.0, lo=0.0, hi=0.3, open_lo=False),
        thrust_scatter_frac=e.in_range("thrust_scatter_frac", 0.0, lo=0.0, hi=0.1,
                                       open_lo=False),
        tau_scatter_frac=e.in_range("tau_scatter_frac", 0.0, lo=0.0, hi=0.3, open_lo=False),
        inertia_error_frac=e.in_range("inertia_error_frac", 0.0, lo=0.0, hi=0.1, open_lo=False),
        wheel_inertia_error_sd=e.in_range("wheel_inertia_error_sd", 0.0, lo=0.0, hi=0.03,
                                          open_lo=False),
        thrusters=names, **kw)


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
    m = len(c.thrusters)
    offset = 1.0 + rng.uniform(-c.thrust_offset_frac, c.thrust_offset_frac, m)
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
        thrust = c.thrust_n * offset * (1.0 + _uniform(rng, c.thrust_scatter_frac, m))
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
