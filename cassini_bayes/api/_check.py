"""What a telemetry file holds, after every check: :func:`check_telemetry`.

The file (and pulse log) must pass every rule of :mod:`cassini_bayes.telemetry` and the physics
checks of :mod:`cassini_bayes.consistency` (attitude against body rates; pulse log against the
``on_*`` columns; with a spacecraft model, the wheel units by momentum conservation); otherwise
:class:`~cassini_bayes.errors.InputError`. What ``cassini-bayes check`` prints.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from cassini_bayes._devices import jax_entry
from cassini_bayes.errors import InputError, spelled

if TYPE_CHECKING:
    from cassini_bayes.api._inputs import PulsesArg, SpacecraftArg, TelemetryArg
    from cassini_bayes.consistency import AttitudeAgreement, MomentumScale
    from cassini_bayes.spacecraft import Spacecraft
    from cassini_bayes.telemetry import PulseLog, Telemetry

__all__ = ["TelemetryCheck", "WheelStats", "ThrusterStats", "check_telemetry"]


@dataclass(frozen=True)
class WheelStats:
    """One wheel: ``on`` (it has data), and its rate's min, max, first and last value, rpm;
    ``idle`` when it has data but its rms rate is at most ``IDLE_RPM`` (treated as off)."""

    name: str
    on: bool
    min_rpm: float = float("nan")
    max_rpm: float = float("nan")
    first_rpm: float = float("nan")
    last_rpm: float = float("nan")
    idle: bool = False


@dataclass(frozen=True)
class ThrusterStats:
    """One thruster that fired: its pulse count and total on-time, s."""

    name: str
    pulses: int
    on_time_s: float


@dataclass(frozen=True)
class TelemetryCheck:
    """A telemetry file that passed every check, and what it holds.

    ``t`` (n,) s; ``max_rate_rad_s`` the largest body rate; ``max_turn_rad`` the largest turn from
    the first attitude; ``attitude`` and ``momentum`` the physics checks' results
    (:func:`cassini_bayes.consistency.check_telemetry_data`; ``None`` where not made) and
    ``physics`` what they established, in words; ``wheels``; ``thruster_source`` (``"on_*
    columns"``, ``"pulse log FILE"`` or ``None`` when there is neither), ``thrusters`` (those
    that fired) and ``model_thrusters`` (the names the spacecraft model has, Cassini's without
    one; empty for a spacecraft without thrusters); ``quiet`` the quiet periods ``(t0, t1)`` s
    and the rules that made them (``min_quiet_s``; ``rate_max_rad_s`` the body-rate bound
    applied, rad/s, and ``rate_rule`` where it came from; ``wheel_tol_rpm`` the largest wheel
    bound before its noise floor, and ``wheel_tol_rule`` where it came from: ``"given"``, ``"the
    model's quiet_tol_rpm"`` or ``"the default"``); ``n_pulses`` of the pulse log (``None``
    without one); ``notes`` warnings to show; ``quanta`` the rate columns on a lattice
    (:func:`cassini_bayes.consistency.quantised_rates`).
    """

    t: np.ndarray
    max_rate_rad_s: float
    max_turn_rad: float
    attitude: AttitudeAgreement | None
    momentum: MomentumScale | None
    physics: str
    wheels: tuple[WheelStats, ...]
    thruster_source: str | None
    thrusters: tuple[ThrusterStats, ...]
    quiet: tuple[tuple[float, float], ...]
    min_quiet_s: float
    rate_max_rad_s: float
    wheel_tol_rpm: float
    n_pulses: int | None
    notes: tuple[str, ...]
    quanta: tuple = ()
    model_thrusters: tuple[str, ...] = ()
    rate_rule: str = "given"
    wheel_tol_rule: str = "given"

    @property
    def n(self) -> int:
        """Number of rows."""
        return int(self.t.size)

    def sampling(self) -> str:
        """The sampling rate in words (median step, and the range when irregular)."""
        dt = np.diff(self.t)
        med = float(np.median(dt))
        text = f"{1.0 / med:.4g} Hz (median step {med:.4g} s"
        if dt.max() > 1.5 * med or dt.min() < 0.5 * med:
            text += f", irregular: {dt.min():.4g} to {dt.max():.4g} s"
        return text + ")"


def _physics_line(attitude: AttitudeAgreement | None, momentum: MomentumScale | None,
                  spacecraft: Spacecraft | None) -> str:
    """What the physics checks of :mod:`cassini_bayes.consistency` established, on one line."""
    from cassini_bayes.consistency import (AXES_CONDITION_MIN, MOMENTUM_ALIGN_MIN,
                                           axis_angle_max_deg)
    from cassini_bayes.errors import spelled

    if attitude is None:
        text = "q vs ω not checked (the attitude hardly turns)"
    else:
        text = (f"q vs ω consistent (alignment {attitude.alignment[0]:.3f} over "
                f"{attitude.segments} turning stretches, rate scale {attitude.scale:.3f})")
    if spacecraft is None:
        return text + f"; wheel units not checked (give {spelled('--spacecraft', 'spacecraft')})"
    axes = momentum.axes if momentum is not None else None
    angle_max = axis_angle_max_deg(spacecraft)
    named = ([n for n in axes.vectors if axes.determined(n, angle_max)]
             if axes is not None else [])
    if axes is not None and named:
        worst = max(axes.angle_deg(n, spacecraft.wheel(n).axis) for n in named)
        which = ("each wheel's momentum along its axis" if len(named) == len(axes.vectors)
                 else f"the momenta of {', '.join(named)} along their axes")
        axes_text = (f"; {which} in the model (within {worst:.1f}°; "
                     f"scales {min(map(axes.scale, named)):.3f}–"
                     f"{max(map(axes.scale, named)):.3f})")
        rest = [n for n in axes.vectors if n not in named]
        if rest:
            axes_text += (f"; {', '.join(rest)} not checked (too little motion between "
                          f"firings: angular sd {max(axes.angle_sd_deg[n] for n in rest):.2g}°)")
    elif axes is not None:
        if axes.conditioning < AXES_CONDITION_MIN:
            why = f"the wheels' rates move together: conditioning {axes.conditioning:.2g}"
        elif not axes.judged:
            why = f"the balance does not fit: alignment {axes.alignment:.2f}"
        else:
            why = (f"too little motion between firings: angular sd "
                   f"{min(axes.angle_sd_deg.values()):.2g}° or more")
        axes_text = f"; wheel signs and column order not checked ({why})"
    else:
        axes_text = ""
    if momentum is None or momentum.alignment < MOMENTUM_ALIGN_MIN:
        return text + "; wheel units not checked (no clean momentum exchange)" + axes_text
    return (text + f"; wheel rpm confirmed by momentum conservation (scale {momentum.scale:.3f}, "
            "rad/s would give 9.55)" + axes_text)


def _check_shared_span(tel: Telemetry, log: PulseLog) -> None:
    """Refuse a pulse log none of whose pulses touches the telemetry's span: the two files use
    different time bases, or belong to different events (``check`` had said "none fired")."""
    from cassini_bayes.telemetry import check_pulses_in_span

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if check_pulses_in_span(log, tel).t_on.size:
            return
    t0, t1 = float(tel.t[0]), float(tel.t[-1])
    raise InputError(f"none of its {log.t_on.size} pulses (t_on {log.t_on.min():.10g}.."
                     f"{log.t_on.max():.10g} s) falls inside the telemetry span {t0:.10g}.."
                     f"{t1:.10g} s of {tel.source}: the two files use different time bases (an "
                     "epoch offset?) or belong to different events", path=log.source)


def _pulse_count(on: np.ndarray) -> int:
    """Pulses in a cumulative on-time column: the rises of its increments."""
    return int(np.count_nonzero(np.diff((np.diff(on) > 0).astype(int)) == 1) + (on[1] > on[0]))


@jax_entry
def _check_quiet_options(min_quiet_s: float, rate_max_rad_s: float | None,
                         wheel_tol_rpm: float | None) -> None:
    """One-line errors for a quiet-period option that is not a positive finite number (the
    rate and wheel bounds may be ``None``: the file's own rule)."""
    for value, option, argument in ((min_quiet_s, "--min-quiet", "min_quiet_s"),
                                    (rate_max_rad_s, "--rate-max", "rate_max_rad_s"),
                                    (wheel_tol_rpm, "--wheel-tol", "wheel_tol_rpm")):
        if value is None and argument != "min_quiet_s":
            continue
        if (isinstance(value, bool) or not isinstance(value, (int, float))
                or not 0 < value < float("inf")):
            raise InputError(f"must be a positive finite number, got {value!r}",
                             path=spelled(option, argument))


def _on_times(tel: Telemetry, log: PulseLog | None,
              notes: list[str]) -> tuple[Telemetry, str | None]:
    """The telemetry with its thruster on-times and where they came from: its own ``on_*``
    columns (the pulse log, if any, only validated), else the pulse log's; notes appended."""
    from cassini_bayes.telemetry import PulseSpanWarning, with_on_times

    if log is None:
        return tel, None if tel.on_times is None else "on_* columns"
    if tel.on_times is not None:
        notes.append(f"{tel.source} has on_* columns; they are used and {log.source} is only "
                     "validated")
        return tel, "on_* columns"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PulseSpanWarning)
        tel = with_on_times(tel, log)
    notes += [str(w.message) for w in caught if issubclass(w.category, PulseSpanWarning)]
    return tel, f"pulse log {log.source}"


def _wheel_stats(tel: Telemetry) -> list[WheelStats]:
    """Each wheel's range, first and last rate (rpm) and whether it idles; a wheel with a
    missing rate is off."""
    from cassini_bayes.telemetry import RPM_TO_RAD_S

    wheels = []
    active = tel.active_mask()
    for j, name in enumerate(tel.wheel_names):
        rpm = tel.wheel_rates[:, j] / RPM_TO_RAD_S
        if not np.all(np.isfinite(rpm)):
            wheels.append(WheelStats(name, False))
            continue
        wheels.append(WheelStats(name, True, float(rpm.min()), float(rpm.max()),
                                 float(rpm[0]), float(rpm[-1]), idle=not active[j]))
    return wheels


def _thruster_stats(tel: Telemetry, log: PulseLog | None) -> list[ThrusterStats]:
    """Each thruster that fires: its pulse count (from ``log`` when it gave the on-times, else
    counted in the on-time column) and its total on-time (s)."""
    thrusters: list[ThrusterStats] = []
    if tel.on_times is None:
        return thrusters
    for k, name in enumerate(tel.thruster_names):
        on = tel.on_times[:, k]
        total = float(on[-1] - on[0])
        if total <= 0:
            continue
        count = (int(np.count_nonzero(log.thruster == k)) if log is not None
                 else _pulse_count(on))
        thrusters.append(ThrusterStats(name, count, total))
    return thrusters


def check_telemetry(telemetry: TelemetryArg, *, pulses: PulsesArg | None = None,
                    spacecraft: SpacecraftArg | None = None, min_quiet_s: float = 60.0,
                    rate_max_rad_s: float | None = None, wheel_tol_rpm: float | None = None,
                    check_units: bool = True) -> TelemetryCheck:
    """Validate a telemetry file (and pulse log) and say what it holds.

    Parameters
    ----------
    telemetry : a telemetry CSV/Parquet path or a :class:`~cassini_bayes.telemetry.Telemetry`.
    pulses : a pulse-log CSV path or a :class:`~cassini_bayes.telemetry.PulseLog`, validated and
        used for the thruster on-times (the telemetry's ``on_*`` columns win when it has them).
    spacecraft : a model TOML path, a shipped model's name or a
        :class:`~cassini_bayes.spacecraft.Spacecraft`: its wheels and thrusters name the columns
        (without one, Cassini's: ``rwa1..rwa4``, ``on_Z1..on_Y4``), and the wheel units are
        checked by momentum conservation.
    min_quiet_s, rate_max_rad_s, wheel_tol_rpm : a quiet period is at least ``min_quiet_s``
        long, with ``|ω| ≤ rate_max_rad_s``, running wheels within ``wheel_tol_rpm`` over 10 s
        and no thruster firing: the rule ``fit wheel-axis`` detects its windows with
        (:func:`cassini_bayes.windows.quiet_periods`). By default the rate bound is a third of
        the file's top rate and each wheel's bound the model's ``[[wheel]] quiet_tol_rpm``
        (:data:`~cassini_bayes.windows.QUIET_WHEEL_TOL_RPM` without one), each at least 8 sd of
        the file's own noise; given values override them (still floored by the noise).
    check_units : the rad/s-vs-rpm and deg/s heuristics (off for wheels idling below 12 rpm).

    Raises
    ------
    InputError
        The first rule or physics check the file breaks, in one line naming where.
    """
    from cassini_bayes.api._inputs import one_pulse_log, one_telemetry, spacecraft_input
    from cassini_bayes.consistency import (
        GyroBiasWarning,
        QuantisedRatesWarning,
        check_telemetry_data,
        quantised_rates,
    )
    from cassini_bayes.telemetry import _turn_angle
    from cassini_bayes.windows import (
        QUIET_WHEEL_TOL_RPM,
        quiet_periods,
        quiet_rate_max,
        quiet_wheel_tol_rpm,
    )

    _check_quiet_options(min_quiet_s, rate_max_rad_s, wheel_tol_rpm)
    sc = spacecraft_input(spacecraft)[0] if spacecraft is not None else None
    tel = one_telemetry(telemetry, check_units=check_units, spacecraft=sc)
    log = one_pulse_log(pulses, spacecraft=sc) if pulses is not None else None
    if log is not None and log.t_on.size:
        _check_shared_span(tel, log)
    with warnings.catch_warnings(record=True) as physics_warnings:
        warnings.simplefilter("always")
        attitude, momentum = check_telemetry_data(tel, sc, log)
    notes: list[str] = [str(w.message) for w in physics_warnings
                        if issubclass(w.category, (GyroBiasWarning, QuantisedRatesWarning))]
    tel, source = _on_times(tel, log, notes)

    wheels = _wheel_stats(tel)
    thrusters = _thruster_stats(tel, log if source != "on_* columns" else None)
    tols = quiet_wheel_tol_rpm(tel, wheel_tol_rpm, sc)
    running = np.all(np.isfinite(tel.wheel_rates), axis=0)
    tols = tols[running] if np.any(running) else tols
    wheel_tol = float(np.max(tols))
    quiet = quiet_periods(tel, min_duration_s=min_quiet_s, rate_max=rate_max_rad_s,
                          wheel_tol_rpm=wheel_tol_rpm, spacecraft=sc)
    return TelemetryCheck(
        t=np.asarray(tel.t, float),
        max_rate_rad_s=float(np.linalg.norm(tel.omega, axis=1).max()),
        max_turn_rad=float(_turn_angle(tel.q, tel.q[0]).max()),
        attitude=attitude, momentum=momentum,
        physics=_physics_line(attitude, momentum, sc),
        wheels=tuple(wheels), thruster_source=source, thrusters=tuple(thrusters),
        quiet=tuple((float(a), float(b)) for a, b in quiet), min_quiet_s=min_quiet_s,
        rate_max_rad_s=quiet_rate_max(tel, rate_max_rad_s), wheel_tol_rpm=wheel_tol,
        rate_rule="given" if rate_max_rad_s is not None else "a third of the file's top rate",
        wheel_tol_rule=("given" if wheel_tol_rpm is not None
                        else "the model's quiet_tol_rpm" if np.any(tols != QUIET_WHEEL_TOL_RPM)
                        else "the default"),
        n_pulses=None if log is None else len(log.t_on), notes=tuple(notes),
        quanta=quantised_rates(tel), model_thrusters=tuple(tel.thruster_names))
