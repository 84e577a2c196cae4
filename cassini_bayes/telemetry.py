"""Telemetry and pulse-log containers (DESIGN.md §4).

SI inside: wheel rates are rad/s in :class:`Telemetry` (rpm only in files). Readers, writers and
validation live beside the containers in this module.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cassini_bayes.physics.impulse import THRUSTER_NAMES

__all__ = ["Telemetry", "PulseLog", "RPM_TO_RAD_S", "WHEEL_NAMES", "THRUSTER_NAMES"]

RPM_TO_RAD_S = 2.0 * np.pi / 60.0
WHEEL_NAMES = ("RWA1", "RWA2", "RWA3", "RWA4")


@dataclass(frozen=True)
class Telemetry:
    """Sampled attitude-control telemetry, SI units.

    Attributes
    ----------
    t : (n,) sample times, s, strictly increasing.
    q : (n, 4) attitude quaternions ``(q1, q2, q3, q4)``, scalar last, inertial → body.
    omega : (n, 3) body rates in body axes, rad/s.
    wheel_rates : (n, k) wheel spin rates about their own axes relative to the body, rad/s;
        a column of NaN is a wheel that is off.
    wheel_names : the k wheel names, matching the spacecraft model's wheels (``RWA1`` …).
    on_times : (n, 8) cumulative thruster on-times since the first row, s, in the order
        ``Z1 … Y4``; ``None`` when the file had none.
    source : where the data came from (a file name), for error messages.
    """

    t: np.ndarray
    q: np.ndarray
    omega: np.ndarray
    wheel_rates: np.ndarray
    wheel_names: tuple[str, ...] = WHEEL_NAMES
    on_times: np.ndarray | None = None
    source: str = "<telemetry>"

    @property
    def n(self) -> int:
        return int(self.t.shape[0])

    def wheel_rate(self, name: str) -> np.ndarray:
        """Rates (rad/s) of one wheel by name."""
        return self.wheel_rates[:, self.wheel_names.index(name.upper())]

    def active_wheels(self) -> tuple[str, ...]:
        """Names of the wheels with any finite rate."""
        return tuple(n for i, n in enumerate(self.wheel_names)
                     if np.any(np.isfinite(self.wheel_rates[:, i])))

    def slice(self, t0: float, t1: float) -> "Telemetry":
        """Rows with ``t0 ≤ t ≤ t1``."""
        m = (self.t >= t0) & (self.t <= t1)
        return Telemetry(self.t[m], self.q[m], self.omega[m], self.wheel_rates[m],
                         self.wheel_names, None if self.on_times is None else self.on_times[m],
                         self.source)


@dataclass(frozen=True)
class PulseLog:
    """Thruster pulse commands.

    Attributes
    ----------
    t_on : (m,) command times, s.
    thruster : (m,) thruster indices 0..7 into ``THRUSTER_NAMES`` (``Z1 … Y4``).
    width : (m,) commanded on-times, s.
    """

    t_on: np.ndarray
    thruster: np.ndarray
    width: np.ndarray
    source: str = field(default="<pulses>")

    @property
    def names(self) -> list[str]:
        return [THRUSTER_NAMES[i] for i in self.thruster]
