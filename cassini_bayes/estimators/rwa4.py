"""Spin axis of the articulated wheel RWA4 by least squares (Brown 2012 §III).

All three of Brown's methods equate the change of one wheel's *average inertial* momentum between
a quiet window "Time A" and a quiet window "Time B" to minus the change of everything else's:

    J_u [⟨ρ_u C⟩_B − ⟨ρ_u C⟩_A] u = −[⟨C (I ω + Σ_k J_k ρ_k g_k)⟩_B − ⟨…⟩_A]          (*)

with ``C = A(q)ᵀ`` (body → inertial, Brown's ``ᴵC_B``), ``ρ`` spin rates (rad/s), ``J`` spin
inertias (kg m²), ``g_k`` the known wheel axes and ``u`` the unknown one (body axes), ``⟨·⟩`` the
window average.

* RCS method (Brown Eq 1): RWA4 is spun up while the spacecraft drifts freely; the other wheels
  are off and the body-momentum term ``C I ω`` (``I`` known) balances RWA4.
* RWA method (Brown Eq 3): the spacecraft slews on wheels; A and B are quiescent (``ω ≈ 0``) at
  two attitudes and RWA4's change balances RWA2's and RWA3's. One A/B pair gives one estimate;
  several pairs stack into one least-squares estimate. Solving for any wheel with the others
  known is the 2011 flight test (RWA1 with RWA2, RWA3 known: 0.41°).
* Four-wheel method (Brown §III.A, 2003): at a fixed attitude RWA4 changes speed and the three
  fixed wheels absorb it; then ``C`` is constant and (*) is the body-frame balance.

As printed, Eqs 1 and 3 multiply by the "inverse" of the bracket ``[⟨ρ_u C⟩_B − ⟨ρ_u C⟩_A]``: read
with ``ρ_u`` a scalar it is a 3×3 matrix that may be singular or ill-conditioned (e.g. when the
spin rate is unchanged and the attitude turns about one axis), read with ``ω^R`` a vector it has
no inverse at all. What is physically meant is the direction ``u`` that satisfies (*): here (*)
is solved by least squares (stacked over all window pairs given), rank-checked, and the solution
normalised to a unit vector; the norm of the raw solution (≈ 1 when the data and the wheel
inertia are consistent) is returned as a check.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import numpy as np

from cassini_bayes.errors import InputError, UnidentifiableError
from cassini_bayes.estimators.lstsq import solve_lstsq
from cassini_bayes.frames import angle_between, dcm

__all__ = ["Rwa4Fit", "window_mask", "momentum_balance", "fit_axis_rcs", "fit_axis_rwa",
           "fit_axis_four_wheel", "axis_error_deg"]

_NAMES = ("u_x", "u_y", "u_z")
_dcm = jax.jit(dcm)


class Rwa4Fit(NamedTuple):
    """Wheel spin-axis estimate.

    Attributes
    ----------
    axis : (3,) unit spin axis in body axes.
    raw : (3,) the least-squares solution before normalisation (``|raw| ≈ 1`` is a check).
    per_pair : (k, 3) unit estimates from each A/B window pair alone (NaN where one pair cannot
        determine the axis), or ``None`` for a single pair.
    residual_rms : rms of the momentum balance (*), N m s.
    rank, condition, warnings : as in :class:`~cassini_bayes.estimators.lstsq.LstsqFit`.
    """

    axis: np.ndarray
    raw: np.ndarray
    per_pair: np.ndarray | None
    residual_rms: float
    rank: int
    condition: float
    warnings: tuple[str, ...]


def window_mask(t_s, t0_s: float, t1_s: float, what: str = "window") -> np.ndarray:
    """(n,) bool mask of the samples with ``t0 ≤ t ≤ t1`` (s); raises if it is empty."""
    t = np.asarray(t_s, float)
    m = (t >= t0_s) & (t <= t1_s)
    if not m.any():
        raise InputError(f"{what} {t0_s}:{t1_s} s holds no telemetry samples (data span "
                         f"{t[0]}:{t[-1]} s); pick a window inside the data")
    return m


def momentum_balance(q, omega, wheel_rates, wheel_axes, wheel_inertias, unknown: int,
                     mask_a, mask_b, inertia=None):
    """``(M, b)`` of the window balance (*) for the wheel with index ``unknown``.

    ``q`` (n, 4); ``omega`` (n, 3) rad/s; ``wheel_rates`` (n, k) rad/s (NaN = off, counted as 0);
    ``wheel_axes`` (k, 3) body axes (row ``unknown`` ignored); ``wheel_inertias`` (k,) kg m²;
    ``mask_a``, ``mask_b`` (n,) bool windows; ``inertia`` (3, 3) kg m², or ``None`` to leave the
    body-momentum term out (Brown Eq 3, quiescent windows). Returns ``M`` (3, 3) N m s per unit
    axis and ``b`` (3,) N m s with ``M u = b``.
    """
    c = np.swapaxes(np.asarray(_dcm(np.asarray(q, float))), -1, -2)  # body -> inertial
    rates = np.nan_to_num(np.asarray(wheel_rates, float))
    axes = np.asarray(wheel_axes, float)
    j = np.asarray(wheel_inertias, float)
    known = [k for k in range(rates.shape[1]) if k != unknown]
    h_body = (rates[:, known] * j[known]) @ axes[known]
    if inertia is not None:
        h_body = h_body + np.asarray(omega, float) @ np.asarray(inertia, float).T
    h_in = np.einsum("nij,nj->ni", c, h_body)
    ma, mb = np.asarray(mask_a, bool), np.asarray(mask_b, bool)
    rc = rates[:, unknown, None, None] * c
    # Brown Eq 1 / Eq 3: change of the average inertial momentum of the unknown wheel ...
    m = j[unknown] * (rc[mb].mean(0) - rc[ma].mean(0))
    # ... equals minus the change of the average inertial momentum of everything else
    b = -(h_in[mb].mean(0) - h_in[ma].mean(0))
    return m, b


def _solve(ms, bs, per_pair: bool) -> Rwa4Fit:
    m = np.concatenate(ms, 0)
    b = np.concatenate(bs, 0)
    fit = solve_lstsq(m, b, _NAMES, "wheel spin-axis components",
                      "use window pairs with different attitudes or a larger wheel-speed change")
    raw = fit.estimate
    warns = list(fit.warnings)
    norm = float(np.linalg.norm(raw))
    if abs(norm - 1.0) > 0.05:
        warns.append(f"the raw axis solution has norm {norm:.3f}, not 1: the wheel inertia, the "
                     "spacecraft inertia or the windows may be inconsistent with the data")
    pairs = None
    if per_pair and len(ms) > 1:
        pairs = np.full((len(ms), 3), np.nan)
        for i, (mi, bi) in enumerate(zip(ms, bs)):
            try:
                x = solve_lstsq(mi, bi, _NAMES, "wheel spin-axis components").estimate
                pairs[i] = x / np.linalg.norm(x)
            except UnidentifiableError as e:
                warns.append(f"window pair {i}: {e}")
    return Rwa4Fit(raw / norm, raw, pairs, fit.residual_rms, fit.rank, fit.condition, tuple(warns))


def fit_axis_rcs(q, omega, wheel_rates, wheel_axes, wheel_inertias, inertia, mask_a, mask_b,
                 unknown: int = 3) -> Rwa4Fit:
    """RCS-controlled drift method, Brown Eq 1: spacecraft inertia ``I`` (kg m²) known.

    ``mask_a``/``mask_b``: "Time A" before and "Time B" after the spin-rate change of wheel
    ``unknown`` (default index 3, RWA4). Other wheels, if spinning, are included as known.
    """
    m, b = momentum_balance(q, omega, wheel_rates, wheel_axes, wheel_inertias, unknown,
                            mask_a, mask_b, inertia)
    return _solve([m], [b], False)


def fit_axis_rwa(q, omega, wheel_rates, wheel_axes, wheel_inertias, pairs, unknown: int = 3,
                 inertia=None) -> Rwa4Fit:
    """RWA-controlled slew method, Brown Eq 3, over one or more A/B window pairs.

    ``pairs``: sequence of ``(mask_a, mask_b)``. Each pair alone gives ``per_pair[i]``; all
    pairs stacked give ``axis``. ``inertia`` (kg m²) optional: include ``C I ω`` when the windows
    are not perfectly quiescent (Eq 3 leaves it out). ``unknown`` is any wheel's index for the
    flight-test variant (solve for RWA1 with RWA2, RWA3 known).
    """
    if len(pairs) == 0:
        raise InputError("the RWA method needs at least one pair of windows "
                         "(--window-a/--window-b)")
    ms, bs = [], []
    for ma, mb in pairs:
        m, b = momentum_balance(q, omega, wheel_rates, wheel_axes, wheel_inertias, unknown,
                                ma, mb, inertia)
        ms.append(m)
        bs.append(b)
    return _solve(ms, bs, True)


def fit_axis_four_wheel(wheel_rates, wheel_axes, wheel_inertias, steps, unknown: int = 3,
                        q=None, omega=None, inertia=None) -> Rwa4Fit:
    """Four-wheel method (Brown §III.A): the fixed wheels absorb RWA4's speed changes.

    ``steps``: sequence of ``(mask_a, mask_b)`` windows before/after each commanded change of
    wheel ``unknown``. At a fixed attitude ``q`` may be omitted (identity used; the balance is
    then in body axes); with ``q`` given, small attitude changes are accounted for.
    """
    rates = np.asarray(wheel_rates, float)
    n = rates.shape[0]
    qq = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)) if q is None else q
    w = np.zeros((n, 3)) if omega is None else omega
    ms, bs = [], []
    for ma, mb in steps:
        m, b = momentum_balance(qq, w, rates, wheel_axes, wheel_inertias, unknown, ma, mb,
                                inertia)
        ms.append(m)
        bs.append(b)
    return _solve(ms, bs, True)


def axis_error_deg(u_est, u_true) -> float:
    """Angle (deg) between an estimated and a reference axis (:func:`frames.angle_between`)."""
    return float(np.degrees(angle_between(np.asarray(u_est, float), np.asarray(u_true, float))))
