"""The thrust sampler's coordinates: the map from the sampler's vector to the physical
parameters, with the prior carried over by the Jacobians (:mod:`cassini_bayes.inference.thrust`,
"Sampler coordinates").
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import numpyro.distributions as dist

from cassini_bayes.inference.thrust.prior import (HALF_NORMAL_MEDIAN, NOISE_STEP,
                                                  THRUST_PRIOR_LOG_SD, tag_log_scale)
from cassini_bayes.physics.pulse import pulse_impulse

__all__ = ["C_SCALE_S", "A_LOG_SCALE", "long_pulse_excess", "rise_deficit"]

C_SCALE_S = 0.01              # long-pulse excess c (s) per unit of its sampler coordinate
A_LOG_SCALE = 0.4             # log of the rise deficit a per unit of its sampler coordinate


class Coordinates(NamedTuple):
    """The sampler vector's parts (:func:`unpack`), in its order."""

    f_z: jax.Array        # (n_f,)
    com_z: jax.Array      # (n_c,)
    tau_z: jax.Array      # (3,) (s_z, a_z, c_z), tau_from_z
    noise_z: jax.Array    # (E,)
    inertia_z: object     # (6,), or None where the inertia is fixed
    tag_z: jax.Array      # (K,): the time-tag scale's coordinate (prior.tag_log_scale)


def n_tag(kw) -> int:
    """1 where the model learns the time tags' sd (``kw.tag_sd`` given), else 0 (static)."""
    return 0 if kw.tag_sd is None else 1


def unpack(theta, n_f: int, n_c: int, n_ev: int, sample_inertia: bool,
           n_tags: int = 0) -> Coordinates:
    """Split the sampler vector into its :class:`Coordinates`."""
    k = n_f + n_c
    noise_end = k + 3 + n_ev
    inertia_end = noise_end + (6 if sample_inertia else 0)
    return Coordinates(theta[:n_f], theta[n_f:k], theta[k:k + 3], theta[k + 3:noise_end],
                       theta[noise_end:inertia_end] if sample_inertia else None,
                       theta[inertia_end:inertia_end + n_tags])


def long_pulse_excess(tau_delay, tau_rise, tau_fall):
    """``c = τf − τr e^{−τd/τr}`` (s): a pulse of width ``Δ ≫ τr`` delivers ``F (Δ + c)``.

    The limit ``e^{−Δ/τr} → 0`` of Feldman & Lee §V's closed form
    ``(Δ + τf) + τr (e^{−Δ/τr} − e^{−τd/τr}) − (τf + τd) e^{−Δ/τr}``; for the 125 ms minimum
    pulse ``e^{−Δ/τr} ≈ 0.002``. Pulse logs of widths ≥ 125 ms determine ``F`` and ``c`` and
    little else: the time constants lie on the curved surface ``c(τ) = const``.
    """
    return tau_fall - tau_rise * jnp.exp(-tau_delay / tau_rise)


def rise_deficit(tau_delay, tau_rise):
    """``a = τd + τr e^{−τd/τr}`` (s): a pulse has delivered ``F (t − a)`` by a time ``t ≫ τr``
    after its command while it is still on (Feldman & Lee §V profile, rising phase,
    :func:`~cassini_bayes.physics.pulse.pulse_impulse_until`). Samples taken during pulses pin
    ``a`` as the long pulses' impulses pin :func:`long_pulse_excess`."""
    return tau_delay + tau_rise * jnp.exp(-tau_delay / tau_rise)


def _lambert_w0(x):
    """Principal branch of Lambert's W for ``x ≥ 0`` (``w e^w = x``): Halley's iteration from
    ``l − log(1 + l) l/(1 + l)``, ``l = log(1 + x)`` (``≈ log x − log log x`` for large ``x``),
    converged to rounding in 4 steps for ``1e-14 ≤ x ≤ 1e12``; differentiable."""
    lx = jnp.log1p(x)
    w = lx - jnp.log1p(lx) * lx / (1.0 + lx)
    for _ in range(4):
        ew = jnp.exp(w)
        f = w * ew - x
        w = w - f / (ew * (w + 1.0) - (w + 2.0) * f / (2.0 * w + 2.0))
    return w


def tau_from_z(tau_z, kw):
    """Time constants (3,) s from the sampler's ``(s_z, a_z, c_z)`` and the log prior density
    of the sampler coordinates (exact: the Jacobians included).

    * ``a_z``: the rise deficit ``a = a_mu e^{A a_z}`` (:func:`rise_deficit`, ``A`` =
      :data:`A_LOG_SCALE`), pinned by the samples taken during pulses.
    * ``s``: how ``a`` splits between the delay and the rise, ``τd = a σ(s)`` and
      ``b = a − τd = τr e^{−τd/τr} = a σ(−s)``; ``τd/b = e^s``, so ``τr = b e^{W(e^s)}``
      (Lambert's W). ``τd → 0`` (a first-order valve) and ``τr → 0`` are the two tails
      ``s → ∓∞``, with no wall between them; the split is what only samples within a few
      ``τr`` of a command resolve. The sampler sees ``s_z = asinh(s)`` (``s = sinh s_z``):
      ``s`` itself has a long, exponential tail towards ``τd → 0`` (the half-normal delay prior
      seen through ``τd = a σ(s)``), which no affine whitening makes Gaussian; ``asinh`` folds it
      to about the tails of a normal (leapfrog steps and step sizes: docs/performance.md, "The
      thrust fit of a long biasing event").
    * ``c_z``: the long-pulse excess ``c = c_mu + C c_z`` (:func:`long_pulse_excess`, ``C`` =
      :data:`C_SCALE_S`), pinned by the long pulses' impulses; ``τf = c + b``.

    Sampling ``(a, c)`` instead of ``(τr, τf)`` turns the two narrow, curved ridges of the
    likelihood into coordinate axes. The prior of ``(τd, τr, τf)`` is carried over with
    ``|∂(τd, b)/∂(s, log a)| = a² σ(s) σ(−s)``, ``∂τr/∂b = e^u/(1 + u)`` (``u = τd/τr``),
    ``ds/ds_z = cosh s_z`` and the coordinates' scales. ``τf ≤ 0`` gives NaN.

    A first-order valve (``τd = 0``, ``τr = τf = τ``) is ``a = τ``, ``s → −∞``, ``c = 0``.
    """
    s = jnp.sinh(tau_z[0])
    log_cosh = jnp.logaddexp(tau_z[0], -tau_z[0]) - jnp.log(2.0)     # log ds/ds_z
    a = kw.a_mu * jnp.exp(A_LOG_SCALE * tau_z[1])
    t_d = a * jax.nn.sigmoid(s)
    b = a * jax.nn.sigmoid(-s)
    u = _lambert_w0(jnp.exp(s))
    t_r = b * jnp.exp(u)
    t_f = kw.c_mu + C_SCALE_S * tau_z[2] + b
    t_f = jnp.where(t_f > 0.0, t_f, jnp.nan)
    log_tau = jnp.log(jnp.stack([t_r, t_f]))
    z_rf = (log_tau - kw.tau_mu) / kw.tau_sd
    std = dist.Normal(0.0, 1.0)
    sd_d = kw.tau_delay_scale
    log_prior_delay = jnp.log(2.0 / sd_d) + std.log_prob(t_d / sd_d)      # half-normal
    log_jac = (2.0 * jnp.log(a) + jax.nn.log_sigmoid(s) + jax.nn.log_sigmoid(-s)
               + jnp.log(A_LOG_SCALE) + u - jnp.log1p(u) + jnp.log(C_SCALE_S) + log_cosh)
    log_prior = (log_prior_delay + jnp.sum(std.log_prob(z_rf) - jnp.log(kw.tau_sd) - log_tau)
                 + log_jac)
    return jnp.stack([t_d, t_r, t_f]), log_prior


_SAME_WIDTH_S = 1e-6    # widths closer than this are one command (commands are ms apart)


def bit_widths(width, thruster, f_index) -> np.ndarray | None:
    """(n_f,) s: the one commanded width of each thrust parameter's pulses, where every thrust
    parameter that fires does so at one width (0 for a parameter that never fires); ``None``
    where any parameter fires at two or more widths.

    ``width``, ``thruster``: the events' padded pulse widths (s, 0 for padding) and thruster
    indices; ``f_index`` (M,): each thruster's thrust parameter. One width measures the impulse
    bit ``F j(Δ; τ)`` and not ``F`` apart from the pulse shape (:func:`log_bit_shift`); two
    widths measure ``j(Δ₁)/j(Δ₂)``, which separates them.
    """
    width = np.asarray(width, float)
    on = width > 0
    param = np.asarray(f_index)[np.asarray(thruster)[on]]
    w = width[on]
    out = np.zeros(int(np.max(f_index)) + 1)
    for k in np.unique(param):
        wk = w[param == k]
        if np.ptp(wk) > _SAME_WIDTH_S:
            return None
        out[k] = wk[0]
    return out if np.any(out > 0) else None


def log_bit_shift(tau, kw):
    """(n_f,) ``log j(Δ̄_k; τ) − log j(Δ̄_k; τ̃)``: how far the pulse shape at ``τ`` moves each
    thrust parameter's impulse bit from its value at the prior-median time constants ``τ̃``
    (``Δ̄_k = kw.bit_width``, :func:`bit_widths`; 0 where a parameter never fires).

    ``j(Δ; τ) = (Δ + τf) + τr (e^{−Δ/τr} − e^{−τd/τr}) − (τf + τd) e^{−Δ/τr}`` is Feldman &
    Lee §V's closed form of one pulse's impulse per newton
    (:func:`~cassini_bayes.physics.pulse.pulse_impulse`).
    """
    w = kw.bit_width
    fired = w > 0
    w = jnp.where(fired, w, 1.0)
    t_med = (HALF_NORMAL_MEDIAN * kw.tau_delay_scale, jnp.exp(kw.tau_mu[0]),
             jnp.exp(kw.tau_mu[1]))
    shift = jnp.log(pulse_impulse(w, tau[0], tau[1], tau[2])) - jnp.log(pulse_impulse(w, *t_med))
    return jnp.where(fired, shift, 0.0)


class Physical(NamedTuple):
    """The physical parameters at a sampler vector (:func:`physical`)."""

    thrust: jax.Array       # (n_f,) N, one per thrust parameter
    per_thruster: jax.Array  # (M,) N, each thruster's thrust
    q_matrix: jax.Array     # (3, M) m, torque per newton about the sampled centre of mass
    com: jax.Array          # (n_c,) m, centre of mass, true minus the model file's
    tau: jax.Array          # (3,) s
    log_sigma: jax.Array    # (E, 2) log rad/s
    inertia: jax.Array      # (6,) kg m²
    whitened: jax.Array     # (n_f + n_c,) prior-whitened (log F, δ): N(0, 1) a priori
    tag_scale: jax.Array    # the time tags' sd over the model file's (1 where not learned)


def physical(theta, kw, n_f: int, n_c: int, sample_inertia: bool) -> Physical:
    """Physical parameters of the non-dimensional vector (:class:`Physical`).

    Per-thruster model (``kw.f_basis`` given): the prior-whitened deviations of ``log F`` (n_f)
    and of the centre of mass (``n_c`` = 3) are the sampler's coordinates rotated by the
    orthogonal ``f_basis`` into the impulse design's singular directions
    (:func:`~cassini_bayes.inference.thrust.design.thrust_design`), so the prior stays
    ``N(0, 1)`` in the sampler's coordinates. The torque per newton about the sampled centre of
    mass is ``(r_s − e − δ) × d_s = Q_s − δ × d_s`` (Feldman & Lee Eq 16 with the offset ``δ``).

    Where every thrust parameter fires at one pulse width (``kw.bit_width`` given,
    :func:`bit_widths`) the thrust coordinates are the prior-whitened log impulse bit instead:
    ``log F_k = log b_k − log j(Δ̄_k; τ) + log j(Δ̄_k; τ̃)`` (:func:`log_bit_shift`), so they equal
    the ``log F`` coordinates at the prior-median ``τ̃``. One width measures ``b_k = F_k j(Δ̄_k)``
    and leaves ``F_k`` to trade against the pulse shape along the curved ridge
    ``F j(τ) = const``; in ``(log b, τ)`` that ridge is a coordinate axis. The map
    ``(log b, τ) → (log F, τ)`` is unit-triangular (Jacobian 1), so the prior carries over as
    ``p_F(log F(b, τ)) p(τ)``: :attr:`Physical.whitened` is ``N(0, 1)`` a priori.
    """
    n_ev = kw.log_noise_hat.shape[0]
    f_z, com_z, tau_z, noise_z, inertia_z, tag_z = unpack(theta, n_f, n_c, n_ev,
                                                          sample_inertia, n_tag(kw))
    q = kw.q_matrix
    com = com_z
    if kw.f_basis is not None:
        x = kw.f_basis @ jnp.concatenate([f_z, com_z])
        f_z, com_z = x[:n_f], x[n_f:]
        com = kw.com_sd * com_z
        q = q - jnp.cross(com[:, None], kw.d_matrix, axis=0)     # Feldman & Lee Eq 16, r − e − δ
    tau, _ = tau_from_z(tau_z, kw)
    if kw.bit_width is not None:
        f_z = f_z - log_bit_shift(tau, kw) / THRUST_PRIOR_LOG_SD
    thrust = jnp.exp(kw.f_mu + THRUST_PRIOR_LOG_SD * f_z)
    log_sigma = kw.log_noise_hat + NOISE_STEP * noise_z[:, None]
    pi = kw.inertia_mean
    if sample_inertia:
        pi = pi + kw.inertia_tril @ inertia_z
    return Physical(thrust, thrust[kw.f_index], q, com, tau, log_sigma, pi,
                    jnp.concatenate([f_z, com_z]), jnp.exp(tag_log_scale(jnp.sum(tag_z))))
