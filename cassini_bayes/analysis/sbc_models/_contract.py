"""The SBC adapter contract (:class:`SbcModel`, :class:`SbcFit`), its plain-data recipe
(:class:`ModelSpec`) and the registry of adapter factories."""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import jax

from cassini_bayes.errors import InputError

__all__ = ["SbcFit", "SbcModel", "ModelSpec", "register", "registered_models", "build_model"]


class SbcFit(NamedTuple):
    """Posterior draws of one replicate.

    Attributes
    ----------
    draws : dict of str to jax.Array
        ``name -> (chains, draws)`` post-warm-up posterior draws (not thinned), in the units of
        ``prior_sample``.
    n_divergent : jax.Array
        Number of divergent transitions after warm-up (all chains), integer scalar.
    """

    draws: dict[str, jax.Array]
    n_divergent: jax.Array


@dataclass(frozen=True)
class SbcModel:
    """A model as SBC sees it (the contract of :mod:`cassini_bayes.analysis.sbc_models`).

    Attributes
    ----------
    name : str
        Registry name (``toy``, ``inertia``, …).
    parameter_names : tuple of str
        Scalar parameters to rank, in order.
    prior_sample : callable
        ``(key) -> {name: scalar}``.
    simulate : callable or None
        ``(key, params) -> data``; ``None`` for a model that gives ``simulate_batch``.
    fit : callable
        ``(key, data) -> SbcFit``; with ``prepare``, ``data`` is what ``prepare`` returns.
    vectorized : bool
        Whether ``fit`` is pure JAX and is vmapped over replicates (and, without
        ``simulate_batch``, ``prior_sample`` and ``simulate`` too).
    settings : dict
        Sampler and scenario settings recorded in the run's ``summary.json``/``config.toml``.
    rhat_max : float
        A replicate with a split R-hat above this (any parameter, thinned draws) or any
        divergence counts as not converged. Its rank is kept (dropping replicates would bias SBC).
    simulate_batch : callable, optional
        ``(prior_keys (B,), sim_keys (B,)) -> ({name: (B,)}, batched data)``: a model whose prior
        sampler is not traceable (e.g. rejection sampling in NumPy) draws its truths here and
        calls the simulator's own vmapped batch. Default: ``jax.vmap`` of ``prior_sample`` and
        ``simulate``. Either way replicate ``i``'s truth and data depend on its keys only.
    prepare : callable, optional
        ``(data of one replicate, NumPy) -> fit data`` (a pytree of arrays of the same shapes for
        every replicate), run replicate by replicate before a vectorised ``fit``; an exception
        there marks that replicate failed.
    """

    name: str
    parameter_names: tuple[str, ...]
    prior_sample: Callable[[jax.Array], dict[str, jax.Array]]
    simulate: Callable[[jax.Array, dict[str, jax.Array]], Any] | None
    fit: Callable[[jax.Array, Any], SbcFit]
    vectorized: bool = True
    settings: Mapping[str, Any] = field(default_factory=dict)
    rhat_max: float = 1.05
    simulate_batch: Callable[[jax.Array, jax.Array], tuple[dict[str, Any], Any]] | None = None
    prepare: Callable[[Any], Any] | None = None

    def __post_init__(self) -> None:
        if self.simulate is None and self.simulate_batch is None:
            raise ValueError(f"SBC model {self.name!r} gives neither simulate nor simulate_batch")


@dataclass(frozen=True)
class ModelSpec:
    """Plain-data recipe for an adapter: picklable, hashable, the same on every Dask worker.

    Attributes
    ----------
    name : str
        Registered model name.
    scenario_text : str or None
        Contents of the ``--scenario`` TOML file (not its path: workers may not share files).
    options : tuple of (str, value) pairs
        Extra settings (sampler sizes, mis-specification switches), sorted by name.
    scenario_source : str
        Where the scenario text came from (its file name), for error messages only.
    """

    name: str
    scenario_text: str | None = None
    options: tuple[tuple[str, Any], ...] = ()
    scenario_source: str = "<scenario>"

    @classmethod
    def make(cls, name: str, scenario_text: str | None = None, *,
             scenario_source: str = "<scenario>", **options: Any) -> ModelSpec:
        """Build a spec with options given as keywords."""
        return cls(name, scenario_text, tuple(sorted(options.items())), scenario_source)

    def scenario(self) -> dict[str, Any]:
        """The scenario TOML parsed into a dict (empty without one)."""
        from cassini_bayes._toml import parse_toml

        if not self.scenario_text:
            return {}
        return parse_toml(self.scenario_text, self.scenario_source)


_REGISTRY: dict[str, Callable[[ModelSpec], SbcModel]] = {}


def register(name: str):
    """Decorator registering an adapter factory ``(ModelSpec) -> SbcModel`` under ``name``."""

    def deco(factory):
        _REGISTRY[name] = factory
        return factory

    return deco


def registered_models() -> tuple[str, ...]:
    """Names of the registered models, sorted."""
    return tuple(sorted(_REGISTRY))


@functools.lru_cache(maxsize=16)
def build_model(spec: ModelSpec) -> SbcModel:
    """The adapter for ``spec``; cached, so repeated batches reuse the same compiled functions."""
    if spec.name not in _REGISTRY:
        raise InputError(f"unknown SBC model {spec.name!r}; choose one of "
                         f"{', '.join(registered_models())}")
    return _REGISTRY[spec.name](spec)
