"""Telemetry and pulse logs: containers, readers, writers, validation (docs/design.md §4.1-4.2).

SI inside: wheel rates are rad/s in :class:`Telemetry` (rpm only in files). Every problem with a
file is an :class:`~cassini_bayes.errors.InputError` with one line naming the file, the column
and/or the data row (1-based, header not counted, with its ``t``) and what to do about it.

One idea a module; import the names from here:

- ``_types``: :class:`Telemetry`, :class:`PulseLog`;
- :mod:`~cassini_bayes.telemetry.limits`: the validation rules, their tolerances and bounds;
- ``_layout``: the columns of a file, named by the spacecraft model;
- ``_tables``: CSV and Parquet tables parsed to floats, with one-line errors;
- ``_validate``: :func:`validate_telemetry` (arrays, shared by the readers and in-memory data);
- ``_files``: :func:`read_telemetry`, :func:`read_telemetry_many`, :func:`write_telemetry`;
- ``_pulses``: pulse logs, the telemetry span, cumulative on-times;
- ``_noise``: :func:`white_noise_sd`, the package's one white-noise estimator;
- ``_stale``: stale samples (a packet repeating its neighbour's data), found and left out.
"""

from cassini_bayes.names import THRUSTER_NAMES as THRUSTER_NAMES
from cassini_bayes.telemetry import limits as limits
from cassini_bayes.telemetry._files import _write_frame as _write_frame
from cassini_bayes.telemetry._files import check_model_names as check_model_names
from cassini_bayes.telemetry._files import read_telemetry as read_telemetry
from cassini_bayes.telemetry._files import read_telemetry_many as read_telemetry_many
from cassini_bayes.telemetry._files import write_telemetry as write_telemetry
from cassini_bayes.telemetry._noise import RATE_NOISE_FLOORS as RATE_NOISE_FLOORS
from cassini_bayes.telemetry._noise import white_noise_sd as white_noise_sd
from cassini_bayes.telemetry._pulses import PulseAtStartWarning as PulseAtStartWarning
from cassini_bayes.telemetry._pulses import PulsesDroppedWarning as PulsesDroppedWarning
from cassini_bayes.telemetry._pulses import PulseSpanWarning as PulseSpanWarning
from cassini_bayes.telemetry._pulses import check_pulses_in_span as check_pulses_in_span
from cassini_bayes.telemetry._pulses import cumulative_on_times as cumulative_on_times
from cassini_bayes.telemetry._pulses import pulses_in_span as pulses_in_span
from cassini_bayes.telemetry._pulses import read_pulses as read_pulses
from cassini_bayes.telemetry._pulses import validate_pulses as validate_pulses
from cassini_bayes.telemetry._pulses import with_on_times as with_on_times
from cassini_bayes.telemetry._pulses import write_pulses as write_pulses
from cassini_bayes.telemetry._stale import StaleSamplesWarning as StaleSamplesWarning
from cassini_bayes.telemetry._stale import stale_samples as stale_samples
from cassini_bayes.telemetry._stale import without_stale_samples as without_stale_samples
from cassini_bayes.telemetry._tables import _fail_nonfinite as _fail_nonfinite
from cassini_bayes.telemetry._tables import _read_numeric_csv as _read_numeric_csv
from cassini_bayes.telemetry._types import IDLE_NOISE_SD as IDLE_NOISE_SD
from cassini_bayes.telemetry._types import IDLE_RPM as IDLE_RPM
from cassini_bayes.telemetry._types import WHEEL_NAMES as WHEEL_NAMES
from cassini_bayes.telemetry._types import PulseLog as PulseLog
from cassini_bayes.telemetry._types import Telemetry as Telemetry
from cassini_bayes.telemetry._validate import _check_time as _check_time
from cassini_bayes.telemetry._validate import _turn_angle as _turn_angle
from cassini_bayes.telemetry._validate import validate_telemetry as validate_telemetry
from cassini_bayes.telemetry.limits import MAX_ROWS as MAX_ROWS
from cassini_bayes.telemetry.limits import MIN_SAMPLE_SPACING_S as MIN_SAMPLE_SPACING_S
from cassini_bayes.telemetry.limits import OMEGA_ABS_MAX as OMEGA_ABS_MAX
from cassini_bayes.telemetry.limits import OMEGA_MAX as OMEGA_MAX
from cassini_bayes.telemetry.limits import PULSE_WIDTH_MAX as PULSE_WIDTH_MAX
from cassini_bayes.telemetry.limits import QUAT_NORM_TOL as QUAT_NORM_TOL
from cassini_bayes.telemetry.limits import RAD_S_SUSPECT_MAX as RAD_S_SUSPECT_MAX
from cassini_bayes.telemetry.limits import TIME_ABS_MAX as TIME_ABS_MAX
from cassini_bayes.telemetry.limits import WHEEL_RPM_MAX as WHEEL_RPM_MAX
from cassini_bayes.units import RPM_TO_RAD_S as RPM_TO_RAD_S

# The underscore names imported above (_write_frame, _read_numeric_csv, _fail_nonfinite,
# _check_time, _turn_angle) are not public: the trajectory reader (cassini_bayes.ivp.trajectory)
# reads and writes its CSV by the telemetry's table rules, and the physics checks measure turns
# as validation does.
__all__ = [
    "IDLE_NOISE_SD",
    "IDLE_RPM",
    "MAX_ROWS",
    "MIN_SAMPLE_SPACING_S",
    "OMEGA_ABS_MAX",
    "OMEGA_MAX",
    "PULSE_WIDTH_MAX",
    "QUAT_NORM_TOL",
    "RAD_S_SUSPECT_MAX",
    "RATE_NOISE_FLOORS",
    "RPM_TO_RAD_S",
    "THRUSTER_NAMES",
    "TIME_ABS_MAX",
    "WHEEL_NAMES",
    "WHEEL_RPM_MAX",
    "PulseAtStartWarning",
    "PulseLog",
    "PulseSpanWarning",
    "PulsesDroppedWarning",
    "StaleSamplesWarning",
    "Telemetry",
    "check_model_names",
    "check_pulses_in_span",
    "cumulative_on_times",
    "limits",
    "pulses_in_span",
    "read_pulses",
    "read_telemetry",
    "read_telemetry_many",
    "stale_samples",
    "validate_pulses",
    "validate_telemetry",
    "without_stale_samples",
    "white_noise_sd",
    "with_on_times",
    "write_pulses",
    "write_telemetry",
]
