"""The convergence rule of every fit, and the one type that carries its verdict.

A fit converged when its largest rank-normalised split R-hat is at most :data:`R_HAT_MAX`, its
smallest bulk effective sample size at least :data:`ESS_BULK_MIN`, and no transition diverged
(Vehtari et al. 2021: R-hat ≤ 1.01 and 100 effective draws per chain for 4 chains). The fit
writes the verdict to ``summary.json`` (:meth:`Diagnostics.to_dict`); the report recomputes it
from ``posterior.nc`` by the same rule (:func:`converged`).

Pure: no ArviZ, no JAX (the report imports it without either).
"""

from __future__ import annotations

import math
from typing import NamedTuple

__all__ = ["ESS_BULK_MIN", "R_HAT_MAX", "Diagnostics", "converged"]

R_HAT_MAX = 1.01
"""Largest rank-normalised split R-hat of a converged fit (Vehtari et al. 2021)."""
ESS_BULK_MIN = 400.0
"""Smallest bulk effective sample size of a converged fit: 100 per chain for 4 chains (Vehtari
et al. 2021)."""


def converged(max_r_hat: float, min_ess_bulk: float, divergences: int) -> bool:
    """The rule (module docstring); a NaN R-hat or ESS (one chain, constant draws) fails it."""
    return bool(math.isfinite(max_r_hat) and max_r_hat <= R_HAT_MAX
                and math.isfinite(min_ess_bulk) and min_ess_bulk >= ESS_BULK_MIN
                and divergences == 0)


class Diagnostics(NamedTuple):
    """Convergence diagnostics of a fit over the parameters it judges.

    divergences : divergent transitions after warm-up, all chains.
    max_r_hat : largest rank-normalised split R-hat.
    min_ess_bulk, min_ess_tail : smallest bulk / tail effective sample size.
    converged : the rule (:func:`converged`).
    worst : the parameter (element) with the largest R-hat, for messages.
    """

    divergences: int
    max_r_hat: float
    min_ess_bulk: float
    min_ess_tail: float
    converged: bool
    worst: str

    @classmethod
    def judge(cls, divergences: int, max_r_hat: float, min_ess_bulk: float,
              min_ess_tail: float, worst: str = "") -> Diagnostics:
        """The diagnostics with their verdict by the rule."""
        return cls(int(divergences), float(max_r_hat), float(min_ess_bulk), float(min_ess_tail),
                   converged(max_r_hat, min_ess_bulk, divergences), worst)

    def to_dict(self) -> dict[str, int | float | bool]:
        """The ``diagnostics`` entry of ``summary.json`` (docs/design.md §4.5)."""
        return {"divergences": int(self.divergences), "max_r_hat": float(self.max_r_hat),
                "min_ess_bulk": float(self.min_ess_bulk), "min_ess_tail": float(self.min_ess_tail),
                "converged": bool(self.converged)}

    def message(self) -> str:
        """One line saying what failed (empty when converged)."""
        bad = []
        if not (self.max_r_hat <= R_HAT_MAX):           # (NaN fails too)
            bad.append(f"max R-hat {self.max_r_hat:.3f} > {R_HAT_MAX} ({self.worst})")
        if not (self.min_ess_bulk >= ESS_BULK_MIN):
            bad.append(f"min bulk ESS {self.min_ess_bulk:.0f} < {ESS_BULK_MIN:.0f}")
        if self.divergences:
            bad.append(f"{self.divergences} divergent transitions")
        return "; ".join(bad)
