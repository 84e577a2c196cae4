"""Table kinds of the leak-detection campaigns (``benchmarks/leak_detection.py --out`` records,
shown in docs/leak.md), and the campaign table that script prints; registered in
:mod:`_tables` by import."""

from __future__ import annotations

import statistics

from _tables import Records, kind, read_json

MONITORS = {"bayes": "Bayes", "lee": "Lee"}


def _delays(runs: list[dict], mon: str, col: int) -> list[float]:
    return [r[mon][col] - r["onset_s"] for r in runs
            if r[mon][col] is not None and r[mon][0] is not None and r[mon][0] >= r["onset_s"]]


def _cell(values: list[float], fn) -> str:
    return f"{fn(values):.0f}" if values else "–"


def campaign_table(campaigns: list[tuple[list[dict], list[dict], float]]) -> str:
    """Per leak size and monitor, pooled over ``campaigns`` (``(leak runs, control runs,
    hours)`` each): detections after the onset, alarms before it, the thruster named, and the
    delays from the onset (the median per campaign, ``/`` between them); then each monitor's
    false alarms over the control stretches and the hours before the onsets."""
    rows = [r for runs, _, _ in campaigns for r in runs]
    lines = ["| leak | monitor | detected | false alarm before onset | correct thruster | "
             "delay median (s) | delay max (s) | isolation delay median / max (s) |",
             "|" + "---|" * 8]
    for label in dict.fromkeys(r["size"] for r in rows):
        for mon, name in MONITORS.items():
            sub = [r for r in rows if r["size"] == label]
            det = [r for r in sub if r[mon][0] is not None and r[mon][0] >= r["onset_s"]]
            early = sum(r[mon][0] is not None and r[mon][0] < r["onset_s"] for r in sub)
            iso = [r for r in det if r[mon][2] is not None]
            named = sum(r[mon][1] == r["thruster"] for r in iso)
            medians = " / ".join(
                _cell(_delays([r for r in runs if r["size"] == label], mon, 0), statistics.median)
                for runs, _, _ in campaigns)
            d, di = _delays(sub, mon, 0), _delays(sub, mon, 2)
            lines.append(f"| {label} | {name} | {len(det)}/{len(sub)} | {early} | "
                         + (f"{named}/{len(iso)}" if iso else "–") + f" | {medians} | "
                         f"{_cell(d, max)} | {_cell(di, statistics.median)} / {_cell(di, max)} |")
    lines += ["", "| monitor | false alarms | control stretches | hours before the onsets | "
              "hours in all | rate (95 % bound with none) |", "|" + "---|" * 6]
    pre_h = sum(r["onset_s"] for r in rows) / 3600.0
    n_ctrl = sum(len(c) for _, c, _ in campaigns)
    tot_h = sum(len(c) * h for _, c, h in campaigns) + pre_h
    hours = "/".join(dict.fromkeys(f"{h:g} h" for _, _, h in campaigns))
    for mon, name in MONITORS.items():
        fa = sum(c[mon][0] is not None for _, cs, _ in campaigns for c in cs)
        fa += sum(r[mon][0] is not None and r[mon][0] < r["onset_s"] for r in rows)
        rate = f"{fa / tot_h:.3g} per hour" if fa else f"< {3.0 / tot_h:.3g} per hour"
        lines.append(f"| {name} | {fa} | {n_ctrl} of {hours} | {pre_h:.1f} | {tot_h:.1f} | "
                     f"{rate} |")
    return "\n".join(lines)


@kind("leak_campaign")
def leak_campaign(args: list[Records]) -> str:
    """The campaign table of ``benchmarks/leak_detection.py`` records, pooled (the delay
    medians per record)."""
    recs = [read_json(p) for group in args for p in group]
    return campaign_table([(r["leak_runs"], r["controls"], r["args"]["hours"]) for r in recs])


@kind("leak_quadrature_cost")
def leak_quadrature_cost(args: list[Records]) -> str:
    """CPU seconds of the leak monitor per stretch (``benchmarks/leak_quadrature.py cost``)."""
    from leak_quadrature import cost_table

    (path,), = args
    return cost_table(read_json(path))
