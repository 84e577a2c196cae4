"""Unit and convention checks that use the physics in the data, not magnitude thresholds.

A file can pass every rule of :mod:`cassini_bayes.telemetry` and still be read wrongly: wheel
rates written in rad/s where the format wants rpm, a quaternion written scalar-first or
conjugated, a pulse log that does not belong to the telemetry's own ``on_*`` columns, or data
that cannot identify what a fit asks for. Each such mistake gives a wrong answer, not a crash, so
each is refused here (:class:`~cassini_bayes.errors.InputError`, one line naming the file and the
likely cause) from relations the data must obey whatever the unit of a column:

1. **Attitude vs body rates** (:func:`attitude_rate_agreement`). Consecutive attitudes are tied to
   the gyro rates by the kinematics ``q̇ = ½ Ω(ω) q`` (Brown Eq 2 convention,
   :mod:`cassini_bayes.frames`): the rotation from ``q(t_a)`` to ``q(t_b)`` is the integrated body
   rate. Over stretches where the attitude turns measurably the quaternion rotation vectors are
   compared with ``∫ω dt`` under four readings of the columns (as declared; scalar first;
   conjugated; both) by their alignment (the cosine between the stacked vectors, 1 for a perfect
   fit, near 0 or negative for a wrong reading) and, for the declared reading, their ratio (the
   body-rate unit: 57.3 for °/s).
2. **Wheel units, signs and order vs momentum conservation** (:func:`wheel_momentum_scale`).
   Between thruster firings the inertial momentum ``A(q)ᵀ (I ω + Σ J_k ρ_k g_k)`` changes only
   by the external torque's impulse (Feldman & Lee Eqs 2-3; a constant torque is fitted). With
   the model's predicted inertia (known to ±10 %) the balance is fitted with the wheel momentum
   times a free scale ``κ``: ``κ ≈ 1`` for rpm as the file format wants, ``κ ≈ 60/(2π) = 9.55``
   when the wheel columns hold rad/s (the wheel momentum read ×0.105). Where slews about several
   axes separate the wheels, it is fitted again with a free momentum vector per wheel
   (:class:`WheelAxes`): each must lie along its wheel's axis in the model (a flipped sign gives
   the opposite direction, swapped columns another wheel's axis).
3. **Pulse log vs ``on_*`` columns** (:func:`check_pulses_match_on_times`): the cumulative
   on-time the pulse log implies (:func:`cassini_bayes.telemetry.cumulative_on_times`) must match
   the telemetry's own counters.
4. **Quantised rates** (:func:`check_rate_quantisation`, a warning): a body-rate or wheel-rate
   column whose values lie on a lattice ``q k`` with a quantum ``q`` far above the noise
   measured in the column and not small against the column's excursion; its rounding error is
   then no noise the fits model but an error that repeats while the rate holds its value.
5. **Identifiability for the fit asked for** (:func:`check_inertia_excitation`,
   :func:`check_rwa4_method`): an inertia fit needs rotation about more than one body axis; the
   RWA method of the RWA4 calibration needs the wheels that carry the slews (Brown Eq 3).

Each check is one private module with its thresholds beside it (``_attitude``, ``_gyro_bias``,
``_quantisation``, ``_momentum``, ``_pulses``, ``_identifiability``; the entry points in
``_commands``); import the names from here. The margins of the thresholds, measured on every
scenario in ``experiments/scenarios/`` and on corrupted copies, are in ``docs/input_checks.md``.
A check whose statistic is not identifiable from the data (no rotation, no momentum exchange)
says nothing.

The entry points called by the CLI right after reading the inputs are
:func:`check_telemetry_data` (``cassini-bayes check``), :func:`check_inertia_data`,
:func:`check_thrust_data` and :func:`check_rwa4_data`.
"""

from cassini_bayes.consistency._attitude import READINGS as READINGS
from cassini_bayes.consistency._attitude import AttitudeAgreement as AttitudeAgreement
from cassini_bayes.consistency._attitude import attitude_rate_agreement as attitude_rate_agreement
from cassini_bayes.consistency._attitude import check_attitude_rates as check_attitude_rates
from cassini_bayes.consistency._commands import check_inertia_data as check_inertia_data
from cassini_bayes.consistency._commands import check_rwa4_data as check_rwa4_data
from cassini_bayes.consistency._commands import check_telemetry_data as check_telemetry_data
from cassini_bayes.consistency._commands import check_thrust_data as check_thrust_data
from cassini_bayes.consistency._gyro_bias import GyroBias as GyroBias
from cassini_bayes.consistency._gyro_bias import GyroBiasWarning as GyroBiasWarning
from cassini_bayes.consistency._gyro_bias import check_gyro_bias as check_gyro_bias
from cassini_bayes.consistency._gyro_bias import gyro_bias_estimate as gyro_bias_estimate
from cassini_bayes.consistency._identifiability import (
    check_inertia_excitation as check_inertia_excitation,
)
from cassini_bayes.consistency._identifiability import check_rwa4_method as check_rwa4_method
from cassini_bayes.consistency._identifiability import inertia_excitation as inertia_excitation
from cassini_bayes.consistency._momentum import AXES_CONDITION_MIN as AXES_CONDITION_MIN
from cassini_bayes.consistency._momentum import MOMENTUM_ALIGN_MIN as MOMENTUM_ALIGN_MIN
from cassini_bayes.consistency._momentum import MomentumScale as MomentumScale
from cassini_bayes.consistency._momentum import WheelAxes as WheelAxes
from cassini_bayes.consistency._momentum import axis_angle_max_deg as axis_angle_max_deg
from cassini_bayes.consistency._momentum import check_wheel_units as check_wheel_units
from cassini_bayes.consistency._momentum import wheel_momentum_scale as wheel_momentum_scale
from cassini_bayes.consistency._pulses import _derived_on_times as _derived_on_times
from cassini_bayes.consistency._pulses import (
    check_pulses_match_on_times as check_pulses_match_on_times,
)
from cassini_bayes.consistency._quantisation import QUANTUM_NOISE_RATIO as QUANTUM_NOISE_RATIO
from cassini_bayes.consistency._quantisation import QuantisedRatesWarning as QuantisedRatesWarning
from cassini_bayes.consistency._quantisation import RateQuantum as RateQuantum
from cassini_bayes.consistency._quantisation import (
    check_rate_quantisation as check_rate_quantisation,
)
from cassini_bayes.consistency._quantisation import quantised_rates as quantised_rates
from cassini_bayes.consistency._quantisation import rate_quantum as rate_quantum

# Not in __all__: the three thresholds (read by tests and docs) and _derived_on_times
# (benchmarks/input_check_margins.py).
__all__ = [
    "READINGS",
    "AttitudeAgreement",
    "GyroBias",
    "GyroBiasWarning",
    "MomentumScale",
    "QuantisedRatesWarning",
    "RateQuantum",
    "WheelAxes",
    "attitude_rate_agreement",
    "axis_angle_max_deg",
    "check_attitude_rates",
    "check_gyro_bias",
    "check_inertia_data",
    "check_inertia_excitation",
    "check_pulses_match_on_times",
    "check_rate_quantisation",
    "check_rwa4_data",
    "check_rwa4_method",
    "check_telemetry_data",
    "check_thrust_data",
    "check_wheel_units",
    "gyro_bias_estimate",
    "inertia_excitation",
    "quantised_rates",
    "rate_quantum",
    "wheel_momentum_scale",
]
