"""A flexible or slosh mode in the thrust fit: found in the events, judged, or integrated out.

A mode with coupling ``δ`` adds ``M y(t)`` to the residual of Feldman & Lee Eq 17, with
``M = δ δᵀ`` (kg m², six entries) and ``y`` the body acceleration filtered by the mode at its
frequency ``Ω`` and damping ``ζ`` (:mod:`cassini_bayes.physics.flex_mode`). Given ``(Ω, ζ)`` the
term is linear in ``M``: six more columns of the robust nuisance, zero-mean Normal prior of sd
``[flex_knowledge] share_sd`` × the mean principal moment.

``(Ω, ζ)`` are found before the fit (:func:`search_mode`), at the largest marginal likelihood
of the data: the residual at the prior's centre with everything the fit can move to first order
integrated out with its priors (inertia, thrusts, centre of mass, time constants, the robust
nuisance, each sample's time tag; the offsets flat), noise-whitened; the mode's columns at every
``(Ω, ζ)`` of a grid over the model file's ``[flex_knowledge]`` ranges, fine enough in ``Ω`` to
follow a ring as long as the event; the best peaks refined. A mode is *found* when its Bayes
factor at the best ``(Ω, ζ)`` exceeds the number of independent ``(Ω, ζ)`` cells searched — the
Laplace estimate of the factor averaged over a log-uniform prior on ``(Ω, ζ)`` above 1. The fit
then judges it (the adequacy check ``flex_ringing``) and, on request, integrates its ``M`` out
with ``(Ω, ζ)`` held at their estimate (docs/flex_mode.md: on a small spacecraft's single-width
event that lowered the coverage).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from scipy.optimize import minimize

from cassini_bayes.errors import InputError
from cassini_bayes.inference.inertia.knowledge import InertiaGaussian
from cassini_bayes.inference.nuisance import with_flex_mode
from cassini_bayes.inference.thrust.likelihood import (EventData, event_residual,
                                                       noise_covariances)
from cassini_bayes.inference.thrust.prior import THRUST_PRIOR_LOG_SD, TauPrior
from cassini_bayes.names import FLEX_CHOICES
from cassini_bayes.physics.flex_mode import MODE_ENTRIES, mode_columns, mode_rate_response
from cassini_bayes.physics.momentum import inertia_vector
from cassini_bayes.spacecraft import Spacecraft

__all__ = ["ModeSearch", "ModeEvent", "mode_event", "search_mode", "mode_nuisance_columns",
           "flex_mode_columns",
           "MODE_ENTRIES", "GRID_STEP", "PEAKS", "GAUSS_NEWTON", "ALIAS_CYCLES", "TAG_WIDEN",
           "TAG_MIN"]

GRID_STEP = 1.0
"""Spacing of the frequency grid, rad/s × the longest event's duration (s): a ring as long as
the event dephases by one radian between two grid points (the peaks are then refined)."""
PEAKS = 2
"""Peaks of the grid refined by the exact marginal likelihood."""
GAUSS_NEWTON = 2
"""Gauss-Newton steps of the fit's first-order span before the search."""
TAG_WIDEN = 2.0
"""The search's time-tag terms are this many times the stated sd: time tags worse than stated
leave spikes at the pulses' samples, which a ring aliased to a slow one would take."""
TAG_MIN = 0.1
"""A sample's time-tag column enters the search where it moves the data by at least this many
noise sds (at the sample, or as a step over the samples after it)."""
ALIAS_CYCLES = 4.0
"""A ring whose samples show fewer than this many cycles over the longest event is left out of
the search: sampled, it is a slow trend, which the data cannot tell from the slow errors every
event has (a drifting torque, time tags)."""
_CHUNK = 256
_DAMPING_GRID = 3


class ModeSearch(NamedTuple):
    """The result of :func:`search_mode` (``summary.json``'s ``flex_mode`` block):
    ``ring_over_noise`` is the rms momentum of the mode at its fitted ``M`` over the residual's
    noise sd (what the fit's noise level absorbs when the mode is not modelled); ``modelled``
    whether the fit integrates the mode out."""

    freq_hz: float
    damping: float
    log_bayes_factor: float
    log_cells: float
    found: bool
    prior_sd: float
    ring_over_noise: float = float("nan")
    modelled: bool = False

    def to_dict(self) -> dict:
        return {"found": bool(self.found), "modelled": bool(self.modelled),
                "freq_hz": self.freq_hz, "damping": self.damping,
                "log_bayes_factor": self.log_bayes_factor, "log_cells_searched": self.log_cells,
                "ring_over_noise": self.ring_over_noise, "prior_sd_kg_m2": self.prior_sd,
                "rule": ("a mode is found when its log Bayes factor at the best (freq, damping) "
                         "exceeds the log of the number of (freq, damping) cells searched; the "
                         "adequacy check flex_ringing fails when a found mode, modelled or not, "
                         "rings above the noise; --flex model integrates M = delta "
                         "delta^T out")}


class ModeEvent(NamedTuple):
    """One event's inputs of the mode's response (unpadded)."""

    t: np.ndarray          # (n,) s
    t_on: np.ndarray       # (m,) s
    width: np.ndarray      # (m,) s
    accel: np.ndarray      # (m, 3) rad/s² per unit thrust profile
    smooth: np.ndarray     # (n, 3) rad/s², the other torques' acceleration per interval
    white: np.ndarray      # (3, 3) inverse Cholesky factor of the sample noise
    tag: np.ndarray        # (3, n) N m s, a sample's time-tag sd: the pulses' impulse there
    tag_next: np.ndarray   # (3, n) N m s, and in the gyroscopic impulse of every later sample


def mode_event(t, omega, h, t_on, thruster, width, q_mat, thrust, inertia,
               noise_cov, tag, time_tag_sd) -> ModeEvent:
    """:class:`ModeEvent` of one event: samples ``t`` (n,) s, body rates ``omega`` and wheel
    momentum ``h`` (n, 3), pulses ``t_on``, ``thruster``, ``width`` (m,), torque per newton
    ``q_mat`` (3, M) m, thrust per thruster ``thrust`` (M,) N, ``inertia`` (3, 3) kg m² and the
    sample noise covariance ``noise_cov`` (3, 3) (N m s)², each sample's time-tag term ``tag``
    (3, n) N m s (:func:`~cassini_bayes.inference.thrust.likelihood.time_tag_rates`) and the
    time-tag sd ``time_tag_sd`` (s). A time-tag error ``δ_i`` also moves the trapezoid of the
    gyroscopic impulse (Feldman & Lee Eq 15) by ``½ δ_i (f_{i−1} + f_i)`` at sample ``i`` and by
    ``½ δ_i (f_{i−1} − f_{i+1})`` at every later one, ``f = ω × (I ω + H)``: across a pulse's
    rate step on a spacecraft whose wheels hold momentum, comparable to the sample noise. Each
    pulse's body acceleration per unit profile is ``I⁻¹ Q_k F_k``; the wheel and gyroscopic
    torques' is their mean over each sample interval."""
    t, omega, h = (np.asarray(x, float) for x in (t, omega, h))
    inertia = np.asarray(inertia, float)
    inv = np.linalg.inv(inertia)
    thrust = np.asarray(thrust, float)
    accel = (inv @ (np.asarray(q_mat)[:, thruster] * thrust[thruster][None, :])).T
    dt = np.diff(t, prepend=t[0])
    w_mid = 0.5 * (omega + np.vstack([omega[:1], omega[:-1]]))
    h_mid = 0.5 * (h + np.vstack([h[:1], h[:-1]]))
    dh = np.diff(h, axis=0, prepend=h[:1])
    torque = (-np.divide(dh, dt[:, None], out=np.zeros_like(dh), where=dt[:, None] > 0)
              - np.cross(w_mid, w_mid @ inertia + h_mid))
    white = np.linalg.inv(np.linalg.cholesky(np.asarray(noise_cov, float)))
    f = np.cross(omega, omega @ inertia + h)                               # (n, 3) N m
    f_prev = np.vstack([f[:1], f[:-1]])
    f_next = np.vstack([f[1:], f[-1:]])
    here = np.asarray(tag, float) + 0.5 * time_tag_sd * (f_prev + f).T
    here[:, 0] = 0.0                                                      # the free offset
    later = 0.5 * time_tag_sd * (f_prev - f_next).T
    later[:, -1] = 0.0
    return ModeEvent(t, np.asarray(t_on, float), np.asarray(width, float), accel, torque @ inv.T,
                     white, here, later)


def _responses(events, om, zeta, tau) -> list[np.ndarray]:
    return [mode_rate_response(ev.t, ev.t_on, ev.width, ev.accel, tau, om, zeta, ev.smooth)
            for ev in events]


class _Base(NamedTuple):
    """The fit's first-order span at its MAP point, for the mode's marginal likelihood: the
    data ``d`` (N,) and the prior-weighted columns ``w`` (N, B) with the offsets projected out
    (``off`` (N, 3E) orthonormal), the noise variance ``s2`` and ``k_inv`` = (s2 I + wᵀw)⁻¹."""

    d: np.ndarray
    w: np.ndarray
    off: np.ndarray
    s2: float
    k_inv: np.ndarray

    def project(self, x):
        """``x`` (..., N, k) with the offsets projected out."""
        return x - np.einsum("nb,...bk->...nk", self.off,
                             np.einsum("nb,...nk->...bk", self.off, x))

    def solve(self, x):
        """``C⁻¹ x`` for the marginal covariance ``C = s2 I + w wᵀ`` (Woodbury)."""
        wx = np.einsum("nb,...nk->...bk", self.w, x)
        return (x - np.einsum("nb,...bk->...nk", self.w,
                              np.einsum("bc,...ck->...bk", self.k_inv, wx))) / self.s2


def _log_bf(x, base: _Base, cinv_d, prior_sd):
    """Log Bayes factor (G,) of the mode columns ``x`` (G, N, 6) against none: the data's
    Gaussian marginal likelihood with the mode's ``M`` (prior sd ``prior_sd`` per entry, kg m²)
    and the fit's first-order span integrated out, over that without the mode."""
    xp = base.project(x)
    cx = base.solve(xp)
    gram = np.einsum("gnk,gnl->gkl", xp, cx)
    b = np.einsum("gnk,n->gk", x, cinv_d)               # C⁻¹ d ⟂ offsets
    a = gram + np.eye(6) / prior_sd**2
    sol = np.linalg.solve(a, b[..., None])[..., 0]
    _, logdet = np.linalg.slogdet(np.eye(6) + prior_sd**2 * gram)
    return 0.5 * np.einsum("gk,gk->g", b, sol) - 0.5 * logdet


def _screen(x, cinv_d, s2) -> np.ndarray:
    """Quick ranking statistic (G,) ``bᵀ (xᵀx / s2)⁻¹ b``, the span's covariance left out of
    the Gram matrix (not of ``b``)."""
    gram = np.einsum("gnk,gnl->gkl", x, x) / s2
    gram = gram + 1e-12 * np.trace(gram, axis1=1, axis2=2)[:, None, None] * np.eye(6)
    b = np.einsum("gnk,n->gk", x, cinv_d)
    return np.einsum("gk,gk->g", b, np.linalg.solve(gram, b[..., None])[..., 0])


def _peaks(stat: np.ndarray, k: int) -> np.ndarray:
    """Indices of the ``k`` largest local maxima of ``stat`` (Ω, ζ) along Ω."""
    best = np.max(stat, 1)
    local = np.flatnonzero((best >= np.r_[-np.inf, best[:-1]])
                           & (best >= np.r_[best[1:], -np.inf]))
    return local[np.argsort(best[local])[::-1][:k]]


def _whitened_design(ev_data, fns, p, reduce, nu_cols, mask, events):
    """The whitened residual (N,) at ``p``, its derivatives along the columns of ``reduce``
    (N, P'), the robust columns and the time-tag columns (N, R + T) and each event's offset
    (N, 3E). A sample's time-tag term is a column of its own (prior sd :data:`TAG_WIDEN`): the
    likelihood's rank-one covariance ``B + m mᵀ`` with the gyroscopic part added."""
    residual, jacobian = fns
    r0 = np.asarray(residual(p, ev_data))                              # (E, 3, n)
    jac = np.asarray(jacobian(p, ev_data)) @ reduce                    # (E, 3, n, P')
    n_ev = r0.shape[0]
    rows = []
    for e, ev in enumerate(events):
        keep = np.asarray(mask[e]) > 0
        n = int(keep.sum())
        r = (ev.white @ r0[e][:, keep]).T
        j = np.einsum("ab,bnp->anp", ev.white, jac[e][:, keep]).transpose(1, 0, 2)
        c = np.einsum("ab,rbn->anr", ev.white, nu_cols[e][:, :, keep]).transpose(1, 0, 2)
        here, later = ev.white @ ev.tag, ev.white @ ev.tag_next                # (3, n)
        reach = (np.linalg.norm(here, axis=0)
                 + np.linalg.norm(later, axis=0) * np.sqrt(np.arange(n)[::-1]))
        tagged = np.flatnonzero(reach >= TAG_MIN)
        tags = np.zeros((n, 3, tagged.size))
        tags[tagged, :, np.arange(tagged.size)] = here[:, tagged].T
        after = np.arange(n)[:, None] > tagged[None, :]                     # (n, T)
        tags += after[:, None, :] * later[:, tagged][None]
        rows.append((r, j, c, tags, e, n))
    n_tag = sum(x[3].shape[2] for x in rows)
    out_r, out_j, out_c, out_off = [], [], [], []
    done = 0
    for r, j, c, tags, e, n in rows:
        t_all = np.zeros((n, 3, n_tag))
        t_all[:, :, done:done + tags.shape[2]] = tags
        done += tags.shape[2]
        off = np.zeros((n, 3, 3 * n_ev))
        off[:, :, 3 * e:3 * e + 3] = events[e].white
        out_r.append(r.reshape(-1))
        out_j.append(j.reshape(-1, j.shape[-1]))
        out_c.append(np.concatenate([c, t_all], -1).reshape(3 * n, -1))
        out_off.append(off.reshape(-1, 3 * n_ev))
    return [np.concatenate(x) for x in (out_r, out_j, out_c, out_off)]


def _without_common_thrust(n_p: int, n_thr: int) -> np.ndarray:
    """(P, P − 1): every parameter direction but the thrusts' common log scale. Scaling the
    inertia, the thrusts and the wheels together scales the residual itself (the likelihood's
    Jacobian ``|det I|`` holds it; a least squares does not): with it, the residual would be
    in the span, the mode's ringing with it."""
    f = np.eye(n_thr) - 1.0 / n_thr
    u, _, _ = np.linalg.svd(f)
    out = np.zeros((n_p, n_p - 1))
    out[:6, :6] = np.eye(6)
    out[6:6 + n_thr, 6:5 + n_thr] = u[:, :n_thr - 1]
    out[6 + n_thr:, 5 + n_thr:] = np.eye(n_p - 6 - n_thr)
    return out


def _base(ev_data, fns, p0, p_sd, n_thr, nu_cols, nu_sd, mask, events) -> _Base:
    """:class:`_Base` at the MAP point of the fit's first-order span (:data:`GAUSS_NEWTON`
    steps from the prior's centre ``p0``, prior sds ``p_sd`` and ``nu_sd``: a flat span would
    take the ring with a gyro scale factor of one and the time constants' freedom)."""
    reduce = _without_common_thrust(p0.size, n_thr)
    a = np.zeros(reduce.shape[1])
    for _ in range(GAUSS_NEWTON + 1):
        r, j, c, off = _whitened_design(ev_data, fns, p0 + reduce @ a, reduce, nu_cols, mask,
                                        events)
        sd = np.r_[np.sqrt(np.einsum("pq,p->q", reduce**2, p_sd**2)), nu_sd,
                   np.full(c.shape[1] - nu_sd.size, TAG_WIDEN)]
        q_off, _ = np.linalg.qr(off)
        d = r - j @ a                                    # d = −J a + C ν + offsets + noise
        g = np.concatenate([-j, c], 1) * sd[None, :]
        d_p = d - q_off @ (q_off.T @ d)
        w = g - q_off @ (q_off.T @ g)
        u = np.linalg.solve(w.T @ w + np.eye(w.shape[1]), w.T @ d_p)
        a = sd[:a.size] * u[:a.size]
    hat = w @ np.linalg.solve(w.T @ w + np.eye(w.shape[1]), w.T)
    dof = d_p.size - off.shape[1] - float(np.trace(hat))
    s2 = float(np.sum((d_p - w @ u)**2)) / max(dof, 1.0)
    return _Base(d_p, w, q_off, s2, np.linalg.inv(s2 * np.eye(w.shape[1]) + w.T @ w))


def _alias_hz(freq_hz, period_s: float):
    """The frequency (Hz) at which a ring of ``freq_hz`` shows in samples ``period_s`` apart."""
    return np.abs(freq_hz - np.round(freq_hz * period_s) / period_s)


def search_mode(ev_data, fns, p0, p_sd, n_thr: int, nu_cols, nu_sd, mask,
                events: list[ModeEvent], tau, freq_hz_range, damping_range, prior_sd: float):
    """Find the flexible mode of the module docstring; returns the :class:`ModeSearch` and,
    when found, its columns (E, 6, 3, n) in the layout of the robust nuisance (per kg m² of
    each entry of ``M``, :data:`MODE_ENTRIES`), else ``None``.

    ``fns = (residual, jacobian)``: ``residual(p, ev_data)`` (E, 3, n) is Eq 17's residual at
    the physical parameters ``p`` = (π (6), log F (``n_thr``), δ (3), τ (3)), ``jacobian`` its
    derivative (E, 3, n, P); ``p0`` the prior's centre and
    ``p_sd`` its sds; ``nu_cols`` (E, R, 3, n) the robust nuisance columns, ``nu_sd`` (R,)
    their prior sds."""
    base = _base(ev_data, fns, np.asarray(p0, float), np.asarray(p_sd, float), n_thr,
                 nu_cols, np.asarray(nu_sd, float), mask, events)
    cinv_d = base.solve(base.d[:, None])[:, 0]
    span = max(float(ev.t[-1] - ev.t[0]) for ev in events)
    period = float(np.median(np.concatenate([np.diff(ev.t) for ev in events])))
    om_lo, om_hi = 2.0 * np.pi * np.asarray(freq_hz_range, float)
    n_om = int(np.clip(np.ceil((om_hi - om_lo) * span / GRID_STEP), 2, 200_000))
    om = np.linspace(om_lo, om_hi, n_om)
    seen = _alias_hz(om / (2.0 * np.pi), period) >= ALIAS_CYCLES / span
    om = om[seen]
    n_om = om.size
    zetas = np.exp(np.linspace(*np.log(damping_range), _DAMPING_GRID))

    def columns(o, z):
        ys = _responses(events, o, z, tau)
        return np.concatenate([mode_columns(y, ev.white).reshape(y.shape[0], -1, 6)
                               for y, ev in zip(ys, events)], 1)

    stat = np.zeros((n_om, zetas.size))
    for j, z in enumerate(zetas):
        for s in range(0, n_om, _CHUNK):
            o = om[s:s + _CHUNK]
            stat[s:s + o.size, j] = _screen(columns(o, np.full(o.size, z)), cinv_d, base.s2)

    def neg(v):
        o, z = np.exp(v)
        if _alias_hz(o / (2.0 * np.pi), period) < ALIAS_CYCLES / span:
            return 0.0
        return -float(_log_bf(columns(np.array([o]), np.array([z])), base, cinv_d,
                              prior_sd)[0])

    if n_om == 0:                      # every frequency aliases to a slow trend: nothing to find
        return ModeSearch(float("nan"), float("nan"), 0.0, 0.0, False, float(prior_sd), 0.0), None
    bounds = [(np.log(om_lo), np.log(om_hi)), tuple(np.log(damping_range))]
    best = None
    for i in _peaks(stat, PEAKS):
        z0 = zetas[int(np.argmax(stat[i]))]
        x0 = np.log([om[i], z0])
        simplex = x0 + np.array([[0.0, 0.0], [GRID_STEP / (span * om[i]), 0.0], [0.0, 0.5]])
        res = minimize(neg, x0, method="Nelder-Mead", bounds=bounds,
                       options={"xatol": 1e-5, "fatol": 0.05, "maxiter": 80,
                                "initial_simplex": simplex})
        if best is None or res.fun < best.fun:
            best = res
    o, z = np.exp(best.x)
    cells = (om_hi - om_lo) * span / (2.0 * np.pi) * (1.0 + np.log(damping_range[1]
                                                                   / damping_range[0]))
    log_cells = float(np.log(max(cells, 1.0)))
    x = columns(np.array([o]), np.array([z]))[0]
    xp = base.project(x)
    coef = np.linalg.solve(xp.T @ base.solve(xp) + np.eye(6) / prior_sd**2, x.T @ cinv_d)
    ring = float(np.sqrt(np.mean((xp @ coef)**2)))           # whitened: in noise sds
    found = -best.fun > log_cells
    search = ModeSearch(float(o / (2.0 * np.pi)), float(z), float(-best.fun), log_cells,
                        bool(found), float(prior_sd), ring)
    if not found:
        return search, None
    return search, mode_nuisance_columns(events, search.freq_hz, z, tau, mask)


def mode_nuisance_columns(events: list[ModeEvent], freq_hz: float, damping: float, tau,
                          mask) -> np.ndarray:
    """(E, 6, 3, n): the columns of a mode at ``freq_hz``, ``damping`` in the layout of the
    robust nuisance (per kg m² of each entry of ``M``, :data:`MODE_ENTRIES`), zero on the
    padding of ``mask`` (E, n)."""
    mask = np.asarray(mask, float)
    om = np.array([2.0 * np.pi * freq_hz])
    cols = np.zeros((len(events), 6, 3, mask.shape[1]))
    for e, y in enumerate(_responses(events, om, np.array([damping]), tau)):
        cols[e, :, :, :y.shape[1]] = mode_columns(y[0]).transpose(2, 1, 0)
    return cols * mask[:, None, None, :]


def _flex_residual_at(p, ev, q_mat, d_mat, n_thr: int):
    """Eq 17's residual (E, 3, n) of every event at ``p = (π (6), log F (M), δ (3), τ (3))``."""
    pi, log_f = p[:6], p[6:6 + n_thr]
    com, tau = p[6 + n_thr:9 + n_thr], p[9 + n_thr:]
    q = q_mat - jnp.cross(com[:, None], d_mat, axis=0)                   # Feldman & Lee Eq 16
    q_f = q * jnp.exp(log_f)[None, :]
    return jax.vmap(lambda e: event_residual(pi, q_f, (tau[0], tau[1], tau[2]), e))(ev)


# compiled once per shape class, not once per problem
_flex_residual = jax.jit(_flex_residual_at, static_argnums=4)
_flex_jacobian = jax.jit(jax.jacfwd(_flex_residual_at), static_argnums=4)


def flex_mode_columns(flex, kw: dict, steps: dict, basis, layout_e, tels, logs,
                      spacecraft: Spacecraft, thrust_pred, tp: TauPrior, i_lin,
                      inertia: InertiaGaussian | None, noise, layout, tag_sd):
    """``(search, nu_cols, layout)``: the search for a flexible mode (:func:`search_mode`) on a
    thrust problem in preparation (:func:`~cassini_bayes.inference.thrust.prepare_thrust`'s
    arrays ``kw``), and the robust columns and layout, with the mode's ``M`` appended where one
    is found and modelled or given. ``tag_sd`` (E, 3, n) N m s: each sample's time-tag term at
    the predicted thrust."""
    k = spacecraft.knowledge
    n_thr = len(spacecraft.thrusters)
    if inertia is None:
        pi_mean, pi_sd = np.asarray(inertia_vector(jnp.asarray(i_lin)), float), np.zeros(6)
    else:
        pi_mean = np.asarray(inertia.mean, float)
        pi_sd = np.sqrt(np.diag(np.asarray(inertia.cov, float)))
    thrust = np.broadcast_to(np.asarray(thrust_pred, float), (n_thr,))
    q_mat = spacecraft.moment_matrix
    events = []
    covs = noise_covariances(i_lin, noise, kw["wheel_cov"])
    for e, (tel, log, cov) in enumerate(zip(tels, logs, covs)):
        n, m = tel.n, len(log.t_on)
        events.append(mode_event(kw["t"][e, :n], kw["omega"][e, :n], kw["h_wheels"][e, :n],
                                 kw["t_on"][e, :m], kw["thruster"][e, :m], kw["width"][e, :m],
                                 q_mat, thrust, i_lin, cov, tag_sd[e][:, :n],
                                 k.time_tag_sd_s))
    prior_sd = k.flex_share_sd * float(np.trace(i_lin)) / 3.0
    if isinstance(flex, str) and flex not in FLEX_CHOICES:
        raise InputError(f"flex = {flex!r}: choose one of {', '.join(FLEX_CHOICES)} or give "
                         "(freq_hz, damping)")
    if flex in ("check", "model"):
        ev = EventData(**{f: None for f in EventData._fields})._replace(
            lhs_wheels=basis[:, 0], lhs_inertia=basis[:, 1:], pulses=layout_e, **steps)
        dirs = np.stack([s.direction for s in spacecraft.thrusters], 1)
        p0 = np.r_[pi_mean, np.log(thrust), np.zeros(3), tp.median()]
        p_sd = np.r_[pi_sd, np.full(n_thr, THRUST_PRIOR_LOG_SD),
                     np.full(3, spacecraft.com_sd_m), np.sqrt(tp.variance())]
        fns = (lambda p, e: _flex_residual(p, e, q_mat, dirs, n_thr),
               lambda p, e: _flex_jacobian(p, e, q_mat, dirs, n_thr))
        search, cols = search_mode(ev, fns, p0, p_sd, n_thr,
                                   kw["nu_cols"], layout.sd, kw["mask"], events, tp.median(),
                                   k.flex_freq_hz, k.flex_damping, prior_sd)
    else:
        freq_hz, damping = (float(x) for x in flex)
        search = ModeSearch(freq_hz, damping, float("nan"), float("nan"), True, prior_sd)
        cols = mode_nuisance_columns(events, freq_hz, damping, tp.median(), kw["mask"])
    if cols is None or flex == "check":
        return search, kw["nu_cols"], layout
    return (search._replace(modelled=True), np.concatenate([kw["nu_cols"], cols], 1),
            with_flex_mode(layout, prior_sd))
