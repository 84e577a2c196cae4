"""Non-gravitational torque from wheel-rate drift at a fixed attitude (Feldman & Lee App. A).

While the spacecraft holds an Earth-pointed attitude on wheels, the external torque goes into the
wheels: ``T ≈ T_matrix (Δω_RWA · 2π/60) · 0.16 / T_Earth`` N m, with ``T_matrix`` the RWA → body
matrix (columns = wheel spin axes), ``Δω_RWA`` the change of the three wheel rates in **rpm** over
``T_Earth`` seconds and 0.16 kg m² the mean wheel spin inertia. Table A1 (9.055 AU) gives totals
of −0.53, −2.11, +1.83 µN m.
"""

from __future__ import annotations

import numpy as np

from cassini_bayes.units import RPM_TO_RAD_S

__all__ = ["CASSINI_T", "MEAN_WHEEL_INERTIA", "nongravitational_torque"]

_S2, _S3, _S6 = np.sqrt(2.0), np.sqrt(3.0), np.sqrt(6.0)
# Feldman & Lee (2006) App. A: RWA -> body matrix; columns are the spin axes of RWA1, RWA2, RWA3.
CASSINI_T = np.array([[0.0, -1 / _S2, 1 / _S2],
                      [_S2 / _S3, -1 / _S6, -1 / _S6],
                      [1 / _S3, 1 / _S3, 1 / _S3]])
MEAN_WHEEL_INERTIA = 0.16  # kg m^2, Feldman & Lee App. A


def nongravitational_torque(delta_rates_rpm, duration_s, t_matrix=CASSINI_T,
                            wheel_inertia_kgm2=MEAN_WHEEL_INERTIA) -> np.ndarray:
    """Body torque (N m) from the wheel-rate change ``delta_rates_rpm`` (3,) over ``duration_s``.

    Feldman & Lee App. A. At a held attitude (``ω ≈ 0``) Euler's equation reduces to
    ``Ḣ_RWA = T_ext``: the wheels absorb the external torque, so ``T ≈ ΔH_RWA / T_Earth``.
    ``t_matrix`` (3, 3) columns are the wheel axes; ``wheel_inertia_kgm2`` scalar or (3,).
    """
    d = np.asarray(delta_rates_rpm, float)
    # Feldman & Lee App. A: T = T_matrix (dw_RWA 2 pi / 60) 0.16 / T_Earth
    return np.asarray(t_matrix, float) @ (d * RPM_TO_RAD_S) * wheel_inertia_kgm2 / duration_s
