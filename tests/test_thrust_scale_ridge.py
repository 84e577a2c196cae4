"""The robust thrust fit's density along the common-scale ridge.

Scaling the inertia, every thrust and every wheel's spin inertia by one factor leaves a biasing
event's rates and wheel speeds unchanged (Feldman & Lee Eq 17 is homogeneous in them), so only
the wheels' spin-inertia prior may tell that factor: along the ridge the fit's density must fall
as that prior does, with the prior's sd and its maximum at the truth
(``benchmarks/thrust_scale_ridge.py``, docs/planning.md, "The fit's density does not keep that
ridge flat").
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

STEP = 0.005


def _ridge(case: str) -> tuple[float, float, float]:
    """``(sd, peak offset, the wheel prior's sd along the ridge)`` of the scale ``s`` from the
    fit's density at ``F``, ``I`` × ``s`` on the event flown without noise (noise at the
    sensors')."""
    from cassini_bayes.inference.nuisance import wheel_inertia_sd
    from cassini_bayes.inference.thrust.model import log_density
    from cassini_bayes.plan.thrust import (_site_names, _truth, _truth_vector,
                                           noise_free_problem, representable)
    from cassini_bayes.simulate import load_scenario

    name, mode = case.split(":")
    sc = load_scenario(name)
    _, problem, _ = noise_free_problem(sc, mode)
    names = _site_names(problem)
    truth = _truth(representable(sc, mode), problem, names)
    scaled = np.array([n.startswith("F") or n[0] == "I" for n in names])
    k = problem.n_f + problem.n_c + 3

    def theta(factor):
        x = _truth_vector(problem, names, np.where(scaled, truth * factor, truth))
        return np.r_[x[:k], 0.0, x[k:]]                 # the noise at the sensors'

    steps = STEP * np.array([-2.0, -1.0, 0.0, 1.0, 2.0])
    thetas = jnp.asarray(np.stack([theta(1.0 + d) for d in steps]), float)
    lp = jax.jit(jax.vmap(lambda t, kw: log_density(t, kw, problem.n_f, problem.n_c, True),
                          in_axes=(0, None)))(thetas, problem.data)
    b, a, _ = np.polyfit(steps, np.asarray(lp), 2)
    lay = problem.layout
    sd = np.array([wheel_inertia_sd(sc.prior, w) for w in lay.wheels])
    common = sc.prior.knowledge.wheel_common_inertia_sd_frac if lay.has_common else 0.0
    return (float(1.0 / np.sqrt(-2.0 * b)), float(-a / (2.0 * b)),
            float(np.sqrt(common**2 + 1.0 / np.sum(1.0 / sd**2))))


def test_cassini_ridge_falls_as_the_wheel_prior():
    """Day 028 (Cassini's tachometers add ~1 % of the left side's noise): the density's sd of
    ``s`` within 3 % of the wheel prior's (0.575 % against 0.577 %, measured) and its maximum
    within 0.5 % of the truth (+0.20 %). Deterministic: no sampling."""
    sd, peak, prior_sd = _ridge("biasing_day028:mean")
    assert abs(sd / prior_sd - 1.0) < 0.03 and abs(peak) < 0.005


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="known: the wheel-rate noise and the rate-step "
                   "corrections hold the wheels at the model file's spin inertias while the "
                   "nuisance scales them (docs/planning.md); remove this mark with the fix")
def test_espa_ridge_falls_as_the_wheel_prior():
    """The ESPA bus (tachometer noise as large in momentum as the gyro's): the same check,
    within 10 % and 0.5 %. It fails today: 0.43 % against the prior's 0.56 %, the maximum
    +1.56 % off the truth."""
    sd, peak, prior_sd = _ridge("biasing_espa_bus:thruster")
    assert abs(sd / prior_sd - 1.0) < 0.10 and abs(peak) < 0.005
