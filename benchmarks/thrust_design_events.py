"""The impulse design of shipped biasing events in per-thruster mode: pulses per thruster, the
design's rank, the thrusters it identifies, the identified combinations of the others and the
centre of mass's linearised contraction (docs/thrust_any_layout.md).

For each scenario: simulate it (simulation key ``--key``), then prepare the per-thruster
problem against the scenario's prior model (``prepare_thrust(..., mode="thruster")``: the
design and the Laplace step, no sampling). Deterministic; ``--json`` writes the designs as a
record with its manifest.

    python benchmarks/thrust_design_events.py [--scenarios biasing_day028 fsds_biasing]
        [--key 0] [--json FILE.json]
"""

from __future__ import annotations

import argparse
import sys
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def design_of(name: str, key: int) -> dict:
    """The ``thrust_design`` block of one simulated scenario, with its pulses per thruster."""
    import jax

    from cassini_bayes.inference.thrust import prepare_thrust
    from cassini_bayes.simulate import scenario_from_dict, simulate

    path = ROOT / "experiments" / "scenarios" / f"{name}.toml"
    scenario = scenario_from_dict(tomllib.loads(path.read_text()), src=str(path))
    sim = simulate(jax.random.key(key), scenario)
    problem = prepare_thrust([(sim.telemetry, sim.pulses)], scenario.prior, mode="thruster")
    names = list(scenario.prior.thruster_names)
    counts = np.bincount(np.asarray(sim.pulses.thruster), minlength=len(names))
    return {"scenario": name, "key": key, "model": scenario.prior.name,
            "pulses": {n: int(c) for n, c in zip(names, counts, strict=True)},
            **problem.design.to_dict()}


def main(argv: list[str] | None = None) -> list[dict]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenarios", nargs="+", default=["biasing_day028", "fsds_biasing"])
    ap.add_argument("--key", type=int, default=0)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args(argv)
    if args.json:
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        from _provenance import start

        start(args.json, vars(args), argv, replace=True)
    from cassini_bayes import setup_jax
    from cassini_bayes.files import json_text, write_text

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    designs = []
    for name in args.scenarios:
        d = design_of(name, args.key)
        designs.append(d)
        print(f"{name}: pulses {' '.join(map(str, d['pulses'].values()))}, rank {d['rank']} of "
              f"{d['parameters']}, identified {' '.join(d['identified']) or '-'}, combinations "
              f"{[c['label'] for c in d['combinations']] or '-'}, com contraction "
              f"{[round(c, 3) for c in d['com_contraction'].values()]}", flush=True)
    if args.json:
        write_text(args.json, json_text({"designs": designs}))
    return designs


if __name__ == "__main__":
    main()
