"""A planned manoeuvre flown by the simulator without sensor noise, differentiably.

:func:`make_flight` takes a scenario without slews (the spacecraft, its initial state, the
controller, the telemetry's sampling) and returns a function of the slews (and, optionally, the
wheel speeds at the start) that runs the simulator's compiled core
(:func:`cassini_bayes.simulate.run.simulate_arrays`'s) on the commanded profile built in JAX
(:func:`cassini_bayes.plan.manoeuvre.command`). The result is the truth the telemetry would
show, as a differentiable function of the manoeuvre: what the predicted posterior
(:mod:`cassini_bayes.plan.inertia`) and the limit checks are computed from.

``dt_s`` may be coarser than the scenario's, for the optimiser's many evaluations: the
controller's feedback is then sampled less often, which changes the truth by far less than the
gradients need; every plan is checked again at the scenario's own step.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.plan.manoeuvre import Slews, command
from cassini_bayes.simulate import run as _run
from cassini_bayes.simulate.scenario import Scenario
from cassini_bayes.simulate.sensors import NoiseParams

__all__ = ["make_flight", "no_noise", "planning_step"]

CONTROL_STEPS_PER_BANDWIDTH = 0.1
"""The optimiser's integration step is at most this fraction of ``1/ω_n`` of the attitude
controller (``bandwidth_rad_s``): a zero-order-hold PD loop so sampled tracks as the continuous
one to within a few per cent."""


def no_noise() -> NoiseParams:
    """Sensor noise switched off: the telemetry is the truth."""
    z = jnp.zeros(())
    return NoiseParams(z, z, z, z, jnp.zeros(3), jnp.zeros(3), z)


def planning_step(scenario: Scenario) -> float:
    """The optimiser's integration step, s: the scenario's, or coarser up to
    :data:`CONTROL_STEPS_PER_BANDWIDTH` / bandwidth, a whole fraction of the sample period."""
    coarse = max(scenario.dt_s, CONTROL_STEPS_PER_BANDWIDTH / scenario.rwa.bandwidth_rad_s)
    return scenario.sample_period_s / int(np.ceil(scenario.sample_period_s / coarse - 1e-9))


def make_flight(base: Scenario, dt_s: float | None = None,
                truth: _run.TruthParams | None = None) -> Callable:
    """``fly(slews, wheel0_rad_s=None) -> SimArrays`` (noise-free) for the scenario ``base``
    (its own slews ignored) at integration step ``dt_s`` (default the scenario's); ``truth``
    overrides the true parameters (default the scenario's)."""
    s = base if dt_s is None else replace(base, dt_s=float(dt_s))
    if dt_s is not None and abs(s.steps_per_sample * s.dt_s - s.sample_period_s) > 1e-9:
        raise ValueError(f"dt_s = {dt_s} is not a whole fraction of the sample period")
    cfg = _run._config(s)
    carr = _run._controller_arrays(s)
    tp = _run.truth_params(s) if truth is None else truth
    t_steps = jnp.arange(s.n_steps) * s.dt_s
    t_samples = jnp.arange(s.n_samples) * s.sample_period_s
    q0 = jnp.asarray(s.q0)
    noise = no_noise()
    key = jax.random.key(0)   # unused: the noise is off

    def fly(slews: Slews, wheel0_rad_s=None):
        plan = command(t_steps, q0, slews).reshape(cfg.n_out, cfg.sps, 10)
        c = dict(carr, cmd_samples=command(t_samples, q0, slews))
        if wheel0_rad_s is not None:
            c["rho0"] = jnp.asarray(wheel0_rad_s)
        return _run._simulate_core(key, tp, noise, plan, c, cfg)

    fly.scenario = s
    return fly
