"""One vocabulary of parameter and effect names, shared by the physics, the inference, the
summaries and the report (posterior site names in ``posterior.nc`` and ``summary.json``).

Pure constants: any layer may import this module.
"""

from __future__ import annotations

__all__ = ["axis_label", "INERTIA_NAMES", "THRUSTER_NAMES", "F_NAMES", "TAU_NAMES", "U4_NAMES",
           "COM_NAMES", "INERTIA_NOISE_NAMES", "EFFECTS", "FLEX_CHOICES", "THRUST_MODES",
           "AXIS_METHODS", "AXIS_PRIORS", "WHEEL_ERRORS", "unit_of", "a_kind"]

INERTIA_NAMES = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")
"""Inertia-tensor entries (kg m²), in the order of every ``π`` vector."""
THRUSTER_NAMES = ("Z1", "Z2", "Z3", "Z4", "Y1", "Y2", "Y3", "Y4")
"""Cassini's eight A-branch RCS thrusters (Feldman & Lee 2006 Eq 16 order): the expansion of the
model file's ``[thrusters]`` shorthand, the thrust fit's sites and the default file layout
without a model (a model file names its own thrusters, docs/model_file.md)."""
F_NAMES = ("F",) + tuple(f"F_{t}" for t in THRUSTER_NAMES)
"""Thrust sites (N): the mean ``F`` and one per thruster (the branch sites are ``F_Z``, ``F_Y``)."""
TAU_NAMES = ("tau_delay", "tau_rise", "tau_fall")
"""Pulse time constants (s)."""
U4_NAMES = ("u4_x", "u4_y", "u4_z")
"""Components of the solved wheel's spin axis (body axes)."""
COM_NAMES = ("com_x", "com_y", "com_z")
"""The per-thruster thrust model's centre-of-mass offset, m: the true centre of mass minus the
model file's (``[center_of_mass]``), body axes."""
INERTIA_NOISE_NAMES = ("sigma_omega", "sigma_rho", "sigma_theta")
"""White-noise levels of the inertia model: gyro (rad/s), wheel rate (rad/s), attitude (rad)."""
EFFECTS = {"gyro_bias": "gyro_bias", "gyro_scale": "gyro_scale",
           "wheel_inertia": "wheel_scale", "wheel_inertia_common": "wheel_scale_common",
           "wheel_axes": "wheel_tilt", "body_torque": "T_body",
           "inertial_torque": "T_inertial", "torque_rate": "T_N_rate",
           "flex_mode": "flex_inertia"}
"""Robust nuisance effect → its posterior site name."""
FLEX_CHOICES = ("check", "model", "off")
"""The thrust fit's flexible mode: searched for and judged (an adequacy check), searched for and
integrated out where found, or neither."""
THRUST_MODES = ("mean", "branch", "thruster")
"""The thrust fit's sites: one mean thrust, one per branch, or one per thruster."""
AXIS_METHODS = ("rcs", "rwa")
"""The wheel-axis calibration's methods: Brown §III.B (a spin-up while the RCS holds the
attitude) and §III.C (slews under wheel control)."""
AXIS_PRIORS = ("uniform", "cone")
"""The wheel-axis prior: uniform on the sphere, or the model file's cone."""
WHEEL_ERRORS = ("per_wheel", "common")
"""The robust models' wheel spin-inertia errors: one scale per wheel, or one common scale."""


def unit_of(name: str) -> str | None:
    """SI unit of a calibration parameter's site (``"kg m^2"``, ``"N"``, ``"s"``, ``"m"``, ``"1"``
    for the axis components); ``None`` for any other site."""
    if name in INERTIA_NAMES:
        return "kg m^2"
    if name == "F" or name.startswith("F_"):   # F, F_Z1 … F_Y4, the branch sites F_Z, F_Y
        return "N"
    if name in TAU_NAMES:
        return "s"
    if name in U4_NAMES:
        return "1"
    if name in COM_NAMES:
        return "m"
    return None



def a_kind(kind: str) -> str:
    """A run kind as a message says it, with its article: ``"an inertia"``, ``"a thrust"``,
    ``"an RWA4"`` (then ``f"{a_kind(k)} fit"``)."""
    from cassini_bayes.errors import with_article

    return with_article("RWA4" if kind == "rwa4" else str(kind))


def axis_label(v, digits: int = 4) -> str:
    """``+Z`` (or ``−X`` …) for a body axis of either sign, else the vector to ``digits``
    significant figures: how verdicts and reports name a cone axis."""
    import numpy as np   # here: the command line imports names.py before it needs NumPy

    v = np.asarray(v, float)
    for k, c in enumerate("XYZ"):
        for sign, mark in ((1.0, "+"), (-1.0, "−")):
            if np.allclose(v, sign * np.eye(3)[k], atol=1e-9):
                return mark + c
    return "[" + ", ".join(f"{x:.{digits}g}" for x in v) + "]"
