"""Telemetry and pulse-log containers: SI inside (wheel rates in rad/s; rpm only in files).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cassini_bayes.names import THRUSTER_NAMES
from cassini_bayes.telemetry._noise import white_noise_sd
from cassini_bayes.units import RPM_TO_RAD_S

WHEEL_NAMES = ("RWA1", "RWA2", "RWA3", "RWA4")
"""Cassini's wheels: the telemetry's wheel columns ``rwa1 … rwa4`` when no model names others."""
IDLE_RPM = 1.0
"""A wheel whose rate's root mean square is at most this (rpm) is idle, as if off: a wheel sized
to its spacecraft exchanges hundreds of rpm in a slew, so this carries ~1e-3 of a slew's momentum
(docs/model_file.md, "Constants that remain"); tachometer noise about 0 rpm is idle, a wheel
through zero speed is not."""
IDLE_NOISE_SD = 3.0
"""… or whose rms rate is at most this many times its own white noise
(:func:`white_noise_sd`): a coarse tachometer's noise about 0 rpm (a CubeSat's hall sensors,
±1 rpm steps) is idle too."""


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
    on_times : (n, m) cumulative thruster on-times since the first row, s, in the order of
        ``thruster_names``; ``None`` when the file had none.
    source : where the data came from (a file name), for error messages.
    thruster_names : the m thrusters of ``on_times`` (the model's; Cassini's ``Z1 … Y4``).
    """

    t: np.ndarray
    q: np.ndarray
    omega: np.ndarray
    wheel_rates: np.ndarray
    wheel_names: tuple[str, ...] = WHEEL_NAMES
    on_times: np.ndarray | None = None
    source: str = "<telemetry>"
    thruster_names: tuple[str, ...] = THRUSTER_NAMES

    @property
    def n(self) -> int:
        return int(self.t.shape[0])

    def wheel_rate(self, name: str) -> np.ndarray:
        """Rates (rad/s) of one wheel by name."""
        return self.wheel_rates[:, self.wheel_names.index(name.upper())]

    def active_mask(self) -> np.ndarray:
        """(k,) which wheels carry momentum: finite rates whose root mean square exceeds
        :data:`IDLE_RPM` and :data:`IDLE_NOISE_SD` times their white noise. A wheel written as
        0 rpm (or within tachometer noise of it) all along is as good as off: its momentum is
        below the noise, and a wheel the data cannot see must not get a spin-inertia scale of
        its own (it moved the inertia fit by −2.4 %)."""
        rates = np.asarray(self.wheel_rates, float)
        finite = np.isfinite(rates)
        n = finite.sum(axis=0)
        ms = np.where(finite, rates, 0.0) ** 2
        rms = np.sqrt(ms.sum(axis=0) / np.maximum(n, 1))
        noise = np.array([white_noise_sd(rates[:, j]) for j in range(rates.shape[1])])
        return (n > 0) & (rms > np.maximum(IDLE_RPM * RPM_TO_RAD_S, IDLE_NOISE_SD * noise))

    def active_wheels(self) -> tuple[str, ...]:
        """Names of the wheels that carry momentum (:meth:`active_mask`)."""
        return tuple(n for n, on in zip(self.wheel_names, self.active_mask()) if on)

    def slice(self, t0: float, t1: float) -> Telemetry:
        """Rows with ``t0 ≤ t ≤ t1``."""
        m = (self.t >= t0) & (self.t <= t1)
        return Telemetry(self.t[m], self.q[m], self.omega[m], self.wheel_rates[m],
                         self.wheel_names, None if self.on_times is None else self.on_times[m],
                         self.source, self.thruster_names)


@dataclass(frozen=True)
class PulseLog:
    """Thruster pulse commands.

    Attributes
    ----------
    t_on : (p,) command times, s.
    thruster : (p,) thruster indices into ``thruster_names``.
    width : (p,) commanded on-times, s.
    thruster_names : the spacecraft model's thrusters (Cassini's ``Z1 … Y4`` by default).
    """

    t_on: np.ndarray
    thruster: np.ndarray
    width: np.ndarray
    source: str = field(default="<pulses>")
    thruster_names: tuple[str, ...] = THRUSTER_NAMES

    @property
    def names(self) -> list[str]:
        return [self.thruster_names[i] for i in self.thruster]
