"""SBC campaigns: determinism, checkpoints and resume, Dask executor (``analysis.campaign``).

All campaigns here run the toy model with the same batch size as ``test_sbc.py``, so the session
compiles its sampler once.
"""

from __future__ import annotations

import json
import pickle

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from cassini_bayes.analysis import campaign
from cassini_bayes.analysis.campaign import replicate_keys, run_campaign
from cassini_bayes.analysis.sbc_models import ModelSpec, build_model
from cassini_bayes.errors import InputError

BATCH = 16
N = 40  # three batches, the last one partly past N
SEED = 7
SPEC = ModelSpec.make("toy")


def _assert_same(a, b):
    assert a.names == b.names
    for field in ("truth", "draws", "rank", "n_divergent", "rhat", "failed", "converged"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field), err_msg=field)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """An uninterrupted local campaign."""
    return run_campaign(SPEC, N, tmp_path_factory.mktemp("ref"), seed=SEED, batch_size=BATCH)


def test_reference_campaign_shapes(reference):
    res = reference
    assert res.names == ("alpha", "beta", "sigma")
    assert res.n_draws == 100  # 2 chains x 150 draws, thinned by 3
    assert res.rank.shape == (N, 3) and res.draws.shape == (N, 3, 100)
    assert res.rank.min() >= 0 and res.rank.max() <= res.n_draws
    assert res.batches_run == 3 and not res.failed.any()


def test_sampler_compiles_once_and_is_shared_by_simulator_variants(reference, tmp_path):
    run_campaign(SPEC, N, tmp_path, seed=SEED + 3, batch_size=BATCH)  # new data, same shapes
    fit_program = campaign._programs(SPEC)[2]
    assert fit_program._cache_size() == 1
    # A simulator-only variant (used as the mis-specified model) reuses the same program.
    assert campaign._programs(ModelSpec.make("toy", simulator_noise_factor=2.0))[2] is fit_program


def test_replicate_keys_do_not_depend_on_batching():
    all_keys = np.asarray(jax.random.key_data(replicate_keys(SEED, np.arange(48))))
    some = jax.random.key_data(replicate_keys(SEED, np.array([17, 40])))
    np.testing.assert_array_equal(all_keys[[17, 40]], some)


def test_same_seed_same_ranks_other_seed_other_ranks(reference, tmp_path):
    again = run_campaign(SPEC, N, tmp_path / "a", seed=SEED, batch_size=BATCH)
    _assert_same(reference, again)
    other = run_campaign(SPEC, BATCH, tmp_path / "b", seed=SEED + 1, batch_size=BATCH)
    assert not np.array_equal(other.rank, reference.rank[:BATCH])


def test_resume_after_interruption_equals_uninterrupted_run(reference, tmp_path):
    work = tmp_path / "work"
    seen = []

    def stop_after_first_batch(b, n_done, n_total):
        seen.append(b)
        if n_done == 1:
            raise KeyboardInterrupt  # what a Ctrl-C or a kill between batches looks like

    with pytest.raises(KeyboardInterrupt):
        run_campaign(SPEC, N, work, seed=SEED, batch_size=BATCH, on_batch=stop_after_first_batch)
    assert sorted(p.name for p in work.glob("batch_*.npz")) == ["batch_000000.npz"]
    # A kill in the middle of writing leaves at most a temporary file, never a partial batch.
    (work / ".batch_000001.abcd.npz.tmp").write_bytes(b"half a file")

    resumed = run_campaign(SPEC, N, work, seed=SEED, batch_size=BATCH)
    assert resumed.batches_run == 2  # batch 0 came from its checkpoint
    _assert_same(reference, resumed)


def test_unreadable_checkpoint_is_recomputed(reference, tmp_path):
    work = tmp_path / "work"
    run_campaign(SPEC, BATCH, work, seed=SEED, batch_size=BATCH)
    (work / "batch_000000.npz").write_bytes(b"not an npz")
    res = run_campaign(SPEC, BATCH, work, seed=SEED, batch_size=BATCH)
    assert res.batches_run == 1
    np.testing.assert_array_equal(res.rank, reference.rank[:BATCH])


def test_extending_a_campaign_reuses_its_batches(reference, tmp_path):
    work = tmp_path / "work"
    first = run_campaign(SPEC, 20, work, seed=SEED, batch_size=BATCH)
    assert first.batches_run == 2
    more = run_campaign(SPEC, N, work, seed=SEED, batch_size=BATCH)
    assert more.batches_run == 1
    _assert_same(reference, more)


def test_a_smaller_resume_keeps_the_finished_batches(reference, tmp_path):
    """Resuming with fewer replicates than are finished is refused (its work folder, with the
    batches beyond, would be dropped), and nothing on disk changes."""
    work = tmp_path / "work"
    run_campaign(SPEC, N, work, seed=SEED, batch_size=BATCH)
    before = sorted(p.name for p in work.iterdir())
    with pytest.raises(InputError, match=f"resume with --replicates {2 * BATCH + 1} or more"):
        run_campaign(SPEC, BATCH, work, seed=SEED, batch_size=BATCH)
    assert sorted(p.name for p in work.iterdir()) == before


def test_checkpoints_of_another_campaign_are_refused(tmp_path):
    work = tmp_path / "work"
    run_campaign(SPEC, 1, work, seed=SEED, batch_size=BATCH)
    manifest = json.loads((work / "manifest.json").read_text())
    assert manifest["seed"] == SEED and manifest["batch_size"] == BATCH
    with pytest.raises(InputError, match="different campaign"):
        run_campaign(SPEC, 1, work, seed=SEED + 1, batch_size=BATCH)


def test_bad_settings_are_input_errors(tmp_path):
    with pytest.raises(InputError, match="replicates"):
        run_campaign(SPEC, 0, tmp_path, batch_size=BATCH)
    with pytest.raises(InputError, match="executor"):
        run_campaign(SPEC, 1, tmp_path, batch_size=BATCH, executor="spark")
    with pytest.raises(InputError, match="unknown SBC model"):
        build_model(ModelSpec.make("nosuch"))


def test_dask_task_is_plain_picklable_data():
    # What a remote worker receives: the function by reference and plain-data arguments.
    fn, spec = pickle.loads(pickle.dumps((campaign.run_batch, SPEC)))
    assert fn is campaign.run_batch and spec == SPEC


def test_dask_executor_gives_identical_ranks(reference, tmp_path):
    pytest.importorskip("dask.distributed")
    # A 2-worker LocalCluster (threads of this process, so the compiled sampler is shared).
    res = run_campaign(SPEC, N, tmp_path / "dask", seed=SEED, batch_size=BATCH,
                       executor="dask", n_workers=2, dask_processes=False)
    assert res.batches_run == 3
    _assert_same(reference, res)


def test_dask_scheduler_that_cannot_be_reached_is_an_input_error(tmp_path):
    pytest.importorskip("dask.distributed")
    with pytest.raises(InputError, match="Dask scheduler"):
        run_campaign(SPEC, 1, tmp_path, seed=SEED, batch_size=BATCH, executor="dask",
                     scheduler="tcp://127.0.0.1:9", scheduler_timeout_s=1)


@pytest.mark.slow
def test_dask_process_workers_give_identical_ranks(reference, tmp_path):
    res = run_campaign(SPEC, N, tmp_path / "dask", seed=SEED, batch_size=BATCH,
                       executor="dask", n_workers=2, dask_processes=True)
    _assert_same(reference, res)


def test_cli_resume_finishes_an_interrupted_campaign(run_cli, reference, tmp_path):
    from cassini_bayes.analysis.sbc_run import work_dir

    out = tmp_path / "run"

    def stop(b, n_done, n_total):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):  # the campaign the CLI would have started, killed
        run_campaign(SPEC, N, work_dir(out), seed=SEED, batch_size=BATCH, on_batch=stop)
    args = ("sbc", "toy", "--replicates", N, "--batch", BATCH, "--seed", SEED, "--out", out)
    code, _, stderr = run_cli(*args)
    assert code == 2 and "--resume" in stderr and not out.exists()
    code, _, stderr = run_cli(*args, "--resume")
    assert code == 0, stderr
    with np.load(out / "replicates.npz") as z:
        np.testing.assert_array_equal(z["rank"], reference.rank)
        np.testing.assert_array_equal(z["draws"], reference.draws)
    assert not work_dir(out).exists()
    assert json.loads((out / "summary.json").read_text())["replicates"] == N


# A model with exact posterior draws (normal mean, known noise) fitted one replicate at a time,
# whose fit raises for some replicates: the non-vectorised path and failure accounting.
def _exact_normal(spec):
    import jax.numpy as jnp

    from cassini_bayes.analysis.sbc_models import SbcFit, SbcModel

    n_obs = 5

    def prior_sample(key):
        return {"theta": jax.random.normal(key)}

    def simulate(key, params):
        return params["theta"] + jax.random.normal(key, (n_obs,))

    def fit(key, y):
        y = np.asarray(y)
        if y[0] > 1.5:
            raise FloatingPointError("pretend the sampler blew up")
        post_var = 1.0 / (1.0 + n_obs)
        draws = post_var * y.sum() + np.sqrt(post_var) * jax.random.normal(key, (2, 50))
        return SbcFit({"theta": jnp.asarray(draws)}, jnp.asarray(0))

    return SbcModel("exact-normal", ("theta",), prior_sample, simulate, fit, vectorized=False)


def test_a_model_needs_a_simulator():
    """``simulate`` may be ``None`` only beside ``simulate_batch``: one of them makes the data."""
    from cassini_bayes.analysis.sbc_models import SbcModel

    model = _exact_normal(None)
    with pytest.raises(ValueError, match="neither simulate nor simulate_batch"):
        SbcModel("no-data", ("theta",), model.prior_sample, None, model.fit)
    batch = SbcModel("batched", ("theta",), model.prior_sample, None, model.fit,
                     simulate_batch=lambda prior_keys, sim_keys: ({}, None))
    assert batch.simulate is None


def test_failed_fits_are_counted_not_fatal(tmp_path):
    from cassini_bayes.analysis.sbc_models import register

    register("_exact_normal_flaky")(_exact_normal)
    spec = ModelSpec.make("_exact_normal_flaky")
    with pytest.warns(RuntimeWarning, match="recorded as a failure"):
        res = run_campaign(spec, 32, tmp_path, seed=SEED, batch_size=8)
    assert 0 < res.failed.sum() < 32
    assert np.all(res.rank[res.failed] == -1) and not res.converged[res.failed].any()
    ok = res.rank[~res.failed, 0]
    assert ok.min() >= 0 and ok.max() <= res.n_draws == 100


def test_campaign_fit_is_the_runners_sampler():
    """The vectorised campaign fit draws what :func:`run_nuts` draws with the same key and data
    (the one NUTS driver of the package, vmapped over data sets), and vmapped over a batch each
    replicate gets the fit it would get alone (to rounding: a vmapped program may order
    floating-point reductions differently)."""
    from cassini_bayes.analysis.sbc_models._toy import _toy_numpyro_model, _toy_settings
    from cassini_bayes.inference.runner import run_nuts

    model = build_model(SPEC)
    s = model.settings
    key = jax.random.key(3)
    data = model.simulate(jax.random.key(4), model.prior_sample(jax.random.key(5)))
    fit = model.fit(key, data)
    idata = run_nuts(key, _toy_numpyro_model(s["n_obs"], s["likelihood_noise_factor"]),
                     model_kwargs=data, prior_draws=0,
                     settings=_toy_settings(s["num_warmup"], s["num_draws"], s["num_chains"])
                     ._replace(chain_method="vectorized"))
    for name in model.parameter_names:
        np.testing.assert_allclose(np.asarray(fit.draws[name]), idata.posterior[name].values,
                                   rtol=1e-9, atol=1e-12)
    assert int(fit.n_divergent) == int(idata.sample_stats["diverging"].values.sum())
    keys = replicate_keys(SEED, np.arange(2))
    chains, _ = campaign._vmapped_fit(model.fit, model.parameter_names)(
        keys, jax.tree.map(lambda a: jnp.stack([a, 2.0 * a]), data))
    alone = model.fit(jax.random.split(keys[0], 4)[2], data)
    # the same trajectory to rounding, amplified along the chain (more on another instruction
    # set, docs/performance.md); another draw would differ by the posterior sd, ~0.07 here
    np.testing.assert_allclose(np.asarray(chains[0, 0]), np.asarray(alone.draws["alpha"]),
                               rtol=1e-3, atol=1e-5)


def test_thinning_and_effective_sample_size_are_recorded(reference):
    """``L`` = 2 chains x 150 draws / thin 3; the ESS of the 300 draws before thinning is
    recorded per replicate and is at least ``L`` for most (NUTS on a 3-parameter Gaussian-like
    posterior: ESS ~ the number of draws)."""
    res = reference
    assert res.ess.shape == (N,) and np.all(np.isfinite(res.ess))
    assert np.mean(res.ess >= res.n_draws) > 0.8


def _exact_normal_prepared(spec):
    """The exact normal model, vectorised, whose per-replicate ``prepare`` raises sometimes."""
    from cassini_bayes.analysis.sbc_models import SbcFit, SbcModel

    n_obs = 5

    def prior_sample(key):
        return {"theta": jax.random.normal(key)}

    def simulate(key, params):
        return params["theta"] + jax.random.normal(key, (n_obs,))

    def prepare(y):
        if y[0] > 1.5:
            raise FloatingPointError("pretend the preparation blew up")
        return {"total": np.sum(y)}

    def fit(key, data):
        post_var = 1.0 / (1.0 + n_obs)
        draws = post_var * data["total"] + jnp.sqrt(post_var) * jax.random.normal(key, (2, 50))
        return SbcFit({"theta": draws}, jnp.asarray(0))

    return SbcModel("exact-normal-prepared", ("theta",), prior_sample, simulate, fit,
                    vectorized=True, prepare=prepare)


def test_failed_preparations_are_counted_not_fatal(tmp_path):
    """A vectorised model's ``prepare`` that raises for a replicate: that replicate is a
    recorded failure (NaN draws, rank -1), the others of its batch are fitted in the one vmapped
    call and are exact posterior draws (their ranks pass a loose uniformity check)."""
    from cassini_bayes.analysis import sbc
    from cassini_bayes.analysis.sbc_models import register

    register("_exact_normal_prepared")(_exact_normal_prepared)
    spec = ModelSpec.make("_exact_normal_prepared")
    with pytest.warns(RuntimeWarning, match="recorded as a failure"):
        res = run_campaign(spec, 64, tmp_path, seed=SEED, batch_size=16)
    assert 0 < res.failed.sum() < 64
    assert np.all(res.rank[res.failed] == -1) and np.all(np.isnan(res.draws[res.failed]))
    ok = ~res.failed
    assert np.all(np.isfinite(res.draws[ok])) and np.all(res.ess[ok] > 50)
    assert sbc.chi2_uniformity(res.rank[ok, 0], res.n_draws, bins=4).p_value > 1e-3


def test_a_failed_scheduler_leaves_dask_as_it_was():
    """A malformed --scheduler is an InputError, and the half-made client does not stay dask's
    global scheduler (later ArviZ/xarray work in the process would try to reach it)."""
    import dask
    from distributed.client import _get_global_client

    from cassini_bayes.analysis.campaign import _dask_client
    from cassini_bayes.errors import InputError

    before = dask.config.get("scheduler", None)
    with pytest.raises(InputError, match="cannot reach the Dask scheduler"):
        with _dask_client("not an address", None, False, 2.0):
            pass
    assert dask.config.get("scheduler", None) == before
    assert _get_global_client() is None
