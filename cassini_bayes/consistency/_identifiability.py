"""Check 5: identifiability for the fit asked for (inertia excitation, the RWA4 method).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cassini_bayes.errors import InputError, UnidentifiableError, arg
from cassini_bayes.physics.momentum import INERTIA_NAMES
from cassini_bayes.telemetry import (
    RPM_TO_RAD_S,
    Telemetry,
    white_noise_sd,
)

# Thresholds (margins measured in docs/input_checks.md)

EXCITATION_MIN = 1e-3
"""Second-largest over largest eigenvalue of ``Σ ω ωᵀ dt``: below it the slews turn the
spacecraft about one axis only."""
RWA_METHOD_MIN_KNOWN = 2
"""The RWA method (Brown Eq 3) needs this many running wheels besides the one solved for."""
CONTROL_WHEEL_RPM = 10.0
"""A wheel whose rate changes by more than this (rpm) over the record takes part in the control
(a rate: a wheel sized to its spacecraft exchanges hundreds of rpm in a slew, whatever the size)
…"""
CONTROL_NOISE_SD = 10.0
"""… and by more than this many times its own white noise (the range of white noise over
thousands of samples is ~8 sd: a CubeSat's 1-rpm hall sensors)."""


def inertia_excitation(tels: Sequence[Telemetry]) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues (ascending, rad² s) and eigenvectors of ``Σ ω ωᵀ dt`` over all files.

    The momentum balance sees the inertia only through ``I ω`` (Feldman & Lee Eq 10): rotation
    about a single unit axis ``e`` determines ``I e`` (three of the six entries' combinations)
    and nothing else.
    """
    m = np.zeros((3, 3))
    for tel in tels:
        w = np.asarray(tel.omega, float)
        dt = np.gradient(np.asarray(tel.t, float)) if tel.n > 1 else np.ones(tel.n)
        m += np.einsum("n,ni,nj->ij", dt, w, w)
    return np.linalg.eigh(m)


def check_inertia_excitation(tels: Sequence[Telemetry]) -> None:
    """Raise :class:`UnidentifiableError` when the slews turn the spacecraft about one axis only.

    The ratio of the second-largest to the largest eigenvalue of :func:`inertia_excitation`
    below :data:`EXCITATION_MIN` means all rotation is about one axis ``e``; only ``I e`` is
    learnable (the posterior of the rest is the prior, and the sampler does not converge on
    that ridge). A weak second or third axis is the inertia fit's own "weakly identified"
    warning.
    """
    vals, vecs = inertia_excitation(tels)
    if not vals[-1] > 0 or vals[1] / vals[-1] >= EXCITATION_MIN:
        return
    e = vecs[:, -1] * np.sign(vecs[np.argmax(np.abs(vecs[:, -1])), -1])
    src = ", ".join(t.source for t in tels)
    axis = int(np.argmax(np.abs(e)))
    if abs(e[axis]) > 0.99:
        learn = {0: ("Ixx", "Ixy", "Ixz"), 1: ("Ixy", "Iyy", "Iyz"), 2: ("Ixz", "Iyz", "Izz")}[axis]
        lost = [n for n in INERTIA_NAMES if n not in learn]
        about = f"body {'XYZ'[axis]}"
        what = (f"{', '.join(lost)} cannot be learned from them (only {', '.join(learn)})")
    else:
        about = f"the body axis [{e[0]:.2f}, {e[1]:.2f}, {e[2]:.2f}]"
        what = "only the three combinations I·e of the six entries can be learned"
    raise UnidentifiableError(f"{src}: the slews turn the spacecraft about {about} only "
                              f"(second axis {vals[1] / vals[-1]:.1e} of the first in Σ ω ωᵀ dt); "
                              f"{what}; add slews about other axes")


def check_rwa4_method(tel: Telemetry, method: str, wheel: str = "RWA4") -> None:
    """Refuse data that the chosen RWA4 method cannot use.

    * ``rwa`` (Brown Eq 3): the slews are carried by the other wheels, whose momentum is known;
      with fewer than :data:`RWA_METHOD_MIN_KNOWN` of them running the data hold no RWA slew
      pairs (RCS-controlled drift).
    * ``rcs`` (Brown Eq 1): under RCS control the body drift takes up the wheel's momentum and
      the thrusters hold the attitude. When at least :data:`RWA_METHOD_MIN_KNOWN` other wheels
      run and change by more than :data:`CONTROL_WHEEL_RPM` (and :data:`CONTROL_NOISE_SD` ×
      their white noise) while no thruster fires (``on_*``
      columns flat or absent), the wheels carry the attitude control: RWA-controlled data.
    """
    others = [n for n in tel.active_wheels() if n.upper() != wheel.upper()]
    if method == "rwa" and len(others) < RWA_METHOD_MIN_KNOWN:
        running = ", ".join(tel.active_wheels()) or "none"
        raise InputError(f"{arg('method', 'rwa')} needs RWA slew pairs, carried by at least "
                         f"{RWA_METHOD_MIN_KNOWN} wheels besides {wheel} (Brown Eq 3), but the "
                         f"wheels running are {running}: this looks like RCS-controlled data; "
                         f"use {arg('method', 'rcs')}", path=tel.source)
    if method != "rcs" or len(others) < RWA_METHOD_MIN_KNOWN:
        return
    fired = tel.on_times is not None and bool(np.any(np.diff(tel.on_times, axis=0) > 0))
    span = {n: float(np.ptp(tel.wheel_rate(n))) / RPM_TO_RAD_S for n in others}
    noise = {n: white_noise_sd(np.asarray(tel.wheel_rate(n), float)) / RPM_TO_RAD_S
             for n in others}
    varying = [n for n, v in span.items()
               if v > max(CONTROL_WHEEL_RPM, CONTROL_NOISE_SD * noise[n])]
    if not fired and len(varying) >= RWA_METHOD_MIN_KNOWN:
        spans = ", ".join(f"{n} {span[n]:.0f} rpm" for n in varying)
        raise InputError(f"{arg('method', 'rcs')} needs RCS-controlled data (Brown Eq 1: the "
                         "body drifts, thrusters fire), but no thruster fires and the other "
                         f"wheels carry the control (they change by {spans}): these are "
                         "RWA-controlled "
                         f"slews; use {arg('method', 'rwa')}", path=tel.source)
