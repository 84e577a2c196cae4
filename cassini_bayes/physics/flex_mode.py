"""The momentum a flexible appendage or slosh mode holds, as the body's acceleration drives it.

Feldman & Lee §II describe Cassini's booms (0.13 and 0.7 Hz, damping 0.2-1 %) and leave them out
of the rigid-body balance. In hybrid coordinates a mode with coupling ``δ`` (3,) kg^½ m, natural
frequency ``Ω`` and damping ratio ``ζ`` obeys

    η̈ + 2ζΩ η̇ + Ω² η = −δᵀ ω̇,

and adds ``δ η̇`` to the spacecraft's angular momentum ``H = I ω + H_w + δ η̇``. The rigid left
side of Feldman & Lee Eq 17 then misses ``−δ Δη̇`` (and its gyroscopic integral, ``ω/Ω`` smaller,
below 1e-3 of it for rates of mrad/s and modes above 0.05 Hz: left out). With ``M = δ δᵀ`` (kg m²)

    δ η̇(t) = −M y(t),   y(t) = ∫ g(t − s) ω̇(s) ds,   g(t) = Im[λ e^{λt}] / Ω_d,

``λ = −ζΩ + iΩ_d``, ``Ω_d = Ω √(1 − ζ²)``: ``y`` (rad/s) is the body acceleration filtered by the
mode, and Eq 17's residual ``V − Q (F ⊙ j)`` gains ``M y(t)`` (a constant ``M y(t_0)`` is the
event's free offset). Given ``(Ω, ζ)``, ``y`` is data and the momentum is linear in the six
entries of ``M`` (:func:`mode_columns`).

``ω̇`` comes from the pulses, ``I⁻¹ Q_k F_k p_k(t)`` with the thrust profile ``p`` of
:mod:`~cassini_bayes.physics.pulse` (its transform ``∫ p(u) e^{−λu} du`` in closed form,
:func:`profile_transform`), and from the other torques (wheels, gyroscopic), known from the
telemetry only as each sample interval's mean and taken constant over it. Sums over the pulses
and intervals run as one recursion over the samples, vectorised over many ``(Ω, ζ)`` at once.
"""

from __future__ import annotations

import numpy as np

__all__ = ["SETTLE_FALL_TIMES", "profile_transform", "mode_rate_response", "mode_columns",
           "MODE_ENTRIES"]

SETTLE_FALL_TIMES = 40.0
"""A pulse has settled ``τd + 40 τf`` after its command ends: its thrust is below e^{−40}."""

_BLOCK_DECAYS = 20.0     # a recursion block spans at most e^20 of the fastest decay

MODE_ENTRIES = ("xx", "yy", "zz", "xy", "xz", "yz")
"""The entries of the symmetric ``M = δ δᵀ`` (kg m²) in the order of :func:`mode_columns`."""


def _segment(a, b, k):
    """``∫_a^b e^{−k u} du`` (``b ≥ a``, complex ``k``)."""
    return (np.exp(-k * a) - np.exp(-k * b)) / k


def profile_transform(s, width, tau, lam):
    """``∫_0^s p(u) e^{−λu} du`` (complex, s) of the unit thrust profile ``p`` of a pulse of
    command width ``width`` (s) with time constants ``tau = (τd, τr, τf)`` (s)
    (:func:`~cassini_bayes.physics.pulse.thrust_profile`), up to ``s`` (s) after the command;
    arrays broadcast, ``lam`` (1/s) complex with a negative real part."""
    td, tr, tf = (float(x) for x in tau)
    s, w = np.asarray(s, float), np.asarray(width, float)
    rise_end = np.clip(s, td, np.maximum(w, td))               # rising on [τd, Δ)
    rising = _segment(td, rise_end, lam) - _segment(td, rise_end, lam + 1.0 / tr)
    held = 1.0 - np.exp(-w / tr)
    hold = held * _segment(w, np.clip(s, w, w + td), lam)      # held on [Δ, Δ + τd)
    a = w + td
    v = np.maximum(s - a, 0.0)                                 # decaying from Δ + τd on
    k = lam + 1.0 / tf
    decay = held * np.exp(-lam * a) * (1.0 - np.exp(-k * v)) / k
    return rising + hold + decay


def mode_rate_response(t, t_on, width, accel, tau, freq_rad_s, damping, smooth=None):
    """``y(t_i)`` (G, n, 3) rad/s of the module docstring for ``G`` modes at once.

    Parameters
    ----------
    t : (n,) s sample times, increasing.
    t_on, width : (m,) s pulse commands and widths.
    accel : (m, 3) rad/s², each pulse's body acceleration per unit of its thrust profile,
        ``I⁻¹ Q_k F_k``.
    tau : (3,) s, the pulses' ``(τd, τr, τf)``.
    freq_rad_s, damping : (G,) natural frequencies ``Ω`` (rad/s) and damping ratios ``ζ < 1``.
    smooth : (n, 3) rad/s², the body acceleration of every other torque over the interval
        ending at each sample (row 0 unused), or ``None``.
    """
    t = np.asarray(t, float)
    t_on, width = np.asarray(t_on, float), np.asarray(width, float)
    accel = np.asarray(accel, float)
    om = np.atleast_1d(np.asarray(freq_rad_s, float))
    zeta = np.atleast_1d(np.asarray(damping, float))
    om_d = om * np.sqrt(1.0 - zeta**2)
    lam = (-zeta * om + 1j * om_d)[:, None]                    # (G, 1)
    n, g = t.size, om.size
    settle = width + tau[0] + SETTLE_FALL_TIMES * tau[2]
    first = np.searchsorted(t, t_on, side="right")             # first sample after the command
    done = np.searchsorted(t, t_on + settle, side="left")      # first sample settled
    keep = done < n
    inputs = np.zeros((g, n, 3), complex)                      # added to the state at sample i
    if np.any(keep):
        k = np.flatnonzero(keep)
        lag = t[done[k]] - t_on[k]
        c = profile_transform(settle[k], width[k], tau, lam) * np.exp(lam * lag)   # (G, m')
        inputs += _scatter(c, accel[k], done[k], n)
    direct = np.zeros((g, n, 3), complex)                      # samples inside a pulse
    for j in range(int(np.max(done - first, initial=0))):
        k = np.flatnonzero(first + j < done)
        i = first[k] + j
        lag = t[i] - t_on[k]
        c = profile_transform(lag, width[k], tau, lam) * np.exp(lam * lag)
        direct += _scatter(c, accel[k], i, n)
    if smooth is not None:
        gain = np.expm1(lam * np.diff(t)[None, :]) / lam       # ∫ e^{λ(t_i − s)} ds, a step
        inputs[:, 1:] += gain[..., None] * np.asarray(smooth, float)[None, 1:]
    # S_i = e^{λ Δt_i} S_{i−1} + u_i, in blocks short enough that e^{−λ (t − t_block)} stays
    # far from overflow: S_i = e^{λ τ_i} (S_before + Σ_j e^{−λ τ_j} u_j), τ from the block's start
    rate = float(np.max(zeta * om))
    span = _BLOCK_DECAYS / max(rate, 1e-300)
    state = np.zeros((g, n, 3), complex)
    carry, start = np.zeros((g, 3), complex), 0
    while start < n:
        ref = t[start - 1] if start else t[0]
        stop = max(int(np.searchsorted(t, ref + span, side="right")), start + 1)
        tau_b = t[start:stop] - ref
        ph = np.exp(lam * tau_b[None, :])                      # (G, L)
        inner = np.cumsum(inputs[:, start:stop] / ph[..., None], axis=1)
        state[:, start:stop] = ph[..., None] * (carry[:, None] + inner)
        carry, start = state[:, stop - 1], stop
    return np.imag((lam / om_d[:, None])[..., None] * (state + direct))


def _scatter(c, accel, rows, n: int) -> np.ndarray:
    """(G, n, 3): ``Σ_k c[g, k] accel[k]`` summed into sample ``rows[k]``."""
    out = np.zeros((c.shape[0], n, 3), complex)
    np.add.at(out, (slice(None), rows), c[..., None] * accel[None])
    return out


def mode_columns(y, white=None) -> np.ndarray:
    """(..., n, 3, 6): ``M y`` is ``columns @ (M_xx, M_yy, M_zz, M_xy, M_xz, M_yz)``
    (:data:`MODE_ENTRIES`) for the response ``y`` (..., n, 3); with ``white`` (3, 3) the columns
    are ``white @ E_k y``, ``E_k`` the symmetric unit matrices (written out: an einsum over the
    unwhitened columns costs several times more in the mode search)."""
    y = np.asarray(y, float)
    w = np.eye(3) if white is None else np.asarray(white, float)
    x, yy, z = (y[..., a, None] for a in range(3))
    cols = np.empty(y.shape[:-1] + (3, 6))
    cols[..., 0] = x * w[:, 0]
    cols[..., 1] = yy * w[:, 1]
    cols[..., 2] = z * w[:, 2]
    cols[..., 3] = yy * w[:, 0] + x * w[:, 1]
    cols[..., 4] = z * w[:, 0] + x * w[:, 2]
    cols[..., 5] = z * w[:, 1] + yy * w[:, 2]
    return cols
