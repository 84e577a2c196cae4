"""What every fit returns (:class:`FitResult`) and how a fit's run directory is written.

One writer for every run directory of a fit: ``cassini-bayes fit …`` (through
:meth:`FitResult.save`) and the experiments' per-fit sub-runs (:func:`write_run_files`) write the
same four files, ``posterior.nc``, ``summary.json``, ``config.toml`` and ``report.html``
(docs/cli.md, "Run directory").
"""

from __future__ import annotations

import copy
import os
import warnings
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from cassini_bayes import __version__, _jax_cache

if TYPE_CHECKING:
    from arviz import InferenceData

    from cassini_bayes.diagnostics import Diagnostics
    from cassini_bayes.inference.runner import SamplerSettings
    from cassini_bayes.spacecraft import Spacecraft

__all__ = ["FitResult", "fit_config", "collect_warnings", "write_run", "write_run_files"]


@contextmanager
def collect_warnings() -> Iterator[list[str]]:
    """Record ``warnings.warn`` messages raised inside the block as one-line strings (not shown);
    deprecation warnings are dropped, repeats kept once."""
    lines: list[str] = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        yield lines
    for w in caught:
        if issubclass(w.category, (DeprecationWarning, FutureWarning)):
            continue
        msg = " ".join(str(w.message).split())
        if msg not in lines:
            lines.append(msg)


def fit_config(command: str, *, seed: int, spacecraft: Spacecraft, settings: SamplerSettings,
               inputs: Mapping,
               options: Mapping) -> dict:
    """``config.toml`` of a fit: the resolved inputs, options, sampler settings, spacecraft model,
    seed and package version, enough to re-run it (docs/cli.md, "Run directory"). ``[sampler]``
    records the chain method asked for (``"auto"``) and the one used with the CPU devices the
    process had: parallel and vectorized chains agree only to the last bits."""
    import jax

    from cassini_bayes.inference.runner import choose_chain_method

    used = settings.chain_method or choose_chain_method(settings.chains)
    return {
        "command": command,
        "version": __version__,
        "seed": seed,
        "inputs": dict(inputs),
        "options": dict(options),
        "sampler": settings._asdict() | {"chain_method": settings.chain_method or "auto",
                                          "chain_method_used": used,
                                          "cpu_devices": jax.local_device_count(),
                                          "progress": False},
        "spacecraft": spacecraft.to_dict(),
        "jax_cache": _jax_cache.stats().to_dict(),  # did this fit load compiled programs?
    }


def write_run_files(run_dir: Path, *, idata: InferenceData, summary: Mapping, config: Mapping,
                    display_dir: Path | None = None) -> list[str]:
    """Write a fit's four files into the existing directory ``run_dir`` (not atomically: the
    caller's directory is the temporary one); returns the report's warnings (one line each).

    ``display_dir`` is the directory the report names (the final one when ``run_dir`` is a
    temporary sibling).
    """
    from cassini_bayes.report import write_report
    from cassini_bayes.rundir import write_config, write_posterior, write_summary

    write_posterior(run_dir, idata)
    write_summary(run_dir, summary)
    write_config(run_dir, config)
    with collect_warnings() as report_warnings:
        write_report(run_dir, display_dir=display_dir, summary=summary)
    return report_warnings


def write_run(out: str | os.PathLike, *, idata: InferenceData, summary: Mapping, config: Mapping,
              force: bool = False, inputs: Iterable[str | os.PathLike] = ()
              ) -> tuple[Path, list[str]]:
    """Write a fit's run directory ``out`` atomically (:class:`cassini_bayes.rundir.RunDir`);
    returns the final directory and the report's warnings.

    ``force`` replaces an existing ``out`` only when this package wrote it; ``out`` may never hold
    one of ``inputs`` (the run's input files).
    """
    from cassini_bayes.rundir import RunDir

    with RunDir(out, force=force, inputs=inputs) as rd:
        report_warnings = write_run_files(rd.path, idata=idata, summary=summary, config=config,
                                          display_dir=rd.final)
    return rd.final, report_warnings


@dataclass(frozen=True)
class FitResult:
    """A fitted posterior with everything ``cassini-bayes fit`` writes about it.

    Attributes
    ----------
    kind : ``"inertia"``, ``"thrust"`` or ``"rwa4"``.
    posterior : the inference module's result (``InertiaPosterior``, ``ThrustPosterior`` or
        ``Rwa4Posterior``): ``idata``, ``diagnostics``, the prepared ``problem``.
    baseline : the papers' least-squares estimate on the same data, by parameter name (SI units:
        kg m², N, s, unit-vector components), or ``None`` when it could not be computed.
    sensitivity : how far each sensor/actuator error of prior size would move the answer if the
        model left it out (summary.json ``sensitivity``), or ``None`` (idealised thrust fits).
    config : the resolved inputs, options and sampler settings (``config.toml``).
    """

    kind: str
    posterior: Any
    baseline: dict[str, float] | None
    sensitivity: dict | None
    config: dict
    _summary: dict = field(repr=False)
    _inputs: tuple[Path, ...] = field(default=(), repr=False)

    def __str__(self) -> str:
        """How a message names an unsaved fit: ``<fit inertia result, seed 0>``."""
        return f"<{self.config.get('command', self.kind)} result, seed {self.config.get('seed')}>"

    @property
    def idata(self) -> Any:
        """The ArviZ InferenceData (``posterior``, ``sample_stats``, ``prior``,
        ``observed_data``, …); typed ``Any``: ArviZ sets its groups as attributes at run time,
        which a type checker cannot see."""
        return self.posterior.idata

    @property
    def diagnostics(self) -> Diagnostics:
        """:class:`~cassini_bayes.diagnostics.Diagnostics` (R-hat, ESS, divergences)."""
        return self.posterior.diagnostics

    @property
    def converged(self) -> bool:
        """Whether the sampler converged (the rule of :mod:`cassini_bayes.diagnostics`)."""
        return bool(self._summary["diagnostics"]["converged"])

    @property
    def adequate(self) -> bool | None:
        """Whether every adequacy check passed (``None`` when the fit has none)."""
        adequacy = self._summary.get("adequacy")
        return None if adequacy is None else bool(adequacy["ok"])

    @property
    def warnings(self) -> list[str]:
        """The warnings raised during the fit (weak identification, baseline, adequacy …)."""
        return list(self._summary.get("warnings", []))

    def summary(self) -> dict:
        """The ``summary.json`` dict (a copy): parameters, baseline, diagnostics, adequacy,
        sensitivity, seed, version."""
        return copy.deepcopy(self._summary)

    def save(self, out: str | os.PathLike, *, force: bool = False,
             progress: bool = False) -> Path:
        """Write the run directory ``out`` atomically: ``posterior.nc``, ``summary.json``,
        ``config.toml``, ``report.html``; returns its absolute path.

        An existing non-empty ``out`` is replaced only with ``force=True`` and only when
        cassini-bayes wrote it; ``out`` may not hold the fit's input files. A problem building
        the full report is a warning (a minimal report is written instead). ``progress`` shows
        the step on the terminal (rich), as the fits' ``progress`` does.
        """
        from cassini_bayes.inference.progress import shown, step

        with shown(progress), step(f"writing {out} (posterior.nc, summary.json, config.toml, "
                                   "report.html)"):
            final, report_warnings = write_run(out, idata=self.idata, summary=self._summary,
                                               config=self.config, force=force,
                                               inputs=self._inputs)
        for line in report_warnings:
            warnings.warn(line, stacklevel=2)
        return final
