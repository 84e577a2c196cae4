"""Z-thruster magnitude from an accelerometer-measured ΔV burn (Feldman & Lee App. D).

``ΔV = ΔV_dn · 2.0202e−3 m/s/dn + bias_ACC · T_burn`` and, by conservation of linear momentum
along Z, ``F = M_SC ΔV / (Δτ_Z1 + Δτ_Z2 + Δτ_Z3 + Δτ_Z4)`` (mean of the four Z thrusters).
"""

from __future__ import annotations

import numpy as np

from cassini_bayes.errors import InputError

__all__ = ["ACC_SCALE_M_S_PER_DN", "accelerometer_delta_v", "z_thrust_from_delta_v"]

ACC_SCALE_M_S_PER_DN = 2.0202e-3  # Feldman & Lee App. D: 2.0202 mm/s per data number


def accelerometer_delta_v(delta_v_dn, bias_m_s2, burn_s,
                          scale_m_s_per_dn=ACC_SCALE_M_S_PER_DN) -> float:
    """ΔV (m/s) from the accelerometer count ``delta_v_dn`` (dn), Feldman & Lee App. D.

    ``bias_m_s2``: accelerometer bias (m/s²) from its output rate before the burn;
    ``burn_s``: burn duration (s).
    """
    # Feldman & Lee App. D: dV = dV_dn * 2.0202e-3 + Bias_ACC * T_burn
    return float(delta_v_dn * scale_m_s_per_dn + bias_m_s2 * burn_s)


def z_thrust_from_delta_v(mass_kg, delta_v_m_s, z_on_times_s) -> float:
    """Mean Z-thruster force (N): ``M ΔV / Σ Δτ_Zi`` (Feldman & Lee App. D).

    ``z_on_times_s`` (4,) on-times of Z1..Z4 over the burn (s).
    """
    total = float(np.sum(np.asarray(z_on_times_s, float)))
    if total <= 0:
        raise InputError("the Z thrusters' on-times over the burn sum to zero; no thrust to "
                         "estimate")
    # Feldman & Lee App. D: F = M_SC dV / (dtau_Z1 + dtau_Z2 + dtau_Z3 + dtau_Z4)
    return float(mass_kg) * float(delta_v_m_s) / total
