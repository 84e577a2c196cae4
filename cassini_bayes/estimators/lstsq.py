"""Plain linear least squares with rank checks, shared by the papers' estimators.

Every estimator of the papers is ``x̂ = (Aᵀ A)⁻¹ Aᵀ b`` (Feldman & Lee Eqs 7, 11, 19-23). Here it is
solved by SVD, which also gives the rank, the condition number and — when the data cannot
identify every unknown — the null space, from which the unidentifiable parameters are named
(:class:`~cassini_bayes.errors.UnidentifiableError`), instead of returning garbage.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from cassini_bayes.errors import InputError, UnidentifiableError

__all__ = ["LstsqFit", "solve_lstsq", "null_space_groups", "RANK_RTOL", "COND_WARN"]

# Singular values below RANK_RTOL × s_max count as zero (columns scaled to unit norm first).
RANK_RTOL = 1e-9
# Above this condition number (of the column-scaled matrix) the fit is returned with a warning.
COND_WARN = 1e6


class LstsqFit(NamedTuple):
    """Least-squares solution of ``A x ≈ b``.

    Attributes
    ----------
    estimate : (p,) solution, in the units of ``b`` per unit of ``A``'s columns.
    residual_rms : root-mean-square of ``b − A x̂`` (units of ``b``).
    rank : numerical rank of ``A``.
    condition : condition number of ``A`` with its columns scaled to unit norm.
    warnings : human-readable warnings (ill conditioning, ...).
    """

    estimate: np.ndarray
    residual_rms: float
    rank: int
    condition: float
    warnings: tuple[str, ...]


def null_space_groups(vt_null: np.ndarray, names, tol: float = 1e-6) -> list[list[str]]:
    """Group the parameters that the null space couples (connected components of ``N Nᵀ``).

    ``vt_null`` (k, p) orthonormal null-space basis (rows). Parameters ``i, j`` are linked when
    the null-space projector has ``|P_ij| > tol``; each group is a set of parameters of which
    only some combination is identified (a singleton is a parameter the data does not touch).
    """
    p = vt_null.T @ vt_null
    n = p.shape[0]
    involved = [i for i in range(n) if p[i, i] > tol]
    seen: set[int] = set()
    groups = []
    for i in involved:
        if i in seen:
            continue
        stack, comp = [i], []
        seen.add(i)
        while stack:
            a = stack.pop()
            comp.append(a)
            for b in involved:
                if b not in seen and abs(p[a, b]) > tol:
                    seen.add(b)
                    stack.append(b)
        groups.append([names[k] for k in sorted(comp)])
    return groups


def solve_lstsq(a, b, names, what: str = "parameters", hint: str = "") -> LstsqFit:
    """Solve ``A x ≈ b`` by SVD; raise :class:`UnidentifiableError` if ``A`` is rank deficient.

    Parameters
    ----------
    a : (m, p) design matrix.
    b : (m,) data.
    names : p parameter names, used to name what the data cannot identify.
    what : what the unknowns are, for messages (``"inertia entries"``).
    hint : what to do about it, appended to the error message.
    """
    a = np.asarray(a, float)
    b = np.asarray(b, float)
    if a.ndim != 2 or b.shape != (a.shape[0],):
        raise ValueError(f"shapes do not match: A {a.shape}, b {b.shape}")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise InputError(f"the least-squares system for the {what} has NaN/inf entries; "
                                  "remove the bad rows from the input")
    m, p = a.shape
    scale = np.linalg.norm(a, axis=0)
    zero_cols = scale == 0
    scale = np.where(zero_cols, 1.0, scale)
    a_s = a / scale
    if m == 0:
        raise UnidentifiableError(f"no data rows to estimate the {what}")
    u, s, vt = np.linalg.svd(a_s, full_matrices=False)
    smax = s[0]
    rank = int(np.sum(s > RANK_RTOL * smax)) if smax > 0 else 0
    if rank < p:
        null = np.linalg.svd(a_s, full_matrices=True)[2][rank:]
        groups = null_space_groups(null, list(names))
        parts = []
        for g in groups:
            parts.append(g[0] + " (not excited by the data)" if len(g) == 1
                         else "{" + ", ".join(g) + "} (only a combination is identified)")
        raise UnidentifiableError(
            f"the data cannot identify the {what}: rank {rank} of {p}; "
            f"unidentifiable: {'; '.join(parts)}" + (f". {hint}" if hint else ""))
    cond = float(s[0] / s[-1])
    x_s = vt.T @ ((u.T @ b) / s)
    x = x_s / scale
    r = b - a @ x
    warns = []
    if cond > COND_WARN:
        warns.append(f"ill-conditioned least squares for the {what} (condition number "
                     f"{cond:.3g}); the estimate is sensitive to noise")
    return LstsqFit(x, float(np.sqrt(np.mean(r * r))), rank, cond, tuple(warns))
