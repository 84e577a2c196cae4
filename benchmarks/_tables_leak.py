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


def _spread(values: list[float]) -> str:
    """``v (all)`` when every value is the same, else the median and the range; "–" for none."""
    if not values:
        return "–"
    if max(values) == min(values):
        return f"{values[0]:.0f} (all)"
    return f"{statistics.median(values):.0f} ({min(values):.0f}–{max(values):.0f})"


def _before(run: dict, onset_s: float) -> float:
    """The largest P(leak) of the checks before ``onset_s``."""
    return max((p for t, p in zip(run["t_check_s"], run["p_leak"]) if t < onset_s), default=0.0)


def leak_espa_table(record: dict) -> str:
    """Per leak size (``benchmarks/leak_espa.py``): detections, the thruster isolated, alarms
    and the largest ``P(leak)`` before the onset, the delays, and the fraction's and onset's
    errors (the fraction in the monitor's units, of the model file's thrust); then the clean
    stretches."""
    lines = ["| leak | runs | detected | right thruster | false alarm before the onset | "
             "largest P(leak) before the onset | detection delay (s) | isolation delay (s) | "
             "fraction's 90 % interval covers | fraction error, largest (relative) | "
             "onset error, largest (s) | adequacy ok |", "|" + "---|" * 12]
    for frac in dict.fromkeys(r["fraction"] for r in record["leaks"]):
        runs = [r for r in record["leaks"] if r["fraction"] == frac]
        bs = [(r, r["bayes"]) for r in runs]
        det = [(r, b) for r, b in bs if b["detection_time_s"] is not None
               and b["detection_time_s"] >= r["onset_s"]]
        early = sum(b["detection_time_s"] is not None and b["detection_time_s"] < r["onset_s"]
                    for r, b in bs)
        right = sum(b["thruster"] == r["thruster"] for r, b in bs)
        delay = [b["detection_time_s"] - r["onset_s"] for r, b in det]
        iso = [b["isolation_time_s"] - r["onset_s"] for r, b in det
               if b["isolation_time_s"] is not None]
        lo_hi = [(b["fraction_interval_90"], r["fraction_model_units"]) for r, b in bs]
        covers = sum(lo <= f <= hi for (lo, hi), f in lo_hi)
        f_err = max(abs(b["fraction_mean"] / r["fraction_model_units"] - 1.0) for r, b in bs)
        t_err = max(abs(b["onset_s"] - r["onset_s"]) for r, b in bs)
        lines.append(
            f"| {100 * frac:g} % | {len(runs)} | {len(det)} | {right} | {early} | "
            f"{max(_before(r, r['onset_s']) for r in runs):.4f} | {_spread(delay)} | "
            f"{_spread(iso)} | {covers}/{len(runs)} | {100 * f_err:.2f} % | {t_err:.2g} | "
            f"{sum(r['adequacy_ok'] for r in runs)}/{len(runs)} |")
    clean = record["clean"]
    if clean:
        lines += ["", "| clean stretches | hours each | alarms | largest P(leak) | adequacy ok |",
                  "|---|---|---|---|---|",
                  f"| {len(clean)} | {clean[0]['hours']:g} | "
                  f"{sum(c['bayes']['detection_time_s'] is not None for c in clean)} | "
                  f"{min(max(c['p_leak']) for c in clean):.4f}–"
                  f"{max(max(c['p_leak']) for c in clean):.4f} | "
                  f"{sum(c['adequacy_ok'] for c in clean)}/{len(clean)} |"]
    return "\n".join(lines)


@kind("leak_espa")
def leak_espa(args: list[Records]) -> str:
    """The ESPA bus's leak runs (``benchmarks/leak_espa.py --json``)."""
    (path,), = args
    return leak_espa_table(read_json(path))


def _offset(x: float) -> str:
    return f"{x:.0f}" if x >= 10 else f"{x:.2g}"


_LEVELS = {"none": "none", "first": "first order", "second": "first and second order"}


@kind("residual_at_truth")
def residual_at_truth(args: list[Records]) -> str:
    """The health design's residual at the truth, noise-free, per rate-step level
    (``benchmarks/leak_health_residual_at_truth.py --json``), over the gyro noise."""
    def axes(v: list[float]) -> str:
        return ", ".join(f"{x:.2g}" for x in v)

    lines = ["| scenario | sampled | rate-step correction | health residual rms / noise (X, Y, Z) "
             "| estimate's largest offset (white sd) | monitor's residual rms / noise |",
             "|" + "---|" * 6]
    for group in args:
        for path in group:
            for row in read_json(path):
                at = (f"every {row['sample_period_s']:g} s" if row["sample_period_s"]
                      else "as flown")
                for level, label in _LEVELS.items():
                    m = row[level]
                    leak = m.get("leak_rms_over_noise")
                    lines.append(f"| `{row['scenario']}` | {at} | {label} | "
                                 f"{axes(m['health_rms_over_noise'])} | "
                                 f"{_offset(m['health_offset_max_abs'])} | "
                                 f"{axes(leak) if leak else '–'} |")
    return "\n".join(lines)
