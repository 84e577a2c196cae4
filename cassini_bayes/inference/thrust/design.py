"""What the biasing events can tell about each thruster: the impulse design of the per-thruster
model, its singular directions, its rank and the identifiable combinations of thrusts
(:mod:`cassini_bayes.inference.thrust`, "Per-thruster model").

The design is Feldman & Lee Eq 17 linearised at the prior's centre: the derivative of the
predicted left side ``V(t_i) = Σ_s F_s Q_s j_s(t_i)`` in each parameter, with

* ``∂V/∂log F_s = F_s Q_s j_s(t)`` (the column ``Q[:, s] · ∫on-time_s`` of Eqs 17-19, the
  on-time corrected for the pulse response at the prior's median time constants), times the
  prior sd of ``log F`` (0.3);
* ``∂V/∂δ_k = −Σ_s F_s (e_k × d_s) j_s(t)`` for the centre-of-mass offset ``δ`` (Eq 16 with
  ``r_s − e − δ``: only firings with a net force move it), times ``[center_of_mass] sd_m``;

each event's rows centred over its samples (the free offset of the likelihood) and whitened by
its white-noise covariance ``B`` at the data's noise levels. In these prior-whitened units the
squared singular values ``s²`` of the stacked design are the data's information against the
prior's (1) along each singular direction: the posterior sd there is ``1/√(1 + s²)`` of the
prior's. The **rank** counts the directions with ``s ≥ 1`` (:data:`INFORMATION_MIN`: the data
know a direction at least as well as the prior does).

Thrust combinations: the posterior covariance of the thrusts alone (the offset marginalised),
``C_FF``, in the same units; its eigenvectors with contraction ``1 − λ ≥ 0.5`` span the
identified thrust subspace. A thruster is *identified* when its own direction lies in that
subspace to :data:`IN_SUBSPACE_MIN` of its squared length. For the others, the identified
combinations are the vectors of that subspace made of them alone, in reduced row-echelon form
(so Cassini's Y pairs fired together come out as ``0.5 F[Y1] + 0.5 F[Y3]``, the pair mean of
Eq 21, with nothing named by hand), as weights of the thrusts in newtons (``w_s ∝ v_s / F_s``,
the log-space direction ``v`` at the predicted thrusts), scaled so that ``Σ |w_s| = 1``.
"""

from __future__ import annotations

from typing import NamedTuple, Sequence

import numpy as np

from cassini_bayes.estimators.thrust import combination_label

__all__ = ["ThrustDesign", "thrust_design", "INFORMATION_MIN", "CONTRACTION_MIN",
           "IN_SUBSPACE_MIN", "combination_label"]

INFORMATION_MIN = 1.0
"""A singular direction counts towards the rank when its singular value is at least this (the
data's information along it at least the prior's)."""
CONTRACTION_MIN = 0.5
"""A thrust direction is identified when its posterior variance is at most this share of its
prior variance in the linearised design (contraction ≥ 0.5, the summary's weak-identification
line)."""
IN_SUBSPACE_MIN = 0.9
"""A thruster is identified on its own when at least this share of its unit direction's squared
length lies in the identified thrust subspace."""


class ThrustDesign(NamedTuple):
    """The linearised impulse design of a per-thruster problem (module docstring).

    Attributes
    ----------
    thrusters : the thrusters' names (M).
    basis : (M + 3, M + 3) orthogonal: the right singular vectors, columns by decreasing
        singular value, in the prior-whitened ``(log F, δ)`` coordinates.
    singular : (M + 3,) singular values (prior-whitened units).
    rank : directions with ``singular ≥ INFORMATION_MIN``.
    thrust_rank : identified thrust directions (contraction ≥ :data:`CONTRACTION_MIN`).
    identified : (M,) bool, thrusters identified on their own.
    fired : (M,) bool, thrusters with a pulse in any event.
    combinations : (C, M) weights of the thrusts (N per N) of each identified combination of
        thrusters that are not identified on their own.
    com_contraction : (3,) linearised posterior/prior contraction of the offset per axis.
    """

    thrusters: tuple[str, ...]
    basis: np.ndarray
    singular: np.ndarray
    rank: int
    thrust_rank: int
    identified: np.ndarray
    fired: np.ndarray
    combinations: np.ndarray
    com_contraction: np.ndarray

    def to_dict(self) -> dict:
        """The ``thrust_design`` block of ``summary.json`` (without the combinations'
        posterior, which :func:`~cassini_bayes.api.thrust_summary` adds)."""
        return {
            "rank": int(self.rank), "parameters": int(self.basis.shape[0]),
            "thrust_rank": int(self.thrust_rank), "thrusters": list(self.thrusters),
            "singular_values": [float(x) for x in self.singular],
            "identified": [n for n, ok in zip(self.thrusters, self.identified) if ok],
            "not_fired": [n for n, ok in zip(self.thrusters, self.fired) if not ok],
            "combinations": [{"label": combination_label(w, self.thrusters),
                              "weights": {n: float(x) for n, x in zip(self.thrusters, w) if x}}
                             for w in self.combinations],
            "com_contraction": {f"com_{a}": max(float(c), 0.0)
                                for a, c in zip("xyz", self.com_contraction)},
            "rule": (f"rank: singular values >= {INFORMATION_MIN:g} of the prior-whitened, "
                     "noise-whitened impulse design (Feldman & Lee Eq 17 linearised at the prior "
                     f"centre); a thruster is identified when {IN_SUBSPACE_MIN:g} of its "
                     "direction lies in the thrust subspace whose linearised contraction is "
                     f">= {CONTRACTION_MIN:g}; the others' identified combinations are listed"),
        }


def _rref(rows: np.ndarray, tol: float = 1e-8) -> np.ndarray:
    """Reduced row-echelon form of ``rows`` (r, M), zero rows dropped (Gauss-Jordan with partial
    pivoting; entries below ``tol`` of the largest set to 0)."""
    a = np.array(rows, float)
    r, m = a.shape
    scale = max(float(np.max(np.abs(a), initial=0.0)), 1e-300)
    lead = 0
    for i in range(r):
        while lead < m:
            piv = i + int(np.argmax(np.abs(a[i:, lead])))
            if abs(a[piv, lead]) > tol * scale:
                break
            lead += 1
        if lead == m:
            return a[:i]
        a[[i, piv]] = a[[piv, i]]
        a[i] /= a[i, lead]
        for k in range(r):
            if k != i:
                a[k] -= a[k, lead] * a[i]
        lead += 1
    a[np.abs(a) < tol] = 0.0
    return a


def thrust_design(j, mask, q_matrix, d_matrix, thrust_pred, noise_cov, log_sd: float,
                  com_sd: float, names: Sequence[str], fired) -> ThrustDesign:
    """The design of the module docstring (NumPy).

    Parameters
    ----------
    j : (E, M, n) s, each thruster's impulse per newton delivered by each sample (at the
        prior's median time constants), counted from any constant.
    mask : (E, n) 1 for a sample, 0 for padding.
    q_matrix, d_matrix : (3, M) torque per newton (m) and unit force direction of each thruster.
    thrust_pred : (M,) N, the prior's centres.
    noise_cov : (E, 3, 3) (N m s)², each event's white-noise covariance ``B`` of one sample.
    log_sd, com_sd : prior sds of ``log F`` and of each offset component (m).
    names : the thrusters' names. fired : (M,) bool, thrusters with a pulse in any event.
    """
    j, mask = np.asarray(j, float), np.asarray(mask, float)
    q, d = np.asarray(q_matrix, float), np.asarray(d_matrix, float)
    f = np.asarray(thrust_pred, float)
    m = q.shape[1]
    blocks = []
    for e in range(j.shape[0]):
        keep = mask[e] > 0
        je = j[e][:, keep]                                               # (M, n)
        je = je - je.mean(1, keepdims=True)                              # the free offset
        cols_f = log_sd * f[:, None, None] * q.T[:, :, None] * je[:, None, :]   # (M, 3, n)
        force = d * f[None, :]                                           # (3, M) N per N
        cols_c = np.stack([-com_sd * np.cross(np.eye(3)[k][:, None], force, axis=0) @ je
                           for k in range(3)])                           # (3, 3, n)
        cols = np.concatenate([cols_f, cols_c])                          # (M + 3, 3, n)
        chol = np.linalg.cholesky(np.asarray(noise_cov[e], float))
        white = np.linalg.solve(chol, cols.transpose(1, 0, 2).reshape(3, -1))
        blocks.append(white.reshape(3, m + 3, -1).transpose(0, 2, 1).reshape(-1, m + 3))
    g = np.concatenate(blocks)
    _, sv, vt = np.linalg.svd(g, full_matrices=True)
    sv = np.r_[sv, np.zeros(m + 3 - sv.size)]
    basis = vt.T
    post = basis @ np.diag(1.0 / (1.0 + sv**2)) @ basis.T                # posterior cov, whitened
    lam, w = np.linalg.eigh(post[:m, :m])
    ident = w[:, 1.0 - lam >= CONTRACTION_MIN]                            # (M, r)
    proj = ident @ ident.T
    identified = np.diag(proj) >= IN_SUBSPACE_MIN
    rest = np.flatnonzero(~identified)
    combos = np.zeros((0, m))
    if rest.size and ident.shape[1]:
        lam_r, v_r = np.linalg.eigh(proj[np.ix_(rest, rest)])
        rows = v_r[:, lam_r >= IN_SUBSPACE_MIN].T
        if rows.size:
            rows = _rref(rows)
            full = np.zeros((rows.shape[0], m))
            full[:, rest] = rows / f[rest][None, :]                     # log-space → newtons
            full /= np.sum(np.abs(full), 1, keepdims=True)
            full *= np.sign(full[np.arange(full.shape[0]), np.argmax(np.abs(full), 1)])[:, None]
            full[np.abs(full) < 1e-9] = 0.0
            combos = full
    return ThrustDesign(tuple(names), basis, sv, int(np.sum(sv >= INFORMATION_MIN)),
                        int(ident.shape[1]), identified, np.asarray(fired, bool), combos,
                        1.0 - np.diag(post)[m:])
