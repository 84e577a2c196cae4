"""The onset integral of the leak monitor: quadrature of each onset cell's evidence.

Per cell the leak's fraction is integrated in closed form, leaving a bounded integrand in ``w``
with one peak or trough (:mod:`cassini_bayes.inference.leak`); :class:`Rule` sets the
Gauss-Legendre rule adapted to it and :class:`OnsetCheck` holds one check's evidence.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from scipy.special import log_ndtr, logsumexp

from cassini_bayes.inference.leak._inputs import FRACTION_SCALES


@dataclass(frozen=True)
class Rule:
    """The onset quadrature: a cell whose integrand varies by less than ``easy_nats`` over at
    most ``easy_span`` in ``w`` takes Gauss-Legendre with ``easy_nodes`` nodes; any other is
    split at its peak or trough, each side at the points ``levels`` nats below its top, each
    piece mapped by ``w = w_top ± δ sinh y`` (``δ`` the e-folding length at the piece's top) and
    cut into parts of at most ``part_w`` in ``w`` and ``part_y`` in ``y``, each with
    ``part_nodes`` Gauss-Legendre nodes. Cells whose upper bound is ``prune_nats`` below their
    thruster's evidence are dropped. A finer rule is for measuring this one's error
    (benchmarks/leak_quadrature.py, docs/leak.md)."""

    easy_nats: float = 0.3
    easy_span: float = 2.0
    easy_nodes: int = 4
    levels: tuple[float, ...] = (1.0, 4.0, 12.0, 40.0)
    part_w: float = 0.5
    part_y: float = 1.0
    part_nodes: int = 5
    prune_nats: float = 40.0


RULE = Rule()


@functools.cache
def _gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on [−1, 1]."""
    return np.polynomial.legendre.leggauss(n)


# The onset integral of one cell is ∫ exp(log_g(w)) dw over w ∈ [asinh r₀, asinh r₁]; log_g
# is unimodal in the angle θ = atan(sinh w) + atan2(g, b) (its peak at θ = 0, its trough at ±π).
# The rule and its settings: Rule (above).
LOG_SQRT_2PI = 0.5 * np.log(2.0 * np.pi)


def _log_g(w, b, g):
    """The cell's onset integrand, log: ``−A²/2 + log Φ(B)`` with ``A = b tanh w + g sech w``,
    ``B = b sech w − g tanh w`` (``A² + B² = b² + g²``)."""
    th, sh = np.tanh(w), 1.0 / np.cosh(w)
    a = b * th + g * sh
    return -0.5 * a * a + log_ndtr(b * sh - g * th)


def _mills(b):
    """φ(B) / Φ(B)."""
    return np.exp(-0.5 * b * b - LOG_SQRT_2PI - log_ndtr(b))


def _dlog_g(w, b, g):
    """d log_g / dw = −A sech w (B + φ(B)/Φ(B))."""
    th, sh = np.tanh(w), 1.0 / np.cosh(w)
    bb = b * sh - g * th
    return -(b * th + g * sh) * sh * (bb + _mills(bb))


def _h_inverse(h, start):
    """``B`` with ``B²/2 + log Φ(B) = h`` by Newton from ``start`` above the root (the function
    is convex and increasing, so the iterates fall monotonically to it)."""
    b = np.array(start, float)
    live = np.arange(b.size)
    for _ in range(30):
        x = b[live]
        step = (0.5 * x * x + log_ndtr(x) - h[live]) / (x + _mills(x))
        b[live] = x - step
        live = live[np.abs(step) > 1e-10 * (1.0 + np.abs(x))]
        if not live.size:
            break
    return b


def _pieces(b, g, r0, r1, levels):
    """Bounds (…, 2 × len(levels)) of the pieces of each cell: the two monotone sides of its
    peak or trough, each cut where ``log_g`` has fallen ``levels`` nats below the side's top.
    Returns ``(top, end)``: each piece's end with the larger ``log_g`` and its other end
    (``w``)."""
    rho, phi = np.hypot(b, g), np.arctan2(g, b)
    w0, w1 = np.arcsinh(r0), np.arcsinh(r1)
    th0, th1 = np.arctan(r0) + phi, np.arctan(r1) + phi
    turn = np.select([(th0 < 0) & (th1 > 0), (th0 < np.pi) & (th1 > np.pi),
                      (th0 < -np.pi) & (th1 > -np.pi)], [0.0, np.pi, -np.pi], np.nan)
    split = ~np.isnan(turn)
    w_turn = np.where(split, np.arcsinh(-g / np.where(split, b, 1.0)), w1)
    th_turn = np.where(split, turn, th1)
    tops, ends = [], []
    for lo, hi, w_lo, w_hi in ((th0, th_turn, w0, w_turn), (th_turn, th1, w_turn, w1)):
        e_lo, e_hi = _log_g(w_lo, b, g), _log_g(w_hi, b, g)
        up = e_lo >= e_hi
        w_top, w_end = np.where(up, w_lo, w_hi), np.where(up, w_hi, w_lo)
        e_top, e_end = np.where(up, e_lo, e_hi), np.where(up, e_hi, e_lo)
        th_top, th_end = np.where(up, lo, hi), np.where(up, hi, lo)
        # on this side cos θ is monotone: θ = kπ ± acos(B/ρ)
        k = np.floor(0.5 * (lo + hi) / np.pi)
        odd = np.mod(k, 2.0) == 1.0
        bt = rho * np.cos(th_top)
        bound = w_top
        for level in levels:
            reached = e_end < e_top - level
            bt = np.where(reached, bt, 0.0)
            bt[reached] = _h_inverse(e_top[reached] + 0.5 * rho[reached] ** 2 - level,
                                     bt[reached])
            ac = np.arccos(np.clip(bt / np.where(rho > 0, rho, 1.0), -1.0, 1.0))
            th = np.clip(np.where(odd, (k + 1.0) * np.pi - ac, k * np.pi + ac),
                         np.minimum(th_top, th_end), np.maximum(th_top, th_end))
            w = np.where(reached, np.arcsinh(np.tan(th - phi)), w_end)
            w = np.where(w_end >= w_top, np.clip(w, bound, w_end), np.clip(w, w_end, bound))
            tops.append(bound)
            ends.append(w)
            bound = w
    return np.stack(tops, axis=-1), np.stack(ends, axis=-1)


def _nodes(b, g, r0, r1, easy, rule):
    """Quadrature of ``∫ exp(log_g(w)) dw`` over ``[asinh r0, asinh r1]`` for flat arrays of
    cells: ``(cell, w, log_weight)`` with each cell's nodes contiguous."""
    ie, ih = np.flatnonzero(easy), np.flatnonzero(~easy)
    x, wt = _gauss_legendre(rule.easy_nodes)
    w0, w1 = np.arcsinh(r0[ie]), np.arcsinh(r1[ie])
    half = 0.5 * (w1 - w0)[:, None]
    w_easy = (0.5 * (w0 + w1))[:, None] + half * x
    lw_easy = _log_g(w_easy, b[ie, None], g[ie, None]) + np.log(half * wt)
    top, end = _pieces(b[ih], g[ih], r0[ih], r1[ih], rule.levels)
    cell = np.repeat(ih, top.shape[-1])
    top, end = top.ravel(), end.ravel()
    length = np.abs(end - top)
    bp, gp = b[cell], g[cell]
    delta = np.maximum(np.minimum(length, 1.0 / np.maximum(np.abs(_dlog_g(top, bp, gp)),
                                                           1e-300)), 1e-300)
    y_max = np.arcsinh(length / delta)
    parts = np.where(length > 0, np.maximum(np.ceil(length / rule.part_w),
                                            np.ceil(y_max / rule.part_y)), 0).astype(int)
    piece = np.repeat(np.arange(top.size), parts)
    step = (y_max / np.maximum(parts, 1))[piece]
    first = (np.arange(piece.size) - np.repeat(np.cumsum(parts) - parts, parts)) * step
    x, wt = _gauss_legendre(rule.part_nodes)
    y = first[:, None] + 0.5 * step[:, None] * (x + 1.0)
    d = delta[piece, None]
    w_hard = top[piece, None] + np.sign(end - top)[piece, None] * d * np.sinh(y)
    cell = cell[piece]
    lw_hard = (_log_g(w_hard, b[cell, None], g[cell, None])
               + np.log(0.5 * step[:, None] * wt * d * np.cosh(y)))
    return (np.r_[np.repeat(ie, rule.easy_nodes), np.repeat(cell, rule.part_nodes)],
            np.r_[w_easy.ravel(), w_hard.ravel()], np.r_[lw_easy.ravel(), lw_hard.ravel()])


def _segment_logsumexp(idx, v, size):
    """logsumexp of ``v`` over each run of equal ``idx`` into ``size`` slots (each index's
    values one contiguous run)."""
    out = np.full(size, -np.inf)
    if idx.size == 0:
        return out
    start = np.flatnonzero(np.r_[True, idx[1:] != idx[:-1]])
    m = np.maximum.reduceat(v, start)
    out[idx[start]] = m + np.log(np.add.reduceat(np.exp(v - np.repeat(m, np.diff(
        np.r_[start, idx.size]))), start))
    return out


@dataclass
class OnsetCheck:
    """The evidence at one check: per cell (onset in ``[t_ref − width, t_ref)``), thruster,
    torque component and fraction scale (axes ``(cells, m, torques, scales)``), the Gram terms of
    the leak's columns ``P = F Q[:, k] (t − t_ref)₊`` and ``O = F Q[:, k] 1(t ≥ t_ref)`` and their
    scores, nuisances integrated; ``log_prior`` the torque components' posterior weights under
    no leak; ``rule`` the onset quadrature."""

    t_ref: np.ndarray
    width: np.ndarray
    t_c: float
    log_prior: np.ndarray
    a_pp: np.ndarray
    a_po: np.ndarray
    a_oo: np.ndarray
    z_p: np.ndarray
    z_o: np.ndarray
    rule: Rule = RULE

    def __post_init__(self):
        s = FRACTION_SCALES
        self.shift = self.a_po / self.a_oo               # s; onset offset of the D-P decoupling
        prec = np.maximum(self.a_pp - self.a_po * self.shift, 0.0) + 1.0 / s ** 2
        self.b = (self.z_p - self.shift * self.z_o) / np.sqrt(prec)
        self.g = -self.z_o / np.sqrt(self.a_oo)
        self.scale = np.sqrt(self.a_oo / prec)           # r = scale × (d + shift), 1/s
        self.r0 = self.scale * self.shift
        self.r1 = self.scale * (self.width[:, None, None, None] + self.shift)
        self.const = (self.log_prior[:, None] - np.log(self.t_c) - 0.5 * np.log(self.a_oo)
                      + np.log(2.0) - np.log(s) + 0.5 * (self.b ** 2 + self.g ** 2))
        w0, w1 = np.arcsinh(self.r0), np.arcsinh(self.r1)
        e0, e1 = _log_g(w0, self.b, self.g), _log_g(w1, self.b, self.g)
        ws = np.arcsinh(-self.g / np.where(self.b != 0, self.b, np.inf))
        inside = (self.b != 0) & (ws > w0) & (ws < w1)
        rho = np.hypot(self.b, self.g)
        top = np.maximum(np.maximum(e0, e1), np.where(inside & (self.b > 0), log_ndtr(rho),
                                                      -np.inf))
        low = np.minimum(np.minimum(e0, e1), np.where(inside & (self.b < 0), log_ndtr(-rho),
                                                      np.inf))
        self.easy = (top - low <= self.rule.easy_nats) & (w1 - w0 <= self.rule.easy_span)
        upper = self.const + top + np.log(np.maximum(w1 - w0, 1e-300))
        # every easy cell, and per thruster the hard cell of largest bound, exactly; then the
        # hard cells within rule.prune_nats of that thruster's evidence
        self.log_bf = np.full(self.const.shape, -np.inf)
        m = self.const.shape[1]
        hard = np.moveaxis(np.where(self.easy, -np.inf, upper), 1, 0).reshape(m, -1)
        first = np.zeros(hard.shape, bool)
        top_k = np.argmax(hard, axis=1)
        first[np.arange(m), top_k] = np.isfinite(hard[np.arange(m), top_k])
        first = np.moveaxis(first.reshape(np.moveaxis(upper, 1, 0).shape), 0, 1)
        self._integrate(self.easy | first)
        bound = (logsumexp(self.log_bf, axis=(0, 2, 3)) - self.rule.prune_nats
                 - np.log(upper.size))
        keep = ~self.easy & ~first & (upper >= bound[None, :, None, None])
        self._integrate(keep)

    def _integrate(self, sel):
        idx = np.flatnonzero(sel)
        cell, _, lw = self._nodes(idx)
        self.log_bf.flat[idx] = self.const.ravel()[idx] + _segment_logsumexp(cell, lw, idx.size)

    def _nodes(self, idx):
        """Quadrature nodes ``(i, w, log_weight)`` of the flat entries ``idx`` (``i`` indexes
        ``idx``; each entry's nodes contiguous)."""
        def f(a):
            return np.broadcast_to(a, self.const.shape).ravel()[idx]
        return _nodes(f(self.b), f(self.g), f(self.r0), f(self.r1), f(self.easy), self.rule)

    def log_evidence(self) -> np.ndarray:
        """(m,) log Bayes factor of each thruster's leak against none (onset uniform over the
        data seen, fraction scales equally weighted)."""
        return logsumexp(self.log_bf, axis=(0, 2, 3)) - np.log(FRACTION_SCALES.size)

    def mixture(self, k: int):
        """Thruster ``k``'s posterior of (onset, fraction) as a mixture over quadrature nodes:
        ``(weight, onset_s, mean, sd)``, the fraction given each onset a normal ``(mean, sd)``
        cut at 0 (weights normalised)."""
        sel = np.zeros(self.const.shape, bool)
        sel[:, k] = np.isfinite(self.log_bf[:, k])
        idx = np.flatnonzero(sel)
        i, w, lw = self._nodes(idx)
        def f(a):
            return np.broadcast_to(a, self.const.shape).ravel()[idx[i]]
        lw = lw + f(self.const)
        d = np.sinh(w) / f(self.scale) - f(self.shift)          # onset before t_ref, s
        s = f(np.broadcast_to(FRACTION_SCALES, self.const.shape))
        z = f(self.z_p) + d * f(self.z_o)
        prec = 1.0 / s ** 2 + np.maximum(f(self.a_pp) + d * (2.0 * f(self.a_po)
                                                             + d * f(self.a_oo)), 0.0)
        onset = f(np.broadcast_to(self.t_ref[:, None, None, None], self.const.shape)) - d
        return np.exp(lw - logsumexp(lw)), onset, z / prec, 1.0 / np.sqrt(prec)


    def onset_cdf(self, k: int, t_s: float) -> float:
        """Thruster ``k``'s posterior probability that its onset is before ``t_s`` (s from the
        stretch's first row)."""
        cell = int(np.searchsorted(self.t_ref, t_s, side="right"))   # the cell holding t_s
        total = logsumexp(self.log_bf[:, k])
        parts = [logsumexp(self.log_bf[:cell, k])] if cell else []
        if cell < self.t_ref.size:
            d = max(self.t_ref[cell] - t_s, 0.0)
            def f(a):
                return np.broadcast_to(a, self.const.shape)[cell, k].ravel()
            r = f(self.scale) * (d + f(self.shift))
            i, _, lw = _nodes(f(self.b), f(self.g), r, f(self.r1), np.zeros(r.size, bool),
                              self.rule)
            parts.append(logsumexp(f(self.const) + _segment_logsumexp(i, lw, r.size)))
        return float(np.exp(logsumexp(parts) - total)) if parts else 0.0


