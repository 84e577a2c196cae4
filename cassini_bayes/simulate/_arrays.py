"""The traced inputs and the outputs of a run: the true parameters and noise levels
(:class:`TruthParams`, :class:`~cassini_bayes.simulate.sensors.NoiseParams`) built from a scenario
or varied per replicate, and the raw and container results (:class:`SimArrays`,
:class:`SimResult`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np
from jax import Array

from cassini_bayes.physics.momentum import inertia_vector
from cassini_bayes.simulate.scenario import Scenario
from cassini_bayes.simulate.sensors import NoiseParams
from cassini_bayes.spacecraft import tilted_axis
from cassini_bayes.telemetry import PulseLog, Telemetry


class TruthParams(NamedTuple):
    """True parameters of a run (all traceable arrays; SI units).

    inertia : (6,) ``(Ixx, Iyy, Izz, Ixy, Ixz, Iyz)`` kg m², incl. wheels.
    wheel_axes : (k, 3) true unit spin axes (RWA4 wherever it really is).
    wheel_inertias : (k,) spin inertias, kg m² (0 for a wheel that is off).
    thrust_n : (m,) steady thrust per thruster of the truth model (Cassini: ``Z1 … Y4``), N.
    tau_s : (3,) ``(tau_delay, tau_rise, tau_fall)``, s.
    torque_inertial_nm : (3,) external torque at t = 0, inertial axes, N m.
    torque_body_nm : (3,) constant external torque, body axes, N m.
    torque_inertial_rate_nm_s : (3,) slow linear change of the inertial torque, N m/s
        (``T_N(t) = T_N + Ṫ_N t``, integrated exactly).
    flex_freq_rad_s, flex_damping, flex_coupling : the flexible/slosh mode's ``Ω`` (rad/s), ``ζ``
        and ``δ`` (3,) kg^½ m (zeros, and ignored, when the scenario has no mode).
    """

    inertia: Array
    wheel_axes: Array
    wheel_inertias: Array
    thrust_n: Array
    tau_s: Array
    torque_inertial_nm: Array
    torque_body_nm: Array
    torque_inertial_rate_nm_s: Array
    flex_freq_rad_s: Array
    flex_damping: Array
    flex_coupling: Array


class SimArrays(NamedTuple):
    """Raw simulation output; leading axis = samples (and a batch axis first when batched).

    t : (n,) s. q, omega, wheel_rates : true attitude, body rate (rad/s), wheel rates (rad/s).
    q_meas, omega_meas, wheel_rates_meas : the same through the sensors.
    h_inertial : (n, 3) true total inertial momentum, N m s.
    impulse_inertial : (n, 3) cumulative angular impulse of the body-fixed torques (thrusters and
        body-axis external torque) in inertial axes, N m s.
    impulse_body : (n, 3) the same accumulated in body axes (no rotation), N m s.
    thruster_impulse : (n, m) cumulative impulse of each thruster, N s.
    on_times : (n, m) cumulative commanded on-time, s.
    pointing_error : (n, 3) attitude error w.r.t. the command, rad.
    pulse_units : (n_steps, m) int8 widths (units of 1/8 s) commanded at each step (empty when
        the scenario fires no thrusters).
    t_meas : (n,) recorded (time-tag-jittered) sample times, s; equal to ``t`` without jitter.
    flex_eta : (n,) modal coordinate ``η`` of the flexible/slosh mode, kg^½ m (zeros without).
    """

    t: Array
    q: Array
    omega: Array
    wheel_rates: Array
    q_meas: Array
    omega_meas: Array
    wheel_rates_meas: Array
    h_inertial: Array
    impulse_inertial: Array
    impulse_body: Array
    thruster_impulse: Array
    on_times: Array
    pointing_error: Array
    pulse_units: Array
    t_meas: Array
    flex_eta: Array


@dataclass(frozen=True)
class SimResult:
    """One simulated run as the package's containers (NumPy, SI units).

    truth : noise-free :class:`Telemetry` (on-times included when thrusters can fire).
    telemetry : noisy :class:`Telemetry`, what a calibration sees.
    pulses : :class:`PulseLog` of every commanded pulse, or ``None`` when none fired.
    arrays : the raw :class:`SimArrays` (momentum, impulses, pointing error …).
    params : the :class:`TruthParams` used.
    """

    scenario: Scenario
    truth: Telemetry
    telemetry: Telemetry
    pulses: PulseLog | None
    arrays: SimArrays
    params: TruthParams


def truth_params(scenario: Scenario) -> TruthParams:
    """The scenario's true parameters as arrays."""
    sc = scenario.truth
    on = np.array(scenario.wheels_on, float)
    fm = scenario.flex
    return TruthParams(
        inertia=jnp.asarray(inertia_vector(sc.inertia)),
        wheel_axes=jnp.asarray(sc.wheel_axes),
        wheel_inertias=jnp.asarray(sc.wheel_inertias * on),
        thrust_n=jnp.asarray(scenario.thrust_n),
        tau_s=jnp.asarray([sc.pulse.tau_delay, sc.pulse.tau_rise, sc.pulse.tau_fall]),
        torque_inertial_nm=jnp.asarray(scenario.external_torque_inertial_nm),
        torque_body_nm=jnp.asarray(scenario.external_torque_body_nm),
        torque_inertial_rate_nm_s=jnp.asarray(scenario.external_torque_inertial_rate_nm_s),
        flex_freq_rad_s=jnp.asarray(0.0 if fm is None else 2.0 * np.pi * fm.freq_hz),
        flex_damping=jnp.asarray(0.0 if fm is None else fm.damping),
        flex_coupling=jnp.asarray(np.zeros(3) if fm is None else fm.coupling),
    )


def noise_params(scenario: Scenario) -> NoiseParams:
    """The scenario's noise levels as arrays."""
    n = scenario.noise
    return NoiseParams(*(jnp.asarray(float(x)) for x in
                         (n.gyro_rad_s, n.star_tracker_rad, n.tach_quantum_rpm,
                          n.tach_noise_rpm)),
                       gyro_bias_rad_s=jnp.asarray(n.gyro_bias_rad_s, float),
                       gyro_scale_factor=jnp.asarray(n.gyro_scale_factor, float),
                       time_tag_jitter_s=jnp.asarray(float(n.time_tag_jitter_s)))


def with_errors(scenario: Scenario, truth: TruthParams, noise: NoiseParams, *,
                wheel_scale: dict | None = None, wheel_tilt_rad: dict | None = None,
                gyro_bias_rad_s=None, gyro_scale_factor=None) -> tuple[TruthParams, NoiseParams]:
    """``truth`` and ``noise`` of one run with the sensor and wheel errors the robust models'
    nuisance parameters describe (:mod:`cassini_bayes.inference.nuisance`), relative to the
    ``[prior]`` model, the reference those parameters are errors of.

    ``wheel_scale`` (wheel name → ``c_k``): that wheel's true spin inertia is ``(1 + c_k) J_k``
    with ``J_k`` the prior model's (zero while the wheel is off); ``wheel_tilt_rad`` (name →
    ``(a_k1, a_k2)``): its true axis is the prior model's tilted along
    :func:`~cassini_bayes.spacecraft.wheel_tilt_basis` (an articulated wheel the scenario has moved
    off its model axis stays where the scenario put it); ``gyro_bias_rad_s`` (3,) and
    ``gyro_scale_factor`` (3,): ``ω_meas = (1 + s) ω + b + noise``. Wheels not named keep the
    scenario's truth. NumPy, one run: the campaigns stack the results over replicates.
    """
    prior = scenario.prior
    on = dict(zip(scenario.wheel_names, scenario.wheels_on))
    axes = np.array(truth.wheel_axes, float)
    inertias = np.array(truth.wheel_inertias, float)
    for name, c in (wheel_scale or {}).items():
        k = scenario.wheel_names.index(name)
        inertias[k] = prior.wheel(name).inertia * (1.0 + float(c)) * float(on[name])
    for name, tilt in (wheel_tilt_rad or {}).items():
        k, w = scenario.wheel_names.index(name), prior.wheel(name)
        if not w.articulated or np.allclose(axes[k], w.axis):
            axes[k] = tilted_axis(w.axis, tilt)
    truth = truth._replace(wheel_axes=jnp.asarray(axes), wheel_inertias=jnp.asarray(inertias))
    if gyro_bias_rad_s is not None:
        noise = noise._replace(gyro_bias_rad_s=jnp.asarray(gyro_bias_rad_s, float))
    if gyro_scale_factor is not None:
        noise = noise._replace(gyro_scale_factor=jnp.asarray(gyro_scale_factor, float))
    return truth, noise
