"""Run a scenario: closed-loop dynamics + controllers + sensors, one compiled ``lax.scan``.

``simulate(key, scenario) -> SimResult`` gives the truth and the noisy telemetry as the package's
containers; ``simulate_batch(keys, scenario, truth=None)`` runs many replicates as one compiled,
vmapped call and returns raw arrays (:class:`SimArrays` with a leading batch axis). The true
parameters (:class:`TruthParams`: inertia, wheel axes incl. RWA4, thrust, pulse time constants,
external torques) and the noise levels are traced inputs, so simulation-based calibration can vmap
over prior draws without recompiling; only the scenario's shape and its controller settings are
compile-time constants.

The parts: :mod:`._arrays` (parameters and results), :mod:`._commands` (a scenario as the core's
inputs), :mod:`._core` (the compiled scan); here the drivers that put them together.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from cassini_bayes._devices import require_x64
from cassini_bayes.simulate import controllers as ctl
from cassini_bayes.simulate._arrays import (SimArrays, SimResult, TruthParams, noise_params,
                                            truth_params, with_errors)
from cassini_bayes.simulate._commands import (_config, _controller_arrays, _plan,
                                              believed_allocation)
from cassini_bayes.simulate._core import PULSE_RING, _batch_jit, _core_jit, trace_count
from cassini_bayes.simulate._core import _simulate_core  # noqa: F401  (plan/flight.py's)
from cassini_bayes.simulate.scenario import Scenario, check_size
from cassini_bayes.simulate.sensors import NoiseParams
from cassini_bayes.telemetry import PulseLog, Telemetry

__all__ = ["TruthParams", "SimArrays", "SimResult", "truth_params", "noise_params", "simulate",
           "simulate_arrays", "simulate_batch", "measured_telemetry", "pulse_log", "quiet_windows",
           "PULSE_RING", "trace_count", "with_errors"]

QUIET_TORQUE_KNOWLEDGE = 10.0
"""A wheel is busy (biasing) in :func:`quiet_windows` while its motor torque exceeds this many
times the truth model's ``[torque_knowledge] sd_nm``: more than holding the attitude against the
environment takes (Cassini: 1.5e-4 N m)."""
# a thruster fires while its impulse grows by this × the run's largest step
_IMPULSE_RTOL = 1e-9


_PREPARED: dict[int, tuple] = {}   # id(scenario) → (scenario, plan, controller arrays), a few


def _prepared(s: Scenario):
    """Plan and controller arrays of a scenario, cached for the last few scenarios used."""
    hit = _PREPARED.get(id(s))
    if hit is not None and hit[0] is s:
        return hit[1], hit[2]
    check_size(s)  # before the (n_steps, P) plan is allocated
    plan, carr = jnp.asarray(_plan(s)), _controller_arrays(s)
    if len(_PREPARED) >= 8:
        _PREPARED.pop(next(iter(_PREPARED)))
    _PREPARED[id(s)] = (s, plan, carr)
    return plan, carr


def simulate_arrays(key: Array, scenario: Scenario, truth: TruthParams | None = None,
                    noise: NoiseParams | None = None) -> SimArrays:
    """One run as raw arrays (compiled once per scenario shape); ``truth``: the file's."""
    require_x64("simulate")
    truth = truth_params(scenario) if truth is None else truth
    noise = noise_params(scenario) if noise is None else noise
    plan, carr = _prepared(scenario)
    return _core_jit(key, truth, noise, plan, carr, cfg=_config(scenario))


def simulate_batch(keys: Array, scenario: Scenario, truth: TruthParams | None = None,
                   noise: NoiseParams | None = None, *, noise_batched: bool = False,
                   believed_axes: np.ndarray | None = None) -> SimArrays:
    """Replicates of a scenario as one compiled, vmapped call.

    Parameters
    ----------
    keys : (b,) jax.random keys, one per replicate (sensor noise).
    scenario : the scenario.
    truth : optional :class:`TruthParams` with a leading batch axis (b, ...) to vary the true
        parameters per replicate (e.g. prior draws for SBC); default: the scenario's, shared.
        New draws of the same shape reuse the compiled program (no recompilation).
    noise : optional noise levels and sensor errors, shared; with ``noise_batched`` every field
        has a leading batch axis (b, ...), one set per replicate (e.g. gyro biases drawn for SBC).
    believed_axes : optional (b, k, 3) wheel axes the RWA controller allocates with, one set per
        replicate (an SBC that draws a wheel's axis flies it as the controller knows it);
        default the scenario's.

    Returns
    -------
    :class:`SimArrays` with a leading batch axis.
    """
    require_x64("simulate")
    batched = truth is not None
    truth = truth_params(scenario) if truth is None else truth
    noise = noise_params(scenario) if noise is None else noise
    plan, carr = _prepared(scenario)
    carr_batched: tuple[str, ...] = ()
    if believed_axes is not None:
        carr = {**carr, **believed_allocation(scenario, believed_axes)}
        carr_batched = ("axes_believed", "axes_pinv")
    return _batch_jit(keys, truth, noise, plan, carr, cfg=_config(scenario),
                      truth_batched=batched, noise_batched=noise_batched,
                      carr_batched=carr_batched)


def _telemetry(s: Scenario, t, q, w, rho, on_times, source) -> Telemetry:
    return Telemetry(t=np.asarray(t), q=np.asarray(q), omega=np.asarray(w),
                     wheel_rates=np.asarray(rho), wheel_names=s.wheel_names,
                     on_times=np.asarray(on_times) if s.uses_thrusters else None, source=source,
                     thruster_names=s.truth.thruster_names)


def measured_telemetry(arrays: SimArrays, scenario: Scenario, source: str) -> Telemetry:
    """The noisy :class:`~cassini_bayes.telemetry.Telemetry` of one run, as a fit reads it: the
    recorded (time-tag-jittered) times ``t_meas`` and the measured attitude, rates and wheel
    speeds; ``source`` names it in messages."""
    return _telemetry(scenario, arrays.t_meas, arrays.q_meas, arrays.omega_meas,
                      arrays.wheel_rates_meas, arrays.on_times, source)


def pulse_log(arrays: SimArrays, scenario: Scenario) -> PulseLog | None:
    """The commanded pulses of one run (``None`` when none fired)."""
    units = np.asarray(arrays.pulse_units)
    if units.size == 0 or not units.any():
        return None
    step, thr = np.nonzero(units)
    order = np.lexsort((thr, step))
    step, thr = step[order], thr[order]
    return PulseLog(t_on=step * scenario.dt_s, thruster=thr.astype(int),
                    width=units[step, thr].astype(float) * ctl.COMMAND_RESOLUTION_S,
                    source=f"<simulated {scenario.name}>",
                    thruster_names=scenario.truth.thruster_names)


def simulate(key: Array, scenario: Scenario, truth: TruthParams | None = None) -> SimResult:
    """Simulate a scenario: the truth beside the noisy telemetry and the pulse log.

    Parameters
    ----------
    key : jax.random key for the sensor noise.
    scenario : a loaded :class:`Scenario`.
    truth : optional override of the true parameters.
    """
    params = truth_params(scenario) if truth is None else truth
    arr = jax.tree_util.tree_map(np.asarray, simulate_arrays(key, scenario, params))
    src = f"<simulated {scenario.name}>"
    tel_truth = _telemetry(scenario, arr.t, arr.q, arr.omega, arr.wheel_rates, arr.on_times, src)
    tel = measured_telemetry(arr, scenario, src)
    return SimResult(scenario, tel_truth, tel, pulse_log(arr, scenario), arr, params)


def quiet_windows(result: SimResult, settle_s: float = 120.0,
                  min_length_s: float = 120.0) -> list[tuple[float, float]]:
    """Quiet windows ``[(t0, t1), …]`` of a run: no slew commanded, no wheel biasing (wheel
    torques below :data:`QUIET_TORQUE_KNOWLEDGE` × the model's external-torque knowledge), no
    thruster impulse, at least ``settle_s`` after any of them, and at least ``min_length_s``
    long. Computed from the truth."""
    a, s = result.arrays, result.scenario
    t = np.asarray(a.t)
    active = np.zeros(t.size, bool)
    for sl in s.slews:
        active |= (t >= sl.t_start_s) & (t <= sl.t_end_s)
    j = np.asarray(result.params.wheel_inertias)
    rho = np.nan_to_num(np.asarray(a.wheel_rates))
    torque = np.abs(np.diff(rho, axis=0)) * j / np.diff(t)[:, None]
    busy = np.any(torque > QUIET_TORQUE_KNOWLEDGE * s.truth.knowledge.torque_sd_nm, axis=1)
    step = np.abs(np.diff(np.asarray(a.thruster_impulse), axis=0))
    imp = np.any(step > _IMPULSE_RTOL * step.max(initial=0.0), axis=1)
    active[1:] |= busy | imp
    active[:-1] |= busy | imp
    # grow the activity by the settling time
    last = np.where(active, t, -np.inf)
    last = np.maximum.accumulate(last)
    quiet = ~active & (t - last > settle_s)
    out = []
    i = 0
    while i < t.size:
        if quiet[i]:
            k = i
            while k + 1 < t.size and quiet[k + 1]:
                k += 1
            if t[k] - t[i] >= min_length_s:
                out.append((float(t[i]), float(t[k])))
            i = k + 1
        else:
            i += 1
    return out
