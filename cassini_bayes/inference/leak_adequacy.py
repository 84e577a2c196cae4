"""Does the leak monitor's model fit its stretch? Self-checks that need no truth.

The monitor's model (:mod:`cassini_bayes.inference.leak`, Lee Eq 10) explains the residual
momentum ``R`` of the rows it uses by an offset, a constant external torque, the thrusters'
fractional thrust errors and, under a leak hypothesis, the leak, plus white noise of the level
it reads from the data. The checks take the hypothesis most probable at the last check (no leak,
or that thruster's leak with its fraction fitted and its onset refined around the monitor's),
integrate the Gaussian nuisance parameters as the monitor does (under the component of the
torque's prior that the data favour) and look at the posterior mean:

* ``residual_fit`` — ``χ² = Σ_i Σ_a e_ia² / σ_a²`` of the residuals against the noise level
  ``σ_a`` the monitor assumed, on ``3n − p_eff`` degrees of freedom (``p_eff`` the trace of the
  hat matrix), as the normal deviate of its upper tail: a signal the model has no term for (a
  torque that changes within the stretch, a step) left in the residual. (A wrong inertia does
  not show here: its dead-band ``δI Δω`` raises the noise level the monitor reads as well.)
* ``prior_data_conflict`` — the torque's posterior mean in its prior sd (the mixture's, ``σ_T
  √(Σ w_c s_c²)``) and each thrust error's in ``η``: the monitor explains a secular misfit by a
  torque or a thrust error, and one pulled several prior sd says the model file's knowledge
  (``[torque_knowledge]``, its thrust) is wrong for this stretch.
* ``residual_autocorrelation`` — the lag-1 autocorrelation of the residual per axis (blocks of
  at least 64 rows; :func:`~cassini_bayes.inference.adequacy.residual_autocorrelation`): a
  slow wander the white model does not hold.

Thresholds as the fits' (4, 4 prior sd, 0.5); false-alarm rates and power: docs/leak.md.
"""

from __future__ import annotations

import numpy as np
from scipy import optimize, stats

from cassini_bayes.inference.adequacy.check import (PRIOR_CONFLICT_SD, Z_THRESHOLD, Adequacy,
                                                    z_check, normal_deviate)
from cassini_bayes.inference.adequacy.residuals import residual_autocorrelation
from cassini_bayes.inference.leak import (OFFSET_SD_NMS, TORQUE_SCALES, LeakInputs,
                                          LeakPosterior)
from cassini_bayes.inference.leak._posterior import thinned

__all__ = ["leak_adequacy", "nuisance_posterior"]


def _design(t: np.ndarray, impulse: np.ndarray, q: np.ndarray) -> np.ndarray:
    """(n, 3, 6 + m) the nuisance columns of the monitor: offset ``r_0`` (3), torque ``T`` (3),
    thrust errors ``δ_j Q[:, j] J_j`` of the ``m`` thrusters (Lee Eq 10-11)."""
    n = t.size
    eye = np.eye(3)
    return np.concatenate([np.broadcast_to(eye, (n, 3, 3)), t[:, None, None] * eye[None],
                           q[None, :, :] * impulse[:, None, :]], axis=2)


def nuisance_posterior(cols: np.ndarray, y: np.ndarray, noise_sd: np.ndarray,
                       torque_sd_nm: float, eta: float, extra_sd=(),
                       offset_sd_nms: float = OFFSET_SD_NMS):
    """Posterior of the monitor's nuisance parameters given rows ``y`` (n, 3) and design
    ``cols`` (n, 3, 6 + m + e), under the component of the torque's prior mixture that the data
    favour (the larger evidence; the mixture's mean would average two fits and fit neither);
    ``extra_sd`` the prior sds of ``e`` more columns after the monitor's 6 + m (a leak's);
    ``offset_sd_nms`` the offsets' prior sd, N m s (the monitor's, ``LeakInputs.offset_sd_nms``).

    Returns ``(mean (6 + m + e,), p_eff)``: the posterior mean and the effective number of
    parameters (the trace of the hat matrix)."""
    lam = 1.0 / np.asarray(noise_sd, float) ** 2
    nn = np.einsum("iap,a,iaq->pq", cols, lam, cols)
    b = np.einsum("iap,a,ia->p", cols, lam, y)
    means, traces, log_z = [], [], []
    n_thrusters = cols.shape[-1] - 6 - len(extra_sd)
    for (scale, weight) in TORQUE_SCALES:
        prec = 1.0 / np.r_[np.full(3, offset_sd_nms ** 2),
                           np.full(3, (scale * max(torque_sd_nm, 1e-12)) ** 2),
                           np.full(n_thrusters, max(eta, 1e-12) ** 2), np.asarray(extra_sd) ** 2]
        a = np.diag(prec) + nn
        m = np.linalg.solve(a, b)
        means.append(m)
        traces.append(float(np.trace(np.linalg.solve(a, nn))))
        log_z.append(np.log(weight) + 0.5 * (np.sum(np.log(prec)) - np.linalg.slogdet(a)[1]
                                             + b @ m))
    c = int(np.argmax(log_z))
    return means[c], traces[c]


ONSET_SCAN = 161
"""Onsets tried around the monitor's posterior mean, over ± two sample steps (the check fits
the onset that suits its own fit of the fraction, which a posterior mean need not be)."""


def leak_adequacy(inp: LeakInputs, post: LeakPosterior, *, eta: float,
                  sample_step_s: float) -> Adequacy:
    """The checks of the monitor's run ``post`` over the stretch ``inp`` (module docstring);
    ``eta`` and ``sample_step_s`` as the monitor ran.

    Under a leak hypothesis the leak's fraction is fitted with the nuisance parameters (a
    Gaussian of sd 1, i.e. 100 % of the thrust) and its onset scanned over ± two sample steps
    around the monitor's posterior mean and refined: the check judges the model at its best
    fit, which the note sets beside the monitor's estimate."""
    used = thinned(inp, sample_step_s)
    t = used.t - used.t[0]
    y = np.asarray(used.residual, float)
    cols = _design(t, used.impulse, used.q_matrix)
    sd = np.asarray(post.noise_sd_nms, float)
    torque_sd_nm = used.torque_sd_nm
    last, names, p0 = post.prob[-1], used.thruster_names, cols.shape[-1]
    if np.argmax(last) > 0:      # a leak is the most probable answer: fit it with the rest
        k = names.index(post.thruster) if post.thruster else int(np.argmax(last[1:]))
        torque = used.thrust_n[k] * used.q_matrix[:, k]                 # N m per unit fraction
        def fit_at(onset: float):
            leak = (np.maximum(used.t - onset, 0.0)[:, None] * torque[None, :])[..., None]
            c2 = np.concatenate([cols, leak], axis=2)
            m, p_eff = nuisance_posterior(c2, y, sd, torque_sd_nm, eta, extra_sd=(1.0,),
                                          offset_sd_nms=used.offset_sd_nms)
            e = y - np.einsum("iap,p->ia", c2, m)
            return float(np.sum((e / sd[None, :]) ** 2)), m[:p0], p_eff, e, onset, m[p0]

        # the onset: a scan over ± two sample steps, then the best point refined within its
        # neighbours (the χ² is smooth in the onset between the rows)
        grid = np.linspace(post.onset_s - 2 * sample_step_s, post.onset_s + 2 * sample_step_s,
                           ONSET_SCAN)
        chi = [fit_at(x)[0] for x in grid]
        i = int(np.argmin(chi))
        bounds = (grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)])
        res = optimize.minimize_scalar(lambda x: fit_at(x)[0], method="bounded", bounds=bounds,
                                       options={"xatol": 1e-3})
        best = min((fit_at(x) for x in (grid[i], float(res.x))), key=lambda r: r[0])
        chi2, mean, p_eff, e, onset, frac = best
        hyp = (f"a leak of {names[k]}, {100 * frac:.3g} % from {onset:.0f} s (the "
               f"monitor's estimate {100 * post.fraction_mean:.3g} % from {post.onset_s:.0f} s)")
    else:
        mean, p_eff = nuisance_posterior(cols, y, sd, torque_sd_nm, eta,
                                         offset_sd_nms=used.offset_sd_nms)
        e = y - np.einsum("iap,p->ia", cols, mean)
        chi2 = float(np.sum((e / sd[None, :]) ** 2))
        hyp = "no leak"
    dof = max(3 * t.size - p_eff, 1.0)
    fit = z_check("residual_fit", normal_deviate(min(2.0 * float(stats.chi2.sf(chi2, dof)), 1.0)),
                 Z_THRESHOLD, note=f"chi2 {chi2:.4g} on {dof:.4g} dof under {hyp}; residual rms "
                 + ", ".join(f"{a} {r:.3g}" for a, r in zip("XYZ", np.sqrt(np.mean(e * e, 0))))
                 + " N m s against the assumed noise " + ", ".join(f"{s_:.3g}" for s_ in sd))
    torque_sd = used.torque_sd_nm * np.sqrt(sum(w * s * s for s, w in TORQUE_SCALES))
    z = np.r_[np.abs(mean[3:6]) / max(torque_sd, 1e-300), np.abs(mean[6:]) / max(eta, 1e-300)]
    labels = [f"torque[{a}]" for a in "XYZ"] + [f"thrust_error[{n}]" for n in names]
    j = int(np.argmax(z))
    conflict = z_check("prior_data_conflict", float(z[j]), PRIOR_CONFLICT_SD, labels[j],
                      f"torque {', '.join(f'{x * 1e6:.3g}' for x in mean[3:6])} µN m (prior sd "
                      f"{torque_sd * 1e6:.3g}); thrust errors up to "
                      f"{100 * np.max(np.abs(mean[6:])):.3g} % (prior sd {100 * eta:.3g} %), "
                      f"under {hyp}")
    return Adequacy((fit, conflict,
                     residual_autocorrelation(e, np.zeros(t.size, int), labels=["stretch"])))
