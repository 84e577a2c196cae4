"""The thrust model's likelihood of one biasing event: the impulse of the pulse train (Feldman
& Lee 2006 Eq 17 and §V), the white-noise and time-tag covariances, the offset integrated out,
and the residuals at given parameters (:mod:`cassini_bayes.inference.thrust`, "Error model").
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.inference.gaussian import ColumnStatistics, RankOneRows, offset_marginal
from cassini_bayes.physics.momentum import inertia_matrix
from cassini_bayes.physics.impulse import rate_step_correction
from cassini_bayes.physics.rate_step_moments import (StepPairs, second_order_correction,
                                                     curvature_correction)
from cassini_bayes.physics.pulse import (pulse_impulse, pulse_impulse_area, pulse_impulse_until,
                                         thrust_profile)

if TYPE_CHECKING:
    from cassini_bayes.inference.thrust.data import ThrustProblem

__all__ = ["EventData", "PulseLayout", "pulse_layout", "tag_expectation", "thruster_impulse",
           "jump_area",
           "event_residual",
           "time_tag_rates",
           "time_tag_rows", "TAG_RELATIVE_SD", "noise_covariances", "events_time_tag_rates",
           "events_impulse", "impulse_residuals", "moment_matrix_at"]


class EventData(NamedTuple):
    """One biasing event's arrays, padded to the events' common lengths (``n`` samples, ``m``
    pulses, ``p`` rank-one rows): a pytree the likelihood is vmapped over. In
    ``ThrustData.events`` each field has a leading event axis (E). Per-sample arrays the
    likelihood reads hold one axis component per row (``(3, n)``, ``(R, 3, n)``;
    :func:`~cassini_bayes.inference.gaussian.offset_marginal`)."""

    t: jax.Array               # (n,) s; padding repeats the last sample
    omega: jax.Array           # (n, 3) rad/s body rates
    h_wheels: jax.Array        # (n, 3) N m s wheel momentum, body axes
    mask: jax.Array            # (n,) 1 for a sample, 0 for padding
    t_on: jax.Array            # (m,) s pulse commands
    thruster: jax.Array        # (m,) int index into the spacecraft's thrusters
    width: jax.Array           # (m,) s commanded widths (0: padding, no impulse)
    slot: jax.Array            # (m,) index of each pulse's first sample (n: padding, dropped)
    pulses: PulseLayout        # where the pulses act (:func:`pulse_layout`)
    wheel_cov: jax.Array       # (3, 3) kg² m⁴, Σ_k J_k² g_k g_kᵀ of the active wheels
    nu_cols: jax.Array         # (R, 3, n) columns of the robust nuisance ν (0 on padding)
    time_tag_rates: jax.Array  # (M, p) s, σ_t ∂j/∂t per thruster at ``rank_one.rows``
    time_tag_gyro: jax.Array   # (3, p) N m s, σ_t ∂V_i/∂t_i there (thrust.time_tags)
    rank_one: RankOneRows      # the samples with a time-tag term (:func:`time_tag_rates`)
    lhs_wheels: jax.Array      # (3, n) N m s, V at I = 0: the wheels' part
    lhs_inertia: jax.Array     # (6, 3, n) N m s, ∂V/∂π: V = lhs_wheels + Σ π_k lhs_inertia[k]
    omega_mid: jax.Array       # (3, n) rad/s, body rate at the middle of the interval ending at i
    h_mid: jax.Array           # (3, n) N m s, wheel momentum there
    d_omega: jax.Array         # (3, n) rad/s, the body rate's change over that interval
    d_h: jax.Array             # (3, n) N m s, the wheel momentum's
    dt: jax.Array              # (n,) s, its length (0 at i = 0)
    step_moments: jax.Array    # (M, n) s², the thrusters' rate-step moments (rate_step_moments)
    step_pairs: StepPairs      # their products, the non-zero ones (padded to the events')
    nu_stats: ColumnStatistics  # sums of ``nu_cols`` (gaussian.column_statistics)


class PulseLayout(NamedTuple):
    """Where each pulse of one event acts on its samples (data only, :func:`pulse_layout`).

    A pulse changes ``j`` only at its first ``K`` samples at or after its command; from sample
    ``slot + K`` on it has delivered its whole impulse (it has *settled*). Pulses are ordered by
    that sample, so the pulses settled by any sample are a leading run of them.

    A transient sample's time-tag rate (:func:`time_tag_rates`) is its expectation over the
    sample's time-tag error, Normal with sd ``tag_spread`` (0: the rate at the sample's time),
    by Gauss–Hermite quadrature on ``tag_nodes`` (standard normal) with ``tag_weights`` (summing
    to 1); :func:`pulse_layout` gives one node at 0."""

    dt: jax.Array        # (m, K) s, each transient sample's time after the command
    dt_prev: jax.Array   # (m,) s, the sample before the first's (= dt[:, 0] when none)
    width: jax.Array     # (m,) s commanded widths (0: padding, no impulse)
    thruster: jax.Array  # (m,) int index into the spacecraft's M thrusters
    at: jax.Array        # (m, K) int, flat index thruster·n + sample into (M, n); M n: none
    settled: jax.Array   # (n,) int, how many pulses have settled by each sample
    tag_spread: jax.Array   # (m, K) s, the time-tag sd each transient sample is averaged over
    tag_nodes: jax.Array    # (H,) standard-normal quadrature nodes
    tag_weights: jax.Array  # (H,) their weights


def pulse_layout(t, t_on, thruster, width, slot, k: int, n_thrusters: int) -> PulseLayout:
    """:class:`PulseLayout` (NumPy) of pulses commanded at ``t_on`` (m,) s on ``thruster`` (m,)
    (indices into the spacecraft's ``n_thrusters`` thrusters) with widths ``width`` (m,) s,
    first sample at or after the command ``slot`` (m,) (``n``: none), on samples ``t`` (n,) s,
    ``k`` transient samples per pulse."""
    t = np.asarray(t, float)
    n = t.size
    order = np.argsort(np.asarray(slot), kind="stable")
    slot, t_on = np.asarray(slot)[order], np.asarray(t_on, float)[order]
    rows = slot[:, None] + np.arange(k)[None, :]
    row_ok = rows < n
    dt = np.where(row_ok, t[np.minimum(rows, n - 1)] - t_on[:, None], 0.0)
    at = np.where(row_ok, np.asarray(thruster)[order][:, None] * n + rows, n_thrusters * n)
    settled = np.searchsorted(slot + k, np.arange(n), side="right")
    prev = np.clip(slot - 1, 0, n - 1)
    dt_prev = np.where((slot >= 1) & (slot < n), t[prev] - t_on, dt[:, 0])
    return PulseLayout(dt, dt_prev, np.asarray(width, float)[order],
                       np.asarray(thruster)[order], at, settled, np.zeros_like(dt),
                       np.zeros(1), np.ones(1))


def tag_expectation(fn, layout: PulseLayout, *args):
    """(m, K): ``E[fn(dt − δ, width, *args)]`` at each pulse's transient samples over their
    time-tag errors ``δ`` (:class:`PulseLayout`): ``fn`` a function of the time after a pulse's
    command (the thrust profile), ``args`` its time constants. Of the profile it is the slope of
    the impulse's regression on the tag (Stein's lemma): the statistical linearisation of the
    tag, which a first-order expansion at the sample misses where an edge is within reach."""
    dt = (layout.dt[..., None]
          - layout.tag_spread[..., None] * layout.tag_nodes[None, None, :])  # (m, K, H)
    return fn(dt, layout.width[:, None, None], *args) @ layout.tag_weights


def thruster_impulse(layout: PulseLayout, q_f, tau_delay, tau_rise, tau_fall):
    """The thrusters' accumulated angular impulse ``Q (F ⊙ j(t_i))`` (3, n) N m s, one axis per
    row (Feldman & Lee Eq 17, right side): ``q_f = Q diag(F)`` (3, M) N m per thruster (Eq 16
    times the thrust), ``j`` the actual impulse per newton of the pulse log — the sparse form of
    :func:`~cassini_bayes.physics.impulse.impulse_from_pulses`.

    At a pulse's ``K`` transient samples (:class:`PulseLayout`) its impulse so far,
    :func:`~cassini_bayes.physics.pulse.pulse_impulse_until`; from the next sample on the whole
    pulse's, Feldman & Lee §V closed form (:func:`pulse_impulse`), accumulated by one cumulative
    sum over the pulses. ``O(m K + n)`` instead of ``O(n m)`` work; identical to the dense form
    when every pulse has decayed ``K`` samples after its command.
    """
    w = layout.width
    n = layout.settled.shape[0]
    until = pulse_impulse_until(layout.dt, w[:, None], tau_delay, tau_rise, tau_fall)
    full = pulse_impulse(w, tau_delay, tau_rise, tau_fall)           # Feldman & Lee §V
    qcol = q_f[:, layout.thruster]                                    # (3, m)
    settled = jnp.cumsum(qcol * full[None, :], 1)
    settled = jnp.concatenate([jnp.zeros_like(settled[:, :1]), settled], 1)[:, layout.settled]
    m = q_f.shape[1]
    transient = jnp.zeros(m * n).at[layout.at].add(until, mode="drop").reshape(m, n)
    return settled + q_f @ transient


def jump_area(layout: PulseLayout, q_f, tau_delay, tau_rise, tau_fall):
    """``Q (F ⊙ ε)`` (3, n) N m s²: the thrusters' trapezoid errors of ``∫ j dt`` per interval
    (the sparse form of :func:`~cassini_bayes.physics.impulse.jump_areas`), at the sampled time
    constants: a pulse lands inside an interval at its thrust's centroid, which the time
    constants move. Only a pulse's transient samples (:class:`PulseLayout`) have one."""
    dts = jnp.concatenate([layout.dt_prev[:, None], layout.dt], 1)      # (m, K + 1)
    w = layout.width[:, None]
    j = pulse_impulse_until(dts, w, tau_delay, tau_rise, tau_fall)
    area = pulse_impulse_area(dts, w, tau_delay, tau_rise, tau_fall)
    eps = (area[:, 1:] - area[:, :-1]) - 0.5 * (dts[:, 1:] - dts[:, :-1]) * (j[:, 1:] + j[:, :-1])
    m, n = q_f.shape[1], layout.settled.shape[0]
    per = jnp.zeros(m * n).at[layout.at].add(eps, mode="drop").reshape(m, n)
    return q_f @ per


def _jump_correction(inertia, q_f, tau, ev: EventData):
    """(3, n) N m s: the trapezoidal ``ΔG``'s error across the pulses' rate steps at ``q_f = Q
    diag(F)`` (3, M) and the time constants ``tau``: first order
    (:func:`~cassini_bayes.physics.impulse.rate_step_correction`) and second
    (:func:`~cassini_bayes.physics.rate_step_moments.second_order_correction`, its moments at
    the prior's time constants: a change of ``τ`` moves this small term by less still), and the
    rate's bend inside each interval by Euler's equation
    (:func:`~cassini_bayes.physics.rate_step_moments.curvature_correction`)."""
    first = rate_step_correction(inertia, jump_area(ev.pulses, q_f, *tau), ev.omega_mid,
                                 ev.h_mid)
    second = second_order_correction(inertia, q_f, ev.step_moments, ev.step_pairs, ev.d_omega,
                                     ev.d_h, ev.dt)
    second = second + curvature_correction(inertia, q_f, ev.step_moments, ev.d_omega, ev.d_h,
                                           ev.dt, ev.omega_mid, ev.h_mid)
    return first + jnp.cumsum(second, 1)


def event_residual(pi, q_f, tau, ev: EventData):
    """``r = V(t_i) − Q (F ⊙ j(t_i))`` (3, n) N m s: Feldman & Lee Eq 17, left minus right;
    ``V`` from its basis in the inertia ``pi`` (6,) kg m²
    (:func:`~cassini_bayes.physics.impulse.impulse_lhs_basis`) with the gyroscopic impulse's
    trapezoid error across the pulses' rate steps added back (:func:`_jump_correction`),
    ``q_f = Q diag(F)`` (3, M)."""
    # Feldman & Lee Eq 17 (left); six fused multiply-adds, where a product with the (6, 3 n)
    # basis copied it into the layout of XLA's matrix-vector kernel at every gradient
    v = ev.lhs_wheels
    for k in range(6):
        v = v + pi[k] * ev.lhs_inertia[k]
    v = v + _jump_correction(inertia_matrix(pi), q_f, tau, ev)
    return v - thruster_impulse(ev.pulses, q_f, *tau)                # Feldman & Lee Eq 17


def event_loglik(pi, f_m, tau, log_sigma, ev: EventData, q_matrix, tag_scale=1.0):
    """Offset-marginal statistics of one event (:func:`offset_marginal`) at ``ν = 0``; ``pi``
    (6,) kg m² the inertia, ``tag_scale`` the time tags' sd over the one the event's terms were
    prepared with.

    Residual ``r_i = V(t_i) − Q (F ⊙ j(t_i)) − cols_i ν − b`` (Feldman & Lee Eq 17 plus the
    robust terms) with covariance ``B + m_i m_iᵀ``: white gyro and wheel-rate noise ``B`` (module
    docstring) and the time-tag term ``m_i = Q (F ⊙ ev.time_tag_rates_i) − ev.time_tag_gyro_i``,
    ``σ_t`` times the thrusters' torque at the sample less the gyroscopic one
    (:mod:`~cassini_bayes.inference.thrust.time_tags`): the first scales with the sampled ``F``,
    as the momentum that a time-tag error moves does (:func:`time_tag_rates`).
    The offset ``b`` (flat prior) is integrated out here, the nuisance ``ν`` by
    :func:`nuisance_marginal` over all events.

    The measurements are the gyro rates, not ``V``: ``V`` is the rates mapped through ``I``, so
    the density of the data is that of ``V`` times the Jacobian ``|det I|`` per sample (for any
    ``B``, ``N(I⁻¹r; 0, I⁻¹ B I⁻ᵀ) = |det I| N(r; 0, B)``), less one for the offset's integral.
    With the inertia fixed this is a constant; with the inertia sampled it is what keeps the
    likelihood invariant under the unidentifiable common scale of ``I``, ``F`` and the wheel
    inertias. Without it the density of ``V`` alone grows as ``|det I|⁻ⁿ`` when all three shrink
    together, and the sampled inertia runs the wrong way, dragging ``F`` and the wheel scale.
    """
    inertia = inertia_matrix(pi)
    q_f = q_matrix * f_m[None, :]
    r = event_residual(pi, q_f, tau, ev)
    st = offset_marginal(r, _noise_cov(inertia, log_sigma, ev.wheel_cov),
                         tag_scale * (q_f @ ev.time_tag_rates - ev.time_tag_gyro), ev.mask,
                         ev.rank_one,
                         ev.nu_cols, ev.nu_stats)
    log_jacobian = (jnp.sum(ev.mask) - 1.0) * _log_abs_det3(inertia)
    return st._replace(loglik=st.loglik + log_jacobian)


def _log_abs_det3(a):
    """``log |det a|`` of a 3×3 matrix by its cofactor expansion (what ``slogdet`` gives, without
    an LU factorisation and its derivative's solves in every gradient)."""
    det = (a[0, 0] * (a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1])
           - a[0, 1] * (a[1, 0] * a[2, 2] - a[1, 2] * a[2, 0])
           + a[0, 2] * (a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]))
    return jnp.log(jnp.abs(det))


def _noise_cov(inertia, log_sigma, wheel_cov):
    """``B = σ_ω² I I + σ_ρ² Σ_k J_k² g_k g_kᵀ`` (3, 3) (N m s)²: the white gyro and wheel-rate
    noise of one sample's left side (module docstring, "Error model")."""
    s2 = jnp.exp(2.0 * log_sigma)
    return s2[0] * inertia @ inertia + s2[1] * wheel_cov


def noise_covariances(inertia, noise, wheel_cov) -> np.ndarray:
    """(E, 3, 3) (N m s)²: each event's ``B`` (:func:`_noise_cov`) in NumPy, at the inertia
    matrix ``inertia`` (3, 3) kg m², the white-noise levels ``noise`` (E, 2) rad/s and the wheels'
    ``wheel_cov`` (E, 3, 3) kg² m⁴."""
    i_sq = np.asarray(inertia, float) @ np.asarray(inertia, float)
    noise = np.asarray(noise, float)
    return (noise[:, 0, None, None]**2 * i_sq[None]
            + noise[:, 1, None, None]**2 * np.asarray(wheel_cov, float))


TAG_RELATIVE_SD = 1e-10
"""A sample keeps a time-tag term when its time-tag sd (at the predicted thrust) is at least this
fraction of its white-noise sd at the data's noise levels (:func:`time_tag_rows`)."""


def time_tag_rates(layout: PulseLayout, tau, time_tag_sd, n_thrusters: int):
    """(M, n) s (``M = n_thrusters``): ``σ_t ∂j/∂t``, the time-tag sd ``σ_t`` (s) times each
    thruster's impulse rate per newton at each sample (module docstring, "Robust model"): the
    thrust profile (:func:`~cassini_bayes.physics.pulse.thrust_profile`, the derivative of
    :func:`thruster_impulse` per newton, in the sample times) at each pulse's transient samples,
    expected over their time tags (:func:`tag_expectation`),
    at the time constants ``τ`` (3,) s, the prior's medians: evaluated once, so the covariance
    does not move with ``τ`` (evaluated at each draw it made some fits take tens of minutes).

    The likelihood's time-tag column is ``Q (F ⊙ rates)`` at the *sampled* thrust
    (:func:`event_loglik`), so that it keeps the likelihood's invariance under the common scale
    of ``I``, ``F`` and the wheel inertias that the data cannot see: at a fixed thrust, shrinking
    all three would shrink the residuals a time-tag error leaves but not their stated variance,
    and time tags wider than stated would pull ``F`` down (``benchmarks/time_tag_bias.py``)."""
    n = layout.settled.shape[0]
    rate = tag_expectation(thrust_profile, layout, *tau)
    m = n_thrusters
    return time_tag_sd * jnp.zeros(m * n).at[layout.at].add(rate, mode="drop").reshape(m, n)


def time_tag_rows(rates, torque, noise_sd, mask) -> np.ndarray:
    """(n,) bool: the samples whose time-tag term the likelihood keeps (NumPy, data only).

    ``rates`` (M, n) s (:func:`time_tag_rates`), ``torque`` (3, M) N m the thrusters' torques at
    the predicted thrust, ``noise_sd`` the smallest white-noise sd of one sample's left side at
    the data's noise levels (N m s). A pulse's rate decays as ``e^{−t/τf}`` after its command
    ends but stays above zero for every sample up to :class:`PulseLayout`'s ``K`` transient
    samples after it; the term ``m_i m_iᵀ`` of a sample whose time-tag sd ``|m_i|`` is below
    :data:`TAG_RELATIVE_SD` of ``noise_sd`` changes its covariance by less than 1e-20 of itself,
    which double precision does not represent (``B + m mᵀ == B``): the rank-one algebra of
    :func:`offset_marginal` is left out there, and the likelihood is unchanged.
    """
    tag_sd = np.linalg.norm(np.asarray(torque) @ np.asarray(rates), axis=0)
    return (tag_sd >= TAG_RELATIVE_SD * noise_sd) & (np.asarray(mask) > 0)


# one XLA program each over the events (run eagerly, the vmapped forward-mode derivative
# compiles some seventy one-operation programs)
_events_rates = jax.jit(jax.vmap(time_tag_rates, in_axes=(0, None, None, None)),
                        static_argnums=3)
_events_impulse = jax.jit(jax.vmap(lambda lay, q, tau: thruster_impulse(lay, q, *tau),
                                   in_axes=(0, None, None)))


def events_time_tag_rates(layouts: PulseLayout, tau, time_tag_sd,
                          n_thrusters: int) -> np.ndarray:
    """(E, M, n) s: :func:`time_tag_rates` of every event's layout (stacked, leading axis E)."""
    return np.asarray(_events_rates(jax.device_put(layouts),
                                    tuple(jax.device_put(float(x)) for x in tau),
                                    jax.device_put(float(time_tag_sd)), n_thrusters))


def events_impulse(layouts: PulseLayout, q_f, tau) -> np.ndarray:
    """(E, R, n): :func:`thruster_impulse` of every event's layout (stacked) at the torques
    ``q_f`` (R, M) per thruster (the identity: the impulse per newton, s) and the time
    constants ``tau`` (3,) s."""
    return np.asarray(_events_impulse(jax.device_put(layouts), jax.device_put(np.asarray(q_f)),
                                      tuple(jax.device_put(float(x)) for x in tau)))


@jax.jit
def _residuals_jit(pi, f_m, tau, log_sigma, nu, ev: EventData, q_matrix, tag_scale):
    i_m = inertia_matrix(pi)
    q_f = q_matrix * f_m[None, :]

    def one(log_sigma, ev):
        r = event_residual(pi, q_f, tau, ev) - jnp.tensordot(nu, ev.nu_cols, 1)
        none = ColumnStatistics(jnp.zeros((0, 0, 3, 3)), jnp.zeros((3, 0)))
        rank_one = ev.rank_one._replace(cols=tuple(c[:0] for c in ev.rank_one.cols))
        return offset_marginal(r, _noise_cov(i_m, log_sigma, ev.wheel_cov),
                               tag_scale * (q_f @ ev.time_tag_rates - ev.time_tag_gyro),
                               ev.mask, rank_one,
                               ev.nu_cols[:0],
                               none).resid

    return jax.vmap(one)(log_sigma, ev)


def moment_matrix_at(kw, com=None) -> np.ndarray:
    """(3, M) m: the torque per newton of each thruster about the model file's centre of mass
    moved by ``com`` (3,) m (``None``: not moved), ``Q_s − δ × d_s`` (Feldman & Lee Eq 16)."""
    q = np.asarray(kw.q_matrix, float)
    if com is None or kw.d_matrix is None:
        return q
    return q - np.cross(np.asarray(com, float)[:, None], np.asarray(kw.d_matrix, float), axis=0)


def impulse_residuals(problem: ThrustProblem, thrust, tau, sigma, pi=None,
                      nu=None, com=None, tag_scale=1.0) -> np.ndarray:
    """Offset-free residuals ``V − Q (F ⊙ j) − cols ν − b̂`` (E, n_max, 3) N m s at given
    parameters (thrust per parameter of the mode, ``tau`` (3,) s, ``sigma`` (E, 2), robust
    nuisance ``nu`` (R,), default 0, centre-of-mass offset ``com`` (3,) m of the per-thruster
    model, default 0, the time tags' sd over the prepared one ``tag_scale``); padded rows
    are 0."""
    kw = problem.data
    idx = np.asarray(kw.f_index)
    f_m = np.asarray(thrust, float).ravel()[idx]
    pi = np.asarray(kw.inertia_mean) if pi is None else np.asarray(pi, float)
    nu = np.zeros(kw.nu_sd.shape[0]) if nu is None else np.asarray(nu, float)
    d = _residuals_jit(jax.device_put(pi), jax.device_put(f_m),
                       tuple(jax.device_put(float(x)) for x in tau),
                       jnp.log(jax.device_put(np.asarray(sigma, float))), jax.device_put(nu),
                       kw.events, jax.device_put(moment_matrix_at(kw, com)),
                       jax.device_put(float(tag_scale)))
    return np.swapaxes(np.asarray(d), 1, 2) * np.asarray(kw.events.mask)[..., None]
