"""Plan a wheel-axis calibration (RWA method, Brown 2012 §III.C): a documented search.

**The manoeuvre** (:func:`axis_scenario`). Brown's procedure: the solved wheel biased to a speed
and held there by the RWA controller with the other wheels; ``n`` slew pairs, each a quiet
"Time A" rest, a slew out, a quiet "Time B" rest and the slew back (the last pair does not
slew back), every rest of the same length ``w``; the fit's windows are the rests less the
settling time after a slew (:data:`SETTLE_BANDWIDTHS`), given to it explicitly
(``--window-a/--window-b``, the scenario's ``[[window]]`` entries). What the plan chooses,
within the limits:

* ``n`` pairs (at least two: one pair's rotation about ``e`` leaves the axis's component along
  ``e`` unseen, ``(Rᵀ − 1) e = 0``);
* the slew angle ``θ`` (at most 180° and the limits' ``max_slew_deg``), flown at the largest rate
  and acceleration the limits allow about each axis (:func:`~cassini_bayes.plan.manoeuvre.
  rate_limit`, ``accel_limit``);
* the rest ``w``: the duration shared equally (Brown's), or at least the limits' ``quiet_s``
  and the settling time plus the shortest quiet period (:func:`min_window_s`), as a multiple
  of that shortest (:data:`REST_FACTORS`; 0 is the shared duration).
  Longer windows average the sensor noise down, but the external torques the robust model
  integrates out (``T Δt``) grow with the time between A and B: on a small spacecraft whose
  torque knowledge is wide against its wheel momentum the shortest windows win. The
  calibration ends with the last window; the rest of the duration is not used;
* the slew axes, one family of :data:`AXIS_FAMILIES`: ``"brown"``, Brown's pairs in turn
  (Z −45°, X +60°, Y +90°, multi-axis +30°, each angle scaled by ``θ``/90°); ``"body"``,
  Brown's axes Z, X, Y and the multi-axis direction in turn, each by ``θ``; or
  ``"perpendicular"``, perpendicular to the wheel's
  model axis ``g`` (a rotation by ``θ`` about ``e`` moves ``g`` by ``2 sin(θ/2) |e × g|``), at
  angles ``φ₀ + jπ/n`` in the plane perpendicular to ``g``. Which wins is not obvious: the
  inertial torque the robust model integrates out is one vector shared by every pair, so what
  matters is how differently the pairs move the axis in inertial space, and a family that moves
  ``g`` most may move it the same way in every pair;
* the solved wheel's bias speed, a fraction of its speed and momentum limits, or the limits
  file's speed (set before the calibration starts, as Brown's wheels were biased to
  −850 rpm); the other wheels keep the limits file's speeds.

**The search** (:func:`plan_axis`): the choices are few and partly discrete, and each evaluation
runs the simulator and the fit's own preparation (:mod:`cassini_bayes.plan.wheel_axis`), which
is not written in JAX; so the planner searches a grid instead of following gradients. Stage 1:
every ``(n, θ, family)`` of :data:`PAIR_COUNTS` × :data:`ANGLES_DEG` × :data:`AXIS_FAMILIES`
that fits, the duration shared, the wheel at the limits file's speed. Stage 2, from the best:
the rests of :data:`REST_FACTORS`, then the wheel fractions of :data:`WHEEL_FRACTIONS`, then the
axes turned by ``π/2n`` (perpendicular family). The objective is the predicted largest angular sd of
the axis; a candidate whose simulated flight exceeds a rate limit, or the wheel margin
(:data:`~cassini_bayes.plan.checks.WHEEL_MARGIN`) of a wheel limit, is rejected.

The comparison (:func:`brown_slews`) is Brown's manoeuvre within the same limits: Z ∓45°,
X ±60°, Y ±90° and a multi-axis ±30°, at the largest rates the limits allow, nine equal quiet
periods, the wheels at the limits file's speeds.
"""

from __future__ import annotations

import copy
import time
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from cassini_bayes.errors import InputError
from cassini_bayes.plan import checks
from cassini_bayes.plan.limits import Limits, base_scenario_dict
from cassini_bayes.plan.manoeuvre import accel_limit, rate_limit
from cassini_bayes.plan.optimise import slew_bounds
from cassini_bayes.plan.wheel_axis import AxisPrediction, evaluate_wheel_axis
from cassini_bayes.simulate.controllers import slew_duration
from cassini_bayes.simulate.scenario import Scenario, scenario_from_dict

__all__ = [
    "ANGLES_DEG",
    "AXIS_FAMILIES",
    "AxisChoice",
    "AxisPlan",
    "PAIR_COUNTS",
    "WHEEL_FRACTIONS",
    "axis_scenario",
    "brown_slews",
    "min_window_s",
    "plan_axis",
    "scenario_pairs",
    "settle_s",
]

PAIR_COUNTS = (2, 4, 6)
ANGLES_DEG = (45.0, 90.0)
AXIS_FAMILIES = ("brown", "body", "perpendicular")
WHEEL_FRACTIONS = (0.8, 0.65, 0.5)
"""Stage 2's bias speeds of the solved wheel, fractions of its speed (and momentum) limit
(stage 1 keeps the limits file's speed)."""
REST_FACTORS = (1.0, 1.5, 2.0)
"""Stage 2's rests as multiples of the shortest (:func:`min_window_s`); stage 1 shares the
duration equally."""
SETTLE_BANDWIDTHS = 6.0
"""A window starts this many controller time constants ``1/ω_n`` after a slew ends: the quiet
periods the fit detects need the body rate settled."""
QUIET_DETECT_S = 60.0      # the shortest quiet period the fit's window detection accepts
_BODY_CYCLE = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
                        [1.0 / np.sqrt(3.0)] * 3])
BROWN_SLEWS = ((2, -45.0), (2, 45.0), (0, 60.0), (0, -60.0), (1, 90.0), (1, -90.0),
               (3, 30.0), (3, -30.0))
"""Brown §III.C's slews: (axis: X, Y, Z or the equal-parts multi-axis, angle deg)."""


class AxisChoice(NamedTuple):
    """One candidate manoeuvre: ``pairs``, slew ``angle_deg``, the axes' ``family`` and (the
    perpendicular family) ``phase_deg`` in the plane perpendicular to the wheel, the solved
    wheel's ``wheel_fraction`` of its limit (0: the limits file's speed), the rest as
    ``rest_factor`` × :func:`min_window_s` (0: the duration shared equally)."""

    pairs: int
    angle_deg: float
    family: str = "body"
    wheel_fraction: float = 0.0
    phase_deg: float = 0.0
    rest_factor: float = 0.0


class AxisPlan(NamedTuple):
    """A planned wheel-axis calibration: the scenario dict, its prediction, the comparison's,
    the choice and the search (one row per candidate evaluated)."""

    limits: Limits
    wheel: str
    scenario: dict
    prediction: AxisPrediction
    choice: AxisChoice
    baseline: AxisPrediction
    baseline_name: str
    baseline_scenario: dict | None
    search: tuple[dict, ...]


def settle_s(base: Scenario) -> float:
    """Settling time after a slew before a window opens, s (:data:`SETTLE_BANDWIDTHS`)."""
    return SETTLE_BANDWIDTHS / base.rwa.bandwidth_rad_s


def min_window_s(limits: Limits, base: Scenario) -> float:
    """The shortest rest the plan uses, s: the limits' ``quiet_s``, and at least the fit's
    shortest quiet period plus the settling time."""
    return max(limits.quiet_s, QUIET_DETECT_S + settle_s(base))


def _wheel_limit_rad_s(limits: Limits, base: Scenario, wheel: str) -> float:
    j = base.prior.wheel(wheel).inertia
    return min(limits.wheel_rate_max_rad_s, limits.wheel_momentum_max_nms / j)


def _perpendicular_axes(g: np.ndarray, n: int, phase_rad: float) -> np.ndarray:
    from cassini_bayes.plan.wheel_axis import tangent_basis

    e = tangent_basis(g)
    phi = phase_rad + np.arange(n) * np.pi / n
    return np.cos(phi)[:, None] * e[0] + np.sin(phi)[:, None] * e[1]


def _timeline(limits: Limits, base: Scenario, axes_angles: list[tuple[np.ndarray, float]],
              n_quiet: int, rest_s: float | None = None
              ) -> tuple[list[dict], float, list[tuple[float, float]]] | None:
    """Slews one after another with ``n_quiet`` equal rests around them (the first before the
    first slew), each ``rest_s`` long or, when ``None``, filling the duration; ``None`` when
    a rest would be shorter than :func:`min_window_s` or the whole longer than the duration.
    Each slew at the largest rate and acceleration the limits allow about its axis. Returns the
    slews, the rest and the quiet windows (each rest less the settling time after a slew)."""
    b = slew_bounds(limits, base, max(len(axes_angles), 1))
    rows, total = [], 0.0
    for e, ang in axes_angles:
        r = float(rate_limit(b, e[None])[0])
        a = float(accel_limit(b, e[None])[0])
        d = slew_duration(abs(np.deg2rad(ang)), r, a)
        rows.append((e, ang, r, a, d))
        total += d
    w = (limits.duration_s - total) / n_quiet if rest_s is None else float(rest_s)
    if w < min_window_s(limits, base) - 1e-9 or total + n_quiet * w > limits.duration_s + 1e-6:
        return None
    settle = settle_s(base)
    out, quiet, t = [], [(0.0, w)], w
    for e, ang, r, a, d in rows:
        out.append({"t_start_s": float(t), "axis": [float(x) for x in e],
                    "angle_deg": float(ang), "rate_mrad_s": r * 1e3, "accel_mrad_s2": a * 1e3})
        t += d + w
        quiet.append((t - w + settle, min(t, limits.duration_s)))
    return out, float(w), quiet


def axis_scenario(limits: Limits, base: Scenario, spacecraft_path: str, wheel: str,
                  c: AxisChoice) -> dict | None:
    """The scenario dict of choice ``c`` (module docstring); ``None`` when it does not fit."""
    g = np.asarray(base.prior.wheel(wheel).axis, float)
    angle = min(c.angle_deg, 180.0, float(np.rad2deg(limits.slew_max_rad)))
    cycle = np.arange(c.pairs) % 4
    if c.family == "perpendicular":
        axes = _perpendicular_axes(g, c.pairs, np.deg2rad(c.phase_deg))
        angles = np.full(c.pairs, angle)
    else:
        axes = _BODY_CYCLE[cycle]
        angles = (np.array([a for _, a in BROWN_SLEWS[0::2]])[cycle] * angle / 90.0
                  if c.family == "brown" else np.full(c.pairs, angle))
    seq = []
    for j in range(c.pairs):
        seq.append((axes[j], float(angles[j])))
        if j < c.pairs - 1:
            seq.append((axes[j], -float(angles[j])))
    rest = c.rest_factor * min_window_s(limits, base) if c.rest_factor > 0 else None
    tl = _timeline(limits, base, seq, 2 * c.pairs, rest)
    if tl is None:
        return None
    slews, w, quiet = tl
    d = base_scenario_dict(limits, spacecraft_path)
    rho0 = dict(d["initial"].get("wheel_rpm", {}))
    key = next((k for k in rho0 if k.upper() == wheel.upper()), wheel)
    sign = -1.0 if float(rho0.get(key, 0.0)) < 0 else 1.0
    if c.wheel_fraction > 0:
        rho0[key] = (sign * c.wheel_fraction * _wheel_limit_rad_s(limits, base, wheel)
                     * 30.0 / np.pi)
    d["initial"]["wheel_rpm"] = rho0
    d["name"] = f"plan_axis_{limits.name}"
    d["description"] = (f"Planned {wheel} spin-axis calibration (RWA method, {c.pairs} slew "
                        f"pairs of {angle:g} deg about {c.family} axes, {w:.0f}-s rests) within "
                        f"{limits.name}'s limits")
    d["slew"] = slews
    d["window"] = _windows(quiet[0::2], quiet[1::2])
    return d


def _windows(a_windows, b_windows) -> list[dict]:
    """The A/B windows as a scenario's ``[[window]]`` entries (``A1``, ``B1``, …)."""
    return [{"name": f"{ab}{i + 1}", "t0_s": float(w[0]), "t1_s": float(w[1])}
            for i, pair in enumerate(zip(a_windows, b_windows)) for ab, w in zip("AB", pair)]


def scenario_pairs(d: dict) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    """The Time A / Time B pairs of a planned scenario dict's ``[[window]]`` entries."""
    w = {x["name"]: (x["t0_s"], x["t1_s"]) for x in d["window"]}
    n = len(w) // 2
    return [(w[f"A{i + 1}"], w[f"B{i + 1}"]) for i in range(n)]


def brown_slews(limits: Limits, base: Scenario, spacecraft_path: str) -> dict:
    """Brown's manoeuvre (§III.C) within the same limits as a scenario dict (module
    docstring); angles scaled down together when they do not fit."""
    dirs = np.concatenate([np.eye(3), np.full((1, 3), 1.0 / np.sqrt(3.0))])
    for scale in (1.0, 0.75, 0.5, 0.25):
        seq = [(dirs[i], scale * a) for i, a in BROWN_SLEWS]
        tl = _timeline(limits, base, seq, len(seq) + 1)
        if tl is not None:
            break
    else:
        raise InputError(f"'limits.duration_s' = {limits.duration_s:g} s cannot hold Brown's "
                         "eight slews with their windows, the comparison: give another "
                         "(--baseline SCENARIO)", path=limits.source)
    d = base_scenario_dict(limits, spacecraft_path)
    d["name"] = f"brown_{limits.name}"
    d["description"] = ("Brown's RWA-method slews (Z -45/+45, X +60/-60, Y +90/-90, multi-axis "
                        f"+30/-30 deg, scaled by {scale:g}) within the same limits")
    d["slew"] = tl[0]
    quiet = tl[2]
    d["window"] = _windows(quiet[0:-1:2], quiet[1::2])
    return d


def _limits_ok(p: AxisPrediction) -> bool:
    return all(v <= (1.0 if k in ("body_rate", "axis_rate") else checks.WHEEL_MARGIN)
               for k, v in p.usage.items())


def _evaluate(limits, spacecraft_path, d: dict, wheel: str, prior: str) -> AxisPrediction:
    s = scenario_from_dict(copy.deepcopy(d), f"<plan {limits.name}>")
    return evaluate_wheel_axis(s, wheel, limits, prior=prior, pairs=scenario_pairs(d))


def plan_axis(limits: Limits, base: Scenario, spacecraft_path: str, wheel: str, *,
              prior: str = "uniform", pairs=None, baseline: Scenario | None = None,
              progress: Callable[[str], None] | None = None) -> AxisPlan:
    """Search the manoeuvre of a wheel-axis calibration within ``limits`` (module docstring);
    ``pairs`` restricts the pair counts tried; ``baseline`` replaces Brown's slews as the
    comparison."""
    counts = PAIR_COUNTS if pairs is None else tuple(pairs)
    rows: list[dict] = []
    best: tuple[float, AxisChoice, dict, AxisPrediction] | None = None
    over: list[tuple[float, AxisChoice, dict]] = []       # candidates beyond a limit's margin

    def consider(c: AxisChoice):
        nonlocal best
        d = axis_scenario(limits, base, spacecraft_path, wheel, c)
        if d is None:
            return
        t0 = time.perf_counter()
        try:
            p = _evaluate(limits, spacecraft_path, d, wheel, prior)
        except InputError as e:         # windows the fit cannot use: not a candidate
            rows.append({**c._asdict(), "sd_direction_deg": None, "rejected": str(e),
                         "seconds": time.perf_counter() - t0})
            return
        ok = _limits_ok(p)
        rows.append({**c._asdict(), "sd_direction_deg": p.sd_direction_deg,
                     "cone90_deg": p.cone_deg["90"], "limits_ok": ok, "usage": p.usage,
                     "seconds": time.perf_counter() - t0})
        if progress is not None:
            progress(f"{c.pairs} pairs of {c.angle_deg:g}° ({c.family}, phase "
                     f"{c.phase_deg:g}°), rest ×{c.rest_factor:g}, wheel {c.wheel_fraction:g}: "
                     f"sd {p.sd_direction_deg:.4g}°"
                     + ("" if ok else " (limits exceeded)"))
        if ok and (best is None or p.sd_direction_deg < best[0]):
            best = (p.sd_direction_deg, c, d, p)
        if not ok:
            over.append((max(p.usage.values()), c, p.usage))

    for n in counts:
        for ang in ANGLES_DEG:
            if ang <= np.rad2deg(limits.slew_max_rad) + 1e-9 or ang == ANGLES_DEG[0]:
                for fam in AXIS_FAMILIES:
                    consider(AxisChoice(n, ang, fam))
    if best is None:
        near = ""
        if over:
            _, c, use = min(over, key=lambda x: x[0])
            near = (f"; the nearest, {c.pairs} pairs of {c.angle_deg:g}° ({c.family}), uses "
                    + ", ".join(f"{k} {v:.2f}" for k, v in use.items()) + " of the limits")
        raise InputError(f"no manoeuvre of {', '.join(map(str, counts))} slew pairs fits the "
                         f"limits (windows of at least {min_window_s(limits, base):.0f} s, "
                         f"body rates within the limits and wheels within "
                         f"{checks.WHEEL_MARGIN:g} of theirs on the simulated flight){near}",
                         path=limits.source)
    for f in REST_FACTORS:
        consider(best[1]._replace(rest_factor=f))
    c0 = best[1]
    for f in WHEEL_FRACTIONS:
        consider(c0._replace(wheel_fraction=f))
    c1 = best[1]
    if c1.family == "perpendicular":
        consider(c1._replace(phase_deg=90.0 / c1.pairs))
    _, choice, d, pred = best
    if baseline is None:
        bd = brown_slews(limits, base, spacecraft_path)
        bname = "Brown's slews (Z ∓45°, X ±60°, Y ±90°, multi-axis ±30°) within the same limits"
        base_pred = _evaluate(limits, spacecraft_path, bd, wheel, prior)
    else:
        bd, bname = None, f"scenario {baseline.name}"
        base_pred = evaluate_wheel_axis(baseline, wheel, limits, prior=prior)
    return AxisPlan(limits, wheel, d, pred, choice, base_pred, bname, bd, tuple(rows))
