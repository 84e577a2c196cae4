"""``cassini-bayes fit rwa4 ...`` (docs/design.md §5): Cassini's RWA4 spin axis, the name of
``fit wheel-axis --wheel RWA4`` (:mod:`.fit_wheel_axis`, the same options but ``--wheel``, the
same numbers).
"""

from __future__ import annotations

from pathlib import Path

import typer

from cassini_bayes.cli.fit import CHAINS, DRAWS, FORCE, OUT, SEED, STRICT, WARMUP, WHEEL_ERRORS
from cassini_bayes.cli.fit_wheel_axis import (IDEALISED, INERTIA_POSTERIOR, METHOD, PRIOR,
                                              SPACECRAFT, TARGET_ACCEPT, WINDOW_A, WINDOW_B,
                                              run_axis_fit)

ORDER = 22

TELEMETRY = typer.Option(..., "--telemetry", help="Calibration telemetry CSV.")


def fit_rwa4_cmd(
    method: str = METHOD,
    telemetry: Path = TELEMETRY,
    spacecraft: str = SPACECRAFT,
    out: Path = OUT,
    window_a: list[str] = WINDOW_A,
    window_b: list[str] = WINDOW_B,
    prior: str = PRIOR,
    inertia_posterior: Path = INERTIA_POSTERIOR,
    idealised: bool = IDEALISED,
    wheel_errors: str = WHEEL_ERRORS,
    seed: int = SEED,
    chains: int = CHAINS,
    warmup: int = WARMUP,
    draws: int = DRAWS,
    target_accept: float = TARGET_ACCEPT,
    strict: bool = STRICT,
    force: bool = FORCE,
) -> None:
    """Posterior of the RWA4 spin axis (fit wheel-axis --wheel RWA4), inertia sampled jointly."""
    run_axis_fit(wheel="RWA4", telemetry=telemetry, spacecraft=spacecraft, method=method,
                 out=out, window_a=window_a, window_b=window_b, prior=prior,
                 inertia_posterior=inertia_posterior, idealised=idealised,
                 wheel_errors=wheel_errors, seed=seed, chains=chains, warmup=warmup, draws=draws,
                 target_accept=target_accept, strict=strict, force=force, rwa4=True)


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    """Add ``fit rwa4`` to the ``fit`` group."""
    groups["fit"].command("rwa4")(fit_rwa4_cmd)
