"""``plan thrust``: a wheel-biasing event chosen within limits for the thrust calibration it gives.

The event is the papers' kind (Feldman & Lee §V, the 2004 day 028 event): the wheels that run are
spun up one after another under the RCS dead-band controller, whose pulses absorb their momentum;
the fit sees the pulses' impulses in the body rates and wheel speeds. What an operator chooses, and
what the search varies, is discrete or bounded:

* the pulse widths: every pulse of one width ``w`` (the controller saturated at ``max_pulse_s =
  w``; ``w`` from :func:`candidate_widths`, on the thrusters' 1/8 s command grid within the limits'
  ``min_pulse_s … max_pulse_s``), or *graded* widths (the controller's proportional law,
  ``width_gain_s_per_mrad`` of the limits' ``[rcs_controller]`` or 0.5 s/mrad, up to
  ``max_pulse_s``: short pulses near the dead-band, long ones far out);
* the spin-up targets: each wheel to a fraction (:data:`WHEEL_FRACTIONS`) of the largest speed the
  limits allow it (:data:`~cassini_bayes.plan.checks.WHEEL_MARGIN` of the speed and momentum
  limits, and what half the torque limit reaches in the wheel's share of the duration), with
  alternating signs so that the thrusters push both ways about the axes.

Each candidate is flown without noise and scored by the predicted posterior
(:func:`~cassini_bayes.plan.thrust.evaluate_thrust`, at the nominal truth or as the median over
truths drawn from the model file's knowledge): the largest sd over its budget (target
``max_ratio``), or over the thrust sites only (``max_ratio_thrust``). A candidate is admitted only
when its simulated flight keeps every limit: body rate and wheel speed, momentum and torque on the
telemetry (:func:`~cassini_bayes.plan.checks.largest_usage`), pulse widths within ``min_pulse_s …
max_pulse_s`` and only the allowed thrusters fired, on the simulated pulse log.
"""

from __future__ import annotations

import copy
import time
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from cassini_bayes.plan.checks import WHEEL_MARGIN
from cassini_bayes.plan.limits import ACCEL_TORQUE_SHARE, Limits, base_scenario_dict
from cassini_bayes.plan.thrust import (ThrustPrediction, evaluate_thrust, noise_free_problem,
                                       sd_at_mode)
from cassini_bayes.simulate.controllers import COMMAND_RESOLUTION_S
from cassini_bayes.simulate.scenario import Scenario, scenario_from_dict

__all__ = ["GRADED_GAIN_S_PER_MRAD", "THRUST_TARGETS", "ThrustChoice", "ThrustPlan",
           "WHEEL_FRACTIONS", "candidate_widths", "pulse_usage", "plan_thrust_event",
           "target_value", "thrust_event_dict"]

THRUST_TARGETS = ("max_ratio", "max_ratio_thrust")
WHEEL_FRACTIONS = (0.5, 1.0)
"""Spin-up targets searched, as fractions of the largest each wheel may reach (module
docstring)."""
GRADED_GAIN_S_PER_MRAD = 0.5
"""Width gain of the graded family when the limits' ``[rcs_controller]`` gives none (Cassini's
day 028 controller, ``biasing_day028``)."""
_SATURATED_GAIN_S_PER_MRAD = 1000.0   # every pulse at max_pulse_s (1/8 s beyond 1e-7 rad)
RAMP_SHARE = 0.7
"""Share of a wheel's slot of the duration its spin-up may take (the rest lets the controller
settle before the next wheel)."""


class ThrustChoice(NamedTuple):
    """One candidate event: ``width_s`` every pulse's width (``graded``: the longest of graded
    widths) and ``wheel_fraction`` of each wheel's largest target."""

    width_s: float
    graded: bool
    wheel_fraction: float


class ThrustPlan(NamedTuple):
    """The chosen event: ``scenario`` (a scenario dict), its ``prediction``, the ``choice``, the
    comparison's prediction (``baseline``, ``baseline_name``, ``baseline_scenario``: ``None``
    without one), the ``limits``, the thrust ``mode``, the ``target`` and every candidate's
    record (``search``)."""

    scenario: dict
    prediction: ThrustPrediction
    choice: ThrustChoice
    baseline: ThrustPrediction | None
    baseline_name: str
    baseline_scenario: dict | None
    limits: Limits
    mode: str
    target: str
    search: list


def target_value(p: ThrustPrediction, target: str) -> float:
    """The objective of a prediction: the largest sd over budget over every site with a budget
    (``max_ratio``) or over the thrust sites and combinations only (``max_ratio_thrust``)."""
    if target == "max_ratio":
        return p.max_ratio
    r = [sd / b for n, sd, b in zip(p.sites, p.site_sd, p.budget)
         if n.startswith("F") and np.isfinite(b)]
    r += [sd / b for sd, _, b in p.combinations.values() if np.isfinite(b)]
    return float(max(r))


def candidate_widths(limits: Limits) -> list[float]:
    """Pulse widths searched (s): the shortest and the longest the limits allow, on the 1/8 s
    command grid (the graded family covers the widths between)."""
    q = COMMAND_RESOLUTION_S
    lo = q * np.ceil(limits.min_pulse_s / q - 1e-9)
    hi = q * np.floor(limits.max_pulse_s / q + 1e-9)
    return sorted({float(lo), float(hi)})


def _largest_targets(limits: Limits, base: Scenario) -> tuple[list[str], np.ndarray, float, float]:
    """The running wheels, the largest spin-up of each (rad/s), the ramp torque (N m) and each
    wheel's slot (s) (module docstring)."""
    on = [n for n, o in zip(base.wheel_names, base.wheels_on) if o]
    sc = base.prior
    slot = (limits.duration_s - 2.0 * limits.quiet_s) / len(on)
    torque = ACCEL_TORQUE_SHARE * limits.wheel_torque_max_nm
    out = []
    for n in on:
        j = sc.wheel(n).inertia
        rho0 = abs(float(base.wheel0_rad_s[list(base.wheel_names).index(n)]))
        cap = WHEEL_MARGIN * min(limits.wheel_rate_max_rad_s, limits.wheel_momentum_max_nms / j)
        reach = torque * RAMP_SHARE * slot / j - rho0
        out.append(max(0.0, min(cap, reach)))
    return on, np.asarray(out), torque, slot


def thrust_event_dict(limits: Limits, base: Scenario, spacecraft_ref: str,
                      choice: ThrustChoice) -> dict[str, Any]:
    """The scenario dict of one candidate (module docstring): the limits' sections, RCS control,
    the wheels ramped one after another from ``quiet_s``."""
    d = base_scenario_dict(limits, spacecraft_ref)
    d["run"]["control"] = "rcs"
    d.pop("rwa_controller", None)
    rcs = copy.deepcopy(d.get("rcs_controller", {}))
    rcs["max_pulse_s"] = choice.width_s
    if choice.graded:
        rcs.setdefault("width_gain_s_per_mrad", GRADED_GAIN_S_PER_MRAD)
    else:
        rcs["width_gain_s_per_mrad"] = (0.0 if choice.width_s <= COMMAND_RESOLUTION_S + 1e-9
                                        else _SATURATED_GAIN_S_PER_MRAD)
    d["rcs_controller"] = rcs
    on, largest, torque, slot = _largest_targets(limits, base)
    d["wheel_ramp"] = [
        {"wheel": n, "t_start_s": float(limits.quiet_s + k * slot),
         "target_rpm": float((1.0 if k % 2 == 0 else -1.0) * choice.wheel_fraction * largest[k]
                             * 30.0 / np.pi),
         "torque_nm": float(torque)}
        for k, n in enumerate(on)]
    d["description"] = (f"planned thrust calibration: {len(on)} wheels biased one after another "
                        f"to {choice.wheel_fraction:g} of their limit under RCS control, "
                        + (f"graded pulses up to {choice.width_s:g} s" if choice.graded
                           else f"{choice.width_s:g} s pulses"))
    return d


def pulse_usage(p: ThrustPrediction, limits: Limits) -> dict[str, float]:
    """The pulse limits on the simulated pulse log, as fractions (≤ 1 respects them):
    ``pulse_short`` = ``min_pulse_s`` over the shortest pulse, ``pulse_long`` = the longest over
    ``max_pulse_s``, ``thrusters_forbidden`` = the share of pulses fired by thrusters the limits
    do not allow, plus 1 when there is any (0 when none)."""
    w = np.asarray(p.pulse_width, float)
    out = {"pulse_short": float(limits.min_pulse_s / np.min(w)) if w.size else 0.0,
           "pulse_long": float(np.max(w) / limits.max_pulse_s) if w.size else 0.0}
    if limits.thrusters is not None:
        bad = np.mean([n not in limits.thrusters for n in p.pulse_thruster]) if w.size else 0.0
        out["thrusters_forbidden"] = float(1.0 + bad) if bad > 0 else 0.0
    return out


def _limits_ok(usage: dict) -> bool:
    return bool(all(v <= 1.0 + 1e-9 for v in usage.values()))


def plan_thrust_event(limits: Limits, base: Scenario, spacecraft_ref: str, *, mode: str = "mean",
                      target: str = "max_ratio", widths: list[float] | None = None,
                      fractions: tuple[float, ...] = WHEEL_FRACTIONS,
                      baseline: Scenario | None = None, truths: int = 0,
                      progress: Callable[[str], None] | None = None) -> ThrustPlan:
    """Search the candidates (module docstring) and return the best that keeps every limit on its
    simulated flight; the comparison is ``baseline`` evaluated with the same model file and
    limits. ``truths``: every prediction, each candidate's included, is the median over the
    nominal truth and that many drawn from the model file's knowledge, the same draws for every
    candidate (:func:`~cassini_bayes.plan.thrust.evaluate_thrust`): a closed-loop event's
    pulses follow the truth, so the ranking does too (``truths + 1`` times the cost). Raises
    :class:`~cassini_bayes.errors.InputError` when no candidate keeps the limits (naming the
    limit the best one breaks)."""
    from cassini_bayes.errors import InputError

    widths = candidate_widths(limits) if widths is None else widths
    choices = [ThrustChoice(w, False, f) for w in widths for f in fractions]
    choices += [ThrustChoice(widths[-1], True, f) for f in fractions]
    best, search, least_bad = None, [], None
    for c in choices:
        t0 = time.perf_counter()
        d = thrust_event_dict(limits, base, spacecraft_ref, c)
        s = scenario_from_dict(copy.deepcopy(d), limits.source)
        p = evaluate_thrust(s, mode, limits, truths=truths, check_mode=False)
        usage = {**p.usage, **pulse_usage(p, limits)}
        p = p._replace(usage=usage)
        value = target_value(p, target)
        ok = _limits_ok(usage)
        rec = {**c._asdict(), "target_value": value, "truths": truths, "worst": p.worst,
               "limits_ok": ok,
               "n_pulses": p.n_pulses, "pulse_widths_s": list(p.pulse_widths_s),
               "largest_usage": max(usage, key=usage.get), "seconds": time.perf_counter() - t0}
        search.append(rec)
        if progress is not None:
            progress(f"  {'graded ≤' if c.graded else 'width'} {c.width_s:g} s, wheels "
                     f"{c.wheel_fraction:g}: {target} {value:.4g} ({p.worst}), "
                     f"{p.n_pulses} pulses, limits {'ok' if ok else 'EXCEEDED'} "
                     f"({rec['seconds']:.0f} s)")
        if ok and (best is None or value < best[0]):
            best = (value, d, p, c, s)
        if least_bad is None or max(usage.values()) < max(least_bad.values()):
            least_bad = usage
    if best is None:
        worst = max(least_bad, key=least_bad.get)
        raise InputError(f"no candidate biasing event keeps the limits of {limits.source}: the "
                         f"best uses {least_bad[worst]:.3g} of '{worst}' on its simulated "
                         "flight; widen that limit or lengthen 'limits.duration_s'",
                         path=limits.source)
    _, d, p, c, s = best
    _, problem, sig = noise_free_problem(s, mode)
    p = p._replace(site_sd_mode=sd_at_mode(problem, sig))
    base_pred, base_name, base_dict = None, "", None
    if baseline is not None:
        base_pred = evaluate_thrust(baseline, mode, limits, truths=truths)
        base_pred = base_pred._replace(usage={**base_pred.usage,
                                              **pulse_usage(base_pred, limits)})
        base_name = f"{baseline.name} (shipped, {baseline.duration_s:g} s)"
        base_dict = None
    return ThrustPlan(d, p, c, base_pred, base_name, base_dict, limits, mode, target, search)
