"""Tolerances and bounds of telemetry and pulse-log validation, the rules they belong to, and why.

- Columns: ``t q1 q2 q3 q4 wx wy wz`` required; one column per wheel of the spacecraft model,
  named as the wheel in lower case (rpm, optional — absent or entirely empty means the wheel is
  off, NaN inside); ``on_<thruster>`` per thruster of the model (s, optional — when any is
  present, a thruster without a column never fired). Without a model the names are Cassini's
  (``rwa1 … rwa4``, ``on_Z1 … on_Y4``; docs/model_file.md). Header names are matched
  case-insensitively; an unknown or duplicate column is an error (a typo must not silently drop
  data), and a column for a wheel or thruster the model lacks names the model's.
- Values: numbers only; a required cell that is empty, NaN or infinite is an error; a wheel column
  that is empty in some rows but not in others is an error.
- Time: strictly increasing (a duplicate or a step back is an error naming both rows).
- Physical bounds (docs/limits.md), checked whatever ``check_units`` says, so that nothing that
  passes validation can overflow later (differences of ``t``, rate × time products): ``|t| ≤
  TIME_ABS_MAX`` (1e10 s, 317 years: any epoch in seconds, SCLK or J2000, fits) and consecutive
  samples at least ``MIN_SAMPLE_SPACING_S`` (1 µs) apart; wheel rates ``|ρ| ≤ WHEEL_RPM_MAX``
  (10 000 rpm: five times Cassini's ~2000 rpm wheels, which the papers bias to 1800 rpm);
  body rates ``|ω_i| ≤ OMEGA_ABS_MAX`` (5 rad/s, 290 °/s: no spacecraft under attitude control
  turns that fast); quaternion components ``|q_i| ≤ 2`` (before the norm test); cumulative on-times
  ``|on| ≤ TIME_ABS_MAX``; pulse ``|t_on| ≤ TIME_ABS_MAX`` and ``0 < width ≤ PULSE_WIDTH_MAX``
  (3600 s; Cassini's RCS pulses are below a second, its longest RCS burns minutes).
- Size: at most ``MAX_ROWS`` (200 000) data rows per file (telemetry or pulse log) and per fit
  (:func:`~cassini_bayes.telemetry.read_telemetry_many`). Telemetry CSV is parsed to floats in
  chunks of rows and the limit is checked while reading, so memory stays bounded and a huge file
  fails fast (docs/limits.md).
- Quaternion norm: ``|‖q‖ − 1| ≤ QUAT_NORM_TOL`` (1e-3, telemetry rounding) is accepted and the row
  renormalised; a larger deviation is an error. Rows within 1e-12 of unit norm are left bit-exact.
- Quaternion sign: ``q`` and ``−q`` are the same attitude. Sign flips between consecutive rows are
  accepted and removed with the rule of :func:`cassini_bayes.frames.quat_continuous` (a NumPy
  twin here, tested equal), which only ever changes signs, never the attitude — a genuine
  attitude jump passes through unchanged.
- Wheel units: a wheel column is taken to be rad/s (an error) when the wheel is clearly spinning
  (median ``|value| ≥ 1``) yet never exceeds ``RAD_S_SUSPECT_MAX`` = 12 in magnitude — in rpm that
  would be a wheel idling between 1 and 12 rpm for the whole record, which Cassini avoids (wheels
  are biased to hundreds of rpm, away from zero-crossing friction); in rad/s it is any wheel slower
  than 115 rpm. Wheels at rest (noise about zero) and real rpm data over 0-2000 rpm never trip it.
  ``check_units=False`` turns the unit checks off for genuinely slow wheels.
- Body-rate units: ``|ω| > OMEGA_MAX`` (0.2 rad/s = 11.5 °/s, far above any Cassini slew rate of a
  few mrad/s) is taken to be °/s or mrad/s. And where the attitude turns by more than 0.01 rad,
  the body rate integrated up to the first row where the quaternions have turned by
  ``min(0.1 rad, largest turn)`` must not exceed that angle by more than ten times (°/s gives
  57×, mrad/s 1000×; rate noise adds only a random walk, far below ten times the angle).
- Pulse logs: thruster names of the model (Cassini's ``Z1 … Y4`` without one; case-insensitive);
  ``0 < width ≤ PULSE_WIDTH_MAX``; ``t_on`` strictly increasing per thruster and no pulse
  starting before the previous pulse of the same thruster has ended. A header-only pulse log is
  valid (no pulses). Against a telemetry
  (:func:`~cassini_bayes.telemetry.check_pulses_in_span`): a pulse entirely outside the telemetry
  span cannot affect it and is dropped with a
  :class:`~cassini_bayes.telemetry.PulseSpanWarning`; one still on at the last sample is kept
  with a warning (its on-time counts up to that sample); one already on at the first sample is
  kept with a :class:`~cassini_bayes.telemetry.PulseAtStartWarning` (its on-time counts from that
  sample, and the thrust fit models exactly what it delivers after it).
"""

from __future__ import annotations

QUAT_NORM_TOL = 1e-3
"""Largest accepted ``|‖q‖ − 1|``; such rows are renormalised, larger is an error."""
OMEGA_MAX = 0.2
"""Largest plausible body rate, rad/s (11.5 °/s); above it the column is in the wrong unit."""
RAD_S_SUSPECT_MAX = 12.0
"""A spinning wheel (median ``|value| ≥ 1``) never above this magnitude is read as rad/s."""
TIME_ABS_MAX = 1e10
"""Largest ``|t|``, ``|t_on|`` and ``|on_*|``, s (317 years; SCLK and J2000 seconds fit)."""
MIN_SAMPLE_SPACING_S = 1e-6
"""Smallest time between consecutive telemetry samples, s (1 MHz; telemetry is ~1 Hz)."""
WHEEL_RPM_MAX = 1e4
"""Largest wheel-rate magnitude, rpm (five times Cassini's ~2000 rpm wheels)."""
OMEGA_ABS_MAX = 5.0
"""Largest body-rate component magnitude, rad/s, checked even without the unit heuristics."""
MAX_ROWS = 200_000
"""Most data rows of one telemetry file, and of all the files of one fit together: reading and
preparing a fit take memory in proportion to the rows (per-row costs: docs/limits.md). 55 h at
1 Hz; longer records: decimate or split."""
_CHUNK_ROWS = 8192  # CSV rows parsed to floats at a time (bounds the text held in memory)
PULSE_WIDTH_MAX = 3600.0
"""Longest accepted pulse width, s (Cassini's RCS pulses are below a second)."""
_EXACT_NORM = 1e-12  # rows this close to unit norm are left bit-exact
_RATE_RATIO_MAX = 10.0  # |∫ω dt| over the quaternion angle turned above this → wrong unit
_MIN_SWEEP_RAD = 0.01  # the ratio test needs the attitude to move at least this much
