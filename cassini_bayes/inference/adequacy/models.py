"""The adequacy checks of each kind of fit (inertia, thrust, RWA4).

See :mod:`cassini_bayes.inference.adequacy`.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from scipy import stats

from cassini_bayes.inference.adequacy.check import (AUTOCORR_MAX, RING_MAX, Z_THRESHOLD,
                                                    Adequacy, Check, normal_deviate,
                                                    not_applicable, z_check)
from cassini_bayes.inference.adequacy.held_out import inertia_held_out
from cassini_bayes.inference.adequacy.prior_conflict import common_wheel_scale, prior_data_conflict
from cassini_bayes.inference.adequacy.residuals import residual_autocorrelation, residual_regression
from cassini_bayes.inference.nuisance import site_prior_sd as nuisance_prior_sd
from cassini_bayes.names import axis_label


def _residual_checks(idata, covariates: np.ndarray | None, names: Sequence[str] | None,
                     block_coord: str, labels: Sequence[str],
                     no_regression: str = "no regressors stored with the residuals"
                     ) -> list[Check]:
    if "residuals" not in idata.groups():
        note = "the run has no per-sample residuals"
        return [not_applicable("residual_autocorrelation", AUTOCORR_MAX, note),
                not_applicable("residual_regression", Z_THRESHOLD, note)]
    res = idata["residuals"]
    r = np.asarray(res["residual_std"] if "residual_std" in res else res["residual"])
    block = (np.asarray(res[block_coord]) if block_coord in res.coords
             else np.zeros(r.shape[0], int))
    times = np.asarray(res["t"], float) if "t" in res.coords else None
    checks = [residual_autocorrelation(r, block, labels=labels)]
    if covariates is None:
        checks.append(not_applicable("residual_regression", Z_THRESHOLD, no_regression))
    else:
        checks.append(residual_regression(r, covariates, block, names=names, labels=labels,
                                          times=times))
    return checks


def inertia_adequacy(post, sites: Sequence[str]) -> Adequacy:
    """The checks of :func:`~cassini_bayes.inference.inertia.fit_inertia`'s result ``post``.

    ``sites``: the posterior sites with proper priors (the inertia entries and the robust
    nuisance sites). Residual regressors: body rate and wheel momentum (body axes).
    """
    pb = post.problem
    cov = np.c_[pb.omega, pb.h_wheels]
    names = ["wx", "wy", "wz", "hwx", "hwy", "hwz"]
    sd = nuisance_prior_sd(pb.layout) if pb.robust else {}
    derived = common_wheel_scale(post.idata, pb.layout) if pb.robust else {}
    return Adequacy((prior_data_conflict(post.idata, sites, prior_sd=sd, derived=derived),
                     inertia_held_out(pb, post.idata),
                     *_residual_checks(post.idata, cov, names, "file", pb.sources)))


def thrust_adequacy(post, sites: Sequence[str]) -> Adequacy:
    """The checks of :func:`~cassini_bayes.inference.thrust.fit_thrust`'s result ``post``.

    No residual regression: on correctly specified simulations the Z-axis impulse residual
    correlates with the wheel momentum and the body-rate change (docs/adequacy.md;
    ``benchmarks/adequacy_false_alarms.py``), a structure of the model's own approximations (the
    neglected random walk of the integrated gyroscopic term, Feldman & Lee Eq 17), not of the
    data; a wrong inertia shows instead as the wheel spin-inertia scale pulled from its prior.
    """
    pb = post.problem
    n_ev = len(pb.sources)
    held = not_applicable("held_out", Z_THRESHOLD,
                          "one event: nothing to hold out" if n_ev < 2 else
                          "not implemented for the thrust model (its nuisance parameters are "
                          "integrated out jointly over the events)")
    sd = nuisance_prior_sd(pb.layout) if pb.layout is not None else {}
    derived = common_wheel_scale(post.idata, pb.layout)
    return Adequacy((prior_data_conflict(post.idata, sites, prior_sd=sd, derived=derived), held,
                     flex_ringing(getattr(pb, "flex_mode", None)),
                     *_residual_checks(post.idata, None, None, "event",
                                       [f"{t} + {p}" for t, p in pb.sources],
                                       no_regression="not used for thrust fits: the model's "
                                       "own approximations correlate the residuals with the "
                                       "wheel momentum (docs/adequacy.md)")))


def flex_ringing(search, threshold: float = RING_MAX) -> Check:
    """Whether the events ring with a flexible or slosh mode
    (:class:`~cassini_bayes.inference.thrust.flex.ModeSearch`): fails when one is found whose
    rms momentum exceeds ``threshold`` noise sds. Not modelled, the fit's noise level absorbs a
    structured residual; modelled (``--flex model``, its frequency and damping held at their
    estimate), the ring's size is still a judge: on a small spacecraft's open-world events such
    fits did not cover either (docs/flex_mode.md)."""
    name = "flex_ringing"
    if search is None:
        return not_applicable(name, threshold, "no search for a flexible mode (--flex off, "
                              "or the idealised model)")
    if not search.found:
        return Check(name, 0.0, threshold, True, note="no mode found in the events")
    ring = float(search.ring_over_noise)
    if not np.isfinite(ring):
        return not_applicable(name, threshold, f"the mode at {search.freq_hz:.4g} Hz was given, "
                              "not searched: its ring is not measured")
    what = ("that the fit models with its frequency and damping held at their estimate: on "
            "the ESPA bus's open-world events such fits did not cover"
            if search.modelled else
            "that the fit does not model: its noise level absorbs it, and its intervals may "
            "not cover")
    return Check(name, ring, threshold, ring <= threshold, parameter=f"{search.freq_hz:.4g} Hz",
                 note=(f"a flexible or slosh mode at {search.freq_hz:.4g} Hz (damping "
                       f"{search.damping:.2g}) holds {ring:.3g} noise sds of momentum {what} "
                       "(docs/flex_mode.md)"))


def _mean_axis(post) -> np.ndarray:
    """(3,) the posterior mean of the RWA4 fit's axis components ``u4_x … u4_z``."""
    from cassini_bayes.inference.rwa4 import U4_NAMES

    p = post.idata.posterior
    return np.array([float(p[n].mean()) for n in U4_NAMES])


def balance_fit(post, threshold: float = Z_THRESHOLD) -> Check:
    """Does the RWA4 model fit its own window balances? ``χ²`` of the balances at the posterior
    mean (:func:`~cassini_bayes.inference.rwa4.balance_misfit`) as the normal deviate of its
    upper χ² tail probability."""
    from cassini_bayes.inference.rwa4 import balance_misfit
    from cassini_bayes.physics.momentum import INERTIA_NAMES

    p = post.idata.posterior
    u = _mean_axis(post)
    pi = np.array([float(p[n].mean()) for n in INERTIA_NAMES])
    chi2, dof = balance_misfit(post.problem, u, pi)
    z = normal_deviate(min(2.0 * float(stats.chi2.sf(chi2, dof)), 1.0))   # one-sided tail
    # the covariance holds the nuisance prior's whole spread (integrated out), so a clean fit
    # sits far below its dof (0.005 on 10): the check fires on misfits beyond that prior
    return z_check("balance_fit", z, threshold, note=f"chi2 {chi2:.3g} on {dof} dof, against "
                  "noise plus the nuisance prior's spread")


CONE_OFFSET_MAX_DEG = 10.0  # farthest the fitted axis may sit from the articulation cone


def articulation_cone(post, threshold_deg: float = CONE_OFFSET_MAX_DEG) -> Check:
    """Is the fitted spin axis where the wheel can point? A wheel whose model entry gives an
    articulation cone (``post.problem.cone``; Cassini's RWA4: 54.74° from +Z at any
    articulation angle, Brown §I) must sit near it: the posterior-mean axis's angle from the
    cone's axis minus the cone's angle must be small. A mounting or articulation error is a
    degree or two, while a wheel-rate sign flipped in the file gives the antipode, 70.5° off
    Cassini's cone (with the uniform prior the fit itself cannot tell). Statistic: that offset,
    deg. Not applicable when the model gives the wheel no cone: nothing says where it may point.
    """
    problem = post.problem
    if problem.cone is None:
        return not_applicable("articulation_cone", threshold_deg,
                              f"the spacecraft model gives {problem.wheel} no articulation cone "
                              "(its [[wheel]] 'cone_axis', 'cone_deg')")
    u = _mean_axis(post)
    cos = float(np.clip(u @ problem.cone.axis / np.linalg.norm(u), -1.0, 1.0))
    polar = float(np.degrees(np.arccos(cos)))
    offset = abs(polar - problem.cone.angle_deg)
    return z_check("articulation_cone", offset, threshold_deg,
                  note=f"axis {polar:.1f}° from {axis_label(problem.cone.axis)}; the wheels' "
                  f"cone is at {problem.cone.angle_deg:.2f}°"
                  + ("; a wheel-rate sign flipped in the file points the axis to the antipode, "
                     "and windows that hold part of the spin-up turn it (check the windows)"
                     if offset > threshold_deg else ""))


def rwa4_adequacy(post, sites: Sequence[str]) -> Adequacy:
    """The checks of :func:`~cassini_bayes.inference.rwa4.fit_rwa4`'s result ``post``:
    prior-data conflict and the fit of the window balances (:func:`balance_fit`; the likelihood
    uses window means, so there are no per-sample residuals; the pairs share integrated-out
    nuisance parameters)."""
    n_pairs = len(post.problem.pairs)
    held = not_applicable("held_out", Z_THRESHOLD,
                          "one window pair: nothing to hold out" if n_pairs < 2 else
                          "not implemented for the RWA4 model (its nuisance parameters are "
                          "integrated out jointly over the pairs)")
    return Adequacy((prior_data_conflict(post.idata, sites), held, balance_fit(post),
                     articulation_cone(post),
                     *_residual_checks(post.idata, None, None, "pair", [])))
