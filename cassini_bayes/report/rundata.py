"""Reading a run directory (docs/design.md §4.4) for the report: ``posterior.nc``, ``summary.json``,
``config.toml``.

Only ``posterior.nc`` is required. A missing ``summary.json`` costs the baseline/truth columns (the
kind is then recognised from the posterior's variable names); a missing ``config.toml`` costs the
configuration listing. Anything present but unreadable is an
:class:`~cassini_bayes.errors.InputError`, and so are files that belong to different runs
(:func:`check_same_run`: a page must never put one run's title and numbers over another's draws).
"""

from __future__ import annotations

import json
import math
import tomllib
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from cassini_bayes.errors import InputError
from cassini_bayes.names import F_NAMES, INERTIA_NAMES, TAU_NAMES, U4_NAMES, a_kind

__all__ = ["RunData", "load_run", "flatten_draws", "KINDS", "check_same_run"]

KINDS = ("inertia", "thrust", "rwa4")
_FIT_COMMANDS = {f"fit {k}": k for k in KINDS}


@dataclass(frozen=True)
class RunData:
    """Everything the report reads from one run directory.

    Attributes
    ----------
    run_dir : Path
        The directory (resolved).
    idata : arviz.InferenceData
        ``posterior.nc``, loaded eagerly (the file is closed).
    summary : dict
        ``summary.json`` (empty when absent).
    config_text : str or None
        ``config.toml`` verbatim, or ``None`` when absent.
    kind : str
        ``"inertia"``, ``"thrust"`` or ``"rwa4"`` (from the summary, else from variable names),
        or ``"unknown"``.
    notes : tuple of str
        What was missing, for the report's warnings.
    """

    run_dir: Path
    idata: Any
    summary: dict = field(default_factory=dict)
    config_text: str | None = None
    kind: str = "unknown"
    notes: tuple[str, ...] = ()

    def has_group(self, name: str) -> bool:
        """Whether the InferenceData has group ``name`` with at least one variable."""
        return name in self.idata.groups() and len(getattr(self.idata, name).data_vars) > 0


def _infer_kind(names: set[str]) -> str:
    # most specific first: an RWA4 or thrust fit may carry the inertia entries as nuisances
    if set(U4_NAMES) <= names:
        return "rwa4"
    if names & set(TAU_NAMES) or names & set(F_NAMES):
        return "thrust"
    if set(INERTIA_NAMES) <= names:
        return "inertia"
    return "unknown"


def check_same_run(run_dir: Path, idata, summary: dict, config: dict | None) -> None:
    """Refuse, naming the file, a run directory whose files come from different runs (one copied
    over from another run): the kind ``summary.json`` records against the draws in
    ``posterior.nc`` (their variable names) and against the command in ``config.toml``; the
    parameters ``summary.json`` reports must all be in ``posterior.nc``; and the chains and
    draws ``config.toml``'s ``[sampler]`` asked for must be the posterior's."""
    nc, sj, ct = run_dir / "posterior.nc", run_dir / "summary.json", run_dir / "config.toml"
    redo = "the run directory's files come from different runs: re-run the fit"
    names = set(idata.posterior.data_vars)
    drawn = _infer_kind(names)
    said = summary.get("kind")
    if said in KINDS and drawn in KINDS and said != drawn:
        raise InputError(f"{nc}: holds the draws of {a_kind(drawn)} fit, but {sj.name} is "
                         f"{a_kind(said)} fit's; {redo}")
    reported = [n for n in (summary.get("parameters") or {}) if n not in names]
    if reported:
        raise InputError(f"{nc}: has no draws of {', '.join(reported[:3])}, which {sj.name} "
                         f"reports; {redo}")
    if not config:
        return
    commanded = _FIT_COMMANDS.get(config.get("command"))
    kind = said if said in KINDS else drawn
    if commanded is not None and kind in KINDS and commanded != kind:
        raise InputError(f"{ct}: written by 'cassini-bayes {config['command']}', but the run is "
                         f"{a_kind(kind)} fit ({sj.name if said in KINDS else nc.name}); "
                         f"{redo}")
    sampler = config.get("sampler") if isinstance(config.get("sampler"), dict) else {}
    for dim, key in (("chain", "chains"), ("draw", "draws")):
        asked, got = sampler.get(key), idata.posterior.sizes.get(dim)
        if isinstance(asked, int) and not isinstance(asked, bool) and got is not None \
                and asked != got:
            raise InputError(f"{nc}: holds {got} {dim}(s), but {ct.name} asked for "
                             f"{key} = {asked}; {redo}")


def load_run(run_dir: str | Path) -> RunData:
    """Load a run directory for reporting.

    Parameters
    ----------
    run_dir : str or Path
        A directory written by ``fit``/``experiment``/``sbc``.

    Raises
    ------
    InputError
        The directory or its ``posterior.nc`` does not exist, or a file cannot be read.
    """
    import arviz as az

    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise InputError(f"{run_dir}: run directory not found; pass the --out directory of a fit")
    nc = run_dir / "posterior.nc"
    if not nc.is_file():
        from cassini_bayes.run_kind import run_command

        command = run_command(run_dir)
        if command is not None and command not in ("fit inertia", "fit thrust", "fit rwa4"):
            raise InputError(f"{run_dir}: a `{command}` run; `report` rebuilds the page of a "
                             "`fit inertia`, `fit thrust` or `fit rwa4` run (run "
                             f"`{command}` again for its own files)")
        raise InputError(
            f"{nc}: not found; a run directory must hold posterior.nc (run `cassini-bayes fit ...` "
            "or pass the right directory)"
        )
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with az.rc_context({"data.load": "eager"}):
                idata = az.from_netcdf(nc)
    except Exception as e:  # netCDF/HDF5 errors have many types
        raise InputError(f"{nc}: cannot be read as ArviZ InferenceData ({type(e).__name__}: {e})")
    if "posterior" not in idata.groups() or not idata.posterior.data_vars:
        raise InputError(f"{nc}: has no posterior group; re-run the fit that wrote it")

    notes: list[str] = []
    summary: dict = {}
    sj = run_dir / "summary.json"
    if sj.is_file():
        try:
            summary = json.loads(sj.read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError) as e:
            raise InputError(f"{sj}: not valid JSON ({e}); re-run the fit or fix the file")
        if not isinstance(summary, dict):
            raise InputError(f"{sj}: expected a JSON object at the top level")
    else:
        notes.append("summary.json not found: baseline and truth columns are empty")

    config_text, config = None, None
    ct = run_dir / "config.toml"
    if ct.is_file():
        config_text = ct.read_text(encoding="utf-8", errors="replace")
        try:
            config = tomllib.loads(config_text)
        except tomllib.TOMLDecodeError as e:
            notes.append(f"config.toml is not valid TOML ({e})")

    check_same_run(run_dir, idata, summary, config)
    kind = summary.get("kind") or _infer_kind(set(idata.posterior.data_vars))
    if kind not in KINDS:
        notes.append(f"unknown run kind {kind!r}: kind-specific sections are skipped")
    return RunData(run_dir.resolve(), idata, summary, config_text, str(kind), tuple(notes))


def flatten_draws(ds, names) -> dict[str, np.ndarray]:
    """Flatten variables of a (chain, draw, ...) dataset into scalar components.

    Parameters
    ----------
    ds : xarray.Dataset
        A posterior or prior group.
    names : iterable of str
        Variables to take; names not in ``ds`` are skipped.

    Returns
    -------
    dict
        ``label -> array (chain, draw)``; labels follow ArviZ: ``"F"`` for a scalar, ``"F[Z1]"``
        for a component (coordinate values joined by ``", "``).
    """
    out: dict[str, np.ndarray] = {}
    for name in names:
        if name not in ds.data_vars:
            continue
        da = ds[name]
        if "chain" not in da.dims or "draw" not in da.dims:
            continue
        da = da.transpose("chain", "draw", ...)
        extra = [d for d in da.dims if d not in ("chain", "draw")]
        vals = np.asarray(da.values, dtype=float)
        if not extra:
            out[name] = vals
            continue
        coords = [list(da.coords[d].values) if d in da.coords else list(range(da.sizes[d]))
                  for d in extra]
        for idx in np.ndindex(*[da.sizes[d] for d in extra]):
            label = ", ".join(str(coords[k][i]) for k, i in enumerate(idx))
            out[f"{name}[{label}]"] = vals[(slice(None), slice(None)) + idx]
    return out


def finite_or_none(x: Any) -> float | None:
    """``float(x)`` when it is a finite number, else ``None`` (JSON nulls, NaN, strings)."""
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None
