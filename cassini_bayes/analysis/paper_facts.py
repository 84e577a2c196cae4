"""The papers' numbers, as data: what ``cassini-bayes reproduce`` puts beside ours.

Every row of :data:`PAPER_FACTS` is one number printed in a paper (docs/design.md lists the
papers): an ``id`` that experiments use to attach their own value to it, a
description, the printed value, its printed precision (decimal places) and the source section.

Two kinds of rows:

* ``"value"`` — a number the papers computed; ours must match it at the printed precision
  (``|ours − paper| ≤ ½·10^−decimals``);
* ``"budget"`` — an accuracy bound (``≤ 1.5°``, ``< 3°``, ``±10 %``); ours passes when it is within
  the bound (``comparator`` says how);
* ``"reference"`` — a statistical outcome of the papers' own test runs (mean 0.4° over 10 testbed
  runs): shown beside ours, judged through the budget rows, not by equality.

The tables the analyses need as inputs (Feldman & Lee Table 1 and Table 2, the FSDS pulse mix) are
kept here too, as plain constants, so that the numbers come from one place.

Sources: Feldman & Lee (2006), Brown (2012), Lee; each with the section or table.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from cassini_bayes.errors import InputError

__all__ = [
    "PaperFact",
    "PAPER_FACTS",
    "fact",
    "facts_by_id",
    "TABLE1",
    "TABLE1_PARAMS",
    "TABLE2",
    "FSDS_PULSE_MIX",
    "FSDS_LS_THRUST_N",
    "FSDS_TRUE_THRUST_N",
    "INERTIA_2000_PREDICTED",
    "INERTIA_2000_ESTIMATED",
    "LEE_POINTING_TABLE2",
]


@dataclass(frozen=True)
class PaperFact:
    """One number printed in a paper.

    Attributes
    ----------
    id : stable identifier experiments use to report their value for this row.
    description : what the number is, in words.
    value : the printed value (in ``unit``).
    decimals : printed precision, decimal places (``None`` for a budget without one).
    unit : unit of ``value`` ("" for ratios).
    source : paper and section, e.g. ``"Feldman & Lee §V"``.
    kind : ``"value"`` (match at printed precision), ``"budget"`` (stay within the bound) or
        ``"reference"`` (shown beside ours, no pass/fail).
    comparator : for budgets, ``"<="`` or ``"<"``: ``ours <comparator> value`` passes.
    """

    id: str
    description: str
    value: float
    decimals: int | None
    unit: str
    source: str
    kind: Literal["value", "budget", "reference"] = "value"
    comparator: Literal["<=", "<"] = "<="

    @property
    def printed(self) -> str:
        """The value as the paper prints it (with the comparator for budgets)."""
        text = f"{self.value:.{self.decimals}f}" if self.decimals is not None else f"{self.value:g}"
        if self.kind == "budget":
            text = ("≤ " if self.comparator == "<=" else "< ") + text
        return f"{text} {self.unit}".strip()

    def passes(self, ours: float) -> bool | None:
        """Whether ``ours`` reproduces this row (printed precision, or within the budget).

        ``None`` for ``"reference"`` rows, which carry no pass/fail of their own.
        """
        if self.kind == "reference":
            return None
        ours = float(ours)
        if not np.isfinite(ours):
            return False
        if self.kind == "budget":
            return ours <= self.value if self.comparator == "<=" else ours < self.value
        half_ulp = 0.5 * 10.0 ** (-self.decimals) if self.decimals is not None else 0.0
        return abs(ours - self.value) <= half_ulp * (1 + 1e-9)


# --- input tables ---------------------------------------------------------------------------

# Feldman & Lee (2006) Table 1: predicted and estimated inertia, kg m^2, and errors (Eq 12: % for
# moments, Eq 13: kg m^2 for products). Parameter order (Ixx, Iyy, Izz, Ixy, Ixz, Iyz).
TABLE1_PARAMS = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")
TABLE1: dict[str, dict[str, tuple[float, ...]]] = {
    "pre_soi": {"pred": (8802, 8155, 4715, -137, 115, 156),
                "est": (8853, 8171, 4651, -161, 114, 161),
                "err": (-0.58, -0.21, 1.34, 24, 1, -5)},
    "post_prm": {"pred": (7589, 6948, 4449, -138, 151, 150),
                 "est": (7637, 6948, 4223, -137, 252, 162),
                 "err": (-0.63, 0.0, 5.08, -1, -102, -12)},
    "post_probe": {"pred": (7403, 6174, 3727, -129, -12, 147),
                   "est": (7362, 6130, 3750, -164, -12, 149),
                   "err": (0.54, 0.73, -0.63, 35, 0, -2)},
}
# Feldman & Lee (2006) Eq 1 (pre-launch "sum of components") and Eq 8 (flight estimate),
# 2000-03-15, in the same order.
INERTIA_2000_PREDICTED = (8810.8, 8157.3, 4721.8, -136.8, 115.3, 156.4)
INERTIA_2000_ESTIMATED = (8655.2, 7922.7, 4586.2, -144.0, 132.1, 192.1)

# Feldman & Lee (2006) Table 2: five RWA-biasing events of 2004 (day of year), biased wheel rates
# (rpm), thrust estimated without adjustment, adjusted with tau_fall = 65 ms and 40 ms (N).
TABLE2 = {
    "day": (28, 49, 61, 71, 94),
    "rates_rpm": ((-794, -870, -296), (1026, 922, 836), (246, -473, -928), (-1004, 226, -407),
                  (-949, -672, -674)),
    "no_adjustment_n": (0.80, 0.79, 0.82, 0.81, 0.83),
    "tf65_n": (0.573, 0.566, 0.588, 0.581, 0.595),
    "tf40_n": (0.669, 0.661, 0.686, 0.678, 0.695),
    "predicted_n": 0.699,
}

# Feldman & Lee (2006) §V: the FSDS biasing scenario's Y2 (= Y4) pulses, (width s, count).
FSDS_PULSE_MIX = ((0.125, 133), (0.250, 16), (0.500, 1), (0.750, 1))
FSDS_LS_THRUST_N = 0.98   # plain least-squares thrust of the FSDS test (000 §V)
FSDS_TRUE_THRUST_N = 0.75  # thrust simulated by the FSDS (000 §V)


# Lee, Table 2: Cassini science pointing control error budget, 3-sigma contributions (mrad) about
# the spacecraft X and Z axes (the camera looks along Y). Their RSS is 1.186 / 0.244 mrad; the paper
# prints 1.18 / 0.23.
LEE_POINTING_TABLE2 = (
    ("Attitude determination error", 0.22, 0.06),
    ("Star tracker geometric distortion error", 0.56, 0.035),
    ("Post-calibration misalignment between camera and star tracker boresight vectors", 1.0, 0.1),
    ("Star tracker boresight vector shift between calibrations", 0.2, 0.2),
    ("Reaction wheel-based attitude control error", 0.04, 0.04),
    ("IVP timing error", 0.037, 0.037),
    ("IVP modeling error", 0.04, 0.04),
)


def _rows() -> tuple[PaperFact, ...]:
    rows = [
        # Feldman & Lee (2006) §V: impulse ratio of the pulse model
        PaperFact("R_125ms_tf65", "impulse ratio R, 125 ms pulse, τf = 65 ms, τr = 20 ms", 1.395, 3,
                  "", "Feldman & Lee §V"),
        PaperFact("R_250ms_tf65", "impulse ratio R, 250 ms pulse, τf = 65 ms, τr = 20 ms", 1.198, 3,
                  "", "Feldman & Lee §V"),
        PaperFact("R_125ms_tf40", "impulse ratio R, 125 ms pulse, τf = 40 ms, τr = 20 ms", 1.195, 3,
                  "", "Feldman & Lee §V"),
        PaperFact("fsds_mix_on_time_s", "FSDS Y2 total on-time (133×125 + 16×250 + 500 + 750 ms)",
                  21.875, 3, "s", "Feldman & Lee §V"),
        PaperFact("R_fsds_mix", "impulse ratio R of the FSDS pulse mix", 1.3406, 4, "",
                  "Feldman & Lee §V"),
        PaperFact("F_fsds_corrected", "FSDS thrust corrected for pulse dynamics, 0.98 / R", 0.731,
                  3, "N", "Feldman & Lee §V"),
        PaperFact("thrust_accuracy_pct", "thrust calibration accuracy", 10.0, 0, "%",
                  "Feldman & Lee §V, §VI", kind="budget"),
        PaperFact("inertia_accuracy_pct", "inertia calibration accuracy", 1.0, 0, "%",
                  "Feldman & Lee §VI", kind="budget"),
        # Brown (2012) §III.B: RWA4 spin axis by the RCS method
        PaperFact("rwa4_rcs_mean_deg", "RCS method, mean axis error over 10 testbed runs", 0.4, 1,
                  "deg", "Brown §III.B", kind="reference"),
        PaperFact("rwa4_rcs_worst_deg", "RCS method, worst axis error over 10 testbed runs", 1.4, 1,
                  "deg", "Brown §III.B", kind="reference"),
        PaperFact("rwa4_mass_property_deg",
                  "extra RWA4 axis error from mass-property uncertainty (Monte Carlo)", 1.5, 1,
                  "deg", "Brown §III.B", kind="budget"),
        PaperFact("rwa4_rcs_total_deg", "RCS method total: testbed worst + mass properties", 3.0, 0,
                  "deg", "Brown §III.B", kind="budget", comparator="<"),
        # Brown (2012) §III.C: RWA method
        PaperFact("rwa4_rwa_worst_deg", "RWA method, worst axis error over 12 testbed runs", 0.8, 1,
                  "deg", "Brown §III.C", kind="budget"),
        PaperFact("rwa4_rwa_mean_deg", "RWA method, mean axis error over 12 testbed runs", 0.5, 1,
                  "deg", "Brown §III.C", kind="budget", comparator="<"),
        PaperFact("rwa4_rwa_flight_deg",
                  "RWA method flight test, RWA1 solved with RWA2, RWA3 known",
                  0.41, 2, "deg", "Brown §III.C", kind="reference"),
        PaperFact("rwa4_rwa_expected_deg", "RWA method expected accuracy", 1.0, 0, "deg",
                  "Brown §III.C", kind="budget"),
        PaperFact("rwa4_four_wheel_from_rwa3_deg", "2003 four-wheel calibration: RWA4 from RWA3",
                  0.53, 2, "deg", "Brown §III.A"),
        # Lee, pointing error budget, Table 2 (3σ RSS)
        PaperFact("lee_pointing_rss_x_mrad", "pointing budget RSS, X (3σ)", 1.18, 2, "mrad",
                  "Lee Table 2"),
        PaperFact("lee_pointing_rss_z_mrad", "pointing budget RSS, Z (3σ)", 0.23, 2, "mrad",
                  "Lee Table 2"),
        # Lee §3.3: the inertial vector propagator's modelling accuracy
        PaperFact("ivp_modelling_error_urad", "IVP modelling error (direction of a propagated "
                  "vector)", 40.0, 0, "µrad", "Lee §3.3.2, Table 2", kind="budget"),
    ]
    # Feldman & Lee (2006) Table 2: adjusted thrusts
    for i, day in enumerate(TABLE2["day"]):
        for col, tf in (("tf65_n", 65), ("tf40_n", 40)):
            rows.append(PaperFact(
                f"table2_day{day:03d}_tf{tf}",
                f"Table 2, day {day}: thrust adjusted with τf = {tf} ms",
                TABLE2[col][i], 3, "N", "Feldman & Lee Table 2"))
    # Feldman & Lee (2006) Table 1: errors of the predictions (Eq 12 %, Eq 13 kg m^2)
    for epoch, cols in TABLE1.items():
        for name, err in zip(TABLE1_PARAMS, cols["err"]):
            moment = name in ("Ixx", "Iyy", "Izz")
            rows.append(PaperFact(
                f"table1_{epoch}_{name}_err", f"Table 1, {epoch.replace('_', '-')}: {name} error "
                f"({'Eq 12' if moment else 'Eq 13'})", float(err), 2 if moment else 0,
                "%" if moment else "kg m^2", "Feldman & Lee Table 1"))
    return tuple(rows)


PAPER_FACTS: tuple[PaperFact, ...] = _rows()


def facts_by_id() -> dict[str, PaperFact]:
    """The rows of :data:`PAPER_FACTS` by ``id``."""
    return {f.id: f for f in PAPER_FACTS}


def fact(fact_id: str) -> PaperFact:
    """The row ``fact_id`` of :data:`PAPER_FACTS` (``InputError`` naming it when unknown)."""
    try:
        return facts_by_id()[fact_id]
    except KeyError:
        raise InputError(f"unknown paper fact '{fact_id}'; see cassini_bayes.analysis.paper_facts"
                         ".PAPER_FACTS for the ids") from None
