"""The wheel-axis fits docs/cli.md quotes: each shipped non-Cassini wheel-axis scenario simulated
once and fitted by ``fit_wheel_axis`` at the default settings (docs/cli.md, "fit wheel-axis").

Cases (``--cases``, any subset):

- ``espa_rwa``, ``cubesat_rwa``: ``wheel_axis_espa_bus`` (RW2) and ``wheel_axis_cubesat_12u``
  (RWS), simulation key 1, the RWA method, windows detected;
- ``espa_rcs_posterior``, ``espa_rcs_model``: ``wheel_axis_espa_bus_rcs`` (the scenario's own
  seed as key), the RCS method with the scenario's windows (Time A 30–60 s, Time B 80–110 s),
  after an inertia fit of ``slews_espa_bus`` (its posterior the inertia prior) and with the
  model file's inertia knowledge;
- ``espa_rcs_detected``: as ``espa_rcs_posterior`` with the windows detected.

Each record: the posterior mean's angle from the true axis, the least squares', the 50/90/95 %
cones (deg), the diagnostics, the adequacy verdict, the windows and the warnings; fit seed 0.
The table kind ``wheel_axis_fits`` (``_tables_evidence.py``) reads them.

    python benchmarks/wheel_axis_fits.py [--cases ...] [--json wheel_axis_fits.json]
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

CASES = ("espa_rwa", "cubesat_rwa", "espa_rcs_posterior", "espa_rcs_model", "espa_rcs_detected")
RCS_WINDOWS = [((30.0, 60.0), (80.0, 110.0))]


def _angle_deg(v, truth) -> float:
    v = np.asarray(v, float)
    return float(np.degrees(np.arccos(np.clip(v @ truth / np.linalg.norm(v), -1.0, 1.0))))


def _telemetry(name: str, key: int | None, folder: Path):
    """The scenario, and its telemetry simulated with ``key`` (the scenario's seed if None)
    written to ``folder``."""
    import jax

    from cassini_bayes.simulate import load_scenario, simulate
    from cassini_bayes.telemetry import write_telemetry

    s = load_scenario(name)
    path = folder / f"{name}.csv"
    if not path.exists():
        write_telemetry(path, simulate(jax.random.key(s.seed if key is None else key),
                                       s).telemetry)
    return s, path


def run_case(case: str, folder: Path, inertia: list) -> dict:
    """Fit one case; ``inertia`` caches the ``slews_espa_bus`` inertia fit between cases."""
    import cassini_bayes as cb

    if case in ("espa_rwa", "cubesat_rwa"):
        name, model, wheel = (("wheel_axis_espa_bus", "espa_bus", "RW2") if case == "espa_rwa"
                              else ("wheel_axis_cubesat_12u", "cubesat_12u", "RWS"))
        s, csv = _telemetry(name, 1, folder)
        kw = {"method": "rwa"}
    else:
        name, model, wheel = "wheel_axis_espa_bus_rcs", "espa_bus", "RW2"
        s, csv = _telemetry(name, None, folder)
        kw = {"method": "rcs", "windows": None if case == "espa_rcs_detected" else RCS_WINDOWS}
        if case != "espa_rcs_model":
            if not inertia:
                _, slews = _telemetry("slews_espa_bus", None, folder)
                inertia.append(cb.fit_inertia(slews, "espa_bus", seed=0))
            kw["inertia_posterior"] = inertia[0]
    t0 = time.perf_counter()
    summ = json.loads(json.dumps(cb.fit_wheel_axis(csv, model, wheel=wheel, seed=0,
                                                   **kw).summary()))
    truth = s.truth.wheel(wheel).axis
    base = summ["baseline"]
    return {"case": case, "scenario": name, "model": model, "wheel": wheel,
            "method": kw["method"], "windows_given": kw.get("windows") is not None,
            "inertia_posterior": "inertia_posterior" in kw,
            "error_deg": _angle_deg(summ["direction"]["mean"], truth),
            "least_squares_error_deg": _angle_deg([base[n] for n in ("u4_x", "u4_y", "u4_z")],
                                                  truth),
            "cone_deg": summ["direction"]["cone_deg"], "diagnostics": summ["diagnostics"],
            "adequacy_ok": summ["adequacy"]["ok"], "windows": summ["windows"],
            "warnings": summ["warnings"], "seconds": time.perf_counter() - t0}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="+", choices=CASES, default=list(CASES))
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    import cassini_bayes

    cassini_bayes.setup_jax()
    records, inertia = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for case in args.cases:
            r = run_case(case, Path(tmp), inertia)
            d = r["diagnostics"]
            print(f"{case:20s} error {r['error_deg']:.3f}° (least squares "
                  f"{r['least_squares_error_deg']:.3f}°), 90 % cone {r['cone_deg']['90']:.2f}°, "
                  f"R-hat {d['max_r_hat']:.3f}, divergences {d['divergences']}, "
                  f"adequacy {'passed' if r['adequacy_ok'] else 'FAILED'}, {r['seconds']:.0f} s",
                  flush=True)
            records.append(r)
    if args.json:
        from _provenance import write_json

        write_json(args.json, records)


if __name__ == "__main__":
    main()
