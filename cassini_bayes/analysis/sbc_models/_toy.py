"""The toy SBC model: a linear-Gaussian regression with unknown noise that tests the machinery."""

from __future__ import annotations

import functools
from collections.abc import Callable

import jax
import jax.numpy as jnp

from cassini_bayes.analysis.sbc_models._contract import ModelSpec, SbcModel, register
from cassini_bayes.analysis.sbc_models._nuts import nuts_fit
from cassini_bayes.errors import InputError, spelled

__all__: list[str] = []


def _toy_model(*, n_obs: int = 20, likelihood_noise_factor: float = 1.0,
              simulator_noise_factor: float = 1.0, num_warmup: int = 150, num_draws: int = 150,
              num_chains: int = 2, thin: int = 3) -> SbcModel:
    """Linear-Gaussian regression with unknown noise, to test the SBC machinery.

    ``y_i = alpha + beta x_i + sigma ε_i`` on ``x`` evenly spaced in ``[-1, 1]`` (dimensionless),
    priors ``alpha, beta ~ Normal(0, 1)``, ``sigma ~ LogNormal(log 0.5, 0.3)``. The posterior is
    fitted by the package's NUTS (:func:`nuts_fit`; ``sigma`` sampled as ``log sigma``, the
    runner's unconstrained coordinates, with a diagonal mass matrix and target acceptance 0.8);
    ``num_chains · num_draws / thin`` draws are ranked.

    Two switches mis-specify it on purpose (SBC must then fail): the fit's likelihood uses
    ``likelihood_noise_factor · sigma``, the simulator ``simulator_noise_factor · sigma``. With
    ``likelihood_noise_factor = 0.5`` (or, equivalently for the ratio, ``simulator_noise_factor =
    2``) the likelihood's noise scale is half the data's: the posterior of ``sigma`` sits near twice
    the truth (or the truth's double is fitted), and its ranks pile up at one end. The
    simulator switch leaves the compiled sampler untouched, which the tests use to compile once.
    """
    x = jnp.linspace(-1.0, 1.0, n_obs)
    names = ("alpha", "beta", "sigma")

    def prior_sample(key):
        k_a, k_b, k_s = jax.random.split(key, 3)
        return {"alpha": jax.random.normal(k_a), "beta": jax.random.normal(k_b),
                "sigma": jnp.exp(_TOY_LOG_SIGMA_LOC + _TOY_LOG_SIGMA_SCALE
                                 * jax.random.normal(k_s))}

    def simulate(key, params):
        mean = params["alpha"] + params["beta"] * x
        noise = simulator_noise_factor * params["sigma"] * jax.random.normal(key, x.shape)
        return {"y": mean + noise}

    fit = _toy_fit(n_obs, likelihood_noise_factor, num_warmup, num_draws, num_chains)
    settings = {"n_obs": n_obs, "likelihood_noise_factor": likelihood_noise_factor,
                "simulator_noise_factor": simulator_noise_factor, "num_warmup": num_warmup,
                "num_draws": num_draws, "num_chains": num_chains, "thin": thin}
    return SbcModel("toy", names, prior_sample, simulate, fit, True, settings)


_TOY_LOG_SIGMA_LOC = float(jnp.log(0.5))
_TOY_LOG_SIGMA_SCALE = 0.3


@functools.lru_cache(maxsize=8)
def _toy_numpyro_model(n_obs: int, likelihood_noise_factor: float) -> Callable:
    """The toy model's NumPyro model ``model(y)`` (one object per setting: compiled once)."""
    import numpyro
    import numpyro.distributions as dist

    x = jnp.linspace(-1.0, 1.0, n_obs)

    def model(y):
        alpha = numpyro.sample("alpha", dist.Normal(0.0, 1.0))
        beta = numpyro.sample("beta", dist.Normal(0.0, 1.0))
        log_sigma = numpyro.sample("log_sigma", dist.Normal(_TOY_LOG_SIGMA_LOC,
                                                            _TOY_LOG_SIGMA_SCALE))
        sigma = numpyro.deterministic("sigma", jnp.exp(log_sigma))
        numpyro.sample("y", dist.Normal(alpha + beta * x, likelihood_noise_factor * sigma), obs=y)

    return model


def _toy_settings(num_warmup: int, num_draws: int, num_chains: int):
    """The toy model's NUTS settings: a diagonal mass matrix, target acceptance 0.8."""
    from cassini_bayes.inference.runner import SamplerSettings

    return SamplerSettings(chains=num_chains, warmup=num_warmup, draws=num_draws,
                           dense_mass=False, target_accept=0.8)


@functools.lru_cache(maxsize=8)
def _toy_fit(n_obs, likelihood_noise_factor, num_warmup, num_draws, num_chains):
    return nuts_fit(_toy_numpyro_model(n_obs, likelihood_noise_factor), ("alpha", "beta", "sigma"),
                    _toy_settings(num_warmup, num_draws, num_chains))


_TOY_KEYS = {"n_obs", "likelihood_noise_factor", "simulator_noise_factor", "num_warmup",
             "num_draws", "num_chains", "thin"}


@register("toy")
def _toy(spec: ModelSpec) -> SbcModel:
    """The toy model with the scenario's ``[toy]`` table and ``--set`` options as settings."""
    from_file = spec.scenario().get("toy", spec.scenario())
    settings = {**from_file, **dict(spec.options)}
    for where, keys in ((spec.scenario_source, set(from_file)),
                        (spelled("--set", "options"), set(dict(spec.options)))):
        unknown = keys - _TOY_KEYS
        if unknown:
            raise InputError(f"unknown toy-model setting(s) {sorted(unknown)}; allowed: "
                             f"{sorted(_TOY_KEYS)}", path=where)
    return _toy_model(**settings)
