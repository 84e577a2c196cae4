"""Check 2: wheel units, signs and order vs momentum conservation.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from cassini_bayes.consistency._programs import _dcm
from cassini_bayes.errors import InputError
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import (
    RATE_NOISE_FLOORS,
    RPM_TO_RAD_S,
    Telemetry,
    white_noise_sd,
)

# Thresholds (margins measured in docs/input_checks.md)

MOMENTUM_ALIGN_MIN = 0.9
"""The wheel-unit check judges ``κ`` only when the balance fits this well (alignment)."""
RAD_S_FACTOR = 1.0 / RPM_TO_RAD_S
"""``κ`` expected when the wheel columns hold rad/s: 60/(2π) = 9.55."""
KAPPA_RANGE = (float(np.sqrt(RPM_TO_RAD_S)), float(1.0 / np.sqrt(RPM_TO_RAD_S)))
"""Accepted wheel-momentum scale ``κ``: the geometric midpoints between 1 (rpm) and 60/(2π)
(rad/s) or its inverse, 0.324 … 3.09; the ±10 % knowledge of the moments moves ``κ`` by 10 %."""
AXES_CONDITION_MIN = 0.1
"""Each wheel's free momentum vector is judged only when the free-axis balance's design is this
well conditioned (smallest/largest singular value, unit columns): slews separate the wheels,
biasing events, whose wheels move together, do not (margins: docs/input_checks.md §2b)."""
AXES_ALIGN_MIN = 0.99
"""In a file without thruster firings (no ``on_*`` columns, no pulse log), the free-axis balance
must fit at least this well where separable: nothing but the wheels exchanges momentum with the
body (margins on correct and corrupted files: docs/input_checks.md §2b)."""
SWING_MIN_SNR = 100.0
"""... and only where the body and the wheels exchange at least this many times the momentum
noise of one sample (:attr:`WheelAxes.noise_nms`; a quiet file's swing is that noise): at 100×
the balance's misfit from noise alone is ~1e-4, far inside :data:`AXES_ALIGN_MIN` (each
spacecraft's swing and noise: docs/input_checks.md §2b)."""
UNSIGNED_TOUCH_RPM = 5.0
"""A wheel that stays on one side of zero yet comes within this (rpm) of it is named as possibly
unsigned in :func:`_balance_error`."""
AXIS_ANGLE_MAX_DEG = 30.0
"""Largest accepted angle between a wheel's fitted momentum and its axis in the model: a flipped
sign gives 180°, another wheel's column the angle between the two axes (Cassini's fixed wheels
90°, a pyramid's 70.5°, a CubeSat's skew wheel 54.7° from each body axis). Smaller where the
model's wheels are closer: half the smallest angle between two of its (non-articulated) wheel
lines (:func:`axis_angle_max_deg`), so another wheel's column always lies beyond it."""


AXIS_JUDGE_SIGMAS = 5.0
"""A wheel's fitted momentum is judged only when this many of its angular standard errors (the
balance's least squares) stay within :func:`axis_angle_max_deg`: a wheel that hardly moves
between firings leaves its vector to the noise, and a correct column would be refused."""


class WheelAxes(NamedTuple):
    """Fit of the momentum balance with each known wheel's momentum a free body vector ``w_k``.

    Attributes
    ----------
    alignment : cosine between the fitted and the measured body-momentum changes (1 = perfect).
    conditioning : smallest over largest singular value of the balance's design (the wheels'
        columns and the external torque's), its columns scaled to unit length: near 0 when the
        wheels' rates move together (a biasing event, a slew about one axis) and the vectors
        cannot be told apart.
    vectors : per known wheel, ``w_k / J_k`` (body frame, per rpm-read rad/s): the model's axis
        ``g_k`` for a correct file, within the inertia's ±10 %; ``−g_k`` for a column with its
        sign flipped, ``g_j`` for a column holding wheel ``j``'s rates, ``9.55 g_k`` for rad/s.
    swing_nms : largest de-meaned body momentum ``|A(q)ᵀ I_pred ω|``, N m s: how much momentum
        the wheels and the body exchange (Cassini's slews: 18–22; gyro noise alone: ~0.01).
    noise_nms : the momentum noise of one sample, N m s: ``√((λ_max σ_ω)² + Σ_k (J_k σ_k)²)``
        with ``λ_max`` the predicted inertia's largest moment and ``σ_ω``, ``σ_k`` the white
        noise of the body rates and of each running wheel's rates
        (:func:`cassini_bayes.telemetry.white_noise_sd`, floored at
        :data:`cassini_bayes.telemetry.RATE_NOISE_FLOORS`).
    angle_sd_deg : per known wheel, the angular standard error of its vector (degrees): the
        least squares' covariance (residual variance × ``(XᵀX)⁻¹``) across the vector's
        direction over its length.
    """

    alignment: float
    conditioning: float
    vectors: dict[str, np.ndarray]
    swing_nms: float = 0.0
    noise_nms: float = 0.0
    angle_sd_deg: dict[str, float] = {}

    @property
    def judged(self) -> bool:
        """Whether the vectors are determined well enough to judge each wheel on its own."""
        return (self.conditioning >= AXES_CONDITION_MIN
                and self.alignment >= MOMENTUM_ALIGN_MIN)

    def determined(self, name: str, angle_max_deg: float) -> bool:
        """Whether wheel ``name``'s vector is known well enough to judge against an angle of
        ``angle_max_deg``: :attr:`judged`, and :data:`AXIS_JUDGE_SIGMAS` of its angular
        standard errors within that angle."""
        sd = self.angle_sd_deg.get(name, 0.0)
        return self.judged and AXIS_JUDGE_SIGMAS * sd <= angle_max_deg

    def angle_deg(self, name: str, axis) -> float:
        """Angle between wheel ``name``'s fitted vector and ``axis``, degrees."""
        w = self.vectors[name]
        cos = float(w @ np.asarray(axis, float)) / (np.linalg.norm(w) * np.linalg.norm(axis))
        return float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))

    def scale(self, name: str) -> float:
        """``|w_k| / J_k``: 1 for rpm (within the inertia's ±10 %), 9.55 for rad/s."""
        return float(np.linalg.norm(self.vectors[name]))


class MomentumScale(NamedTuple):
    """Fit of the momentum balance with the wheel momentum scaled by ``κ`` (1 for a correct file).

    Attributes
    ----------
    scale : ``κ``, the factor on the wheel momentum that balances the body momentum of the
        model's predicted inertia: 1 (within the ±10 % knowledge of the inertia) for rpm,
        60/(2π) = 9.55 when the wheel columns hold rad/s.
    alignment : cosine between the fitted and the measured body-momentum changes (1 = perfect).
    stretches : number of stretches between thruster firings used.
    axes : the same balance with a free momentum vector per known wheel (:class:`WheelAxes`);
        ``None`` when no known wheel runs or the balance cannot be formed.
    """

    scale: float
    alignment: float
    stretches: int
    axes: WheelAxes | None = None


def _quiet_labels(on_times: np.ndarray | None, n: int) -> np.ndarray:
    """Label of the firing-free stretch of every sample; ``-1`` next to a firing.

    An interval in which any cumulative on-time grows carries a thruster impulse (and its
    rise/fall tail into the next interval): both intervals split the record.
    """
    if on_times is None:
        return np.zeros(n, int)
    fired = np.any(np.diff(on_times, axis=0) > 0, axis=1)
    cut = fired | np.concatenate([[False], fired[:-1]])
    labels = np.concatenate([[0], np.cumsum(cut)])
    bad = np.zeros(n, bool)
    bad[1:] |= cut
    bad[:-1] |= cut
    return np.where(bad, -1, labels)


class _Balance(NamedTuple):
    """The de-meaned momentum balance of :func:`wheel_momentum_scale` (inertial frame)."""

    body: np.ndarray                # (n, 3) A(q)ᵀ I_pred ω, each stretch de-meaned
    known: list[str]                # the known wheels running
    known_cols: list[np.ndarray]    # per known wheel, (n, 3, 3): −ρ_k A(q)ᵀ e_j, de-meaned
    free: list[str]                 # the articulated wheels running
    free_cols: list[np.ndarray]     # per free wheel, its three columns
    torque_cols: list[np.ndarray]   # a constant inertial torque's three columns: (t − t̄_s) e_j
    stretches: int
    noise_nms: float                # momentum noise of one sample (WheelAxes.noise_nms)


def _balance(tel: Telemetry, spacecraft: Spacecraft, on_times: np.ndarray | None,
             free_wheels: Sequence[str]) -> _Balance | None:
    """The balance's pieces per firing-free stretch, or ``None`` (no wheel, no stretch)."""
    names = tel.active_wheels()
    free_upper = {n.upper() for n in free_wheels}
    free = [n for n in names if n.upper() in free_upper]
    known = [n for n in names if n not in free]
    if not names:
        return None
    on = tel.on_times if on_times is None else on_times
    labels = _quiet_labels(on, tel.n)
    ids, counts = np.unique(labels[labels >= 0], return_counts=True)
    good = ids[counts >= 3]
    keep = np.isin(labels, good)
    if not np.any(keep):
        return None
    a_t = np.swapaxes(np.asarray(_dcm(np.asarray(tel.q, float))), -1, -2)[keep]  # body → inertial
    body = np.einsum("nij,jk,nk->ni", a_t, np.asarray(spacecraft.inertia, float),
                     np.asarray(tel.omega, float)[keep])
    known_cols = [-np.asarray(tel.wheel_rate(n), float)[keep][:, None, None] * a_t
                  for n in known]
    free_cols = [-np.asarray(tel.wheel_rate(f), float)[keep][:, None] * a_t[:, :, j]
                 for f in free for j in range(3)]
    t_keep = np.asarray(tel.t, float)[keep] - float(tel.t[0])
    torque_cols = [t_keep[:, None] * np.eye(3)[j] for j in range(3)]
    lab = labels[keep]
    for s in good:
        m = lab == s
        for x in [body, *known_cols, *free_cols, *torque_cols]:
            x[m] -= x[m].mean(0)
    s_w, s_r = RATE_NOISE_FLOORS
    i_max = float(np.linalg.eigvalsh(np.asarray(spacecraft.inertia, float))[-1])
    noise = (i_max * max(white_noise_sd(np.asarray(tel.omega, float)[keep]), s_w)) ** 2
    for n in names:
        rate = np.asarray(tel.wheel_rate(n), float)[keep]
        noise += (spacecraft.wheel(n).inertia * max(white_noise_sd(rate), s_r)) ** 2
    return _Balance(body, known, known_cols, free, free_cols, torque_cols, len(good),
                    float(np.sqrt(noise)))


def _solve(design: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, float] | None:
    """Least squares of the balance: coefficients and alignment, ``None`` if not identifiable."""
    tt = float(target @ target)
    if tt <= 0 or np.linalg.matrix_rank(design) < design.shape[1]:
        return None
    theta = np.linalg.lstsq(design, target, rcond=None)[0]
    fitted = design @ theta
    align = float(target @ fitted / np.sqrt(tt * (fitted @ fitted))) if fitted.any() else 0.0
    return theta, align


def _wheel_axes(bal: _Balance, spacecraft: Spacecraft) -> WheelAxes | None:
    """:class:`WheelAxes` of the balance: one free body vector ``w_k`` per known wheel."""
    if not bal.known:
        return None
    cols = [c[:, :, j] for c in bal.known_cols for j in range(3)] + bal.free_cols
    cols += bal.torque_cols
    design = np.stack([c.ravel() for c in cols], 1)
    solved = _solve(design, bal.body.ravel())
    if solved is None:
        return None
    theta, align = solved
    norms = np.linalg.norm(design, axis=0)
    sv = np.linalg.svd(design / np.where(norms > 0, norms, 1.0), compute_uv=False)
    js = [spacecraft.wheel(n).inertia for n in bal.known]
    vectors = {n: theta[3 * k: 3 * k + 3] / js[k] for k, n in enumerate(bal.known)}
    swing = float(np.max(np.linalg.norm(bal.body, axis=1)))
    resid = bal.body.ravel() - design @ theta
    dof = max(design.shape[0] - design.shape[1], 1)
    cov = float(resid @ resid) / dof * np.linalg.pinv(design.T @ design)
    angle_sd = {}
    for k, n in enumerate(bal.known):
        th = theta[3 * k: 3 * k + 3]
        length = float(np.linalg.norm(th))
        u = th / length if length > 0 else np.zeros(3)
        across = np.eye(3) - np.outer(u, u)
        var = float(np.trace(across @ cov[3 * k: 3 * k + 3, 3 * k: 3 * k + 3] @ across))
        angle_sd[n] = (float(np.degrees(np.sqrt(max(var, 0.0)) / length)) if length > 0
                       else 180.0)
    return WheelAxes(align, float(sv[-1] / sv[0]), vectors, swing, bal.noise_nms, angle_sd)


def wheel_momentum_scale(tel: Telemetry, spacecraft: Spacecraft,
                         on_times: np.ndarray | None = None,
                         free_wheels: Sequence[str] | None = None) -> MomentumScale | None:
    """Least-squares wheel-momentum scale ``κ`` of the momentum balance (Feldman & Lee Eqs 2-3).

    Per firing-free stretch ``s`` (thruster firings from ``on_times``, default the telemetry's)

        ``A(q_t)ᵀ (I_pred ω_t + κ Σ_known J_k ρ_k,t g_k + ρ_f,t w) = H_s + T t``

    with ``I_pred`` the model's predicted tensor and the known wheels' axes and spin inertias
    from the model, and ``T`` a constant inertial external torque over the whole file (its
    impulse over a long record can be a sizeable part of what a small spacecraft's slews
    exchange). Each articulated wheel (``free_wheels``, default the model's ``articulated``
    wheels: Cassini's RWA4, whose axis is what the RWA4 calibration measures, Brown §III) enters
    with a free momentum vector ``w`` (``J_f u_f`` for rpm data); with no other wheel running
    ``κ`` is the median of ``|w_f| / J_f``. Subtracting each stretch's mean
    removes ``H_s``. The same balance with a free vector ``w_k`` for every known wheel in place
    of ``κ J_k g_k`` is :attr:`MomentumScale.axes`. ``None`` when no wheel runs, no stretch has
    three samples, or nothing varies.
    """
    free_wheels = spacecraft.articulated_wheels if free_wheels is None else free_wheels
    bal = _balance(tel, spacecraft, on_times, free_wheels)
    if bal is None:
        return None
    cols = list(bal.free_cols) + bal.torque_cols
    if bal.known:
        axes = np.stack([spacecraft.wheel(n).axis for n in bal.known])
        js = np.array([spacecraft.wheel(n).inertia for n in bal.known])
        momentum = np.einsum("wnij,wj,w->ni", np.stack(bal.known_cols), axes, js)
        cols.insert(0, momentum)
    solved = _solve(np.stack([c.ravel() for c in cols], 1), bal.body.ravel())
    if solved is None:
        return None
    theta, align = solved
    if bal.known:
        scale = float(theta[0])
    else:     # the free wheels alone: their momenta's sizes
        scale = float(np.median([np.linalg.norm(theta[3 * k:3 * k + 3])
                                 / spacecraft.wheel(f).inertia for k, f in enumerate(bal.free)]))
    return MomentumScale(scale, align, bal.stretches, _wheel_axes(bal, spacecraft))


def _unit_error(cols: str, scale: float, what: str, tel: Telemetry) -> InputError:
    """The wheel-unit refusal for ``cols`` whose momentum needs ``scale`` × the rpm reading."""
    if scale > 0 and abs(np.log(scale / RAD_S_FACTOR)) < np.log(2.0):
        return InputError(f"{cols}: wheel rates look like rad/s, the file format wants rpm; "
                          f"multiply by 60/(2*pi) ({what})", path=tel.source)
    return InputError(f"{cols}: {what}; check that the wheel rates are rpm, the body rates "
                      "rad/s, and that the spacecraft model matches the spacecraft",
                      path=tel.source)


def axis_angle_max_deg(spacecraft: Spacecraft) -> float:
    """Largest accepted angle (degrees) between a wheel's fitted momentum and its model axis:
    :data:`AXIS_ANGLE_MAX_DEG`, or half the smallest angle between the lines of two of the
    model's wheels whose axes are trusted (articulated wheels left out) when that is smaller."""
    axes = [w.axis for w in spacecraft.wheels if not w.articulated]
    half = [0.5 * float(np.degrees(np.arccos(min(abs(float(a @ b)), 1.0))))
            for i, a in enumerate(axes) for b in axes[i + 1:]]
    return min([AXIS_ANGLE_MAX_DEG, *half])


def _axis_error(name: str, axes: WheelAxes, spacecraft: Spacecraft,
                tel: Telemetry) -> InputError:
    """The refusal for a wheel whose momentum does not lie along its axis in the model."""
    limit = axis_angle_max_deg(spacecraft)
    col = name.lower()
    angle = axes.angle_deg(name, spacecraft.wheel(name).axis)
    head = (f"column {col}: momentum is conserved only with {col}'s momentum {angle:.0f}° from "
            f"{name}'s axis in the model {spacecraft.name!r} (free-axis balance alignment "
            f"{axes.alignment:.3f})")
    if angle > 180.0 - limit:
        return InputError(f"{head}: its sign looks flipped; negate the column, or correct the "
                          "wheel's axis in the spacecraft model", path=tel.source)
    for other in spacecraft.wheels:
        if other.name == name:
            continue
        off = axes.angle_deg(name, other.axis)
        if min(off, 180.0 - off) < limit:
            flipped = " with the sign flipped" if off > 90.0 else ""
            return InputError(f"{head}, {min(off, 180.0 - off):.0f}° from {other.name}'s: it "
                              f"looks like {other.name}'s rates{flipped}; check the column "
                              "order", path=tel.source)
    return InputError(f"{head}; check the column order, the wheels' signs and the model's wheel "
                      "axes", path=tel.source)


def _balance_error(tel: Telemetry, axes: WheelAxes) -> InputError:
    """The refusal for a file without thruster firings whose momentum does not balance even with
    a free axis per wheel; names the wheels that touch zero without crossing it (unsigned)."""
    unsigned = []
    for name in axes.vectors:
        rpm = np.asarray(tel.wheel_rate(name), float) / RPM_TO_RAD_S
        rpm = rpm[np.isfinite(rpm)]
        for x in (rpm, -rpm):     # never below zero (or above it), yet reaching it
            if x.min() >= 0.0 and x.min() < UNSIGNED_TOUCH_RPM < x.max():
                unsigned.append(f"{name.lower()} stays on one side of 0 rpm yet reaches "
                                f"{x.min():.2g} rpm")
    hint = (f" ({'; '.join(unsigned)}: a tachometer that reports speed without direction?)"
            if unsigned else "")
    cols = " ".join(n.lower() for n in axes.vectors)
    return InputError(f"columns {cols}: with no thruster firing in the file, the wheels' momenta "
                      "do not balance the body's even with a free axis per wheel (alignment "
                      f"{axes.alignment:.4f}; correct files ≥ 0.998){hint}; check the wheel "
                      "columns' signs through zero speed and their units, or give the thruster "
                      "firings (--pulses, or on_* columns) if any fired", path=tel.source)


def check_wheel_units(tel: Telemetry, spacecraft: Spacecraft,
                      on_times: np.ndarray | None = None) -> MomentumScale | None:
    """Refuse wheel columns whose unit, sign or order breaks momentum conservation.

    When the balance of :func:`wheel_momentum_scale` fits (alignment ≥
    :data:`MOMENTUM_ALIGN_MIN`) yet needs a wheel-momentum scale ``κ`` outside
    :data:`KAPPA_RANGE`, raise :class:`InputError`: ``κ`` near 60/(2π) means the wheel columns
    hold rad/s. Then, where the free-axis balance (:class:`WheelAxes`) determines each known
    wheel's momentum on its own (:attr:`WheelAxes.judged`), refuse a wheel whose momentum lies
    more than :func:`axis_angle_max_deg` from its axis in the model (a flipped sign, another
    wheel's column) or whose scale is outside :data:`KAPPA_RANGE` (that column in rad/s). In a
    file without thruster firings (no ``on_times``, no ``on_*`` columns) where the vectors are
    separable and the body swings by :data:`SWING_MIN_SNR` times the momentum noise, refuse a
    free-axis balance below
    :data:`AXES_ALIGN_MIN` (:func:`_balance_error`: unsigned tachometers, mixed units).
    Otherwise (including a balance that does not fit: momentum exchange with unlogged thruster
    firings, or none at all) say nothing. Returns the fit.
    """
    fit = wheel_momentum_scale(tel, spacecraft, on_times)
    if fit is None:
        return fit
    lo, hi = KAPPA_RANGE
    if fit.alignment >= MOMENTUM_ALIGN_MIN and not lo <= fit.scale <= hi:
        cols = "columns " + " ".join(n.lower() for n in tel.active_wheels())
        raise _unit_error(cols, fit.scale, (
            f"momentum is conserved only with the wheel momentum {fit.scale:.3g}x what the "
            f"columns say in rpm with the model {spacecraft.name!r} (alignment "
            f"{fit.alignment:.3f}; rpm gives 1, rad/s {RAD_S_FACTOR:.3g})"), tel)
    axes = fit.axes
    if axes is None:
        return fit
    if (on_times is None and tel.on_times is None and axes.conditioning >= AXES_CONDITION_MIN
            and axes.swing_nms >= SWING_MIN_SNR * axes.noise_nms
            and axes.alignment < AXES_ALIGN_MIN):
        raise _balance_error(tel, axes)
    angle_max = axis_angle_max_deg(spacecraft)
    named = [n for n in axes.vectors if axes.determined(n, angle_max)]
    for name in named:
        if axes.angle_deg(name, spacecraft.wheel(name).axis) > angle_max:
            raise _axis_error(name, axes, spacecraft, tel)
    for name in named:
        if not lo <= axes.scale(name) <= hi:
            scale, j = axes.scale(name), spacecraft.wheel(name).inertia
            raise _unit_error(f"column {name.lower()}", scale, (
                f"momentum is conserved only with {name}'s momentum {scale:.3g}x what the "
                f"column says in rpm with the model {spacecraft.name!r} (free-axis balance "
                f"alignment {axes.alignment:.3f}; rpm gives 1, rad/s {RAD_S_FACTOR:.3g}); or "
                f"the model's {name} spin inertia {j:.4g} kg m^2 is "
                f"{max(scale, 1 / scale):.3g}x too {'small' if scale > 1 else 'large'}"), tel)
    return fit
