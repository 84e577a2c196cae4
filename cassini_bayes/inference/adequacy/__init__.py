"""Does the model fit? Self-checks of a posterior that need no truth (flight data has none).

Each check returns one number, ``statistic``, compared with a ``threshold`` (``ok`` when
``statistic ≤ threshold``). The false-alarm rates on correctly specified data are measured by
``benchmarks/adequacy_false_alarms.py`` and stated in ``docs/adequacy.md``.

* ``prior_data_conflict`` — for every element ``x`` of the named posterior sites that has a
  proper prior, ``|E[x | data] − E[x]| / sd(x)`` in prior sd (nuisance parameters: their stated
  zero-mean Normal priors; others: the ``prior`` group's draws, on the log scale when every draw
  is positive — thrust, time constants, moments). A nuisance parameter pulled several prior sd
  from its prior is how an unmodelled error reaches the answer; the worst element is named
  (``parameter``). Per-wheel robust fits add the wheels' mean spin-inertia error and each
  wheel's error relative to it (:func:`common_wheel_scale`): the directions a wrong inertia and
  a wrong tachometer pull.
* ``held_out`` — leave one telemetry file out: the posterior of the shared parameters from the
  other files (and the prior) predicts the held-out file's information-weighted estimate, exactly
  where the model is linear-Gaussian in its parameters (the inertia model's sufficient
  statistics, :func:`gaussian_held_out`); the statistic is the normal deviate of the smallest
  Bonferroni-adjusted χ² tail probability over the files. Not applicable to one file.
* ``residual_autocorrelation`` — whiteness against time: per block (file, event) and axis the
  lag-1 autocorrelation ``ρ̂₁`` of the posterior-mean residuals; the largest ``|ρ̂₁|``.
* ``residual_regression`` — whiteness against the regressors of the model (inertia fits: body
  rate and wheel momentum; not used for thrust fits, see :func:`thrust_adequacy`): per block and
  axis the F-test of the (AR(1)-prewhitened) residual regressed on them, as the normal deviate
  of the smallest Bonferroni-adjusted p-value; every other sample is tested, against the
  regressors interpolated from its neighbours, so the measurement noise that the residual and
  the regressors share does not make the statistic grow with the number of samples.
* ``flex_ringing`` (thrust fits) — the events searched for a flexible or slosh mode
  (:mod:`cassini_bayes.inference.thrust.flex`); the statistic is the rms momentum of a mode found
  and not modelled, in noise sds: above 1 the fit's noise level absorbs it and, on a small
  spacecraft, its intervals do not cover.
* ``balance_fit`` (RWA4 fits) — the window-mean momentum balances at the posterior mean against
  the likelihood's own covariance (noise plus the integrated-out nuisance effects): ``χ²`` on
  ``3G − 2`` degrees of freedom (G window pairs), as the normal deviate of its upper tail.

Statistics expressed as normal deviates (held-out, regression, balance) fail beyond 4
(two-sided 6e-5 after the Bonferroni correction); the prior–data conflict beyond 4 prior sd; the
autocorrelation beyond 0.5.
"""

from cassini_bayes.inference.adequacy.check import (AUTOCORR_MAX, PRIOR_CONFLICT_SD, RING_MAX,
                                                    Z_THRESHOLD, Adequacy, Check, normal_deviate,
                                                    not_applicable)
from cassini_bayes.inference.adequacy.held_out import gaussian_held_out, inertia_held_out
from cassini_bayes.inference.adequacy.models import (balance_fit, flex_ringing,
                                                     inertia_adequacy, rwa4_adequacy,
                                                     thrust_adequacy)
from cassini_bayes.inference.adequacy.prior_conflict import common_wheel_scale, prior_data_conflict
from cassini_bayes.inference.adequacy.residuals import (residual_autocorrelation,
                                                        residual_regression)
from cassini_bayes.inference.nuisance import site_prior_sd as nuisance_prior_sd

__all__ = ["Check", "Adequacy", "PRIOR_CONFLICT_SD", "Z_THRESHOLD", "AUTOCORR_MAX", "RING_MAX",
           "normal_deviate", "nuisance_prior_sd", "prior_data_conflict", "common_wheel_scale",
           "gaussian_held_out",
           "inertia_held_out", "residual_autocorrelation", "residual_regression", "not_applicable",
           "inertia_adequacy", "thrust_adequacy", "rwa4_adequacy", "balance_fit", "flex_ringing"]
