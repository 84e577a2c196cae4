"""The leak monitor's posterior: prefix sums of a stretch, the closed-form evidence at each
check, and the sequential detection and isolation (:func:`leak_posterior`)."""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy import optimize
from scipy.special import log_ndtr, logsumexp

from cassini_bayes.errors import InputError, spelled
from cassini_bayes.estimators.leak import ETA
from cassini_bayes.inference.leak._inputs import (MAX_GRID, SAMPLE_STEP_S, TORQUE_SCALES,
                                                 LeakInputs, LeakPosterior, noise_sd)
from cassini_bayes.inference.leak._onset import LOG_SQRT_2PI, RULE, OnsetCheck, Rule


def _cum(a: np.ndarray) -> np.ndarray:
    """Cumulative sums along axis 0 with a leading zero row (prefix sums)."""
    return np.concatenate([np.zeros((1,) + a.shape[1:]), np.cumsum(a, axis=0)])


class Sums:
    """Prefix sums of a stretch for the closed-form evidence at any check."""

    def __init__(self, inp: LeakInputs, eta: float, raw: LeakInputs):
        t = inp.t - inp.t[0]
        n = t.size
        y, q = inp.residual, inp.q_matrix
        # nuisance columns (n, 3 axes, p0): r_0 (3), T (3), δ_j Q[:, j] J_j (m)
        eye = np.eye(3)
        cols = np.concatenate([np.broadcast_to(eye, (n, 3, 3)), t[:, None, None] * eye[None],
                               q[None, :, :] * inp.impulse[:, None, :]], axis=2)
        # one nuisance prior precision per component of the torque's scale mixture
        self.prior_prec = [1.0 / np.r_[np.full(3, inp.offset_sd_nms ** 2),
                                       np.full(3, (scale * max(inp.torque_sd_nm, 1e-12)) ** 2),
                                       np.full(q.shape[1], max(eta, 1e-12) ** 2)]
                           for scale, _ in TORQUE_SCALES]
        self.log_w = np.log([w for _, w in TORQUE_SCALES])
        self.t, self.y = t, y
        self.raw_t, self.raw_y = raw.t, raw.residual
        self.floor = inp.noise_floor_nms
        self.nn = _cum(np.einsum("iap,iaq->iapq", cols, cols))
        self.ny = _cum(np.einsum("iap,ia->iap", cols, y))
        self.n1, self.nt = _cum(cols), _cum(t[:, None, None] * cols)
        self.y1, self.yt = _cum(y), _cum(t[:, None] * y)
        self.c1, self.ct, self.ctt = _cum(np.ones(n)), _cum(t), _cum(t * t)
        self.u = q * inp.thrust_n[None, :]              # (3, m): torque per unit fraction, N m

    def noise_sd(self, c: int) -> np.ndarray:
        """White-noise sd per axis (N m s) from the data up to row ``c``: the larger of the
        levels seen between the used rows and between the raw telemetry rows (the latter is
        reliable from a few dozen seconds on, the former holds the slow wander)."""
        raw = self.raw_y[:np.searchsorted(self.raw_t, self.t[c] + self.raw_t[0], "right")]
        return np.maximum(noise_sd(self.y[:c + 1], self.floor), noise_sd(raw, self.floor))

    def check(self, c: int, rule: Rule = RULE) -> OnsetCheck:
        """The evidence of every thruster's leak with the data rows 0..c (module docstring), its
        onset integrated by ``rule``."""
        e, t = c + 1, self.t
        lam = 1.0 / self.noise_sd(c) ** 2               # (3,) noise precision per axis
        cell = np.arange(1, c + 1)                      # onset in [t_{l-1}, t_l): rows l..c
        tr = t[cell]                                    # the leak's columns from t_l on: f P + D O
        s0, s1, s2 = (x[e] - x[cell] for x in (self.c1, self.ct, self.ctt))
        sh, sh2 = s1 - tr * s0, s2 - 2.0 * tr * s1 + tr * tr * s0      # Σ h, Σ h², h = t − t_l
        n1 = self.n1[e] - self.n1[cell]
        nh = self.nt[e] - self.nt[cell] - tr[:, None, None] * n1
        y1 = self.y1[e] - self.y1[cell]
        yh = self.yt[e] - self.yt[cell] - tr[:, None] * y1
        lu = lam[:, None] * self.u
        lu2 = np.einsum("ak,ak->k", lu, self.u)
        g_p = np.einsum("ak,lap->lkp", lu, nh)          # Nᵀ Λ P, Nᵀ Λ O: (cells, m, p0)
        g_o = np.einsum("ak,lap->lkp", lu, n1)
        z_p0 = np.einsum("ak,la->lk", lu, yh)           # Pᵀ Λ y, Oᵀ Λ y
        z_o0 = np.einsum("ak,la->lk", lu, y1)
        p0 = g_p.shape[-1]
        gram, log_z0 = [], []
        for prior_prec in self.prior_prec:
            a_mat = np.diag(prior_prec) + np.einsum("a,apq->pq", lam, self.nn[e])
            b0 = np.einsum("a,ap->p", lam, self.ny[e])
            sol = np.linalg.solve(a_mat, np.concatenate(
                [b0[:, None], g_p.reshape(-1, p0).T, g_o.reshape(-1, p0).T], axis=1))
            sol_b = sol[:, 0]
            sol_p = sol[:, 1:1 + g_p[..., 0].size].T.reshape(g_p.shape)
            sol_o = sol[:, 1 + g_p[..., 0].size:].T.reshape(g_o.shape)
            # log evidence of "no leak" under this torque component, up to a common constant
            # (Gaussian marginal: −½ log|A| + ½ log|P| + ½ bᵀA⁻¹b)
            log_z0.append(0.5 * (np.sum(np.log(prior_prec)) - np.linalg.slogdet(a_mat)[1]
                                 + b0 @ sol_b))
            # Woodbury: the leak columns' Gram terms and scores with the nuisances integrated
            gram.append((lu2 * sh2[:, None] - np.einsum("lkp,lkp->lk", g_p, sol_p),
                         lu2 * sh[:, None] - np.einsum("lkp,lkp->lk", g_p, sol_o),
                         lu2 * s0[:, None] - np.einsum("lkp,lkp->lk", g_o, sol_o),
                         z_p0 - g_p @ sol_b, z_o0 - g_o @ sol_b))
        a_pp, a_po, a_oo, z_p, z_o = (np.stack(x, axis=-1)[..., None] for x in zip(*gram))
        log_z0 = self.log_w + np.array(log_z0)
        return OnsetCheck(t_ref=tr, width=tr - t[cell - 1], t_c=float(t[c]),
                      log_prior=log_z0 - logsumexp(log_z0), a_pp=a_pp, a_po=a_po,
                      a_oo=np.maximum(a_oo, 1e-300), z_p=z_p, z_o=z_o, rule=rule)


def _fraction(weight, mean, sd):
    """Mean, sd and the 5 % and 95 % quantiles of a mixture of normals cut at 0."""
    a = mean / sd
    ratio = np.exp(-0.5 * a * a - LOG_SQRT_2PI - log_ndtr(a))   # φ(a) / Φ(a)
    m1 = mean + sd * ratio
    var = sd * sd * (1.0 - ratio * (a + ratio))
    mu = float(np.sum(weight * m1))
    sig = float(np.sqrt(max(np.sum(weight * (var + m1 * m1)) - mu * mu, 0.0)))
    keep = weight > 1e-12 * weight.max()
    wk, mk, sk = weight[keep] / weight[keep].sum(), mean[keep], sd[keep]
    log_mass = log_ndtr(mk / sk)

    def upper(x, p):        # P(f > x) − p
        return float(np.sum(wk * np.exp(log_ndtr((mk - x) / sk) - log_mass))) - p

    lo, hi = 0.0, float(np.max(mk + 10.0 * sk))
    q = [optimize.brentq(upper, lo, hi, args=(p,), xtol=1e-14, rtol=1e-10)
         for p in (0.95, 0.05)]
    return mu, sig, q[0], q[1]


def thinned(inp: LeakInputs, step_s: float) -> LeakInputs:
    """The rows nearest a grid every ``step_s`` (and the last one)."""
    t = inp.t
    idx = np.unique(np.r_[np.searchsorted(t, np.arange(t[0], t[-1], step_s)), t.size - 1])
    return dataclasses.replace(inp, t=t[idx], residual=inp.residual[idx], impulse=inp.impulse[idx])


def leak_posterior(inp: LeakInputs, *, prior_leak: float = 0.01, eta: float = ETA,
                   sample_step_s: float = SAMPLE_STEP_S, check_step_s: float = 60.0,
                   p_detect: float = 0.99, _rule: Rule = RULE) -> LeakPosterior:
    """Run the Bayesian monitor over a stretch, as it would run on board: the residual taken
    every ``sample_step_s`` (:data:`SAMPLE_STEP_S`); a check every ``check_step_s`` (and at the
    last sample) sees only the data up to it, the onset uniform over that part of the stretch;
    ``prior_leak``: prior probability of a leak in the stretch, split evenly over the ``m``
    thrusters. Detection: the first check with
    ``P(leak) ≥ p_detect``; isolation: the first with one thruster's ``P ≥ p_detect`` (that
    thruster is the answer). ``_rule``: the onset quadrature (a finer one measures its error)."""
    for name, flag, v in (("prior_leak", "--prior-leak", prior_leak),
                          ("p_detect", "--p-detect", p_detect)):
        if not 0.0 < v < 1.0:
            raise InputError(f"must lie strictly between 0 and 1, got {v}",
                             path=spelled(flag, name))
    for name, flag, v in (("sample_step_s", "--sample-step", sample_step_s),
                          ("check_step_s", "--check-step", check_step_s)):
        if not v > 0:
            raise InputError(f"must be positive seconds, got {v}", path=spelled(flag, name))
        span = float(inp.t[-1] - inp.t[0])
        if span / v > MAX_GRID:  # the cells × checks table grows as the square
            raise InputError(f"{v:g} s makes {span / v:.3g} steps over the {span:.6g} s "
                             f"stretch, more than {MAX_GRID}; use at least "
                             f"{span / MAX_GRID:.3g} s", path=spelled(flag, name))
    raw, inp = inp, thinned(inp, sample_step_s)
    n = inp.t.size
    if n < 3:
        raise InputError(f"has {n} rows {sample_step_s:g} s apart; the leak monitor needs at "
                         "least 3", path=inp.source)
    sums = Sums(inp, eta, raw)
    t, m = sums.t, len(inp.thruster_names)
    checks = np.unique(np.r_[np.searchsorted(t, np.arange(check_step_s, t[-1], check_step_s)),
                             n - 1])
    checks = checks[checks >= 2]
    prob, det, iso = [], None, None
    for i, c in enumerate(checks):
        ev = sums.check(c, _rule)
        log_post = np.r_[np.log1p(-prior_leak), np.log(prior_leak / m) + ev.log_evidence()]
        prob.append(np.exp(log_post - logsumexp(log_post)))
        if det is None and 1.0 - prob[-1][0] >= p_detect:
            det = i
        if iso is None and prob[-1][1:].max() >= p_detect:
            iso = i
    prob = np.array(prob)
    # the fraction and onset of the most probable thruster, from all the data (the last check)
    k = int(np.argmax(prob[iso if iso is not None else -1][1:]))
    weight, onset, mean, sd = ev.mixture(k)
    fm, fs, f05, f95 = _fraction(weight, mean, sd)
    om = float(np.sum(weight * onset))
    t_check = inp.t[checks]
    return LeakPosterior(
        t_check=t_check, prob=prob, p_detect=p_detect,
        detection_time_s=None if det is None else float(t_check[det]),
        isolation_time_s=None if iso is None else float(t_check[iso]),
        thruster=None if iso is None else inp.thruster_names[k],
        fraction_mean=fm, fraction_sd=fs, fraction_interval=(f05, f95),
        torque_nm=fm * sums.u[:, k], onset_s=float(inp.t[0] + om),
        onset_sd_s=float(np.sqrt(max(np.sum(weight * (onset - om) ** 2), 0.0))),
        noise_sd_nms=sums.noise_sd(n - 1), hypotheses=inp.hypotheses)
