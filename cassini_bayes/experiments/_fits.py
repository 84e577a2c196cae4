"""Helpers shared by the fit-based experiments (``inertia_table1``, ``thrust_table2``, the RWA4
campaigns): the key of each fit, the sampler settings, posterior draws, and a fit's run directory
written with the library's run writer and summary builders (:mod:`cassini_bayes.api`), so it has
the files and ``summary.json`` keys of ``cassini-bayes fit``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import jax
import numpy as np

from cassini_bayes import __version__


def fit_seed(key: jax.Array) -> tuple[int, jax.Array]:
    """An integer seed drawn from ``key`` and the key ``jax.random.key(seed)`` made from it.

    A sub-run's ``summary.json``/``config.toml`` record the integer, so the fit can be repeated
    with ``cassini-bayes fit … --seed N`` on the sub-run's telemetry.
    """
    seed = int(jax.random.randint(key, (), 0, 2**31 - 1))
    return seed, jax.random.key(seed)


def sampler(settings: Mapping[str, Any]):
    """:class:`~cassini_bayes.inference.runner.SamplerSettings` from ``chains/warmup/draws``."""
    from cassini_bayes.inference.runner import SamplerSettings

    return SamplerSettings(chains=int(settings["chains"]), warmup=int(settings["warmup"]),
                           draws=int(settings["draws"]))


def check_sampler_settings(settings: Mapping[str, Any], ctx) -> None:
    """``InputError`` naming the experiment file for impossible sampler sizes."""
    for k, lo in (("chains", 1), ("warmup", 10), ("draws", 10)):
        if settings[k] < lo:
            raise ctx.error(f"'settings.{k}' must be at least {lo}")


def write_fit_run(path: Path, *, posterior, summary: Mapping[str, Any],
                  config: Mapping[str, Any], telemetry=None, pulses=None) -> dict:
    """Write one fit's run directory at ``path`` inside an experiment's (already temporary)
    directory with the library's run writer (:func:`cassini_bayes.api.write_run_files`: the
    files and ``summary.json`` keys of ``cassini-bayes fit``), plus the simulated
    ``telemetry.csv``/``pulses.csv`` it was fitted to; returns the summary.

    ``summary`` comes from the model's summary builder (:func:`cassini_bayes.api.
    inertia_summary`, ``thrust_summary``, ``rwa4_summary``); ``config`` is completed with the
    package version, the seed and the input files.
    """
    from cassini_bayes.api import write_run_files
    from cassini_bayes.telemetry import write_pulses, write_telemetry

    path.mkdir(parents=True, exist_ok=True)
    inputs = {}
    if telemetry is not None:
        write_telemetry(path / "telemetry.csv", telemetry, force=True)
        inputs["telemetry"] = [_relative_record(path, "telemetry.csv")]
    if pulses is not None:
        write_pulses(path / "pulses.csv", pulses, force=True)
        inputs["pulses"] = _relative_record(path, "pulses.csv")
    write_run_files(path, idata=posterior.idata, summary=summary,
                    config={"version": __version__, "seed": summary["seed"], "inputs": inputs,
                            **config})
    return dict(summary)


def _relative_record(run_dir: Path, name: str) -> dict[str, str]:
    """``{"path": name, "sha256": …}``: the input file inside the run directory, by relative path
    (the experiment directory is renamed into place after writing)."""
    from cassini_bayes.rundir import file_record

    return {"path": name, "sha256": file_record(run_dir / name)["sha256"]}


def posterior_draws(idata, names: Sequence[str]) -> np.ndarray:
    """(n_draws, len(names)) posterior draws, chains stacked."""
    post = idata.posterior
    return np.stack([np.asarray(post[n].values).reshape(-1) for n in names], -1)
