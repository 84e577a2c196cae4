"""The result types of the adequacy checks and their thresholds.

See :mod:`cassini_bayes.inference.adequacy`.
"""

from __future__ import annotations

from typing import NamedTuple

from scipy import stats


PRIOR_CONFLICT_SD = 4.0   # prior sd between the posterior mean and the prior mean
Z_THRESHOLD = 4.0         # normal deviate of the regression and held-out checks (two-sided 6e-5)
AUTOCORR_MAX = 0.5        # largest lag-1 autocorrelation of the residuals
RING_MAX = 1.0            # largest rms momentum of an unmodelled flexible mode, in noise sds


class Check(NamedTuple):
    """One adequacy check: ``ok`` when ``statistic ≤ threshold`` (``statistic`` ``None``:
    not applicable, ``ok`` true, ``note`` says why); ``parameter`` names the worst element."""

    name: str
    statistic: float | None
    threshold: float
    ok: bool
    parameter: str | None = None
    note: str | None = None

    def to_dict(self) -> dict:
        out = {"statistic": self.statistic, "threshold": self.threshold, "ok": bool(self.ok)}
        if self.parameter is not None:
            out["parameter"] = self.parameter
        if self.note is not None:
            out["note"] = self.note
        return out

    def warning(self) -> str:
        """The one-line warning of a failed check."""
        where = f" ({self.parameter})" if self.parameter else ""
        return (f"adequacy check {self.name} failed{where}: statistic {self.statistic:.3g} > "
                f"threshold {self.threshold:g}" + (f"; {self.note}" if self.note else ""))


class Adequacy(NamedTuple):
    """The checks of one fit; ``ok`` when every check is."""

    checks: tuple[Check, ...]

    @property
    def ok(self) -> bool:
        return all(c.ok for c in self.checks)

    @property
    def failed(self) -> list[str]:
        return [c.name for c in self.checks if not c.ok]

    def to_dict(self) -> dict:
        """The ``summary.json`` block: ``{"ok": b, "checks": {NAME: {...}}}``."""
        return {"ok": self.ok, "checks": {c.name: c.to_dict() for c in self.checks}}

    def warnings(self) -> list[str]:
        return [c.warning() for c in self.checks if not c.ok]


def normal_deviate(p: float) -> float:
    """``z`` with two-sided standard-normal tail probability ``p`` (capped at 40)."""
    p = min(max(float(p), 0.0), 1.0)
    return 40.0 if p <= 0.0 else float(min(stats.norm.isf(p / 2.0), 40.0))


def not_applicable(name: str, threshold: float, note: str) -> Check:
    return Check(name, None, threshold, True, note=note)


def z_check(name: str, z: float, threshold: float, parameter: str | None = None,
           note: str | None = None) -> Check:
    z = float(z)
    return Check(name, z, threshold, bool(z <= threshold), parameter, note)
