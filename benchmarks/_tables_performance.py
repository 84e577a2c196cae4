"""Table kinds of the speed and convergence benchmarks' records (docs/performance/,
docs/quick_settings/); registered in :mod:`_tables` by import."""

from __future__ import annotations

import re

from _tables import Records, kind, read_json


@kind("quick_settings")
def quick_settings(args: list[Records]) -> str:
    """Converged fits per sampler setting (benchmarks/quick_settings.py's records, pooled)."""
    from quick_settings import table

    return table([p for group in args for p in group])


@kind("bench_samplers")
def bench_samplers(args: list[Records]) -> str:
    """The package's warm robust fit against nutpie (benchmarks/bench_samplers.py records): a
    row per argument, its label the letter that ends the record's name (``A+B``: pooled)."""
    from statistics import median

    rows = ["| run | `fit inertia` (robust, warm, run directory and report) | nutpie, plain "
            "model | ratio of medians | per round |", "|---|---|---|---|---|"]
    for group in args:
        walls: dict[str, list[float]] = {"pkg_robust_warm": [], "nutpie": []}
        for path in group:
            runs = sorted(read_json(path)["runs"], key=lambda r: r["round"])
            for system, w in walls.items():
                w += [r["wall_s"] for r in runs if r["system"] == system]
        pkg, nut = walls["pkg_robust_warm"], walls["nutpie"]
        per_round = [a / b for a, b in zip(pkg, nut, strict=True)]
        ratio = f"{median(pkg) / median(nut):.2f} | {min(per_round):.2f}–{max(per_round):.2f}"
        if len(group) > 1:
            rows.append(f"| all {len(pkg)} | median {median(pkg):.2f} s | median "
                        f"{median(nut):.2f} s | {ratio} |")
            continue
        label = re.search(r"[a-z]*$", group[0].stem)[0]
        cells = [", ".join(f"{w:.2f}" for w in ws) + f" s (median {median(ws):.2f})"
                 for ws in (pkg, nut)]
        rows.append(f"| {label} ({len(pkg)} rounds) | {cells[0]} | {cells[1]} | {ratio} |")
    return "\n".join(rows)
