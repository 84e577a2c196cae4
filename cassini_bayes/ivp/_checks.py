"""Input checks of the IVP: one-line :class:`~cassini_bayes.errors.InputError` naming the argument
(or, under the ``cassini-bayes`` command, its option) and what to do."""

from __future__ import annotations

import numpy as np

from cassini_bayes.errors import InputError

MAX_ORDER = 12   # Lee §3.3: "polynomial vectors ... with each axis up to twelfth order"


def _first_bad(mask: np.ndarray) -> str:
    idx = np.argwhere(mask)[0]
    return "" if idx.size == 0 else f" (at index {tuple(int(i) for i in idx)})"


def check_finite(x: np.ndarray, name: str) -> None:
    """Refuse NaN or infinite entries of ``x``."""
    bad = ~np.isfinite(x)
    if bad.any():
        raise InputError(f"{name} has a non-finite value{_first_bad(bad)}: give finite numbers")


def check_vectors(x: np.ndarray, name: str) -> None:
    """Refuse an array whose last axis is not of length 3."""
    if x.ndim == 0 or x.shape[-1] != 3:
        raise InputError(f"{name} must hold 3-vectors (last axis of length 3), got shape "
                         f"{x.shape}")


def check_nonzero_vectors(x: np.ndarray, name: str) -> None:
    """Refuse a zero vector: its direction (and a conic about it) is undefined."""
    bad = np.linalg.norm(x, axis=-1) == 0
    if bad.any():
        raise InputError(f"{name} is a zero vector{_first_bad(bad)}: a position relative to the "
                         "central body must be non-zero")


def check_mu(mu: np.ndarray, name: str) -> None:
    """Refuse a negative or non-finite gravitational parameter."""
    check_finite(mu, name)
    if (mu < 0).any():
        raise InputError(f"{name} = {float(np.min(mu)):g} is negative: the gravitational "
                         "parameter G(m1 + m2) is >= 0 (m^3/s^2; 0 for a straight line)")


def check_interval(t_start: float, t_end: float, name: str) -> None:
    """Refuse a segment or validity interval with ``t_end <= t_start`` or non-finite ends."""
    check_finite(np.asarray([t_start, t_end], float), name)
    if not t_end > t_start:
        raise InputError(f"{name} ends at {t_end:g} s, not after its start {t_start:g} s: "
                         "give t_f > t_s")


def check_order(order: int, name: str) -> None:
    """Refuse a polynomial order outside 0 .. 12 (Cassini's limit, Lee §3.3)."""
    if isinstance(order, bool) or int(order) != order or not 0 <= int(order) <= MAX_ORDER:
        raise InputError(f"{name} = {order} is outside 0 .. {MAX_ORDER}: Cassini's polynomial "
                         f"vectors go up to order {MAX_ORDER} on each axis (Lee §3.3)")


def check_positive(x: float, name: str) -> None:
    """Refuse a value that is not a finite positive number."""
    if not (np.isfinite(x) and x > 0):
        raise InputError(f"{name} must be a positive number, got {x}")
