"""The papers' estimates straight from telemetry files' containers (the ``baseline`` of a run).

Thin adapters from :class:`~cassini_bayes.telemetry.Telemetry` / ``PulseLog`` and a
:class:`~cassini_bayes.spacecraft.Spacecraft` to the array-level estimators of
:mod:`~cassini_bayes.estimators.inertia`, :mod:`~cassini_bayes.estimators.thrust` and
:mod:`~cassini_bayes.estimators.rwa4`. Wheels are matched by name; a wheel that is off (NaN rates)
contributes no momentum.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from cassini_bayes.errors import InputError
from cassini_bayes.estimators import inertia as _inertia
from cassini_bayes.estimators import rwa4 as _rwa4
from cassini_bayes.estimators import thrust as _thrust
from cassini_bayes.estimators.lstsq import solve_lstsq
from cassini_bayes.physics.momentum import INERTIA_NAMES, inertia_matrix

__all__ = ["wheel_geometry", "wheel_momentum", "fit_inertia_baseline", "fit_thrust_baseline",
           "fit_rwa4_baseline", "THRUST_GROUPINGS"]

THRUST_GROUPINGS = {"z": _thrust.fit_z_thrusters, "y": _thrust.fit_y_thrusters,
                    "y_pairs": _thrust.fit_y_pairs, "y_mean": _thrust.fit_y_mean,
                    "mean": _thrust.fit_mean}


def wheel_geometry(tel, spacecraft):
    """``(axes (k, 3), inertias (k,))`` of the telemetry's wheels, in its column order, from
    the model; a wheel without data (off) that the model lacks gets zeros (it carries no
    momentum), one with data is an InputError naming the model's wheels."""
    model = {n.upper() for n in spacecraft.wheel_names}
    axes, js = [], []
    for k, name in enumerate(tel.wheel_names):
        if name.upper() not in model and np.all(np.isnan(tel.wheel_rates[:, k])):
            axes.append(np.zeros(3))
            js.append(0.0)
            continue
        w = spacecraft.wheel(name)
        axes.append(w.axis)
        js.append(w.inertia)
    return np.stack(axes), np.array(js)


def wheel_momentum(tel, spacecraft) -> np.ndarray:
    """Wheel momentum in body axes (N m s), (n, 3), Feldman & Lee Eq 2."""
    axes, j = wheel_geometry(tel, spacecraft)
    return (np.nan_to_num(tel.wheel_rates) * j) @ axes


def fit_inertia_baseline(telemetries: Sequence, spacecraft, method: str = "free",
                         torque: bool = False) -> _inertia.InertiaFit:
    """Inertia by least squares from one or more slew telemetries.

    ``method``: ``"free"`` (momentum unknown per file, optional constant torque per file —
    recommended), ``"all_axes"`` (Eq 11, each file anchored on its first sample) or
    ``"axis_by_axis"`` (Eq 7, files concatenated in time order per file).
    """
    tels = list(telemetries)
    if not tels:
        raise InputError("no telemetry given for the inertia fit")
    if method == "free" and len(tels) == 1:
        tel = tels[0]
        return _inertia.fit_free_momentum(tel.q, tel.omega, wheel_momentum(tel, spacecraft),
                                          tel.t, torque)
    if method == "free":
        blocks, ys, names = [], [], list(INERTIA_NAMES)
        per = 6 if torque else 3
        for f, tel in enumerate(tels):
            m, y = _inertia._free(np.asarray(tel.q), np.asarray(tel.omega),
                                  wheel_momentum(tel, spacecraft), np.asarray(tel.t),
                                  torque=torque)
            m = np.asarray(m)
            full = np.zeros((m.shape[0], 6 + per * len(tels)))
            full[:, :6] = m[:, :6]
            full[:, 6 + per * f:6 + per * (f + 1)] = m[:, 6:]
            blocks.append(full)
            ys.append(np.asarray(y))
            names += [f"H0_{a}[{f}]" for a in "xyz"] + (
                [f"T_{a}[{f}]" for a in "xyz"] if torque else [])
        fit = solve_lstsq(np.concatenate(blocks), np.concatenate(ys), names,
                          "inertia entries and inertial momenta", _inertia._HINT)
        return _inertia.InertiaFit(np.asarray(inertia_matrix(fit.estimate[:6])), fit.estimate[:6],
                                   fit.residual_rms, fit.rank, fit.condition, fit.warnings)
    if method == "all_axes":
        ss, gs = [], []
        for tel in tels:
            s, g = _inertia._stacked(np.asarray(_inertia._continuous(np.asarray(tel.q))),
                                     np.asarray(tel.omega), wheel_momentum(tel, spacecraft),
                                     ref=0)
            ss.append(np.asarray(s))
            gs.append(np.asarray(g))
        fit = solve_lstsq(np.concatenate(ss), np.concatenate(gs), INERTIA_NAMES,
                          "inertia entries", _inertia._HINT)
        return _inertia.InertiaFit(np.asarray(inertia_matrix(fit.estimate)), fit.estimate,
                                   fit.residual_rms, fit.rank, fit.condition, fit.warnings)
    if method == "axis_by_axis":
        if len(tels) > 1:
            raise InputError("the axis-by-axis method takes one telemetry file; give the slews "
                             "in one file or use --method free")
        tel = tels[0]
        return _inertia.fit_axis_by_axis(tel.q, tel.omega, wheel_momentum(tel, spacecraft))
    raise InputError(f"unknown inertia method {method!r}; use free, all_axes or axis_by_axis")


def fit_thrust_baseline(tel, spacecraft, pulses=None, grouping: str = "mean",
                        tau=None, inertia=None) -> _thrust.ThrustFit:
    """Thrust by least squares (Feldman & Lee Eqs 19-23) from one biasing telemetry.

    ``grouping``: one of :data:`THRUST_GROUPINGS`. ``pulses``: a ``PulseLog`` (used for the
    impulse when given, else the telemetry's ``on_times``); ``tau = (τd, τr, τf)`` s applies the
    pulse-dynamics correction. ``inertia`` (3, 3) kg m² defaults to the spacecraft's.
    """
    if grouping not in THRUST_GROUPINGS:
        raise InputError(f"unknown thrust grouping {grouping!r}; use one of "
                         f"{', '.join(THRUST_GROUPINGS)}")
    q = spacecraft.moment_matrix
    i_m = spacecraft.inertia if inertia is None else np.asarray(inertia, float)
    pl = None if pulses is None else (pulses.t_on, pulses.thruster, pulses.width)
    v, j = _thrust.regression_inputs(tel.t, tel.omega, wheel_momentum(tel, spacecraft), i_m,
                                     on_times=tel.on_times, pulses=pl, tau=tau)
    return THRUST_GROUPINGS[grouping](v, j, q)


def fit_rwa4_baseline(tel, spacecraft, method: str, windows_a: Sequence[tuple[float, float]],
                      windows_b: Sequence[tuple[float, float]], wheel: str = "RWA4",
                      inertia=None) -> _rwa4.Rwa4Fit:
    """Wheel spin axis by Brown's methods from time windows (s).

    ``method``: ``"rcs"`` (Eq 1; one A/B pair; spacecraft inertia from the model or
    ``inertia``), ``"rwa"`` (Eq 3; A/B pairs in order) or ``"four_wheel"`` (§III.A; steps).
    ``wheel``: the wheel whose axis is solved for (others known from the model).
    """
    if len(windows_a) != len(windows_b) or not windows_a:
        raise InputError(f"give the same number of A and B windows (got {len(windows_a)} and "
                         f"{len(windows_b)})")
    axes, j = wheel_geometry(tel, spacecraft)
    names = [n.upper() for n in tel.wheel_names]
    if wheel.upper() not in names:
        raise InputError(f"telemetry {tel.source} has no column for wheel {wheel}")
    k = names.index(wheel.upper())
    pairs = [(_rwa4.window_mask(tel.t, *a, what="window A"),
              _rwa4.window_mask(tel.t, *b, what="window B")) for a, b in zip(windows_a, windows_b)]
    i_m = spacecraft.inertia if inertia is None else np.asarray(inertia, float)
    if method == "rcs":
        if len(pairs) != 1:
            raise InputError("the RCS method takes one window A and one window B")
        return _rwa4.fit_axis_rcs(tel.q, tel.omega, tel.wheel_rates, axes, j, i_m, *pairs[0],
                                  unknown=k)
    if method == "rwa":
        return _rwa4.fit_axis_rwa(tel.q, tel.omega, tel.wheel_rates, axes, j, pairs, unknown=k,
                                  inertia=i_m)
    if method == "four_wheel":
        return _rwa4.fit_axis_four_wheel(tel.wheel_rates, axes, j, pairs, unknown=k, q=tel.q,
                                         omega=tel.omega, inertia=i_m)
    raise InputError(f"unknown RWA4 method {method!r}; use rcs, rwa or four_wheel")
