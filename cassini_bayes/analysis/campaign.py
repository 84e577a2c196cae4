"""SBC campaigns: replicates in vectorised batches, checkpoints, resume, local or Dask executors.

A campaign of ``N`` replicates of a model (:mod:`cassini_bayes.analysis.sbc_models`) is cut into
batches of ``B`` replicates. Batch ``b`` always holds replicates ``bB … bB + B − 1`` and replicate
``i`` always uses the key ``fold_in(key(seed), i)`` (split into prior, simulation, fit and
tie-breaking keys), so a replicate's result depends on ``(seed, i, B)`` only — not on which
batches ran before, on which worker, or whether the campaign was interrupted. (``B`` enters only
through floating-point rounding of the vectorised programs; a resumed campaign must keep its ``B``
and the manifest check enforces it.) A last batch that runs past ``N`` is computed whole (the
compiled program keeps one shape) and its extra replicates are ignored.

Each batch: the parameters and data of all ``B`` replicates are drawn and simulated in one
``jax.vmap`` (or the model's own batched simulator); a vectorised model (toy, inertia) then fits
them with one ``jax.vmap`` of the package's NUTS program over the ``B`` data sets (every
replicate's chains advance in lock-step in one compiled program, compiled once per model and
shapes; see :func:`cassini_bayes.analysis.sbc_models.nuts_fit`), after the model's per-replicate
``prepare`` step when it has one (the inertia model's NumPy data preparation); the thrust and RWA4
fits run one after the other. The draws are thinned by the model's ``thin`` and ranked
(:func:`cassini_bayes.analysis.sbc.ranks`); each replicate's effective sample size before
thinning is recorded beside its R-hat, to check that the ``L`` ranked draws are about as good as
independent ones (``ESS ≥ L``; Talts et al. 2018, Sec. 5.1). Throughput (``benchmarks/
bench_sbc.py``; ``docs/sbc/``): the toy model runs thousands of replicates a minute once compiled;
the inertia model's replicates cost mostly their NumPy preparation, not the sampler.

Checkpoints: ``WORKDIR/manifest.json`` records what the campaign is (model, options, scenario
hash, seed, batch size, package version); every finished batch is written to
``WORKDIR/batch_NNNNNN.npz`` atomically (:mod:`cassini_bayes.files`), so a campaign
killed at any moment leaves only whole batches. :func:`run_campaign` on the same ``WORKDIR`` skips
the batches already there and runs the rest: the result equals an uninterrupted run bit for bit.
A damaged batch file (truncated by a full disk, say) is recomputed, with a warning.

Executors: ``local`` runs the batches in this process; ``dask`` submits them to a Dask cluster
(``scheduler`` address, or a ``LocalCluster`` when none is given). A task carries only plain data
(:class:`~cassini_bayes.analysis.sbc_models.ModelSpec`, seed, batch index, batch size); the worker
rebuilds the adapter (compiling once per worker process) and returns NumPy arrays; the client
writes the checkpoints, so workers need no shared file system, only ``cassini_bayes`` installed.
Both executors run the same function on the same keys and give identical ranks.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import warnings
import zipfile
import zlib
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from cassini_bayes import __version__
from cassini_bayes._devices import jax_entry
from cassini_bayes.files import atomic_path, write_text
from cassini_bayes.analysis.sbc_models import ModelSpec, SbcModel, build_model
from cassini_bayes.errors import InputError
from cassini_bayes.analysis._campaign_batch import (  # noqa: F401 - the batch step, re-exported
    BatchResult as BatchResult,
    _programs as _programs,
    _vmapped_fit as _vmapped_fit,
    replicate_keys as replicate_keys,
    run_batch as run_batch,
)

__all__ = [
    "BatchResult",
    "CampaignResult",
    "EXECUTORS",
    "run_batch",
    "run_campaign",
    "replicate_keys",
    "load_checkpoints",
]

EXECUTORS = ("local", "dask")
_FIELDS = ("index", "truth", "draws", "rank", "n_divergent", "rhat", "ess", "failed")


class CampaignResult(NamedTuple):
    """A finished campaign: the first ``N`` replicates, in replicate order.

    Attributes
    ----------
    names : tuple of str
        Parameter names (the ``P`` columns).
    truth, draws, rank, n_divergent, rhat, ess, failed : numpy.ndarray
        As in :class:`BatchResult`, stacked over replicates ``0..N−1``.
    converged : numpy.ndarray
        No divergence and every R-hat ≤ the model's ``rhat_max``, shape ``(N,)``.
    n_draws : int
        ``L``.
    seed, batch_size : int
        Campaign identity.
    batches_run : int
        Batches computed by this call (the rest came from checkpoints).
    settings : dict
        The model's settings.
    """

    names: tuple[str, ...]
    truth: np.ndarray
    draws: np.ndarray
    rank: np.ndarray
    n_divergent: np.ndarray
    rhat: np.ndarray
    ess: np.ndarray
    failed: np.ndarray
    converged: np.ndarray
    n_draws: int
    seed: int
    batch_size: int
    batches_run: int
    settings: dict


# ------------------------------------------------------------------------------ checkpoints


def _batch_path(workdir: Path, b: int) -> Path:
    return workdir / f"batch_{b:06d}.npz"


def _save_batch(workdir: Path, b: int, result: dict[str, Any]) -> None:
    """Write one batch atomically (:func:`cassini_bayes.files.atomic_path`)."""
    with atomic_path(_batch_path(workdir, b)) as tmp, open(tmp, "wb") as f:
        np.savez(f, **{k: result[k] for k in _FIELDS})


def _load_batch(workdir: Path, b: int) -> dict[str, np.ndarray] | None:
    path = _batch_path(workdir, b)
    if not path.exists():
        return None
    try:
        with np.load(path) as z:
            return {k: z[k] for k in _FIELDS}
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, zlib.error) as e:
        # truncated or damaged: the batch is recomputed (same keys, same result)
        warnings.warn(f"{path}: unreadable checkpoint ({type(e).__name__}); recomputing that "
                      "batch", RuntimeWarning, stacklevel=2)
        return None


def load_checkpoints(workdir: str | os.PathLike, n_batches: int) -> dict[int, dict]:
    """The readable batch checkpoints ``0..n_batches−1`` in ``workdir``, by batch index."""
    workdir = Path(workdir)
    out = {}
    for b in range(n_batches):
        res = _load_batch(workdir, b)
        if res is not None:
            out[b] = res
    return out


def _manifest(spec: ModelSpec, model: SbcModel, seed: int, batch_size: int) -> dict[str, Any]:
    scenario_hash = (hashlib.sha256(spec.scenario_text.encode()).hexdigest()
                     if spec.scenario_text else None)
    return {"model": spec.name, "options": {k: v for k, v in spec.options},
            "scenario_sha256": scenario_hash, "seed": int(seed), "batch_size": int(batch_size),
            "parameter_names": list(model.parameter_names), "version": __version__}


def _check_manifest(workdir: Path, manifest: dict[str, Any]) -> None:
    path = workdir / "manifest.json"
    if path.exists():
        try:
            old = json.loads(path.read_text())
        except (OSError, UnicodeDecodeError, json.JSONDecodeError):
            raise InputError(f"{path}: the checkpoint manifest is unreadable; start the "
                             "campaign over with --force") from None
        if old != json.loads(json.dumps(manifest)):
            raise InputError(
                f"{workdir}: holds checkpoints of a different campaign (model, options, scenario, "
                "seed, batch size or version differ); start over with --force or use another --out")
        return
    workdir.mkdir(parents=True, exist_ok=True)
    write_text(path, json.dumps(manifest, indent=2))


# -------------------------------------------------------------------------------- executors


def _local_executor(spec, seed, batch_size, todo: Sequence[int]) -> Iterator[tuple[int, dict]]:
    for b in todo:
        yield b, run_batch(spec, seed, b, batch_size)


@contextlib.contextmanager
def _dask_client(scheduler: str | None, n_workers: int | None, processes: bool,
                 timeout_s: float):
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise InputError("the dask executor needs dask.distributed: "
                         "pip install 'dask[distributed]'") from None
    # set_as_default=False: a client that fails (a malformed or unreachable address) must not
    # stay dask's global scheduler, which later xarray/ArviZ work in the process would use;
    # one that connects is the current client only while the campaign runs
    if scheduler:
        try:
            client = Client(scheduler, timeout=f"{timeout_s}s", set_as_default=False)
        except (OSError, TimeoutError, ValueError) as e:  # unreachable, or a malformed address
            raise InputError(f"cannot reach the Dask scheduler at {scheduler!r} ({e}); check the "
                             "address or omit --scheduler for a local cluster") from None
        try:
            with client.as_current():
                yield client
        finally:
            client.close()
        return
    n = n_workers or max(1, min(2, os.cpu_count() or 1))
    with LocalCluster(n_workers=n, threads_per_worker=1, processes=processes,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        yield client


def _dask_executor(client, spec, seed, batch_size, todo: Sequence[int]):
    from dask.distributed import as_completed

    futures = {client.submit(run_batch, spec, seed, b, batch_size, pure=False): b for b in todo}
    try:
        for fut in as_completed(futures):
            yield futures[fut], fut.result()
    finally:
        for fut in futures:
            fut.cancel()


@jax_entry
def run_campaign(spec: ModelSpec, n_replicates: int, workdir: str | os.PathLike, *,
                 seed: int = 0, batch_size: int = 16, executor: str = "local",
                 scheduler: str | None = None, n_workers: int | None = None,
                 dask_processes: bool = True, scheduler_timeout_s: float = 20.0,
                 on_batch: Callable[[int, int, int], None] | None = None) -> CampaignResult:
    """Run (or resume) an SBC campaign and return its replicates.

    Parameters
    ----------
    spec : ModelSpec
        Which model, scenario and options.
    n_replicates : int
        ``N``.
    workdir : path
        Checkpoint directory; batches already there (of the same campaign) are not recomputed.
    seed : int
        Root seed; replicate ``i`` uses ``fold_in(key(seed), i)``.
    batch_size : int
        ``B``, replicates per vectorised batch.
    executor : {"local", "dask"}
        Where batches run.
    scheduler : str, optional
        Dask scheduler address (``tcp://host:8786``); a ``LocalCluster`` when omitted.
    n_workers : int, optional
        Workers of that local cluster (default ``min(2, cpu_count)``).
    dask_processes : bool
        Local cluster workers as processes (default) or threads of this process.
    scheduler_timeout_s : float
        How long to try to reach ``scheduler`` before giving up, s.
    on_batch : callable, optional
        ``on_batch(batch_index, batches_done, batches_total)`` after each batch is checkpointed;
        an exception raised there stops the campaign (its finished batches stay on disk).

    Returns
    -------
    CampaignResult
    """
    if n_replicates < 1:
        raise InputError(f"--replicates must be at least 1, got {n_replicates}")
    if batch_size < 1:
        raise InputError(f"--batch must be at least 1, got {batch_size}")
    if executor not in EXECUTORS:
        raise InputError(f"unknown executor {executor!r}; use one of {', '.join(EXECUTORS)}")
    if scheduler and executor != "dask":
        raise InputError("--scheduler needs --executor dask")
    workdir = Path(workdir)
    model = build_model(spec)
    _check_manifest(workdir, _manifest(spec, model, seed, batch_size))

    n_batches = math.ceil(n_replicates / batch_size)
    _check_no_batches_beyond(workdir, n_batches, n_replicates, batch_size)
    done = load_checkpoints(workdir, n_batches)
    todo = [b for b in range(n_batches) if b not in done]
    if on_batch is not None and done:
        on_batch(-1, len(done), n_batches)

    with contextlib.ExitStack() as stack:
        if executor == "dask" and todo:
            client = stack.enter_context(_dask_client(scheduler, n_workers, dask_processes,
                                                      scheduler_timeout_s))
            results = _dask_executor(client, spec, seed, batch_size, todo)
        else:
            results = _local_executor(spec, seed, batch_size, todo)
        stack.callback(getattr(results, "close", lambda: None))
        for b, res in results:
            _save_batch(workdir, b, res)
            done[b] = res
            if on_batch is not None:
                on_batch(b, len(done), n_batches)

    cat = {k: np.concatenate([done[b][k] for b in range(n_batches)])[:n_replicates]
           for k in _FIELDS}
    with np.errstate(invalid="ignore"):
        rhat_ok = np.all(np.nan_to_num(cat["rhat"], nan=1.0) <= model.rhat_max, axis=1)
    converged = (cat["n_divergent"] == 0) & rhat_ok & ~cat["failed"]
    return CampaignResult(model.parameter_names, cat["truth"], cat["draws"], cat["rank"],
                          cat["n_divergent"], cat["rhat"], cat["ess"], cat["failed"], converged,
                          int(cat["draws"].shape[-1]), int(seed), int(batch_size), len(todo),
                          dict(model.settings))


def _check_no_batches_beyond(workdir: Path, n_batches: int, n_replicates: int,
                             batch_size: int) -> None:
    """Raise :class:`InputError` when ``workdir`` holds finished batches beyond the first
    ``n_batches``: work a smaller campaign would drop with its work folder."""
    beyond = sorted(int(p.stem.split("_")[1]) for p in workdir.glob("batch_*.npz")
                    if p.stem.split("_")[1].isdigit() and int(p.stem.split("_")[1]) >= n_batches)
    if beyond:
        need = beyond[-1] * batch_size + 1      # the last finished batch then still counts
        raise InputError(f"{workdir}: holds {len(beyond)} finished batch(es) beyond "
                         f"--replicates {n_replicates}; resume with --replicates {need} or more "
                         "to keep them, or start over with --force")
