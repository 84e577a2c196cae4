"""One record of ``validation/results/espa_bus/`` from a ``basilisk_espa.py --cases bias`` run
directory, with its manifest (``benchmarks/_provenance.py``'s format and path).

The record is the run's ``results.json`` (the ``bias`` block: truth, per-entry rows,
diagnostics, adequacy, design, nuisance) plus ``seed`` and ``impulse_bits``: per thruster, the
posterior of the impulse of one 125 ms pulse ``F φ(0.125 s; τ)`` (Feldman & Lee §V,
``cassini_bayes.physics.pulse.pulse_impulse``) against Basilisk's (the truth's thrust times the
impulse per newton Basilisk delivered for its 125 ms pulses): nearly every pulse of the event is
125 ms wide, so the impulse bit is what the event measures, whatever split between ``F`` and
``τ`` the §V profile makes of Basilisk's ramp.

    python validation/espa_bias_record.py RUN OUT.json --seed N --command '...'
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
WIDTH_S = 0.125


def impulse_bits(posterior_nc: Path, truth: dict) -> list[dict]:
    """Per thruster: the impulse bit's posterior (N s) against Basilisk's."""
    import xarray as xr

    from cassini_bayes.physics.pulse import pulse_impulse

    post = xr.open_dataset(posterior_nc, group="posterior")
    f = post["F"].stack(s=("chain", "draw")).transpose("s", ...).values        # (S, M) N
    tau = [post[n].stack(s=("chain", "draw")).values for n in
           ("tau_delay", "tau_rise", "tau_fall")]
    phi = np.asarray(pulse_impulse(WIDTH_S, *tau))                              # (S,) s
    names = [str(v) for v in post["F"].coords[post["F"].dims[-1]].values]
    per_newton = truth["impulse_per_newton_by_width"][f"{WIDTH_S:.3f}"]["basilisk_s"]
    rows = []
    for k, name in enumerate(names):
        bit = f[:, k] * phi
        true = truth["F_n"][name] * per_newton
        q05, q95 = np.quantile(bit, [0.05, 0.95])
        rows.append({"thruster": name, "truth_ns": true, "mean": float(bit.mean()),
                     "sd": float(bit.std()), "q05": float(q05), "q95": float(q95),
                     "covered": bool(q05 <= true <= q95),
                     "rel_error_pct": float(100 * (bit.mean() - true) / true)})
    return rows


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run", type=Path, help="the --out directory of basilisk_espa.py")
    ap.add_argument("out", type=Path, help="the record (JSON); its manifest goes beside it")
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--command", required=True, help="the command that made the run")
    ap.add_argument("--commit", required=True, help="the package commit the run used")
    ap.add_argument("--started", default=None, help="when the run started (ISO, UTC)")
    ap.add_argument("--load", type=float, default=None, help="load average during the run")
    a = ap.parse_args(argv)
    res = json.loads((a.run / "results.json").read_text())
    b = res["bias"]
    b["seed"] = a.seed
    nc = a.run / "bias" / "fit" / "posterior.nc"
    if nc.exists():
        b["impulse_bits"] = impulse_bits(nc, b["truth"])
    a.out.write_text(json.dumps(res, indent=1) + "\n")
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from _provenance import cpu_name, manifest_path

    run = {"command": a.command, "commit": a.commit,
           "started": a.started or dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
           "recorded_by": "validation/espa_bias_record.py "
                          + subprocess.list2cmdline([str(a.run), a.out.name]),
           "machine": f"{cpu_name()}, {os.cpu_count()} cores", "load_average": a.load}
    man = {"records": a.out.name,
           "options": {"tilt_deg": b["truth"]["tilt_angle_deg"],
                       "bias_period_s": b["truth"]["sample_period_s"], "seed": a.seed,
                       "sampler": b.get("fit_command_sampler")},
           "runs": [run]}
    manifest_path(a.out).write_text(json.dumps(man, indent=1) + "\n")
    print(f"{a.out} (+ manifest)")


if __name__ == "__main__":
    main()
