"""The file layout: the columns of a telemetry CSV/Parquet and a pulse log, named by the
spacecraft model (docs/design.md §4.1-4.2).
"""

from __future__ import annotations

from collections.abc import Sequence

from cassini_bayes.names import THRUSTER_NAMES
from cassini_bayes.telemetry._types import WHEEL_NAMES

_Q_COLS = ("q1", "q2", "q3", "q4")
_W_COLS = ("wx", "wy", "wz")
_REQUIRED = ("t",) + _Q_COLS + _W_COLS
_PULSE_COLS = ("t_on", "thruster", "width")


def _on_cols(thruster_names: Sequence[str]) -> tuple[str, ...]:
    """The on-time columns ``on_<name>`` of the thrusters."""
    return tuple(f"on_{n}" for n in thruster_names)


def _names_of(spacecraft) -> tuple[tuple[str, ...], tuple[str, ...], str]:
    """``(wheel names, thruster names, whose)`` of the file layout: the model's, or Cassini's
    (the format's default) when ``spacecraft`` is ``None``."""
    if spacecraft is None:
        return (WHEEL_NAMES, THRUSTER_NAMES,
                "Cassini's layout (the default without a spacecraft model)")
    return (tuple(spacecraft.wheel_names), tuple(spacecraft.thruster_names),
            f"the spacecraft model {spacecraft.name!r}")


def _unknown_column(h: str, wheel_names, thruster_names, whose: str,
                    no_model: bool) -> str:
    """Why header ``h`` is unknown, naming the wheels or thrusters ``whose`` layout expects."""
    give = (", or give the spacecraft model whose wheels and thrusters these are (--spacecraft)"
            if no_model else "")
    if h.lower().startswith("on_"):
        have = " ".join(_on_cols(thruster_names)) or "none: it has no thrusters"
        return (f"column '{h}' is the on-time of no thruster of {whose} (its on_* columns: "
                f"{have}); rename or remove it{give}")
    wheels = " ".join(n.lower() for n in wheel_names)
    return (f"unknown column '{h}': neither a required column ({' '.join(_REQUIRED)}) nor a "
            f"wheel column of {whose} ({wheels}); rename or remove it{give}")
