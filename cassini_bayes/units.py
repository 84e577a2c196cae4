"""Unit conversions at the file boundary: SI inside, wheel rates in rpm only in files,
scenarios and messages.

Pure constants: any layer may import this module.
"""

from __future__ import annotations

import math

__all__ = ["RPM_TO_RAD_S"]

RPM_TO_RAD_S = 2.0 * math.pi / 60.0
"""rad/s per rpm (one revolution, 2π rad, per 60 s)."""
