"""The MCMC runner (cassini_bayes.inference.runner): compile once, determinism, diagnostics.

A tiny conjugate model (Normal mean with known sd, data as a keyword argument) keeps this file
fast; the inertia model's use of the runner is covered in test_inference_inertia.py.
"""

from __future__ import annotations

import arviz as az
import jax
import jax.numpy as jnp
import numpy as np
import numpyro
import numpyro.distributions as dist
import pytest
from jax import monitoring

from cassini_bayes.inference.runner import (SamplerSettings, choose_chain_method, diagnostics,
                                            run_nuts)

TRACES = {"n": 0}
SETTINGS = SamplerSettings(chains=2, warmup=200, draws=300)


def normal_mean(*, y):
    """``mu ~ N(0, 10²)``, ``y_i ~ N(mu, 1)``: posterior N(Σy/(n + 0.01), 1/(n + 0.01))."""
    TRACES["n"] += 1  # Python side effect: counts traces of the likelihood
    mu = numpyro.sample("mu", dist.Normal(0.0, 10.0))
    numpyro.sample("y", dist.Normal(mu, 1.0), obs=y)


@pytest.fixture(scope="module")
def data():
    return jax.random.normal(jax.random.key(0), (50,)) + 3.0


def _count_compiles():
    counter = {"n": 0}

    def listener(event, duration_secs, **kw):
        if event == "/jax/core/compile/backend_compile_duration":
            counter["n"] += 1

    monitoring.register_event_duration_secs_listener(listener)
    return counter, listener


def test_fitting_same_shapes_twice_compiles_once(data):
    run_nuts(jax.random.key(1), normal_mean, model_kwargs={"y": data}, settings=SETTINGS,
             prior_draws=0)
    other = jax.block_until_ready(data[::-1] * 2.0)  # new data, same shape
    key = jax.random.key(2)
    counter, listener = _count_compiles()
    traces_before = TRACES["n"]
    try:
        run_nuts(key, normal_mean, model_kwargs={"y": other}, settings=SETTINGS, prior_draws=0)
    finally:
        monitoring.unregister_event_duration_listener(listener)
    assert counter["n"] == 0, f"{counter['n']} XLA compilations on the second fit"
    # only the abstract shape probe traces the model again (no compilation, no sampling trace)
    assert TRACES["n"] - traces_before <= 1


def test_posterior_matches_conjugate_answer(data):
    idata = run_nuts(jax.random.key(3), normal_mean, model_kwargs={"y": data},
                     settings=SETTINGS, prior_draws=100)
    mu = idata.posterior["mu"].values
    n = data.shape[0]
    exact_mean = float(jnp.sum(data)) / (n + 0.01)
    exact_sd = (n + 0.01) ** -0.5
    # 600 draws, ESS > 200: the mean is within 4 Monte Carlo sd (false-failure rate ~6e-5)
    assert abs(mu.mean() - exact_mean) < 4 * exact_sd / np.sqrt(200)
    assert abs(mu.std() / exact_sd - 1) < 0.2
    assert "prior" in idata.groups() and idata.prior["mu"].shape == (1, 100)
    assert {"diverging", "energy", "tree_depth", "step_size"} <= set(idata.sample_stats)


def test_same_key_same_draws_different_key_different_draws(data):
    a = run_nuts(jax.random.key(4), normal_mean, model_kwargs={"y": data}, settings=SETTINGS,
                 prior_draws=0).posterior["mu"].values
    b = run_nuts(jax.random.key(4), normal_mean, model_kwargs={"y": data}, settings=SETTINGS,
                 prior_draws=0).posterior["mu"].values
    c = run_nuts(jax.random.key(5), normal_mean, model_kwargs={"y": data}, settings=SETTINGS,
                 prior_draws=0).posterior["mu"].values
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


@pytest.mark.parametrize("method", ["vectorized", "parallel"])
def test_chain_methods_agree_in_distribution(data, method):
    if method == "parallel" and jax.local_device_count() < 2:
        pytest.skip("needs 2 host devices")
    idata = run_nuts(jax.random.key(6), normal_mean, model_kwargs={"y": data},
                     settings=SETTINGS._replace(chain_method=method), prior_draws=0)
    assert idata.posterior["mu"].shape == (2, 300)
    d = diagnostics(idata, ["mu"])
    assert d.max_r_hat < 1.05 and d.divergences == 0
    n = data.shape[0]
    # ESS > 100 of the mean: within 4 Monte Carlo sd of the exact posterior mean
    assert abs(float(idata.posterior["mu"].mean()) - float(jnp.sum(data)) / (n + 0.01)) < (
        4 * (n + 0.01) ** -0.5 / np.sqrt(100))


def test_diagnostics_uses_arviz_and_flags_bad_chains():
    rng = np.random.default_rng(0)
    good = az.from_dict(posterior={"x": rng.normal(size=(4, 500))},
                        sample_stats={"diverging": np.zeros((4, 500), bool)})
    d = diagnostics(good)
    assert d.converged and d.divergences == 0
    assert d.max_r_hat == pytest.approx(float(az.rhat(good)["x"]))
    assert d.min_ess_bulk == pytest.approx(float(az.ess(good, method="bulk")["x"]))
    # chains stuck in different places, and a divergence
    stuck = rng.normal(size=(4, 500)) + np.arange(4)[:, None]
    div = np.zeros((4, 500), bool)
    div[0, 0] = True
    bad = az.from_dict(posterior={"x": stuck}, sample_stats={"diverging": div})
    d = diagnostics(bad)
    assert not d.converged and d.divergences == 1 and d.max_r_hat > 1.1
    assert "R-hat" in d.message() and "divergent" in d.message()


def test_choose_chain_method():
    assert choose_chain_method(1) == "vectorized"
    n = jax.local_device_count()
    assert choose_chain_method(n) == ("parallel" if n > 1 else "vectorized")
    assert choose_chain_method(n + 1) == "vectorized"
