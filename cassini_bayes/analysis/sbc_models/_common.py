"""Helpers the SBC adapters share: scenario, sampler settings, options, truths, draws (a
private module: its names serve the adapters of this package)."""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import jax
import jax.numpy as jnp

from cassini_bayes.analysis.sbc_models._contract import ModelSpec, SbcFit
from cassini_bayes.errors import InputError

__all__ = ["IDEAL_PULSE_TAU_S", "scenario_of", "sampler_settings", "check_options", "stacked",
           "tiled_truth", "posterior_draws", "quiet", "active_wheels", "nuisance_names",
           "nuisance_scalars", "truth_nuisance_scalars"]

_AXES = ("x", "y", "z")
IDEAL_PULSE_TAU_S = 1e-6
""""No pulse dynamics": every pulse time constant 1 µs, so a pulse's impulse is ``F·width``."""


def scenario_of(spec: ModelSpec, default: Path):
    """The :class:`~cassini_bayes.simulate.scenario.Scenario` of ``spec``: its ``--scenario``
    text, else the model's shipped default scenario file ``default``."""
    from cassini_bayes.simulate.scenario import load_scenario, scenario_from_dict

    if spec.scenario_text:
        return scenario_from_dict(spec.scenario(), src=spec.scenario_source)
    return load_scenario(default)


def sampler_settings(opts: Mapping[str, Any]):
    """The :class:`~cassini_bayes.inference.runner.SamplerSettings` of an adapter's options."""
    from cassini_bayes.inference.runner import SamplerSettings

    return SamplerSettings(chains=int(opts["num_chains"]), warmup=int(opts["num_warmup"]),
                           draws=int(opts["num_draws"]), chain_method="vectorized")


def check_options(model: str, opts: Mapping[str, Any], allowed: set[str]) -> None:
    """Raise naming the options of ``model`` that are not in ``allowed``."""
    unknown = set(opts) - allowed
    if unknown:
        raise InputError(f"unknown {model} SBC option(s) {sorted(unknown)}; allowed: "
                         f"{sorted(allowed)}")


def stacked(trees: list[Any]) -> Any:
    """The pytrees ``trees`` (one per replicate) stacked along a new leading batch axis."""
    return jax.tree.map(lambda *xs: jnp.stack([jnp.asarray(x) for x in xs]), *trees)


def tiled_truth(base, b: int):
    """The scenario's :class:`~cassini_bayes.simulate.run.TruthParams` tiled over a batch."""
    from cassini_bayes.simulate.run import TruthParams

    return TruthParams(*(jnp.broadcast_to(jnp.asarray(x), (b,) + jnp.shape(x)) for x in base))


def posterior_draws(idata, names: tuple[str, ...]) -> SbcFit:
    """The ``(chains, draws)`` posterior draws of ``names`` and the divergence count."""
    draws = {n: jnp.asarray(idata.posterior[n].values) for n in names}
    return SbcFit(draws, jnp.asarray(int(idata.sample_stats["diverging"].values.sum())))


def quiet(fn: Callable) -> Callable:
    """``fn`` with the expected warnings of synthetic replicates (pulses at the span's end,
    prior-dominated thrusters) silenced."""
    import warnings

    @functools.wraps(fn)
    def wrapped(*args, **kwargs):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            return fn(*args, **kwargs)

    return wrapped


def active_wheels(scenario) -> tuple[str, ...]:
    """The wheels the scenario runs, in its order (the robust model's nuisance wheels)."""
    return tuple(scenario.prior.wheel(n).name
                 for n, on in zip(scenario.wheel_names, scenario.wheels_on) if on)


def nuisance_names(wheels: tuple[str, ...]) -> tuple[str, ...]:
    """The robust models' ranked nuisance scalars: gyro scale factor and bias per axis (one
    file) and each active wheel's spin-inertia scale ``c_k``."""
    return (tuple(f"gyro_scale[{a}]" for a in _AXES) + tuple(f"gyro_bias[{a}]" for a in _AXES)
            + tuple(f"wheel_scale[{w}]" for w in wheels))


def nuisance_scalars(sites: Mapping[str, Any], wheels: tuple[str, ...]) -> dict[str, Any]:
    """:func:`nuisance_names` from the sites ``gyro_scale`` (..., 3), ``gyro_bias``
    (..., 1, 3) and ``wheel_scale`` (..., K) of one file's draws or prior draws."""
    out = {f"gyro_scale[{a}]": sites["gyro_scale"][..., i] for i, a in enumerate(_AXES)}
    out.update({f"gyro_bias[{a}]": sites["gyro_bias"][..., 0, i] for i, a in enumerate(_AXES)})
    out.update({f"wheel_scale[{w}]": sites["wheel_scale"][..., k] for k, w in enumerate(wheels)})
    return out


def truth_nuisance_scalars(d: Mapping[str, Any], wheels: tuple[str, ...]) -> dict[str, Any]:
    """:func:`nuisance_scalars` of one drawn truth (its ``gyro_bias`` of the one file, (3,))."""
    return nuisance_scalars({"gyro_scale": d["gyro_scale"], "gyro_bias": d["gyro_bias"][None],
                             "wheel_scale": d["wheel_scale"]}, wheels)

