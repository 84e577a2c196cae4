"""Report section: how much each neglected effect could move the answer (summary ``sensitivity``).

Reads the ``sensitivity`` block that ``fit inertia`` writes into ``summary.json``
(:func:`cassini_bayes.inference.sensitivity.sensitivity_block`) and shows, per effect and inertia
entry, the shift an effect of prior size causes in a fit that ignores it, in kg m² and in units of
the run's posterior sd. Returns ``None`` when the run has no such block (other kinds, old runs).
"""

from __future__ import annotations

from cassini_bayes.report.html import Section, paragraph, section, table
from cassini_bayes.report.tables import fmt

__all__ = ["sensitivity_section"]

_LABELS = {"external_torque": "external torque T_N", "gyro_bias": "gyro bias",
           "gyro_scale": "gyro scale factor", "wheel_inertia": "wheel spin-inertia scales",
           "wheel_axes": "wheel spin-axis tilts", "body_torque": "body-fixed torque T_body"}


def _unit(block: dict, param: str) -> str:
    """Unit of ``param`` in the block (``units`` of its entries; inertia blocks: kg m²)."""
    for entry in block.values():
        u = entry.get("parameters", {}).get(param, {}).get("units")
        if u is not None:
            return u
    return "kg m²"


def sensitivity_section(summary: dict) -> Section | None:
    """The "Sensitivity to neglected effects" section, or ``None`` without a block."""
    block = summary.get("sensitivity") if isinstance(summary, dict) else None
    if not isinstance(block, dict) or not block:
        return None
    names = None
    rows, classes = [], []
    for effect, entry in block.items():
        params = entry.get("parameters", {})
        names = names or list(params)
        cells = [_LABELS.get(effect, effect), "yes" if entry.get("modelled") else "no"]
        cls = ["", "good" if entry.get("modelled") else ""]
        for p in names:
            v = params.get(p, {})
            x = v.get("shift_in_sd")
            shift = v.get("shift")
            shown = (f"{shift:.3g}" if isinstance(shift, (int, float)) and abs(shift) < 1
                     else fmt(shift, 1))
            cells.append(f"{shown} ({fmt(x, 1)} sd)")
            cls.append("warn" if (x is not None and x > 1 and not entry.get("modelled")) else "")
        rows.append(cells)
        classes.append(cls)
    body = [
        table(["effect", "in model"] + [f"{p} {_unit(block, p)}".strip() for p in names], rows,
              left=2, classes=classes),
        paragraph(
            "Shift of each estimate that an effect of its prior size (one sd, from the "
            "spacecraft model's [gyro] and [wheel_knowledge] sections and the T_N prior of "
            "Feldman & Lee App. A) causes in a fit that leaves it out — the linearised check Lee "
            "recommends, from the data information at the posterior mode (thrust fits: from the "
            "regression of the estimate on the effect's parameters over the posterior draws). "
            "In brackets: the shift "
            "in units of this run's posterior sd; above 1 for an effect not in the model means "
            "this run's intervals are too narrow for it. Effects in the model are already in the "
            "posterior width.", note=True),
    ]
    return section("Sensitivity to neglected effects", body, id="sensitivity")
