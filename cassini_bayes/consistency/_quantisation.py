"""Check 4: body or wheel rates quantised coarsely against their noise and excursion (a warning).
"""

from __future__ import annotations

import warnings
from typing import NamedTuple

import numpy as np

from cassini_bayes.telemetry import (
    RPM_TO_RAD_S,
    Telemetry,
    white_noise_sd,
)

# Thresholds (margins measured in docs/input_checks.md)

QUANTUM_LATTICE_TOL = 1e-3
"""Values lie on a lattice of spacing ``q`` when every difference between two distinct values is
a whole multiple of ``q`` to within this fraction of ``q`` (text round trips and the rpm → rad/s
conversion leave ~1e-12)."""
QUANTUM_NOISE_RATIO = 4.0
"""A rate column's quantum is not hidden in its noise when it is at least this many times the
white-noise sd estimated from the column: a quantiser its noise dithers shows a sd of about
0.6 q, an undithered one 0, so the ratio is below 2 or infinite (docs/input_checks.md §2d)."""
QUANTUM_EXCURSION_MIN = 5e-4
"""... and it is large against the signal when it is at least this fraction of the column's
excursion (its 0.5–99.5 percentile range): undithered quanta from about this fraction on moved
an inertia fit by two posterior sd (docs/input_checks.md)."""


class QuantisedRatesWarning(UserWarning):
    """Body or wheel rates quantised coarsely against their noise and their excursion."""


class RateQuantum(NamedTuple):
    """A rate column on a lattice: ``column`` (``wx`` … ``rwa4``), its ``quantum``, the white-noise
    sd measured in it (``noise``) and its ``excursion`` (0.5–99.5 percentile range, the whole
    range where that is 0), all rad/s;
    ``large``: the quantum is at least :data:`QUANTUM_NOISE_RATIO` × the noise and
    :data:`QUANTUM_EXCURSION_MIN` × the excursion."""

    column: str
    quantum: float
    noise: float
    excursion: float

    @property
    def large(self) -> bool:
        return (self.quantum >= QUANTUM_NOISE_RATIO * self.noise
                and self.quantum >= QUANTUM_EXCURSION_MIN * self.excursion)

    def text(self) -> str:
        """``rwa1 1 rpm (its measured noise 0, 0.088 % of its excursion)``: the quantum in the
        column's file unit, the noise measured in it in quanta, the quantum against the
        excursion."""
        unit, scale = (("rpm", 1.0 / RPM_TO_RAD_S) if self.column.startswith("rwa")
                       else ("rad/s", 1.0))
        return (f"{self.column} {self.quantum * scale:.3g} {unit} (its measured noise "
                f"{self.noise / self.quantum:.2g} quanta, {100 * self.quantum / self.excursion:.2g}"
                " % of its excursion)")


def rate_quantum(x: np.ndarray) -> float | None:
    """The spacing ``q`` of the lattice the finite values of ``x`` lie on: the smallest gap
    between distinct values, when every gap is a whole multiple of it (to
    :data:`QUANTUM_LATTICE_TOL`); ``None`` when the values are not on a lattice or all equal."""
    u = np.unique(np.asarray(x, float)[np.isfinite(x)])
    if u.size < 2:
        return None
    gaps = np.diff(u)
    q = float(gaps.min())
    k = gaps / q
    return q if float(np.max(np.abs(k - np.round(k)))) <= QUANTUM_LATTICE_TOL else None


def quantised_rates(tel: Telemetry) -> tuple[RateQuantum, ...]:
    """Every body-rate column and every active wheel's column (rad/s) that lies on a lattice."""
    cols = [(name, np.asarray(tel.omega[:, i], float)) for i, name in enumerate(("wx", "wy", "wz"))]
    cols += [(name.lower(), np.asarray(tel.wheel_rate(name), float))
             for name in tel.active_wheels()]
    out = []
    for name, x in cols:
        q = rate_quantum(x)
        if q is None:
            continue
        finite = x[np.isfinite(x)]
        lo, hi = np.percentile(finite, [0.5, 99.5])
        excursion = float(hi - lo) if hi > lo else float(np.ptp(finite))
        out.append(RateQuantum(name, q, white_noise_sd(x), excursion))
    return tuple(out)


def check_rate_quantisation(tel: Telemetry) -> tuple[RateQuantum, ...]:
    """Warn (:class:`QuantisedRatesWarning`) when a rate column is quantised coarsely: its
    quantum is at least :data:`QUANTUM_NOISE_RATIO` × the noise measured in it (the rounding is
    not dithered by noise, so its error repeats while the rate holds its value instead of being
    the white noise the fits model) and at least :data:`QUANTUM_EXCURSION_MIN` × its excursion
    (large against the signal). A warning, not a refusal: the file holds no finer rates, and the
    fits' estimates move by up to several posterior sd (docs/input_checks.md). Returns every
    quantised column."""
    found = quantised_rates(tel)
    large = [r for r in found if r.large]
    if large:
        warnings.warn(f"{tel.source}: rates on a coarse lattice: "
                      + "; ".join(r.text() for r in large)
                      + ": with no noise to dither the rounding, its error repeats while a rate "
                      "holds its value, which the fits do not model, so their estimates can move "
                      "by several posterior sd; give the rates at finer resolution if there are "
                      "any",
                      QuantisedRatesWarning, stacklevel=2)
    return found
