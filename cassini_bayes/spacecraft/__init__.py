"""Spacecraft model objects, loaded and validated from the TOML files under ``models/``.

A model file (docs/model_file.md) describes any spacecraft: the *predicted* mass properties and
the hardware geometry a calibration needs. Required: ``[inertia]`` and at least one ``[[wheel]]``.
Thrusters are ``[[thruster]]`` entries (name, position, direction, optional ``F`` and ``branch``)
or Cassini's ``[thrusters]`` shorthand (the lever arms of Feldman & Lee Eq 16, expanded to its
eight entries); a spacecraft without thrusters has neither, nor ``[thrust]`` or ``[pulse]``.
Optional sections: ``[mass]``, ``[center_of_mass]``, ``[pulse]`` (thruster time constants, their
manufacturer ranges and ``tau_log_sd_min``, the smallest log sd of the thrust fit's rise and fall
priors), ``[thrust]`` (predicted force), ``[gyro]`` and ``[wheel_knowledge]`` (the knowledge of
the sensors and wheels, the priors of the robust models' nuisance parameters; :class:`Knowledge`).
Unknown keys are errors, so a typo never goes unnoticed.

Units: kg m² for inertias, m for lengths, s for time constants, N for thrust, rpm and N m for the
optional wheel limits. Wheel axes and thrust directions are unit vectors in body axes.

The model types are in ``_model``, the hardware geometry and Cassini's thruster shorthand in
``_geometry``, the file reader and its physical ranges in ``_read``; this module re-exports
their public names.
"""

from __future__ import annotations

from cassini_bayes.spacecraft._geometry import (  # noqa: F401 - re-exported
    CASSINI_T as CASSINI_T,
)
from cassini_bayes.spacecraft._geometry import (
    CASSINI_WHEEL_AXES as CASSINI_WHEEL_AXES,
)
from cassini_bayes.spacecraft._geometry import (
    QUIET_WHEEL_TOL_RPM as QUIET_WHEEL_TOL_RPM,
)
from cassini_bayes.spacecraft._geometry import (
    Thruster as Thruster,
)
from cassini_bayes.spacecraft._geometry import (
    Wheel as Wheel,
)
from cassini_bayes.spacecraft._geometry import (
    WheelCone as WheelCone,
)
from cassini_bayes.spacecraft._geometry import (
    eq16_moment_matrix as eq16_moment_matrix,
)
from cassini_bayes.spacecraft._geometry import (
    eq16_thrusters as eq16_thrusters,
)
from cassini_bayes.spacecraft._geometry import (
    moment_matrix as moment_matrix,
)
from cassini_bayes.spacecraft._geometry import (
    tilted_axis as tilted_axis,
)
from cassini_bayes.spacecraft._geometry import (
    wheel_tilt_basis as wheel_tilt_basis,
)
from cassini_bayes.spacecraft._model import (  # noqa: F401 - re-exported
    COM_SD_DEFAULT_FRAC as COM_SD_DEFAULT_FRAC,
)
from cassini_bayes.spacecraft._model import (
    WHEEL_SPEED_NOMINAL_RPM as WHEEL_SPEED_NOMINAL_RPM,
)
from cassini_bayes.spacecraft._model import (
    Knowledge as Knowledge,
)
from cassini_bayes.spacecraft._model import (
    PulseConstants as PulseConstants,
)
from cassini_bayes.spacecraft._model import (
    Spacecraft as Spacecraft,
)
from cassini_bayes.spacecraft._read import (  # noqa: F401 - re-exported
    INERTIA_MAX as INERTIA_MAX,
)
from cassini_bayes.spacecraft._read import (
    INERTIA_MIN as INERTIA_MIN,
)
from cassini_bayes.spacecraft._read import (
    LENGTH_MAX as LENGTH_MAX,
)
from cassini_bayes.spacecraft._read import (
    MASS_MAX as MASS_MAX,
)
from cassini_bayes.spacecraft._read import (
    POI_DEFAULT_FRAC as POI_DEFAULT_FRAC,
)
from cassini_bayes.spacecraft._read import (
    TAU_LOG_SD_MAX as TAU_LOG_SD_MAX,
)
from cassini_bayes.spacecraft._read import (
    TAU_MAX as TAU_MAX,
)
from cassini_bayes.spacecraft._read import (
    THRUST_MAX as THRUST_MAX,
)
from cassini_bayes.spacecraft._read import (
    TORQUE_HOLD_MIN_S as TORQUE_HOLD_MIN_S,
)
from cassini_bayes.spacecraft._read import (
    WHEEL_INERTIA_RANGE as WHEEL_INERTIA_RANGE,
)
from cassini_bayes.spacecraft._read import (
    WHEEL_SPEED_MAX_RPM as WHEEL_SPEED_MAX_RPM,
)
from cassini_bayes.spacecraft._read import (
    WHEEL_TORQUE_MAX_NM as WHEEL_TORQUE_MAX_NM,
)
from cassini_bayes.spacecraft._read import (
    check_physical_inertia as check_physical_inertia,
)
from cassini_bayes.spacecraft._read import (
    load_spacecraft as load_spacecraft,
)
from cassini_bayes.spacecraft._read import (
    spacecraft_from_dict as spacecraft_from_dict,
)

__all__ = ["Wheel", "WheelCone", "Thruster", "PulseConstants", "Knowledge", "Spacecraft",
           "wheel_tilt_basis", "WHEEL_SPEED_NOMINAL_RPM", "QUIET_WHEEL_TOL_RPM",
           "tilted_axis", "load_spacecraft", "eq16_thrusters", "moment_matrix",
           "eq16_moment_matrix",
           "spacecraft_from_dict", "CASSINI_WHEEL_AXES"]
