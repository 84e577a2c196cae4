"""Reading a run directory (docs/design.md §4.4) for the report: ``posterior.nc``, ``summary.json``,
``config.toml`` (the JSON and TOML files through :func:`cassini_bayes.rundir.read_run_file`, the
reader of every run directory).

``posterior.nc`` is read with h5py straight into NumPy arrays (:class:`Group`, :class:`Var`):
ArviZ and xarray are not imported to read it, which keeps ``cassini-bayes report DIR`` under a
second and a half of CPU (docs/performance.md). The report's numbers are the fit's own where
``summary.json`` has them, and ArviZ is imported only for what it lacks
(:func:`cassini_bayes.report.tables.diagnostics`).

Only ``posterior.nc`` is required. A missing ``summary.json`` costs the baseline/truth columns (the
kind is then recognised from the posterior's variable names); a missing ``config.toml`` costs the
configuration listing. Anything present but unreadable is an
:class:`~cassini_bayes.errors.InputError`, and so are files that belong to different runs
(:func:`_check_same_run`: a page must never put one run's title and numbers over another's draws).
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from cassini_bayes.errors import InputError
from cassini_bayes.names import F_NAMES, INERTIA_NAMES, TAU_NAMES, U4_NAMES, a_kind
from cassini_bayes.rundir import read_run_file, run_command

__all__ = ["Var", "Group", "RunData", "load_run", "read_groups", "flatten_draws",
           "KINDS"]

KINDS = ("inertia", "thrust", "rwa4")
_FIT_COMMANDS = {f"fit {k}": k for k in KINDS}


class Var:
    """One netCDF variable: ``values`` (NumPy), ``dims`` (names) and ``attrs``."""

    __slots__ = ("values", "dims", "attrs")

    def __init__(self, values: np.ndarray, dims: tuple[str, ...], attrs: dict):
        self.values, self.dims, self.attrs = values, tuple(dims), dict(attrs)

    @property
    def sizes(self) -> dict[str, int]:
        """Length of each dimension."""
        return dict(zip(self.dims, self.values.shape))


@dataclass(frozen=True)
class Group:
    """One group of ``posterior.nc`` (``posterior``, ``prior``, ``sample_stats``, …).

    Attributes
    ----------
    vars : data variables by name (coordinates excluded), in file order.
    coords : coordinate variables by name: a dimension's labels, or a coordinate along another
        dimension (the ``file`` or ``event`` of each residual sample).
    """

    vars: dict[str, Var]
    coords: dict[str, Var] = field(default_factory=dict)

    def __contains__(self, name: str) -> bool:
        return name in self.vars

    def __getitem__(self, name: str) -> Var:
        return self.vars[name]

    @property
    def sizes(self) -> dict[str, int]:
        """Length of every dimension of the group."""
        out: dict[str, int] = {}
        for v in (*self.vars.values(), *self.coords.values()):
            out.update(v.sizes)
        return out

    def labels(self, dim: str) -> list:
        """The labels along ``dim`` (its coordinate values, else ``0 … n−1``)."""
        c = self.coords.get(dim)
        if c is not None and c.dims == (dim,):
            return c.values.tolist()
        return list(range(self.sizes.get(dim, 0)))


def _decode(values: np.ndarray, attrs: dict) -> np.ndarray:
    """NumPy array of a variable as xarray would decode it: strings as ``str``, booleans back
    from their int8 storage (``dtype = "bool"``), fill values as NaN."""
    if values.dtype == object or values.dtype.kind == "S":
        return np.array([x.decode() if isinstance(x, bytes) else str(x)
                         for x in values.ravel()], dtype=object).reshape(values.shape)
    if attrs.get("dtype") == "bool":
        return values.astype(bool)
    fill = attrs.get("_FillValue")
    if values.dtype.kind == "f" and fill is not None:
        fill = np.asarray(fill).ravel()
        if fill.size == 1 and np.isfinite(fill[0]):
            values = np.where(values == fill[0], np.nan, values)
    return values


_SKIP_ATTRS = ("_FillValue", "_Netcdf4Dimid", "_Netcdf4Coordinates", "DIMENSION_LIST",
               "REFERENCE_LIST", "CLASS", "NAME", "coordinates", "dtype")
_PHONY = b"This is a netCDF dimension but not a netCDF variable"


def read_groups(path: Path, skip: tuple[str, ...] = ("observed_data",)) -> dict[str, Group]:
    """The groups of a netCDF-4 InferenceData file (ArviZ's layout) as :class:`Group` objects.

    Read with h5py: each variable's dimensions are the HDF5 dimension scales its
    ``DIMENSION_LIST`` names (netCDF-4's own encoding); a dimension without a coordinate
    variable (a netCDF "phony" scale) has no labels. ``skip`` names groups not read (the report
    does not show the observed data). A third of h5netcdf's time for the same arrays.
    """
    import h5py

    out: dict[str, Group] = {}
    with h5py.File(path, "r") as f:
        for gname, grp in f.items():
            if not isinstance(grp, h5py.Group) or gname in skip:
                continue
            raw = {}
            for name, ds in grp.items():
                if not isinstance(ds, h5py.Dataset):
                    continue
                attrs = dict(ds.attrs)
                if "DIMENSION_LIST" in attrs:
                    dims = tuple(f[refs[0]].name.rsplit("/", 1)[-1]
                                 for refs in attrs["DIMENSION_LIST"])
                elif attrs.get("CLASS") == b"DIMENSION_SCALE":
                    if bytes(attrs.get("NAME", b"")).startswith(_PHONY):
                        continue                  # a bare dimension, no labels
                    dims = (name,)
                else:
                    dims = ()
                raw[name] = (dims, ds[()], attrs)
            dim_names = {d for dd, _, _ in raw.values() for d in dd}
            listed = set()
            for _, _, a in raw.values():
                c = a.get("coordinates", "")
                listed.update((c.decode() if isinstance(c, bytes) else str(c)).split())
            coords, data = {}, {}
            for n, (dd, values, attrs) in raw.items():
                clean = {k: (v.decode() if isinstance(v, bytes) else v)
                         for k, v in attrs.items() if k not in _SKIP_ATTRS}
                var = Var(_decode(np.asarray(values), attrs), dd, clean)
                (coords if (n in dim_names and dd == (n,)) or n in listed else data)[n] = var
            out[gname] = Group(data, coords)
    return out


@dataclass(frozen=True)
class RunData:
    """Everything the report reads from one run directory.

    Attributes
    ----------
    run_dir : Path
        The directory (resolved).
    groups : dict of Group
        ``posterior.nc``'s groups (``posterior``, ``prior``, ``sample_stats``,
        ``constant_data``, ``residuals``, …), read eagerly (the file is closed).
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
    groups: dict
    summary: dict = field(default_factory=dict)
    config_text: str | None = None
    kind: str = "unknown"
    notes: tuple[str, ...] = ()

    def has_group(self, name: str) -> bool:
        """Whether ``posterior.nc`` has group ``name`` with at least one variable."""
        g = self.groups.get(name)
        return g is not None and len(g.vars) > 0

    @property
    def posterior(self) -> Group:
        """The ``posterior`` group."""
        return self.groups["posterior"]

    @property
    def config(self) -> dict:
        """``config.toml`` parsed (empty when absent or unreadable)."""
        if not self.config_text:
            return {}
        try:
            return tomllib.loads(self.config_text)
        except tomllib.TOMLDecodeError:
            return {}


def _infer_kind(names: set[str]) -> str:
    # most specific first: an RWA4 or thrust fit may carry the inertia entries as nuisances
    if set(U4_NAMES) <= names:
        return "rwa4"
    if names & set(TAU_NAMES) or names & set(F_NAMES):
        return "thrust"
    if set(INERTIA_NAMES) <= names:
        return "inertia"
    return "unknown"


def _check_same_run(run_dir: Path, posterior: Group, summary: dict, config: dict | None) -> None:
    """Refuse, naming the file, a run directory whose files come from different runs (one copied
    over from another run): the kind ``summary.json`` records against the draws in
    ``posterior.nc`` (their variable names) and against the command in ``config.toml``; the
    parameters ``summary.json`` reports must all be in ``posterior.nc``; and the chains and
    draws ``config.toml``'s ``[sampler]`` asked for must be the posterior's."""
    nc, sj, ct = run_dir / "posterior.nc", run_dir / "summary.json", run_dir / "config.toml"
    redo = "the run directory's files come from different runs: re-run the fit"
    names = set(posterior.vars)
    drawn = _infer_kind(names)
    said = summary.get("kind")
    if said in KINDS and drawn in KINDS and said != drawn:
        raise InputError(f"{nc}: holds the draws of {a_kind(drawn)} fit, but {sj.name} is "
                         f"{a_kind(said)} fit's; {redo}")
    reported = [n for n in (summary.get("parameters") or {}) if n.split("[")[0] not in names]
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
    sizes = posterior.sizes
    for dim, key in (("chain", "chains"), ("draw", "draws")):
        asked, got = sampler.get(key), sizes.get(dim)
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
    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise InputError(f"{run_dir}: run directory not found; pass the --out directory of a fit")
    nc = run_dir / "posterior.nc"
    if not nc.is_file():
        command = run_command(run_dir)
        if command is not None and command not in ("fit inertia", "fit thrust", "fit rwa4",
                                                   "fit wheel-axis"):
            raise InputError(f"{run_dir}: a `{command}` run; `report` rebuilds the page of a "
                             "`fit inertia`, `fit thrust`, `fit wheel-axis` or `fit rwa4` run (run "
                             f"`{command}` again for its own files)")
        raise InputError(
            f"{nc}: not found; a run directory must hold posterior.nc (run `cassini-bayes fit ...` "
            "or pass the right directory)"
        )
    try:
        groups = read_groups(nc)
    except Exception as e:  # netCDF/HDF5 errors have many types
        raise InputError(f"{nc}: cannot be read as ArviZ InferenceData ({type(e).__name__}: {e})")
    if "posterior" not in groups or not groups["posterior"].vars:
        raise InputError(f"{nc}: has no posterior group; re-run the fit that wrote it")

    notes: list[str] = []
    summary = read_run_file(run_dir, "summary.json", strict=True)
    if summary is None:
        summary = {}
        notes.append("summary.json not found: baseline and truth columns are empty")

    config_text, config = None, None
    ct = run_dir / "config.toml"
    if ct.is_file():
        config_text = ct.read_text(encoding="utf-8", errors="replace")
        config = read_run_file(run_dir, "config.toml")
        if config is None:
            notes.append("config.toml is not valid TOML")

    _check_same_run(run_dir, groups["posterior"], summary, config)
    kind = summary.get("kind") or _infer_kind(set(groups["posterior"].vars))
    if kind not in KINDS:
        notes.append(f"unknown run kind {kind!r}: kind-specific sections are skipped")
    return RunData(run_dir.resolve(), groups, summary, config_text, str(kind), tuple(notes))


def _component_label(name: str, labels: tuple) -> str:
    """A scalar component's label as ``summary.json`` writes it: ``"F"``, ``"H0[0,x]"``."""
    return f"{name}[{','.join(str(x) for x in labels)}]" if labels else name


def flatten_draws(group: Group | None, names) -> dict[str, np.ndarray]:
    """Flatten variables of a (chain, draw, ...) group into scalar components.

    Parameters
    ----------
    group : Group or None
        A posterior or prior group (``None``: no draws).
    names : iterable of str
        Variables to take; names not in ``group`` are skipped.

    Returns
    -------
    dict
        ``label -> array (chain, draw)``; labels as ``summary.json``'s (:func:`_component_label`).
    """
    out: dict[str, np.ndarray] = {}
    if group is None:
        return out
    for name in names:
        if name not in group.vars:
            continue
        var = group[name]
        if var.dims[:2] != ("chain", "draw"):
            continue
        vals = np.asarray(var.values, dtype=float)
        extra = var.dims[2:]
        if not extra:
            out[name] = vals
            continue
        labels = [group.labels(d) for d in extra]
        for idx in np.ndindex(*vals.shape[2:]):
            lab = tuple(labels[k][i] for k, i in enumerate(idx))
            out[_component_label(name, lab)] = vals[(slice(None), slice(None)) + idx]
    return out
