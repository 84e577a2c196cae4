"""Regenerate the markdown tables of ``docs/`` from the records they summarise.

    python benchmarks/docs_tables.py           # rewrite every table block that differs
    python benchmarks/docs_tables.py --check   # exit 1, naming each block that differs

A table block in a markdown file under ``docs/`` is

    <!-- table: KIND RECORDS... -->
    | the table |
    <!-- /table -->

``KIND`` names a function of ``KINDS`` below and ``RECORDS`` are the records' paths, relative to
the markdown file's folder (``A+B``: one argument of several records, pooled where the kind
pools); each record must have a manifest (``benchmarks/_provenance.py``), so
a table can always be traced to the run that made it. The text between the markers is the
function's output and nothing else: a hand-edited cell fails ``--check``
(``tests/test_evidence.py``).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shlex
import sys
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
sys.path.insert(0, str(ROOT / "benchmarks"))

from _provenance import manifest_path  # noqa: E402

BLOCK = re.compile(r"<!-- table: (?P<spec>[^\n]*?) -->\n(?P<body>.*?)<!-- /table -->",
                   re.DOTALL)
Kind = Callable[[list[tuple[Path, ...]]], str]
KINDS: dict[str, Kind] = {}


def kind(name: str) -> Callable[[Kind], Kind]:
    """Register a table generator under ``name`` (the marker's ``KIND``)."""
    def register(fn: Kind) -> Kind:
        KINDS[name] = fn
        return fn
    return register


def _rel(path: Path) -> str:
    try:
        return str(path.relative_to(ROOT))
    except ValueError:
        return str(path)


def _json(path: Path) -> dict:
    return json.loads(path.read_text(encoding="utf-8"))


def _p(p: float) -> str:
    """A p-value as the SBC tables print it: three decimals, two significant digits below 0.01."""
    return f"{p:.3f}" if p >= 0.01 else f"{p:.2g}"


def _sbc_row(name: str, chi2_p: float, ecdf_p: float, cov: list[float]) -> str:
    return (f"| {name} | {_p(chi2_p)} | {_p(ecdf_p)} | "
            + " | ".join(f"{c:.3f}" for c in cov) + " |")


_SBC_HEAD = ("| parameter | χ² p | ECDF p | cov 50 | cov 80 | cov 90 | cov 95 |\n"
             "|-----------|------|--------|--------|--------|--------|--------|")


@kind("sbc")
def sbc(args: list[tuple[Path, ...]]) -> str:
    """Rank uniformity and coverage per parameter of a ``cassini-bayes sbc`` summary.json, or
    of ``benchmarks/health_sbc.py``'s (the health and leak models)."""
    ((path,),) = args
    rows = [_SBC_HEAD]
    for name, par in _json(path)["parameters"].items():
        if "chi2" in par:                                   # cassini-bayes sbc
            cov = [par["coverage"][k]["observed"] for k in ("50", "80", "90", "95")]
            rows.append(_sbc_row(name, par["chi2"]["p_value"], par["ecdf"]["p_value"], cov))
        else:                                               # benchmarks/health_sbc.py
            cov = [par["coverage"][k] for k in ("0.5", "0.8", "0.9", "0.95")]
            rows.append(_sbc_row(name, par["chi2_p"], par["ecdf_p"], cov))
    return "\n".join(rows)


def _calibration(args: list[tuple[Path, ...]], key: str, label: str) -> str:
    ((path,),) = args
    bins = _json(path)[key]
    rows = [f"| {label} | n | mean P | observed rate | sd |", "|---|---|---|---|---|"]
    for i, b in enumerate(bins):
        lo, hi = (f"{x:g}" for x in b["bin"])
        close = "]" if i == len(bins) - 1 else ")"
        rows.append(f"| [{lo}, {hi}{close} | {b['n']} | {b['mean_p']:.2g} | {b['rate']:.2g} | "
                    f"{b['sd']:.2g} |")
    return "\n".join(rows)


@kind("leak_p_calibration")
def leak_p_calibration(args: list[tuple[Path, ...]]) -> str:
    """Calibration of the leak monitor's ``P(leak)`` (health_sbc.py's leak summary.json)."""
    return _calibration(args, "p_leak_calibration", "P(leak) bin")


@kind("leak_hypothesis_calibration")
def leak_hypothesis_calibration(args: list[tuple[Path, ...]]) -> str:
    """Calibration of every leak hypothesis' probability (the same summary.json)."""
    return _calibration(args, "p_hypothesis_calibration", "P bin")


@kind("quick_settings")
def quick_settings(args: list[tuple[Path, ...]]) -> str:
    """Converged fits per sampler setting (benchmarks/quick_settings.py's records, pooled)."""
    from quick_settings import table

    return table([p for group in args for p in group])


@kind("bench_samplers")
def bench_samplers(args: list[tuple[Path, ...]]) -> str:
    """The package's warm robust fit against nutpie (benchmarks/bench_samplers.py records): a
    row per argument, its label the letter that ends the record's name (``A+B``: pooled)."""
    from statistics import median

    rows = ["| run | `fit inertia` (robust, warm, run directory and report) | nutpie, plain "
            "model | ratio of medians | per round |", "|---|---|---|---|---|"]
    for group in args:
        walls: dict[str, list[float]] = {"pkg_robust_warm": [], "nutpie": []}
        for path in group:
            runs = sorted(_json(path)["runs"], key=lambda r: r["round"])
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


def _results(args: list[tuple[Path, ...]]) -> list[dict]:
    return [r for group in args for path in group for r in _json(path)["results"]]


def _ratios(result: dict) -> list[float]:
    return [site["ratio_median"] for site in result["sites"].values()]


@kind("plan_prediction")
def plan_prediction(args: list[tuple[Path, ...]]) -> str:
    """Fitted over predicted posterior sd per site (benchmarks/plan_prediction.py records)."""
    rows = ["| scenario | sites | median over seeds, per site: range | every single fit: range "
            "| within 10 % | predict (s) |", "|---|---|---|---|---|---|"]
    for r in _results(args):
        med, sites = _ratios(r), r["sites"].values()
        lo, hi = min(s["ratio_min"] for s in sites), max(s["ratio_max"] for s in sites)
        rows.append(f"| `{r['scenario']}` | {r['n_sites']} | {min(med):.3f}–{max(med):.3f} | "
                    f"{lo:.3f}–{hi:.3f} | {r['within_10pct']}/{r['n_sites']} | "
                    f"{r['predict_seconds']:.2g} |")
    return "\n".join(rows)


def _share(x: float) -> str:
    """A coverage in a per-entry list: 1.0, else two decimals without the leading zero."""
    return "1.0" if x == 1.0 else f"{x:.2f}".removeprefix("0")


@kind("plan_prediction_open_world")
def plan_prediction_open_world(args: list[tuple[Path, ...]]) -> str:
    """The same over open-world truths (plan_prediction.py --open-world): sites whose median
    ratio is within 25 %, and the inertia's 90 % coverage."""
    rows = ["| scenario, open-world seeds | sites within ±25 % (median fitted/predicted) | "
            "median ratio, range over sites | inertia 90 % coverage (per entry) |",
            "|---|---|---|---|"]
    for r in _results(args):
        med = _ratios(r)
        k = sum(abs(m - 1.0) <= 0.25 for m in med)
        within = f"**{k}/{len(med)}**" if k == len(med) else f"{k}/{len(med)}"
        per = " ".join(_share(x) for x in r["coverage90_per_entry"])
        rows.append(f"| `{r['scenario']}`, {r['seeds']} seeds | {within} | "
                    f"{min(med):.3f}–{max(med):.3f} | {r['coverage90']:.3f} ({per}) |")
    return "\n".join(rows)


@kind("plan_wheel_axis")
def plan_wheel_axis(args: list[tuple[Path, ...]]) -> str:
    """Fitted over predicted sd of the wheel's axis and the inertia, median over open-world
    seeds (range), and the 90 % cone's coverage (benchmarks/plan_wheel_axis.py records)."""
    rows = ["| scenario | u4_x | u4_y | u4_z | Ixx…Iyz | largest angular sd | 90 % cone radius | "
            "90 % cone coverage | per-component coverage |", "|" + "---|" * 9]
    axis = ("u4_x", "u4_y", "u4_z")
    for r in (_json(path) for group in args for path in group):
        med, lo, hi = r["ratio_median"], r["ratio_min"], r["ratio_max"]
        inertia = [v for k, v in med.items() if k not in axis]
        cov, n = r["coverage_cone90"], r["seeds"]
        rows.append(f"| `{r['scenario']}` ({r['wheel']}) | "
                    + " | ".join(f"{med[k]:.3f} ({lo[k]:.2f}–{hi[k]:.2f})" for k in axis)
                    + f" | {min(inertia):.3f}–{max(inertia):.3f} | "
                    f"{r['sd_direction_ratio_median']:.3f} | {r['cone90_ratio_median']:.3f} | "
                    f"**{cov:.2f}** ({round(cov * n)}/{n}) | "
                    + " ".join(f"{r['coverage90_per_site'][k]:.2f}" for k in axis) + " |")
    return "\n".join(rows)


@kind("closed_world_inertia")
def closed_world_inertia(args: list[tuple[Path, ...]]) -> str:
    """Closed-world coverage of the robust inertia model per family
    (benchmarks/coverage_robust_inertia.py records' ``summary``)."""
    rows = ["| family, model | 90 % coverage (seeds × 6) | per entry Ixx … Iyz | moments within "
            "1 % | largest moment error | max R-hat | divergences |", "|" + "---|" * 7]
    for group in args:
        for path in group:
            for key, r in _json(path)["summary"].items():
                n = r["seeds"]
                per = " ".join(f"{x:.1f}" for x in r["coverage_per_entry"].values())
                rows.append(f"| `{key}` | {r['coverage_90']:.3f} ± {r['coverage_se']:.3f} "
                            f"({n} × 6) | {per} | {round(r['budget_pass'] * n)}/{n} | "
                            f"{100 * r['max_rel_moment_error']:.2f} % | {r['max_r_hat']:.3f} | "
                            f"{r['divergences']} |")
    return "\n".join(rows)


def _deg(x: float) -> str:
    return f"{x:.2g}°" if x < 1 else f"{x:.3g}°"


@kind("closed_world_rwa4")
def closed_world_rwa4(args: list[tuple[Path, ...]]) -> str:
    """Closed-world RWA4 axis coverage per family and model
    (benchmarks/coverage_robust_rwa4.py records)."""
    from statistics import median

    rows = ["| family, model | record | 90 % cone covers (binomial sd at 0.9) | axis error median "
            "/ worst | median cone90 | max R-hat | divergences |", "|---|---|---|---|---|---|---|"]
    for group in args:
        for path in group:
            for family, models in _json(path).items():
                for model, fits in models.items():
                    n, k = len(fits), sum(f["covered"] for f in fits)
                    err = [f["err_deg"] for f in fits]
                    div = [f"seed {f['seed']}: {f['divergences']}" for f in fits
                           if f["divergences"]]
                    rows.append(
                        f"| `{family}`, {model} | `{path.name}` | {k}/{n} = {k / n:.2f} ± "
                        f"{(0.09 / n) ** 0.5:.3f} | {_deg(median(err))} / {_deg(max(err))} | "
                        f"{median(f['cone90_deg'] for f in fits):#.3g}° | "
                        f"{max(f['r_hat'] for f in fits):.3f} | "
                        + (f"{sum(f['divergences'] for f in fits)} ({', '.join(div)})" if div
                           else "0") + " |")
    return "\n".join(rows)


def _jsonl(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines() if line]


@kind("open_world_inertia")
def open_world_inertia(args: list[tuple[Path, ...]]) -> str:
    """Open-world inertia coverage per family and model (benchmarks/coverage_open_world.py
    records): all entries' 90 % coverage with its binomial and seed-clustered sd (the sd of
    the per-seed coverage over the seeds, / √seeds), per entry, budget, adequacy, max |z|."""
    from statistics import stdev

    rows = ["| family | model | 90 % coverage (binomial sd; seed-clustered sd) | per entry Ixx "
            "Iyy Izz Ixy Ixz Iyz | budget | adequacy ok | max \\|z\\| |", "|" + "---|" * 7]
    records = [r for group in args for path in group for r in _jsonl(path)]
    for family in dict.fromkeys(r["family"] for r in records):
        seeds = [r for r in records if r["family"] == family]
        for i, model in enumerate(dict.fromkeys(m for r in seeds for m in r["fits"])):
            fits = [r["fits"][model] for r in seeds if model in r["fits"]]
            n_seeds, per_entry = len(fits), list(zip(*(f["hit"] for f in fits), strict=True))
            hits = [h for f in fits for h in f["hit"]]
            k, n = sum(hits), len(hits)
            cov = k / n
            se = (cov * (1 - cov) / n) ** 0.5 if 0 < cov < 1 else (0.09 / n) ** 0.5
            clustered = stdev(sum(f["hit"]) / len(f["hit"]) for f in fits) / n_seeds ** 0.5
            z = max(abs(x) for f in fits for x in f["z"])
            first = f"| `{family}` |" if i == 0 else "| |"
            rows.append(f"{first} {model} | {cov:.3f} ± {se:.3f}; {clustered:.3f} ({k}/{n}) | "
                        + " ".join(_share(sum(e) / n_seeds) for e in per_entry)
                        + f" | {sum(f['budget'] for f in fits)}/{n_seeds} | "
                        f"{sum(f['adequacy_ok'] for f in fits)}/{n_seeds} | "
                        + (f"{z:.1f}" if z < 10 else f"{z:.0f}") + " |")
    return "\n".join(rows)


def _coverage(k: int, n: int) -> str:
    """``k/n = p ± sd``: the binomial sd at p, at the nominal 0.9 where p is 0 or 1."""
    p = k / n
    return f"{k}/{n} = {p:.3f} ± {(p * (1 - p) / n if 0 < p < 1 else 0.09 / n) ** 0.5:.3f}"


@kind("open_world_rwa4")
def open_world_rwa4(args: list[tuple[Path, ...]]) -> str:
    """Open-world RWA4 axis per family and model (benchmarks/coverage_open_world.py records):
    90 % cone coverage, axis error, cone, budget, adequacy, R-hat and divergences."""
    from statistics import median

    rows = ["| family | model | 90 % cone covers | axis error median / worst | median 90 % cone "
            "| budget | adequacy ok | max R-hat, divergences |", "|" + "---|" * 8]
    records = [r for group in args for path in group for r in _jsonl(path)]
    for family in dict.fromkeys(r["family"] for r in records):
        seeds = [r for r in records if r["family"] == family]
        for i, model in enumerate(dict.fromkeys(m for r in seeds for m in r["fits"])):
            fits = [r["fits"][model] for r in seeds if model in r["fits"]]
            n, err = len(fits), [f["error"][0] for f in fits]
            first = f"| `{family}` |" if i == 0 else "| |"
            rows.append(f"{first} {model} | {_coverage(sum(f['hit'][0] for f in fits), n)} | "
                        f"{median(err):#.3g}° / {max(err):#.3g}° | "
                        f"{median(f['cone90_deg'] for f in fits):#.3g}° | "
                        f"{sum(f['budget'] for f in fits)}/{n} | "
                        f"{sum(f['adequacy_ok'] for f in fits)}/{n} | "
                        f"{max(f['r_hat'] for f in fits):.3f}, "
                        f"{sum(f['divergences'] for f in fits)} |")
    return "\n".join(rows)


@kind("open_world_thrust")
def open_world_thrust(args: list[tuple[Path, ...]]) -> str:
    """Open-world thrust coverage per record, family and model (coverage_open_world.py
    records): all entries' 90 % coverage, per entry, F's error and sd relative to its truth
    (sd = error / z), the worst z of F, budget, R-hat and divergences."""
    from statistics import median, quantiles

    rows = ["| family | model, seeds | 90 % coverage | per entry F τd τr τf | \\|F error\\| "
            "median / 90th pct / worst | worst z(F) | median sd(F) | budget (10 %) | max R-hat, "
            "divergences |", "|" + "---|" * 9]
    for group in args:
        records = [r for path in group for r in _jsonl(path)]
        for family in dict.fromkeys(r["family"] for r in records):
            seeds = [r for r in records if r["family"] == family]
            for model in dict.fromkeys(m for r in seeds for m in r["fits"]):
                fits = [r["fits"][model] for r in seeds if model in r["fits"]]
                n = len(fits)
                hits = [h for f in fits for h in f["hit"]]
                per = " ".join(_share(sum(e) / n)
                               for e in zip(*(f["hit"] for f in fits), strict=True))
                err = [100 * abs(f["error"][0]) / f["truth"][0] for f in fits]
                sd = [100 * abs(f["error"][0] / f["z"][0]) / f["truth"][0] for f in fits]
                zcell = f"{max((f['z'][0] for f in fits), key=abs):+.1f}".replace("-", "−")
                rows.append(
                    f"| `{family}` | {model}, {n} | {_coverage(sum(hits), len(hits))} | {per} | "
                    f"{median(err):.2f} % / {quantiles(err, n=10, method='inclusive')[-1]:.2f} % "
                    f"/ {max(err):.2f} % | {zcell} | {median(sd):.2f} % | "
                    f"{sum(f['budget'] for f in fits)}/{n} | "
                    f"{max(f['r_hat'] for f in fits):.3f}, {sum(f['divergences'] for f in fits)} |")
    return "\n".join(rows)


@kind("health_campaign")
def health_campaign(args: list[tuple[Path, ...]]) -> str:
    """The thruster-health acceptance campaign per record (benchmarks/health_campaign.py):
    detection, delay, quiet controls and the change date's interval coverage."""
    rows = ["| seeds | detected | delay, events: median / 90 % / max | control quiet (every look "
            "< 0.05) | before the change quiet | 90 % interval covers (binomial sd) | 50 % "
            "covers (sd) |", "|" + "---|" * 7]
    for r in (_json(path) for group in args for path in group):
        n, d = r["seeds"], r["delay_events"]
        rows.append(f"| {r['first_seed']}-{r['first_seed'] + n - 1} | {d['detected']}/{n} | "
                    f"{d['median']:g} / {d['q90']:g} / {d['max']:g} | "
                    f"{round(r['control_quiet_fraction'] * n)}/{n} | "
                    f"{round(r['pre_change_quiet_fraction'] * n)}/{n} | "
                    f"{r['coverage_90']:.3f} ({r['coverage_90_sd']:.3f}) | "
                    f"{r['coverage_50']:.3f} ({r['coverage_50_sd']:.3f}) |")
    return "\n".join(rows)


def _ratio(x: float) -> str:
    return f"{x:.2f}" if x < 10 else f"{x:.0f}"


@kind("plan_thrust")
def plan_thrust(args: list[tuple[Path, ...]]) -> str:
    """Fitted over predicted sd of the thrust fit's sites, median over open-world seeds
    (benchmarks/plan_thrust.py records; a record's ``repredicted`` sites where it has them)."""
    rows = ["| scenario | F | tau_delay | tau_rise | tau_fall | Ixx…Izz | Ixy…Iyz | sites within "
            "±25 % | 90 % coverage (all sites) | R-hat, divergences |", "|" + "---|" * 10]
    for r in _results(args):
        sites = r.get("repredicted", {}).get("sites", r["sites"])
        med = {k: v["ratio_median"] for k, v in sites.items()}
        f, k = sites["F"], sum(abs(m - 1.0) <= 0.25 for m in med.values())
        within = f"{k}/{len(med)}"
        cov = r["sites"]
        rows.append(
            f"| `{r['scenario']}` | {_ratio(f['ratio_median'])} ({_ratio(f['ratio_min'])}–"
            f"{_ratio(f['ratio_max'])}) | "
            + " | ".join(_ratio(med[t]) for t in ("tau_delay", "tau_rise", "tau_fall")) + " | "
            + " | ".join(f"{_ratio(min(med[e] for e in es))}–{_ratio(max(med[e] for e in es))}"
                         for es in (("Ixx", "Iyy", "Izz"), ("Ixy", "Ixz", "Iyz")))
            + f" | {f'**{within}**' if k == len(med) else within} | {r['coverage90']:.2f} "
            f"(F {cov['F']['coverage90']:.2f}, τ "
            + "/".join(f"{cov[t]['coverage90']:.1f}" for t in ("tau_delay", "tau_rise", "tau_fall"))
            + f") | ≤ {r['max_r_hat']:.3f}, {r['divergences']} |")
    return "\n".join(rows)


def _verdict(values: list[float | None], threshold: float) -> str:
    """``failed/n (median, largest)`` of one check's statistic (``; smallest`` when every one
    failed); a statistic the check could not compute (None) passes."""
    from statistics import median

    ok = [v for v in values if v is not None]
    k, n = sum(v > threshold for v in ok), len(values)
    if not ok:
        return f"{k}/{n} (n/a)"
    if k == n:
        return f"{k}/{n} ({median(ok):.2f}; smallest {min(ok):.2f})"
    return f"{k}/{n} ({median(ok):.2f}, {max(ok):.2f})"


def _verdict_rows(cases: dict[str, list[dict]], thresholds: dict[str, float]) -> list[str]:
    rows = []
    for case, stats in cases.items():
        cells = [_verdict([s[c] for s in stats], t) for c, t in thresholds.items()]
        fails = sum(any(s[c] is not None and s[c] > t for c, t in thresholds.items())
                    for s in stats)
        rows.append(f"| {case} | " + " | ".join(cells) + f" | **{fails}/{len(stats)}** |")
    return rows


def _seeds(records: list[dict]) -> str:
    first = min(r["args"]["first_seed"] for r in records)
    return f"{first}-{first + sum(r['args']['seeds'] for r in records) - 1}"


@kind("verdict_health")
def verdict_health(args: list[tuple[Path, ...]]) -> str:
    """The health campaign's adequacy verdict per model, control and degraded campaigns
    pooled (benchmarks/verdict_false_alarms.py health records; ``A+B``: seeds pooled)."""
    from cassini_bayes.inference.adequacy import PRIOR_CONFLICT_SD, Z_THRESHOLD

    thresholds = {"inertia_conflict": PRIOR_CONFLICT_SD, "held_out": Z_THRESHOLD}
    rows = ["| events | seeds | model | `inertia_conflict` | `held_out` | any check |",
            "|" + "---|" * 6]
    for group in args:
        records = [_json(path) for path in group]
        cases: dict[str, list[dict]] = {}
        for rec in records:
            for campaign in rec["raw"].values():
                for seed in campaign:
                    for model, st in seed.items():
                        if model != "seed":
                            cases.setdefault(f"`{model}`", []).append(st)
        head = f"| {records[0]['args']['events']} | {_seeds(records)} "
        rows += [head + r for r in _verdict_rows(cases, thresholds)]
    return "\n".join(rows)


@kind("verdict_leak")
def verdict_leak(args: list[tuple[Path, ...]]) -> str:
    """The leak monitor's adequacy verdict per model, on stretches without and with a leak
    (benchmarks/verdict_false_alarms.py leak records)."""
    from cassini_bayes.inference.adequacy import AUTOCORR_MAX, PRIOR_CONFLICT_SD, Z_THRESHOLD

    thresholds = {"residual_fit": Z_THRESHOLD, "prior_data_conflict": PRIOR_CONFLICT_SD,
                  "residual_autocorrelation": AUTOCORR_MAX}
    rows = ["| stretches | model | `residual_fit` | `prior_data_conflict` | "
            "`residual_autocorrelation` | any check |", "|" + "---|" * 6]
    for group in args:
        stretches = [s for path in group for s in _json(path)["raw"]["stretches"]]
        for leak in (False, True):
            sel = [s for s in stretches if s["leak"] == leak]
            models = [k for k, v in sel[0].items() if isinstance(v, dict) and "residual_fit" in v]
            cases = {f"{len(sel)} {'with' if leak else 'without'} a leak | `{m}`":
                     [s[m] for s in sel] for m in models}
            rows += _verdict_rows(cases, thresholds)
    return "\n".join(rows)


@kind("verdict_budget")
def verdict_budget(args: list[tuple[Path, ...]]) -> str:
    """The budget's ``shared_inertia`` check on clean and epoch-mixed pairs of runs
    (benchmarks/verdict_false_alarms.py budget records; ``A+B``: seeds pooled)."""
    from cassini_bayes.inference.adequacy import Z_THRESHOLD

    rows = []
    for group in args:
        records = [_json(path) for path in group]
        pairs = [p for rec in records for p in rec["raw"]["pairs"]]
        rows += [f"| seeds {_seeds(records)} | `shared_inertia` (median, largest) | any check |",
                 "|" + "---|" * 3]
        rows += _verdict_rows({f"`{case}`": [{"shared_inertia": p[case]} for p in pairs]
                               for case in ("clean", "epochs")},
                              {"shared_inertia": Z_THRESHOLD})
    return "\n".join(rows)


def blocks(text: str, md: Path) -> list[tuple[re.Match, str, list[tuple[Path, ...]]]]:
    """Each table block of ``text``: the match, its kind and its records' paths; exits with a
    one-line message naming ``md`` for an unknown kind, a missing record or one without a
    manifest."""
    out = []
    for m in BLOCK.finditer(text):
        line = text.count("\n", 0, m.start()) + 1
        name, *rel = shlex.split(m["spec"])
        groups = [tuple((md.parent / r).resolve() for r in arg.split("+")) for arg in rel]
        where = f"{_rel(md)}:{line}"
        if name not in KINDS:
            sys.exit(f"{where}: unknown table kind {name!r}; known: {', '.join(sorted(KINDS))}")
        for p in (p for group in groups for p in group):
            if not p.exists():
                sys.exit(f"{where}: records {_rel(p)} not found")
            if not (manifest_path(p).exists() or (p.parent / "manifest.json").exists()):
                sys.exit(f"{where}: records {_rel(p)} have no manifest; write one "
                         "(benchmarks/_provenance.py)")
        out.append((m, name, groups))
    if text.count("<!-- table:") != len(out) or text.count("<!-- /table -->") != len(out):
        sys.exit(f"{_rel(md)}: a table marker without its pair")
    return out


def render(md: Path) -> tuple[str, list[str]]:
    """The text of ``md`` with every table block regenerated, and the blocks that changed."""
    text = md.read_text(encoding="utf-8")
    pieces, changed, at = [], [], 0
    for m, name, groups in blocks(text, md):
        body = KINDS[name](groups) + "\n"
        if body != m["body"]:
            changed.append(f"{_rel(md)}:{text.count(chr(10), 0, m.start()) + 1}: "
                           f"table {m['spec']!r} differs from its records")
        pieces += [text[at:m.start("body")], body]
        at = m.end("body")
    return "".join(pieces) + text[at:], changed


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true",
                    help="change nothing; exit 1 if a table differs from its records")
    ap.add_argument("--docs", type=Path, default=DOCS, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    differ = []
    for md in sorted(args.docs.rglob("*.md")):
        text, changed = render(md)
        differ += changed
        if changed and not args.check:
            tmp = md.with_name(md.name + ".tmp")
            tmp.write_text(text, encoding="utf-8")
            os.replace(tmp, md)
    for line in differ:
        print(line if args.check else line.replace("differs from its records", "rewritten"))
    return 1 if differ and args.check else 0


if __name__ == "__main__":
    sys.exit(main())
