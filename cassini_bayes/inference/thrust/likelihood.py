"""The thrust model's likelihood of one biasing event: the impulse of the pulse train (Feldman
& Lee 2006 Eq 17 and §V), the white-noise and time-tag covariances, the offset integrated out,
and the residuals at given parameters (:mod:`cassini_bayes.inference.thrust`, "Error model").
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.inference.gaussian import ColumnStatistics, offset_marginal
from cassini_bayes.physics.momentum import inertia_matrix
from cassini_bayes.physics.pulse import pulse_impulse, pulse_impulse_until

if TYPE_CHECKING:
    from cassini_bayes.inference.thrust.data import ThrustProblem

__all__ = ["EventData", "pulse_increments", "time_tag_rates", "impulse_residuals"]


class EventData(NamedTuple):
    """One biasing event's arrays, padded to the events' common lengths (``n`` samples, ``m``
    pulses): a pytree the likelihood is vmapped over. In ``ThrustData.events`` each field has
    a leading event axis (E)."""

    t: jax.Array               # (n,) s; padding repeats the last sample
    omega: jax.Array           # (n, 3) rad/s body rates
    h_wheels: jax.Array        # (n, 3) N m s wheel momentum, body axes
    mask: jax.Array            # (n,) 1 for a sample, 0 for padding
    t_on: jax.Array            # (m,) s pulse commands
    thruster: jax.Array        # (m,) int index into THRUSTER_NAMES
    width: jax.Array           # (m,) s commanded widths (0: padding, no impulse)
    slot: jax.Array            # (m,) index of each pulse's first sample (n: padding, dropped)
    wheel_cov: jax.Array       # (3, 3) kg² m⁴, Σ_k J_k² g_k g_kᵀ of the active wheels
    nu_cols: jax.Array         # (n, 3, R) columns of the robust nuisance ν
    time_tag_rates: jax.Array  # (n, 8) s, σ_t ∂j/∂t per thruster (:func:`time_tag_rates`)
    lhs_basis: jax.Array       # (7, n, 3) N m s, V = lhs_basis[0] + Σ π_k lhs_basis[1 + k]
    nu_stats: ColumnStatistics  # sums of ``nu_cols`` (:func:`~cassini_bayes.inference.gaussian.column_statistics`)


def pulse_increments(t, t_on, thruster, width, slot, slot_offsets, tau_delay, tau_rise, tau_fall):
    """Accumulated actual impulse per newton (n, 8), s — the sparse form of
    :func:`~cassini_bayes.physics.impulse.impulse_from_pulses`.

    A pulse changes ``j`` only at its first ``K = len(slot_offsets)`` samples at or after its
    command (``slot`` (m,) = index of the first); there its increments are the differences of
    :func:`~cassini_bayes.physics.pulse.pulse_impulse_until`, and at sample ``slot + K`` the rest
    of the full pulse impulse (Feldman & Lee §V closed form, :func:`pulse_impulse`) is added. A
    cumulative sum over samples gives ``j``. ``O(m K)`` instead of ``O(n m)`` work; identical to
    the dense form when every pulse has decayed ``K`` samples after its command.
    """
    n = t.shape[0]
    idx = slot[:, None] + slot_offsets[None, :]                       # (m, K)
    t_s = t[jnp.clip(idx, 0, n - 1)]
    until = pulse_impulse_until(t_s - t_on[:, None], width[:, None], tau_delay, tau_rise,
                                tau_fall)
    until = jnp.where(idx < n, until, 0.0)
    inc = jnp.diff(until, axis=1, prepend=jnp.zeros_like(until[:, :1]))
    # Feldman & Lee §V: impulse of the whole pulse; what remains after the K samples
    full = pulse_impulse(width, tau_delay, tau_rise, tau_fall)
    rest = full - until[:, -1]
    idx_all = jnp.concatenate([idx, slot[:, None] + slot_offsets.shape[0]], 1)
    inc_all = jnp.concatenate([inc, rest[:, None]], 1)
    cols = jnp.broadcast_to(thruster[:, None], idx_all.shape)
    grid = jnp.zeros((n, 8)).at[idx_all, cols].add(inc_all, mode="drop")
    return jnp.cumsum(grid, 0)


def _event_residual(pi, f8, tau, lhs_basis, t, t_on, thruster, width, slot, slot_offsets,
                    q_matrix):
    """``r = V(t_i) − Q (F ⊙ j(t_i))`` (n, 3) N m s: Feldman & Lee Eq 17, left minus right;
    ``V`` from its basis in the inertia ``pi`` (6,) kg m²
    (:func:`~cassini_bayes.physics.impulse.impulse_lhs_basis`)."""
    v = lhs_basis[0] + jnp.tensordot(pi, lhs_basis[1:], 1)           # Feldman & Lee Eq 17 (left)
    j = pulse_increments(t, t_on, thruster, width, slot, slot_offsets, *tau)
    return v - (j * f8[None, :]) @ q_matrix.T                        # Feldman & Lee Eq 17


def _event_loglik(pi, f8, tau, log_sigma, ev: EventData, slot_offsets, q_matrix):
    """Offset-marginal statistics of one event (:func:`offset_marginal`) at ``ν = 0``; ``pi``
    (6,) kg m² the inertia.

    Residual ``r_i = V(t_i) − Q (F ⊙ j(t_i)) − cols_i ν − b`` (Feldman & Lee Eq 17 plus the
    robust terms) with covariance ``B + m_i m_iᵀ``: white gyro and wheel-rate noise ``B`` (module
    docstring) and the time-tag term ``m_i = Q (F ⊙ ev.time_tag_rates_i)``, ``σ_t`` times the
    thrusters' torque at the sample: it scales with the sampled ``F``, as the momentum that a
    time-tag error moves does (:func:`time_tag_rates`).
    The offset ``b`` (flat prior) is integrated out here, the nuisance ``ν`` by
    :func:`nuisance_marginal` over all events.

    The measurements are the gyro rates, not ``V``: ``V`` is the rates mapped through ``I``, so
    the density of the data is that of ``V`` times the Jacobian ``|det I|`` per sample (for any
    ``B``, ``N(I⁻¹r; 0, I⁻¹ B I⁻ᵀ) = |det I| N(r; 0, B)``), less one for the offset's integral.
    With the inertia fixed this is a constant; with the inertia sampled it is what keeps the
    likelihood invariant under the unidentifiable common scale of ``I``, ``F`` and the wheel
    inertias. Without it the density of ``V`` alone grows as ``|det I|⁻ⁿ`` when all three shrink
    together: on a 480-sample event whose true inertia was 3 % above the model's, the sampled
    inertia went 4 % the wrong way, dragging ``F`` 3.5 % low and the wheel scale 7 prior sd.
    """
    inertia = inertia_matrix(pi)
    r = _event_residual(pi, f8, tau, ev.lhs_basis, ev.t, ev.t_on, ev.thruster, ev.width,
                        ev.slot, slot_offsets, q_matrix)
    st = offset_marginal(r, _noise_cov(inertia, log_sigma, ev.wheel_cov),
                         _time_tag_cols(ev.time_tag_rates, f8, q_matrix), ev.mask, ev.nu_cols,
                         ev.nu_stats)
    log_jacobian = (jnp.sum(ev.mask) - 1.0) * jnp.linalg.slogdet(inertia)[1]
    return st._replace(loglik=st.loglik + log_jacobian)


def _noise_cov(inertia, log_sigma, wheel_cov):
    """``B = σ_ω² I I + σ_ρ² Σ_k J_k² g_k g_kᵀ`` (3, 3) (N m s)²: the white gyro and wheel-rate
    noise of one sample's left side (module docstring, "Error model")."""
    s2 = jnp.exp(2.0 * log_sigma)
    return s2[0] * inertia @ inertia + s2[1] * wheel_cov


def time_tag_rates(t, t_on, thruster, width, slot, slot_offsets, tau, time_tag_sd):
    """(n, 8) s: ``σ_t ∂j/∂t``, the time-tag sd ``σ_t`` (s) times each thruster's impulse rate per
    newton at each sample (module docstring, "Robust model"); ``∂j/∂t`` is exact (forward-mode
    derivative of :func:`pulse_increments` in the sample times) at the time constants ``τ``
    (3,) s, the prior's medians: evaluated once, so the covariance does not move with ``τ``
    (evaluated at each draw it made some fits take tens of minutes).

    The likelihood's time-tag column is ``Q (F ⊙ rates)`` at the *sampled* thrust
    (:func:`_time_tag_cols`). Fixed at the predicted thrust, as it was, it broke the likelihood's
    invariance under the common scale of ``I``, ``F`` and the wheel inertias that the data cannot
    see (:func:`_event_loglik`): shrinking all three shrank the residuals a time-tag error leaves
    but not their stated variance, so time tags wider than stated pulled the scale, and ``F``,
    down — by 0.19 of ``F``'s sd at 1.5 × the stated spread on ``biasing_day028``
    (``benchmarks/time_tag_bias.py``), the bias the open-world campaigns measured."""
    _, j_dot = jax.jvp(lambda tt: pulse_increments(tt, t_on, thruster, width, slot,
                                                   slot_offsets, *tau), (t,), (jnp.ones_like(t),))
    return time_tag_sd * j_dot


def _time_tag_cols(rates, f8, q_matrix):
    """(n, 3) N m s: the time-tag column ``Q (F ⊙ rates)`` of each sample at thrust ``f8`` (8,) N."""
    return (rates * f8[None, :]) @ q_matrix.T


@jax.jit
def _residuals_jit(pi, f8, tau, log_sigma, nu, ev: EventData, slot_offsets, q_matrix):
    i_m = inertia_matrix(pi)

    def one(log_sigma, ev):
        r = _event_residual(pi, f8, tau, ev.lhs_basis, ev.t, ev.t_on, ev.thruster, ev.width,
                            ev.slot, slot_offsets, q_matrix) - ev.nu_cols @ nu
        none = ColumnStatistics(jnp.zeros((3, 3, 0, 0)), jnp.zeros((3, 0)))
        return offset_marginal(r, _noise_cov(i_m, log_sigma, ev.wheel_cov),
                               _time_tag_cols(ev.time_tag_rates, f8, q_matrix), ev.mask,
                               ev.nu_cols[..., :0], none).resid

    return jax.vmap(one)(log_sigma, ev)


def impulse_residuals(problem: ThrustProblem, thrust, tau, sigma, pi=None,
                      nu=None) -> np.ndarray:
    """Offset-free residuals ``V − Q (F ⊙ j) − cols ν − b̂`` (E, n_max, 3) N m s at given
    parameters (thrust per parameter of the mode, ``tau`` (3,) s, ``sigma`` (E, 2), robust
    nuisance ``nu`` (R,), default 0); padded rows are 0."""
    kw = problem.data
    idx = np.asarray(kw.f_index)
    f8 = np.asarray(thrust, float)[idx]
    pi = np.asarray(kw.inertia_mean) if pi is None else np.asarray(pi, float)
    nu = np.zeros(kw.nu_sd.shape[0]) if nu is None else np.asarray(nu, float)
    d = _residuals_jit(jnp.asarray(pi), jnp.asarray(f8),
                       tuple(jnp.asarray(float(x)) for x in tau), jnp.log(jnp.asarray(sigma)),
                       jnp.asarray(nu), kw.events, kw.slot_offsets, kw.q_matrix)
    return np.asarray(d) * np.asarray(kw.events.mask)[..., None]
