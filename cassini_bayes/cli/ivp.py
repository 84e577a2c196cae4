"""``cassini-bayes ivp fit TRAJECTORY.csv [--requirement-urad 40] [--max-order 12] [--mu MU]
--out DIR``.

Runs :func:`cassini_bayes.api.fit_trajectory` (Chebyshev segments of the vector in the file,
Lee §3.3.2) and writes, atomically, ``DIR/segments.csv`` (the segment table with its
coefficients), ``DIR/summary.json``, ``DIR/config.toml`` and ``DIR/report.html`` (the angle
against time per segment with the requirement line). docs/ivp.md describes the method.
"""

from __future__ import annotations

import time
from pathlib import Path

import typer

from cassini_bayes.cli._console import escape, stderr_console
from cassini_bayes.rundir import check_out

ORDER = 65


def register(app: typer.Typer, groups: dict[str, typer.Typer]) -> None:
    ivp = typer.Typer(help="Inertial vector propagation (Lee §3.3): polynomial segments.",
                      no_args_is_help=True)
    app.add_typer(ivp, name="ivp")

    @ivp.command("fit")
    def fit_cmd(
        trajectory: Path = typer.Argument(..., help="Trajectory CSV: t (s), x, y, z (m)."),
        out: Path = typer.Option(..., "--out", help="Output directory (written atomically)."),
        requirement_urad: float = typer.Option(40.0, "--requirement-urad",
                                               help="Largest angle between fitted and true "
                                                    "vector, µrad (Cassini: 40)."),
        max_order: int = typer.Option(12, "--max-order", help="Highest polynomial order of a "
                                      "segment, 0 .. 12 (Cassini: 12)."),
        mu: float | None = typer.Option(None, "--mu", help="Gravitational parameter (m^3/s^2) "
                                        "of the body the vector is measured from: also fit one "
                                        "conic and report its error."),
        force: bool = typer.Option(False, "--force", help="Replace --out if it is a directory "
                                   "cassini-bayes wrote."),
    ) -> None:
        """Chebyshev segments of a trajectory within an angular requirement."""
        console = stderr_console()
        t0 = time.perf_counter()
        from cassini_bayes.api import fit_trajectory

        check_out(out, force=force, inputs=[trajectory])
        res = fit_trajectory(trajectory, requirement_urad=requirement_urad,
                             max_order=max_order, mu=mu)
        res.save(out, force=force)
        s = res.summary()
        line = (f"{s['n_segments']} segments, {s['n_coefficients']} coefficients, largest "
                f"error {max(s['max_error_urad'], s['max_error_samples_urad']):.1f} µrad "
                f"(requirement {s['requirement_urad']:g})")
        if "conic" in s:
            line += f"; one conic: {s['conic']['max_error_urad']:.3g} µrad"
        mark = "[green]✓[/green]" if s["meets_requirement"] else "[red]✗[/red]"
        console.print(f"{mark} {line} ({time.perf_counter() - t0:.1f} s) → {escape(str(out))}")
