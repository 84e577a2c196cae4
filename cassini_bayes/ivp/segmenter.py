"""Segment boundaries and orders for Chebyshev polynomial vectors (Lee §3.3.2).

Rule: each segment is made as long as the highest allowed order (12 on Cassini) lets it be while
the angle between the fitted and the true vector stays within the requirement (40 µrad, Lee
§3.3.2 and Table 2); then its order is lowered to the smallest that still meets the requirement
on that segment, since a lower order stores fewer coefficients (``3(n+1)+1``).

The angle is checked on ``M + 1 = 16(n+1)+1`` points of each candidate segment spaced as
``cos(πk/M)`` (dense where the Chebyshev error oscillates fastest, near the ends), never at the
fitting nodes alone, against the requirement times ``cos(π/32)`` (0.995): an error shaped like
``T_{n+1}`` peaks at most that far above its largest sample on this grid.
:func:`angular_error` re-checks a fit on any grid.
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np

from cassini_bayes.errors import InputError
from cassini_bayes.ivp._checks import check_interval, check_order, check_positive
from cassini_bayes.ivp.chebyshev import ChebyshevSegments, chebyshev_fit, chebyshev_sum, \
    normalised_time

__all__ = ["SegmentFit", "fit_chebyshev_segments", "angle_between_vectors", "angular_error"]

DEFAULT_REQUIREMENT_RAD = 40e-6   # Lee §3.3.2 and Table 2: IVP modelling error 40 µrad
_CHECK_PER_ORDER = 16             # check points per coefficient of a candidate segment
_BISECT_RATIO = 1.005             # segment lengths are found to 0.5 %
_MAX_SEGMENTS = 100_000


class SegmentFit(NamedTuple):
    """The segmenter's result.

    Attributes
    ----------
    segments : the :class:`~cassini_bayes.ivp.chebyshev.ChebyshevSegments`.
    max_error_rad : ``(S,)`` largest angle between fitted and true vector on each segment's
        check points, rad.
    requirement_rad : the requirement the segments were fitted to, rad.
    """

    segments: ChebyshevSegments
    max_error_rad: np.ndarray
    requirement_rad: float


def angle_between_vectors(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle (rad) between the vectors ``a`` and ``b`` (..., 3), accurate near zero
    (``atan2(|a×b|, a·b)``)."""
    cross = np.linalg.norm(np.cross(a, b), axis=-1)
    return np.arctan2(cross, np.sum(a * b, axis=-1))


_MARGIN = np.cos(np.pi / (2 * _CHECK_PER_ORDER))


def _check_grid(t_s: float, t_f: float, order: int) -> np.ndarray:
    m = _CHECK_PER_ORDER * (order + 1)
    return 0.5 * (t_f + t_s) + 0.5 * (t_f - t_s) * np.cos(np.pi * np.arange(m + 1) / m)


def _segment_error(f, t_s: float, t_f: float, order: int) -> tuple[float, np.ndarray]:
    c = chebyshev_fit(f, t_s, t_f, order)
    t = _check_grid(t_s, t_f, order)
    fitted = chebyshev_sum(normalised_time(t, t_s, t_f), c, xp=np)
    err = angle_between_vectors(fitted, np.asarray(f(t), float))
    if not np.all(np.isfinite(err)):
        raise InputError(f"the vector is not finite between t = {t_s:g} s and {t_f:g} s; "
                         "check the trajectory there")
    return float(err.max()), c


def fit_chebyshev_segments(f: Callable[[np.ndarray], np.ndarray], t_start_s: float,
                           t_end_s: float, *, requirement_rad: float = DEFAULT_REQUIREMENT_RAD,
                           max_order: int = 12) -> SegmentFit:
    """Chebyshev segments of the vector ``f`` over ``[t_start_s, t_end_s]`` whose direction is
    within ``requirement_rad`` of ``f``'s (module docstring).

    Parameters
    ----------
    f : the true vector: times (N,) s → (N, 3), any unit (an n-body solution, an interpolant of
        a trajectory file, a conic).
    t_start_s, t_end_s : the span to cover, s.
    requirement_rad : the largest angle allowed between fitted and true vector, rad.
    max_order : the highest order a segment may have, 0 .. 12.
    """
    check_interval(float(t_start_s), float(t_end_s), "the span to fit")
    check_positive(requirement_rad, "requirement_rad")
    check_order(max_order, "max_order")
    t_start_s, t_end_s, max_order = float(t_start_s), float(t_end_s), int(max_order)

    def ok(t_s, length, order):
        err, c = _segment_error(f, t_s, t_s + length, order)
        return err <= _MARGIN * requirement_rad, err, c

    span = t_end_s - t_start_s
    tiny = 1e-9 * span
    bounds, coeffs, errors = [t_start_s], [], []
    t_s, guess = t_start_s, span
    while t_end_s - t_s > 1e-12 * span:
        remaining = t_end_s - t_s
        length = min(guess, remaining)
        good, _, _ = ok(t_s, length, max_order)
        if good:        # grow until it fails or reaches the end
            lo, hi = length, None
            while hi is None and lo < remaining:
                trial = min(2.0 * lo, remaining)
                if ok(t_s, trial, max_order)[0]:
                    lo = trial
                else:
                    hi = trial
        else:           # shrink until it holds
            hi, lo = length, None
            while lo is None:
                trial = 0.5 * hi
                if trial < tiny:
                    raise InputError(
                        f"no polynomial of order <= {max_order} meets {requirement_rad * 1e6:g} "
                        f"µrad near t = {t_s:g} s (segments shorter than {tiny:.3g} s would be "
                        "needed): the vector jumps or is noisy there, or the requirement is "
                        "tighter than the trajectory's own accuracy")
                if ok(t_s, trial, max_order)[0]:
                    lo = trial
                else:
                    hi = trial
        if hi is not None:
            while hi / lo > _BISECT_RATIO:
                mid = np.sqrt(lo * hi)
                if ok(t_s, mid, max_order)[0]:
                    lo = mid
                else:
                    hi = mid
        t_f = t_end_s if t_end_s - (t_s + lo) <= 1e-12 * span else t_s + lo
        for order in range(max_order + 1):      # the lowest order that holds on [t_s, t_f]
            good, err, c = ok(t_s, t_f - t_s, order)
            if good:
                break
        bounds.append(t_f)
        coeffs.append(c)
        errors.append(err)
        if len(coeffs) > _MAX_SEGMENTS:
            raise InputError(f"more than {_MAX_SEGMENTS} segments would be needed; loosen the "
                             "requirement or raise the order")
        guess, t_s = 2.0 * (t_f - t_s), t_f
    segments = ChebyshevSegments.from_segments(bounds, coeffs)
    return SegmentFit(segments, np.asarray(errors), float(requirement_rad))


def angular_error(segments: ChebyshevSegments, f: Callable[[np.ndarray], np.ndarray],
                  t_s: np.ndarray) -> np.ndarray:
    """Angle (rad) between the segments' vector and ``f`` at times ``t_s`` (s)."""
    t = np.asarray(t_s, float)
    return angle_between_vectors(np.asarray(segments.position(t)), np.asarray(f(t), float))
