"""Truths that a model file's stated knowledge allows, for predictions that must not hang on one.

A manoeuvre flown under closed-loop control flies differently for every truth: the RCS dead-band
controller of a biasing event fires as many pulses, of such widths, as the true inertia, wheels
and torques make it, and the short pulses that resolve a valve's rise come and go with them. A
prediction at the model file's nominal truth is then the prediction of one flight among many;
:func:`knowledge_truths` gives the others, each a scenario whose truth is drawn from what the
prior model says it knows:

- the inertia uniform on the model file's knowledge box
  (:func:`~cassini_bayes.simulate.open_world.inertia_from_knowledge`);
- the valve time constants uniform on the model file's test ranges (Feldman & Lee §V);
- each wheel's spin-inertia error Normal at its ``[wheel_knowledge]`` sd;
- the external torques, body and inertial, Normal at the ``[torque_knowledge]`` sd per axis;
- the centre of mass Normal about the model file's at its ``[center_of_mass] sd_m`` per axis (a
  fit that cannot hold it, modes ``mean`` and ``branch``, flies the model file's instead:
  :func:`~cassini_bayes.plan.thrust.representable`), on its own stream, so the other draws
  stay what they were before it was drawn.

Sensor errors, the thrusts and everything the model file does not state stay as the scenario
has them.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from cassini_bayes.names import TAU_NAMES
from cassini_bayes.simulate.open_world import inertia_from_knowledge
from cassini_bayes.simulate.scenario import Scenario

__all__ = ["knowledge_truths", "median_interval"]

MEDIAN_LEVEL = 0.9
"""Least coverage of :func:`median_interval`."""


def knowledge_truths(s: Scenario, n: int, seed: int = 0) -> list[Scenario]:
    """``n`` copies of ``s`` whose truths are drawn from its prior model's stated knowledge
    (module docstring), by a fixed stream of ``seed``."""
    rng = np.random.default_rng([seed, 3301])
    rng_com = np.random.default_rng([seed, 3302])
    prior, kn = s.prior, s.prior.knowledge
    known = {w.name: w.inertia_sd_frac for w in prior.wheels if w.inertia_sd_frac is not None}
    sd_j = np.array([known.get(w, kn.wheel_inertia_sd_frac) for w in s.truth.wheel_names])
    out = []
    for _ in range(n):
        v, _ = inertia_from_knowledge(rng, prior)
        inertia = np.array([[v[0], v[3], v[4]], [v[3], v[1], v[5]], [v[4], v[5], v[2]]])
        pulse = replace(s.truth.pulse, **{k: float(rng.uniform(*getattr(prior.pulse, f"{k}_range")))
                                          for k in TAU_NAMES})
        torques = rng.normal(0.0, kn.torque_sd_nm, (2, 3))
        com = np.asarray(prior.com_m, float) + rng_com.normal(0.0, prior.com_sd_m, 3)
        out.append(replace(s, truth=replace(s.truth, inertia=inertia, pulse=pulse, com_m=com),
                           wheel_inertia_errors=tuple(rng.normal(0.0, sd_j).tolist()),
                           external_torque_body_nm=tuple(torques[0].tolist()),
                           external_torque_inertial_nm=tuple(torques[1].tolist())))
    return out


def median_interval(x, level: float = MEDIAN_LEVEL) -> tuple[np.ndarray, np.ndarray]:
    """Distribution-free interval of the population median of each column of ``x`` (n, ...):
    the order statistics of SciPy's ``quantile_test`` at coverage ``level`` or more (NaN where
    no pair reaches it, n < 5 at 0.9): a median over a few truths is itself an estimate."""
    from scipy.stats import quantile_test

    x = np.asarray(x, float)
    cols = x.reshape(x.shape[0], -1).T
    ends = np.array([tuple(quantile_test(c, q=np.median(c), p=0.5).confidence_interval(level))
                     for c in cols]).T
    return ends[0].reshape(x.shape[1:]), ends[1].reshape(x.shape[1:])
