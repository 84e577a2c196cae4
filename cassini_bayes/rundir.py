"""Atomic run directories (DESIGN.md §4), shared by ``fit``, ``experiment`` and ``sbc``.

A run directory holds ``posterior.nc``, ``summary.json``, ``config.toml`` and ``report.html``.
Everything is written into a hidden temporary sibling (``.NAME.tmp-…``, same file system) which is
renamed into place only when all files are complete, so a crash or Ctrl-C never leaves a
half-written run under the final name. An existing non-empty ``--out`` is refused unless
``force``; then the old directory is first renamed aside (``.NAME.old-…``), the new one renamed in,
and the old one deleted — at no moment does ``NAME`` hold a mixture of the two.

Usage::

    with RunDir(out, force=force) as rd:          # rd.path is the temporary directory
        write_posterior(rd.path, idata)
        write_summary(rd.path, summary)
        write_config(rd.path, config)
        write_report(rd.path, display_dir=rd.final)
    # here `out` is complete
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import shutil
import tempfile
import warnings
from pathlib import Path
from typing import Any, Mapping

from cassini_bayes.errors import InputError

__all__ = ["RunDir", "file_record", "write_posterior", "write_summary", "write_config",
           "write_report", "minimal_report_html"]


class RunDir:
    """Context manager writing a run directory atomically (module docstring).

    Attributes
    ----------
    final : the directory's final path (absolute).
    path : the temporary directory to write into (inside the context).
    """

    def __init__(self, out: str | os.PathLike, *, force: bool = False):
        self.final = Path(out).expanduser().resolve()
        self.force = force
        self.path: Path | None = None
        if self.final.exists():
            if not self.final.is_dir():
                raise InputError("exists and is not a directory; choose another --out",
                                 path=str(out))
            if any(self.final.iterdir()) and not force:
                raise InputError("already exists and is not empty; choose another --out or "
                                 "pass --force to replace it", path=str(out))

    def __enter__(self) -> "RunDir":
        parent = self.final.parent
        try:
            parent.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise InputError(f"cannot create the parent directory: {e.strerror}",
                             path=str(parent)) from None
        self.path = Path(tempfile.mkdtemp(prefix=f".{self.final.name}.tmp-", dir=parent))
        return self

    def __exit__(self, exc_type, exc, tb) -> bool:
        if exc_type is not None:
            shutil.rmtree(self.path, ignore_errors=True)
            return False
        self.commit()
        return False

    def commit(self) -> None:
        """Move the finished temporary directory to its final name."""
        old = None
        if self.final.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{self.final.name}.old-",
                                        dir=self.final.parent))
            os.rmdir(old)
            os.replace(self.final, old)
        try:
            os.replace(self.path, self.final)
        except OSError:
            if old is not None:  # put the old run back
                os.replace(old, self.final)
            raise
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)


def file_record(path: str | os.PathLike) -> dict[str, str]:
    """``{"path": absolute path, "sha256": hex digest}`` of an input file, for ``config.toml``."""
    p = Path(path).resolve()
    h = hashlib.sha256()
    with open(p, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return {"path": str(p), "sha256": h.hexdigest()}


def _json_clean(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _json_clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_json_clean(v) for v in x]
    if hasattr(x, "tolist"):
        return _json_clean(x.tolist())
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def _toml_clean(x: Any) -> Any:
    """TOML has no null: drop ``None`` entries; arrays become lists."""
    if isinstance(x, dict):
        return {str(k): _toml_clean(v) for k, v in x.items() if v is not None}
    if isinstance(x, (list, tuple)):
        return [_toml_clean(v) for v in x if v is not None]
    if hasattr(x, "tolist"):
        return _toml_clean(x.tolist())
    return x


def write_posterior(run_dir: Path, idata) -> Path:
    """``posterior.nc``: the InferenceData, every group (custom ones such as ``residuals`` too)."""
    p = Path(run_dir) / "posterior.nc"
    idata.to_netcdf(str(p))
    return p


def write_summary(run_dir: Path, summary: Mapping) -> Path:
    """``summary.json`` (NaN and infinities written as ``null``)."""
    p = Path(run_dir) / "summary.json"
    p.write_text(json.dumps(_json_clean(dict(summary)), indent=2) + "\n")
    return p


def write_config(run_dir: Path, config: Mapping) -> Path:
    """``config.toml``: the resolved inputs, seed, sampler settings and package version."""
    import tomli_w

    p = Path(run_dir) / "config.toml"
    p.write_text(tomli_w.dumps(_toml_clean(dict(config))))
    return p


def minimal_report_html(summary: Mapping) -> str:
    """A small self-contained HTML page with the diagnostics table (fallback report)."""
    from html import escape

    d = summary.get("diagnostics", {})
    rows = "".join(f"<tr><td>{escape(str(k))}</td><td>{escape(str(v))}</td></tr>"
                   for k, v in d.items())
    prow = "".join(
        f"<tr><td>{escape(k)}</td>" + "".join(
            f"<td>{escape(str(v.get(c)))}</td>"
            for c in ("mean", "sd", "q05", "q95", "r_hat", "ess_bulk")) + "</tr>"
        for k, v in summary.get("parameters", {}).items())
    return ("<!DOCTYPE html><html><head><meta charset='utf-8'><title>cassini-bayes run</title>"
            "</head><body><h1>cassini-bayes: " + escape(str(summary.get("kind", "run"))) +
            "</h1><h2>Diagnostics</h2><table>" + rows + "</table><h2>Parameters</h2><table>"
            "<tr><th>name</th><th>mean</th><th>sd</th><th>q05</th><th>q95</th><th>r_hat</th>"
            "<th>ess_bulk</th></tr>" + prow + "</table></body></html>\n")


def write_report(run_dir: Path, *, display_dir: Path | None = None,
                 summary: Mapping | None = None) -> Path:
    """``report.html`` from :func:`cassini_bayes.report.build_report`; a minimal page if that fails.

    A failure of the report never loses a finished fit: it is turned into a warning and the
    minimal page (diagnostics and parameter tables from ``summary``) is written instead.
    """
    p = Path(run_dir) / "report.html"
    try:
        from cassini_bayes.report import build_report

        kwargs = {"display_dir": display_dir} if display_dir is not None else {}
        build_report(run_dir, **kwargs)
        if p.exists():
            return p
    except Exception as e:  # report layer missing or broken: keep the run, say so
        warnings.warn(f"report.html: the full report failed ({type(e).__name__}: {e}); "
                      "wrote a minimal one", stacklevel=2)
    if summary is None:
        summary = json.loads((Path(run_dir) / "summary.json").read_text())
    p.write_text(minimal_report_html(summary))
    return p
