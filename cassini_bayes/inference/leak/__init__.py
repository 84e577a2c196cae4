"""Bayesian thruster-leak monitor: posterior probability of a leak per thruster (Lee §3.2).

Model
-----
The residual momentum of Lee Eq 10, ``R(t) = I Δω + ΔH_RWA + ΔG − Q J(t)`` (N m s, counted from
the stretch's first sample; :func:`cassini_bayes.estimators.leak.residual_momentum`), is, under
hypothesis ``k`` (thruster ``k`` leaks a fraction ``f`` of its thrust from ``t_L``) ::

    R(t_i) = r_0 + T (t_i − t_0) + Σ_j δ_j Q[:, j] J_j(t_i) + f F Q[:, k] (t_i − t_L)_+ + e_i

* ``r_0`` (3,) the offset of the first sample's noise, prior ``N(0, C²)`` per axis, ``C`` the
  model's wheel momentum capacity (:attr:`LeakInputs.offset_sd_nms`: the spacecraft's own
  momentum scale, wide);
* ``T`` (3,) an unknown constant external torque (N m), prior a scale mixture of normals: with
  probability 0.9 ``N(0, σ_T²)``, ``σ_T`` the spacecraft model's ``[torque_knowledge] sd_nm``,
  and with 0.1 ten times wider (:data:`TORQUE_SCALES`): a torque several ``σ_T`` off the model
  file's knowledge is then an unusual torque, not a leak that started with the stretch (with a
  normal prior alone one of 7 σ_T raised a false alarm, docs/leak.md);
* ``δ_j`` the fractional thrust error of thruster ``j`` of the model's ``m`` (thruster-to-thruster
  variation, the Bayesian counterpart of Lee Eq 11), prior ``N(0, η²)``, η = 0.05 as Lee's launch
  value, times the modelled impulse ``J_j(t)`` (N s) and the moment arm ``Q[:, j]`` (Feldman & Lee
  Eq 16, column ``(r_j − e) × d_j`` of any thruster set);
* the leak column ``F_k Q[:, k] (t − t_L)_+``: a 10 % Z1 leak at 1 N is (−0.158, +0.123, 0) N m;
* ``e_i`` white noise, per axis, its sd from the data (median absolute deviation of the second
  differences ÷ √6, blind to a leak's slope; the larger of the levels of the raw rows and of
  the rows used; at least :attr:`LeakInputs.noise_floor_nms`, the spacecraft's momentum at the
  package's rate-noise floors). ``R`` is an *integral* of the torque residual, but its noise is
  not a random walk: ``I Δω`` and ``ΔH_RWA`` are differences of sampled states, so the gyro and
  tach noise enter each sample once. What is integrated — the gyroscopic impulse ``ΔG`` from
  noisy 1 s rates, across pulses (the trapezoid's first-order error at each pulse's rate step is
  put back, :func:`leak_inputs`) — makes a random walk of ~2e-3 N m s over hours, which a white
  model on 1 s samples takes for a torque of ~1e-7 N m; the monitor therefore uses the residual
  every :data:`SAMPLE_STEP_S` = 60 s, where the white level covers it (measured, docs/leak.md).
  A random-walk term in the likelihood (a Kalman filter per hypothesis) would be the exact
  remedy; it is not done here.

``r_0``, ``T`` and ``δ`` are Gaussian and the model is linear, so they are integrated out exactly
(Woodbury). The leak fraction has a scale-mixture of half-normal priors (scales 10⁻⁴ … 1, equal
weights: close to log-uniform over the 0.1 % … 100 % range Lee's tests span). The onset is
continuous, uniform over the part of the stretch seen so far, and integrated cell by cell between
the used rows: with the onset in ``[t_{l−1}, t_l)`` the leak's columns are ``f P + D O`` with
``P = F Q[:, k] (t − t_l)₊``, ``O = F Q[:, k] 1(t ≥ t_l)`` and ``D = f d``, ``d = t_l − t_L``,
so the likelihood is Gaussian in ``(f, D)``. For a fixed ``f`` the integral over ``d ∈ [0, t_l −
t_{l−1}]`` is a normal CDF difference; integrating ``f`` against each half-normal component in
closed form first instead leaves, per cell, ``∫ exp(−A²/2 + log Φ(B)) dw`` over
``w = asinh(√(a_OO/p) (d + a_PO/a_OO))`` with ``A = b tanh w + g sech w``, ``B = b sech w −
g tanh w`` (``a`` the Gram terms of ``P, O``, ``p`` the fraction's precision with ``D`` profiled,
``b, g`` the scores of ``f`` and ``D`` in its sd): a bounded integrand with one peak or trough,
taken by Gauss-Legendre quadrature adapted to it (its error against adaptive quadrature:
docs/leak.md). Every quantity for all cells and check times comes from
cumulative sums; the running (sequential) monitor costs O(n + checks × cells × m) integrals.

Identifiability: a leak is told by its torque direction ``Q[:, k]``. On Cassini no two columns of
``Q`` are parallel, so every thruster's leak is distinct; the antiparallel pairs Z1/Z3, Z2/Z4,
Y1/Y4 and Y2/Y3 are told apart only by the sign of ``f`` (a leak only adds thrust). On another
layout two thrusters with parallel columns (same sign) cannot be told apart: their posterior
splits between them and neither is isolated. A leak that starts at the stretch's first sample
looks like an external torque; the torque prior (µN m) against leak torques of mN m resolves
it. The thrust-error term can mimic a leak only through the thruster that fights it, and only
at the cost of a ~100 % thrust error.

The residual and the types are in ``_inputs``, the onset quadrature in ``_onset``, the
posterior in ``_posterior``; this module re-exports their names.
"""

from __future__ import annotations

from cassini_bayes.inference.leak._inputs import (
    FRACTION_SCALES as FRACTION_SCALES,
)
from cassini_bayes.inference.leak._inputs import (
    HYPOTHESES as HYPOTHESES,
)
from cassini_bayes.inference.leak._inputs import (
    MAX_GRID as MAX_GRID,
)
from cassini_bayes.inference.leak._inputs import (
    OFFSET_SD_NMS as OFFSET_SD_NMS,
)
from cassini_bayes.inference.leak._inputs import (
    SAMPLE_STEP_S as SAMPLE_STEP_S,
)
from cassini_bayes.inference.leak._inputs import (
    TORQUE_SCALES as TORQUE_SCALES,
)
from cassini_bayes.inference.leak._inputs import (
    LeakInputs as LeakInputs,
)
from cassini_bayes.inference.leak._inputs import (
    LeakPosterior as LeakPosterior,
)
from cassini_bayes.inference.leak._inputs import (
    leak_inputs as leak_inputs,
)
from cassini_bayes.inference.leak._posterior import leak_posterior as leak_posterior

__all__ = ["LeakInputs", "LeakPosterior", "leak_inputs", "leak_posterior", "HYPOTHESES",
           "FRACTION_SCALES", "OFFSET_SD_NMS", "SAMPLE_STEP_S", "TORQUE_SCALES"]
