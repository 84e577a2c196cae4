"""Thruster health on the ESPA bus: the degradation campaign and its control, one fit each.

``cassini-bayes simulate-health health_degradation_espa_bus`` (16 events over 365 days, A3 loses
20 % on day 180) and the same file less its ``[degradation]`` table (the same seed: the same
dates, wheel targets and errors), each fitted by ``cassini-bayes fit health --spacecraft
espa_bus`` at its defaults. The record holds each fit's ``summary.json``, the truth's dates,
thrusts and degradation, and the fit's wall seconds; the table kind ``health_espa`` reads it.
Not a test: nothing is asserted.

    python benchmarks/health_espa.py [--json health_espa.json] [--work DIR]
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

SCENARIO = "health_degradation_espa_bus"


def _cli(*args: str) -> None:
    exe = shutil.which("cassini-bayes") or str(Path(sys.executable).parent / "cassini-bayes")
    subprocess.run([exe, *args], check=True, stdout=subprocess.DEVNULL)


def _control_file(work: Path) -> Path:
    """The degradation file less its ``[degradation]`` table, its event template by path."""
    from cassini_bayes.files import toml_text
    from cassini_bayes.simulate.scenario import scenario_path

    src = scenario_path(SCENARIO)
    d = tomllib.loads(src.read_text())
    d.pop("degradation")
    d["name"] = "health_control_espa_bus"
    d["event"] = str(src.with_name(d["event"]))
    out = work / "health_control_espa_bus.toml"
    out.write_text(toml_text(d))
    return out


def campaign(work: Path, case: str, scenario: str) -> dict:
    """Simulate and fit one campaign; its summary, truth and fit time."""
    sim, fit = work / case, work / f"{case}_fit"
    _cli("simulate-health", scenario, "--out", str(sim))
    t0 = time.perf_counter()
    _cli("fit", "health", str(sim), "--spacecraft", "espa_bus", "--out", str(fit))
    wall = time.perf_counter() - t0
    truth = json.loads((sim / "truth.json").read_text())
    return {"summary": json.loads((fit / "summary.json").read_text()), "fit_wall_s": wall,
            "truth": {k: truth[k] for k in ("seed", "dates_days", "thrust_n", "degradation")}}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", type=Path, help="write the record here (with a manifest)")
    ap.add_argument("--work", type=Path, default=None, help="keep the runs here")
    args = ap.parse_args(argv)
    if args.json:
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    with tempfile.TemporaryDirectory() as tmp:
        work = args.work or Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        record = {"degradation": campaign(work, "degradation", SCENARIO),
                  "control": campaign(work, "control", str(_control_file(work)))}
    for case, r in record.items():
        s = r["summary"]
        print(f"{case}: P(change) {s['p_change']:.6f}, P(any > 5 % down) "
              f"{s['p_down_last']['any']:.6f}, fit {r['fit_wall_s']:.0f} s")
    if args.json:
        from _provenance import write_json

        write_json(args.json, record)


if __name__ == "__main__":
    main()
