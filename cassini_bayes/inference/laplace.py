"""Laplace approximation used to centre and whiten the samplers' coordinates.

The thrust and RWA4 models hand NUTS a vector ``w`` with ``θ = centre + tril w``, where
``centre`` is the posterior mode and ``tril`` the Cholesky factor of the inverse negative Hessian
there. The density is exact in ``θ`` whatever the centring (the affine map has a constant
Jacobian); a good Laplace step only makes the geometry close to a standard normal, which is what
NUTS's step-size and mass-matrix adaptation handle best (docs/design.md §7.4).

The parameters of these models span many orders of magnitude of posterior scale (thrust to
1e-4 of its prior width, noise scales left at their prior), which stalls a quasi-Newton method
started in the raw coordinates. :func:`laplace` therefore alternates: a trust-region Newton solve
(``scipy.optimize.minimize(method="trust-exact")``, dimensions are small), then a re-whitening
with the Hessian at the new point, until the Newton decrement ``gᵀ H⁻¹ g`` is negligible.

The Hessian is the central difference of the compiled gradient along the current whitened
coordinates (``2 d`` gradients for ``d`` parameters, step ``1e-4`` of the current scale), taken
twice at each round's start: once along the previous round's scales (unit scales at the start),
then along the scales that this gives, so that the step is ``1e-4`` posterior sd in every
direction (:func:`_rewhiten`): the truncation error falls as the step squared, below rounding at
this step. ``jax.hessian`` is exact, but it is a second program of the whole density (forward
over reverse) to trace, lower and load in every process, for a matrix that only sets the
sampler's coordinates (the density sampled is exact whatever they are; the costs are in
docs/performance.md, "Other model choices, measured").

Differences fail where the density is far from quadratic within the step: inside a round the
trust region can move to where the curvature is 1e9 times that at the round's start (an RWA4
SBC replicate near the inertia's physical boundary), so a step of ``1e-4`` of the old scales is
several posterior sd there, the differenced "Hessian" has spurious negative curvature and the
solve stalls. So when the differenced rounds do not reach a negligible Newton decrement,
:func:`laplace` starts again with ``jax.hessian`` (compiled only then) and keeps the better end
point.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any, Callable

import jax
import numpy as np

__all__ = ["laplace"]

_DECREMENT_TOL = 1e-8      # Newton decrement (log-density units) at which the mode is accepted
_FD_STEP = 1e-4            # central-difference step of the Hessian, in the current scales


def _whitening(h: np.ndarray) -> np.ndarray:
    """Cholesky factor of the inverse of the symmetric matrix ``h``; directions of non-positive
    or non-finite curvature get unit scale.

    Computed without a Cholesky decomposition, which can fail ("not positive definite") on the
    rounding of an inverse with condition number ~1e16 (the likely source of the one failed
    replicate of a 208-replicate RWA4 SBC: the other Cholesky decompositions of its preparation
    factor the same prior matrices in every replicate): with
    ``h = V W Vᵀ``, ``A = V W^{−½}`` is a square root of ``h⁻¹``; the QR decomposition
    ``Aᵀ = Q R`` gives ``h⁻¹ = A Aᵀ = Rᵀ R``, i.e. the lower Cholesky factor ``Rᵀ`` (signs made
    positive on the diagonal)."""
    h = 0.5 * (h + h.T)
    w, v = np.linalg.eigh(h)
    w = np.where(np.isfinite(w) & (w > 1e-12), w, 1.0)
    r = np.linalg.qr((v / np.sqrt(w)).T, mode="r")
    sign = np.where(np.diag(r) < 0, -1.0, 1.0)
    return (sign[:, None] * r).T


@lru_cache(maxsize=64)
def _compiled(log_density: Callable):
    """Jitted value-and-gradient of ``−log_density(θ, data)``, one per function object:
    problems of the same shapes reuse the compiled code."""
    def nll(x, data):
        return -log_density(x, data)

    return jax.jit(jax.value_and_grad(nll))


@lru_cache(maxsize=64)
def _compiled_hessian(log_density: Callable):
    """Jitted exact Hessian of ``−log_density(θ, data)`` (the fallback, module docstring)."""
    def nll(x, data):
        return -log_density(x, data)

    return jax.jit(jax.hessian(nll))


def _hessian(grad: Callable[[np.ndarray], np.ndarray], x: np.ndarray,
             scales: np.ndarray) -> np.ndarray:
    """``scalesᵀ H scales`` at ``x`` by central differences of ``grad`` along the columns of
    ``scales`` (step :data:`_FD_STEP`), symmetrised (module docstring)."""
    cols = []
    for k in range(x.size):
        dx = _FD_STEP * scales[:, k]
        cols.append(scales.T @ (grad(x + dx) - grad(x - dx)) / (2.0 * _FD_STEP))
    h = np.stack(cols, 1)
    return 0.5 * (h + h.T)


def _rewhiten(hessian: Callable[[np.ndarray, np.ndarray], np.ndarray], x: np.ndarray,
              tril: np.ndarray, passes: int) -> np.ndarray | None:
    """The whitening at ``x``: :func:`_whitening` of the Hessian taken along ``tril``'s columns,
    then taken again along the new factor's (``None`` where the curvature is not finite).

    With central differences the first pass's step is ``1e-4`` of the scales ``tril`` it is
    given, which at the start (unit scales) or after a long move can be most of a posterior
    sd: the difference then carries the density's third derivative, and along the stiff
    directions it swamps the soft ones' curvature (an RWA4 replicate whose stiffest coordinate
    has sd 1.7e-4: relative error 2e-7 of the largest entry, a soft block of curvature ~1 wrong
    by ~6). The second pass steps ``1e-4`` of the scales just found. (``passes`` 1 for the exact
    Hessian, which does not depend on the scales.)"""
    for _ in range(passes):
        h_w = hessian(x, tril)
        if not np.all(np.isfinite(h_w)):
            return None
        tril = tril @ _whitening(h_w)
    return tril


def _newton_rounds(nll: Callable, hessian: Callable, x: np.ndarray, rounds: int,
                   passes: int) -> tuple[np.ndarray, np.ndarray, bool]:
    """Alternate re-whitening (:func:`_rewhiten`, ``passes``) and a trust-region Newton solve
    (module docstring) from ``x``; ``hessian(x, scales)`` gives ``scalesᵀ H scales``. Returns the
    end point, its whitening and whether the Newton decrement fell below
    :data:`_DECREMENT_TOL`."""
    import scipy.optimize

    tril = np.eye(x.size)
    for _ in range(rounds):
        new = _rewhiten(hessian, x, tril, passes)
        if new is None:
            return x, tril, False
        tril = new
        step = tril.T @ nll(x)[1]               # gradient in whitened coordinates
        if float(step @ step) < _DECREMENT_TOL:
            return x, tril, True
        t_j, x_j = tril, x

        def fun(z):
            v, gx = nll(x_j + t_j @ z)
            gz = t_j.T @ gx
            if not (np.isfinite(v) and np.all(np.isfinite(gz))):
                return np.inf, np.zeros_like(gz)     # outside the support: step rejected
            return v, gz

        def hfun(z):
            hz = hessian(x_j + t_j @ z, t_j)
            # a trial point where the curvature is not finite (e.g. at the edge of the
            # support): use the whitened identity, the curvature at the round's start
            return hz if np.all(np.isfinite(hz)) else np.eye(x.size)

        res = scipy.optimize.minimize(fun, np.zeros(x.size), jac=True, hess=hfun,
                                      method="trust-exact", options={"maxiter": 200})
        if not np.isfinite(res.fun) or res.fun > fun(np.zeros(x.size))[0]:
            return x, tril, False
        x = x + tril @ res.x
    return x, tril, False


def _scanned(nll: Callable, x: np.ndarray, index, values) -> np.ndarray:
    """``x`` with the coordinates ``index`` set together to the value of ``values`` where the
    density is highest (``x`` unchanged where it is nowhere finite)."""
    best, best_v = x, np.inf
    for value in values:
        y = x.copy()
        y[index] = value
        v = nll(y)[0]
        if np.isfinite(v) and v < best_v:
            best, best_v = y, v
    return best


def laplace(log_density: Callable, theta0, data: Any, *, rounds: int = 6,
            scan: tuple[Any, Any] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Mode and Cholesky factor of the inverse negative Hessian of ``log_density``.

    Parameters
    ----------
    log_density : jittable ``f(θ, data)`` (the model's log prior + log likelihood). Pass a
        module-level function (not a fresh closure) so that its compiled derivatives are reused
        across problems of the same shapes.
    theta0 : starting point.
    data : pytree of arrays passed to ``log_density`` as its second argument.
    rounds : at most this many Newton solves, each in coordinates whitened by the Hessian of the
        previous round's end point.
    scan : ``(index, values)``: first set the coordinates ``index`` of ``theta0`` together to
        the one of ``values`` with the highest density. For a scale coordinate (a noise level):
        far from the data's, the density is so steep that the Newton steps leave the mode's basin.

    Returns
    -------
    centre, tril : the mode found and the lower Cholesky factor of the inverse negative Hessian
        there. When no finite mode is found the start point and unit scales are returned (the
        sampler then still samples the exact density, only less efficiently).
    """
    vg_ = _compiled(log_density)

    def nll(x):
        v, g = vg_(jax.device_put(np.asarray(x, float)), data)
        return float(v), np.asarray(g, float)

    def differenced(x, scales):
        return _hessian(lambda y: nll(y)[1], x, scales)

    x0 = np.asarray(theta0, float)
    if scan is not None:
        x0 = _scanned(nll, x0, *scan)
    if not np.isfinite(nll(x0)[0]):
        return x0, np.eye(x0.size)
    x, tril, converged = _newton_rounds(nll, differenced, x0, rounds, passes=2)
    if converged:
        return x, tril
    hess_ = _compiled_hessian(log_density)

    def exact(x, scales):
        return scales.T @ np.asarray(hess_(jax.device_put(np.asarray(x, float)), data)) @ scales

    x_e, tril_e, converged_e = _newton_rounds(nll, exact, x0, rounds, passes=1)
    if converged_e or nll(x_e)[0] <= nll(x)[0]:
        return x_e, tril_e
    return x, tril
