"""The ``thrust`` SBC adapter (idealised model): mean thrust and pulse time constants."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes._paths import SCENARIOS_DIR
from cassini_bayes.analysis.sbc_models._common import (
    IDEAL_PULSE_TAU_S,
    check_options,
    posterior_draws,
    quiet,
    sampler_settings,
    scenario_of,
    tiled_truth,
)
from cassini_bayes.analysis.sbc_models._contract import ModelSpec, SbcFit, SbcModel, register
from cassini_bayes.errors import InputError

__all__ = ["THRUST_SCENARIO", "THRUST_SBC_NAMES", "thrust_scenario"]

# default scenario: the day 028 RWA biasing event cut to 80 s (the file's header says more)
THRUST_SCENARIO = SCENARIOS_DIR / "sbc" / "sbc_thrust_biasing.toml"

THRUST_SBC_NAMES = ("F", "tau_delay", "tau_rise", "tau_fall")
_THRUST_KEYS = {"num_warmup", "num_draws", "num_chains", "thin", "robust", "pulse_dynamics",
                "thrust_factor"}


def thrust_scenario(spec: ModelSpec):
    """The thrust adapters' scenario (default :data:`THRUST_SCENARIO`); one that fires no
    thruster is an error, as it has nothing to calibrate."""
    scenario = scenario_of(spec, THRUST_SCENARIO)
    if not scenario.uses_thrusters:
        raise InputError("the thrust SBC scenario fires no thrusters; give a biasing event "
                         "(control = \"rcs\" or [[pulse]] entries)", path=spec.scenario_source)
    return scenario


@dataclass(frozen=True, eq=False)
class _ThrustReplicates:
    """Truth, simulation and fit of the idealised thrust adapter's replicates (one ``F`` for
    all thrusters, the inertia held at the ``[prior]`` model's)."""

    scenario: Any
    pulse_dynamics: bool
    thrust_factor: float
    settings: Any

    @cached_property
    def base(self):
        """The scenario's truth with the ``[prior]`` model's inertia (the fit holds it)."""
        from cassini_bayes.physics.momentum import inertia_vector
        from cassini_bayes.simulate.run import truth_params

        return truth_params(self.scenario)._replace(
            inertia=jnp.asarray(inertia_vector(self.scenario.prior.inertia)))

    @cached_property
    def tau_prior(self):
        """The pulse time constants' prior of the ``[prior]`` model."""
        from cassini_bayes.inference.thrust import tau_prior

        return tau_prior(self.scenario.prior)

    def prior_sample(self, key) -> dict[str, Any]:
        """``log F ~ Normal(log F_pred, THRUST_PRIOR_LOG_SD)`` and the time constants from
        :func:`~cassini_bayes.inference.thrust.draw_tau_prior`."""
        from cassini_bayes.inference.thrust import THRUST_PRIOR_LOG_SD, draw_tau_prior

        k_f, k_t = jax.random.split(key)
        log_f_mu = float(np.log(self.scenario.prior.thrust))
        f = jnp.exp(log_f_mu + THRUST_PRIOR_LOG_SD * jax.random.normal(k_f))
        tau = draw_tau_prior(k_t, self.tau_prior)
        return dict(zip(THRUST_SBC_NAMES, (f, tau[0], tau[1], tau[2])))

    def simulate_batch(self, prior_keys, sim_keys):
        """The drawn truths flown in one simulator batch: the thrust (times ``thrust_factor``)
        on all eight thrusters, the time constants (1 µs each without ``pulse_dynamics``)."""
        from cassini_bayes.simulate.run import simulate_batch

        params = jax.vmap(self.prior_sample)(prior_keys)
        b = prior_keys.shape[0]
        tau = jnp.stack([params[n] for n in THRUST_SBC_NAMES[1:]], axis=1)
        if not self.pulse_dynamics:
            tau = jnp.full_like(tau, IDEAL_PULSE_TAU_S)
        thrust = params["F"] * self.thrust_factor
        truth = tiled_truth(self.base, b)._replace(
            thrust_n=jnp.broadcast_to(thrust[:, None], (b, 8)), tau_s=tau)
        return params, simulate_batch(sim_keys, self.scenario, truth)

    def fit(self, key, arrays) -> SbcFit:
        """:func:`~cassini_bayes.inference.thrust.fit_thrust` (mode ``mean``) of one replicate's
        telemetry and commanded pulses, the inertia fixed at the model's prediction (the
        replicates' inertia is that prediction: SBC of the stated model)."""
        from cassini_bayes.inference.thrust import fit_thrust
        from cassini_bayes.simulate.run import measured_telemetry, pulse_log

        log = pulse_log(arrays, self.scenario)
        if log is None:
            raise RuntimeError("no thruster fired in this replicate")
        tel = measured_telemetry(arrays, self.scenario, "<sbc thrust replicate>")
        post = fit_thrust(key, [(tel, log)], self.scenario.prior, mode="mean",
                          settings=self.settings, prior_draws=0, robust=False, inertia="fixed")
        return posterior_draws(post.idata, THRUST_SBC_NAMES)


@register("thrust")
def _thrust(spec: ModelSpec) -> SbcModel:
    """Mean thrust and pulse time constants from a biasing event: prior truth, simulator, NUTS.

    Truth per replicate, from the prior the fit states (:mod:`cassini_bayes.inference.thrust`):
    ``log F ~ Normal(log F_pred, THRUST_PRIOR_LOG_SD)`` with ``F_pred`` the ``[prior]``
    spacecraft's thrust (one ``F`` for all eight thrusters, mode ``mean``), and
    ``τd, τr, τf`` from :func:`~cassini_bayes.inference.thrust.tau_prior` (half-normal delay,
    log-normal rise and fall; :func:`~cassini_bayes.inference.thrust.draw_tau_prior`).
    They go into ``TruthParams.thrust_n`` (8,) and ``tau_s`` (3,); the truth's inertia is the
    ``[prior]`` model's (the fit holds it fixed), the rest is the scenario's. Data: the scenario
    (default :data:`THRUST_SCENARIO`, RCS-controlled wheel biasing, so the pulse train depends on
    the truth) through :func:`~cassini_bayes.simulate.run.simulate_batch`; the fit gets the noisy
    telemetry and the commanded pulse log. Fit: :func:`~cassini_bayes.inference.thrust.fit_thrust`
    (mode ``mean``) per replicate.

    Options: ``num_warmup, num_draws, num_chains, thin`` (default 300, 300, 2, 3), ``robust``
    (False: the idealised model, which matches a simulator without sensor/wheel errors; True:
    the robust model ``fit thrust`` runs by default, every truth drawn from its prior and flown,
    :func:`~cassini_bayes.analysis.sbc_models._thrust_robust.robust_thrust_model`), and two
    deliberate mis-specifications SBC must detect: ``pulse_dynamics=False`` makes the simulator
    fire ideal rectangular pulses (every time constant 1 µs, impulse ``F·Δ``) while the fit models
    the pulse response of Feldman & Lee §V (impulse ``F(Δ + c)``, ``c ≈ 45 ms``); and
    ``thrust_factor`` multiplies the simulated thrust (the recorded truth stays the drawn ``F``).
    """
    if dict(spec.options).get("robust"):
        from cassini_bayes.analysis.sbc_models._thrust_robust import robust_thrust_model

        return robust_thrust_model(spec)
    scenario = thrust_scenario(spec)
    opts = {"num_warmup": 300, "num_draws": 300, "num_chains": 2, "thin": 3, "robust": False,
            "pulse_dynamics": True, "thrust_factor": 1.0, **dict(spec.options)}
    check_options("thrust", opts, _THRUST_KEYS)
    reps = _ThrustReplicates(scenario, bool(opts["pulse_dynamics"]), float(opts["thrust_factor"]),
                             sampler_settings(opts))
    record = {**opts, "scenario": scenario.name, "prior_model": scenario.prior_model_path}
    return SbcModel("thrust", THRUST_SBC_NAMES, reps.prior_sample, None, quiet(reps.fit),
                    vectorized=False, settings=record, rhat_max=1.05,
                    simulate_batch=reps.simulate_batch)
