"""Simulation scenarios: TOML files under ``experiments/scenarios/``, loaded and validated.

A scenario names its truth (a spacecraft model file plus overrides), the prior model the
calibration starts from, the run (duration, integration step, telemetry period, controller), the
commanded events (slews, wheel biasing ramps, dead-band changes, open-loop pulses), the sensor
noise and the seed. Unknown keys, missing required values and impossible values are
:class:`~cassini_bayes.errors.InputError` with one line naming the key. Schema::

    name = "..."                 description = "..."          seed = 0
    [run]       duration_s, dt_s, sample_period_s, control = "rwa" | "rcs"
    [truth]     model = "models/…toml" (required); optional overrides:
                inertia = {Ixx = …, …}, thrust_n = 0.75 | [one per thruster], tau_delay_s,
                tau_rise_s,
                tau_fall_s (``tau_delay_s = 0`` and ``tau_rise_s = tau_fall_s`` is a first-order
                valve), rwa4_axis = [x, y, z] (unit), external_torque_inertial_nm = [3],
                external_torque_body_nm = [3], external_torque_inertial_rate_nm_s = [3],
                wheel_inertia_scale = 1.0 (true spin inertias = scale × the model file's),
                wheel_inertia_errors = [e_1, …, e_K] (each wheel's own fractional error, in the
                model file's wheel order), wheel_inertia_error_sd = σ (each wheel's error drawn
                ~ N(0, σ²) independently from the scenario's seed, added to the fixed ones):
                true J_k = scale × (1 + e_k) × the model file's,
                wheel_axis_tilt_deg = {RWA1 = [a1, a2], …} (true axes tilted along
                ``spacecraft.wheel_tilt_basis``; the prior model keeps the nominal ones),
                center_of_mass_offset_m = [3] (true centre of mass minus the model file's, m:
                the thrusters' true torques, Feldman & Lee Eq 16)
    [prior]     model = "…" (required)
    [initial]   wheels_on = ["RWA1", …] (required), q = [q1, q2, q3, q4], rates_rad_s = [3],
                wheel_rpm = {RWA1 = …}
    [rwa_controller]  bandwidth_rad_s, damping, believed_axis = {RWA4 = "RWA1" | [x, y, z]}
    [rcs_controller]  deadband_mrad = [3], rate_gain_s, width_gain_s_per_mrad, max_pulse_s,
                      min_off_s, wheel_rate_gain_per_s
    [[slew]]         t_start_s, axis = [3] (unit), angle_deg, rate_mrad_s, accel_mrad_s2
    [[wheel_ramp]]   wheel, t_start_s, target_rpm, torque_nm
    [[deadband]]     t_s, deadband_mrad = [3]
    [[pulse]]        t_on_s, thruster = a thruster of the truth model ("Z1"…"Y4"), width_s
    [noise]     gyro_rad_s, star_tracker_rad, tach_quantum_rpm, tach_noise_rpm,
                gyro_bias_rad_s = [3], gyro_scale_factor = [3]  (ω_meas = (1 + s) ω + b + noise),
                time_tag_jitter_s (sd of each sample's time-tag error, ≤ sample_period_s / 20)
    [flex_mode] freq_hz, damping, coupling = [3] (kg^½ m): one flexible or slosh mode
                (:class:`FlexMode`; off when the section is absent)
    [[window]]  name, t0_s, t1_s      (quiet windows reported in truth.json)
    [leak]      thruster (of the truth model), fraction (0 < f ≤ 1 of the true thrust),
                t_start_s: from ``t_start_s`` on, a constant torque ``f F_k Q[:, k]`` (a
                stuck-open valve leaking ``f`` of thruster ``k``'s thrust, Lee §3.2; off when the
                section is absent)

Thrusters: RCS control (``control = "rcs"``) flies any model whose thrusters can turn it about
each body axis both ways (the sets of :func:`~cassini_bayes.simulate.controllers.thruster_sets`,
from the prior model's geometry); open-loop ``[[pulse]]`` and ``[leak]`` take any thruster of the
truth model; a model without thrusters flies RWA slews only. Wheels: any number;
the RWA controller allocates torque with the pseudo-inverse of the believed axes, and the truth
model's optional ``max_speed_rpm`` / ``max_torque_nm`` limit each wheel.

Bounds (docs/limits.md): a run has at most :data:`MAX_STEPS` integration steps and
:data:`MAX_SAMPLES` telemetry samples; every number is at most :data:`NUMBER_ABS_MAX` in
magnitude; wheel rates at most ``WHEEL_RPM_MAX``, body and slew rates at most ``OMEGA_ABS_MAX``
(the telemetry bounds of :mod:`cassini_bayes.telemetry`), thrust and pulse time constants within
the spacecraft-model ranges of :mod:`cassini_bayes.spacecraft`; ``seed`` in 0 .. 2**63 − 1.

The readers: :mod:`._truth` (``[truth]``, ``[prior]``), :mod:`._sections` (``[run]``,
``[initial]``, the controllers, ``[noise]``, ``[flex_mode]``), :mod:`._events` (the ``[[...]]``
events and ``[leak]``), each on :class:`cassini_bayes._toml.TomlTable`; :mod:`._read` puts them
together; :mod:`._types` holds the results.
"""

from cassini_bayes.simulate.scenario._read import (load_scenario, scenario_from_dict,
                                                   scenario_path)
from cassini_bayes.simulate.scenario._types import (MAX_SAMPLES, MAX_STEPS, NUMBER_ABS_MAX,
                                                    DeadbandChange, FlexMode, Leak, Noise,
                                                    PulseCommand, RcsControl, RwaControl,
                                                    Scenario, Slew, WheelRamp, Window, check_size)

__all__ = ["Slew", "WheelRamp", "DeadbandChange", "PulseCommand", "Noise", "FlexMode", "Window",
           "RwaControl", "RcsControl", "Leak", "Scenario", "load_scenario", "scenario_from_dict",
           "scenario_path", "check_size", "MAX_STEPS", "MAX_SAMPLES", "NUMBER_ABS_MAX"]
