"""Table kinds of records that docs/ summarised by hand until issue 30 (docs/evidence.md lists
every table and where it comes from); registered in :mod:`_tables` by import."""

from __future__ import annotations

import math

from _provenance import manifest_path
from _tables import Records, kind, read_json, read_jsonl


def _angle_deg(a: list[float], b: list[float]) -> float:
    """The angle between two directions (degrees)."""
    na, nb = math.hypot(*a), math.hypot(*b)
    return math.degrees(math.acos(min(1.0, sum(x * y for x, y in zip(a, b)) / (na * nb))))


@kind("rcs_posterior")
def rcs_posterior(args: list[Records]) -> str:
    """Before against after of ``benchmarks/rcs_slow_spinup.py posterior`` records (arguments:
    BEFORE AFTER), per case: the mean axes' angle against the combined Monte Carlo se of the
    axis along that shift; each cone radius before → after with the difference in combined
    Monte Carlo se; the largest inertia-mean difference in combined se and in posterior sd."""
    (before,), (after,) = args
    b_recs, a_recs = read_json(before)["records"], read_json(after)["records"]
    rows = ["| case | axis shift / MC se | cone 50 % | cone 90 % | cone 95 % | inertia means |",
            "|---|---|---|---|---|---|"]
    for case, b in b_recs.items():
        a = a_recs[case]
        name, _, prior = case.partition(" (")
        shift = [x - y for x, y in zip(a["mean"], b["mean"])]
        norm = math.hypot(*shift)
        se = math.degrees(math.sqrt(sum((sa ** 2 + sb ** 2) * (d / norm) ** 2 for sa, sb, d
                                        in zip(a["mean_mcse"], b["mean_mcse"], shift))))
        cones = []
        for level in ("50", "90", "95"):
            (rb, eb), (ra, ea) = b["cone_deg"][level], a["cone_deg"][level]
            cones.append(f"{rb:.3f} → {ra:.3f} ({(ra - rb) / math.hypot(ea, eb):+.1f})"
                         .replace("-", "−"))
        z = max(abs(a["inertia"][n][0] - b["inertia"][n][0])
                / math.hypot(a["inertia"][n][1], b["inertia"][n][1]) for n in b["inertia"])
        in_sd = max(abs(a["inertia"][n][0] - b["inertia"][n][0]) / a["inertia"][n][2]
                    for n in b["inertia"])
        rows.append(f"| `{name}`, {prior.rstrip(')')} prior | "
                    f"{_angle_deg(a['mean'], b['mean']):.3f}° / {se:.3f}° | {' | '.join(cones)}"
                    f" | ≤ {z:.1f} se (≤ {in_sd:.3f} sd) |")
    return "\n".join(rows)


def _sd(x: float) -> str:
    """A posterior sd: three significant digits, at least four decimals."""
    return f"{x:.{max(4, 2 - math.floor(math.log10(x)))}f}"


@kind("basilisk_plan")
def basilisk_plan(args: list[Records]) -> str:
    """Predicted against achieved posterior sd of a planned manoeuvre flown in Basilisk
    (``validation/basilisk_espa.py --cases plan`` records, one per seed, pooled in one argument):
    the six inertia entries; a ratio cell in bold where a seed is off by more than 10 %."""
    seeds = [read_json(p)["plan"]["plan_vs_achieved"][:6] for group in args for p in group]
    rows = ["| parameter | predicted sd | achieved sd, seeds "
            f"{', '.join(str(i + 1) for i in range(len(seeds)))} | achieved / predicted | "
            "achieved / predicted at the Basilisk truth |", "|---|---|---|---|---|"]
    for entries in zip(*seeds, strict=True):
        ratios = []
        for key in ("ratio", "ratio_at_truth"):
            cell = ", ".join(f"{e[key]:.3f}" for e in entries)
            ratios.append(f"**{cell}**" if any(abs(e[key] - 1) > 0.1 for e in entries) else cell)
        rows.append(f"| {entries[0]['param']} | {_sd(entries[0]['predicted_sd'])} | "
                    f"{', '.join(_sd(e['achieved_sd']) for e in entries)} | {' | '.join(ratios)} |")
    return "\n".join(rows)


def _at_least(ps: list[float]) -> str:
    """``= p`` where every probability rounds to the same three decimals, else ``≥ min``."""
    cells = {f"{p:.3f}" for p in ps}
    return f"= {cells.pop()}" if len(cells) == 1 else f"≥ {min(ps):.3f}"


@kind("leak_answers")
def leak_answers(args: list[Records]) -> str:
    """The leak monitor's answers against the truth with the simulation's model
    (``cassini_post_probe``; benchmarks/verdict_false_alarms.py leak records, one monitor per
    argument, labelled by its onset rule and the commit its manifest names): on the stretches
    with a leak, then on those without."""
    from statistics import median

    rows = ["| monitor (code) | stretches | alarms | right thruster | wrong thruster | "
            "fraction's 90 % interval covers | fraction error, median / max (% of thrust) | "
            "CPU s per stretch, median |", "|" + "---|" * 8]
    for leak in (True, False):
        for (path,) in args:
            rec, man = read_json(path), read_json(manifest_path(path))
            step = rec["args"].get("onset_step")
            label = (f"{step:g} s onset grid" if step else "continuous onset") + \
                f" ({man['runs'][0]['commit'].split()[0].rstrip(',')})"
            sel = [s for s in rec["raw"]["stretches"] if s["leak"] == leak]
            ans = [s["cassini_post_probe"] for s in sel]
            cells = [f"{len(sel)} {'with a 10 % leak' if leak else 'without'}",
                     str(sum(a["detection_time_s"] is not None for a in ans))]
            if leak:
                wrong: dict[tuple[str, str], list[int]] = {}
                for s, a in zip(sel, ans):
                    if a["thruster"] != s["truth"]["thruster"]:
                        wrong.setdefault((a["thruster"], s["truth"]["thruster"]), []).append(
                            s["seed"])
                bad = [a["p_thruster"] for s, a in zip(sel, ans)
                       if a["thruster"] != s["truth"]["thruster"]]
                err = [100 * abs(a["fraction_mean"] - a["fraction_truth"]) for a in ans]
                cover = sum(lo <= a["fraction_truth"] <= hi
                            for a in ans for lo, hi in [a["fraction_interval"]])
                cells += [f"{len(ans) - len(bad)}/{len(ans)}",
                          (f"{len(bad)}, P {_at_least(bad)}: " + ", ".join(
                              f"{named} for {truth} (seed{'s' * (len(seeds) > 1)} "
                              f"{', '.join(map(str, seeds))})"
                              for (named, truth), seeds in wrong.items())) if bad else "0",
                          f"{cover}/{len(ans)}",
                          f"{median(err):.3g} / {max(err):.3g}"]
            else:
                cells += ["–"] * 4
            rows.append(f"| {label} | {' | '.join(cells)} | "
                        f"{median(a['cpu_s'] for a in ans):.2f} |")
    return "\n".join(rows)


@kind("plan_open_world_gain")
def plan_open_world_gain(args: list[Records]) -> str:
    """A planned manoeuvre against the shipped one over open-world truths
    (benchmarks/plan_prediction.py --open-world records), a row per three arguments: SHIPPED
    PLAN PLAN_DIR (the plan's run directory; its summary.json gives the inertia budgets): the
    plan's sites whose median fitted/predicted sd is within 25 % (range over sites), its
    inertia 90 % coverage, and the fitted largest sd/budget over the six inertia entries,
    median over seeds, shipped → plan, as reported and its data part (the wheels' common
    scale divided out)."""
    from statistics import median

    rows = ["| plan, open-world seeds | sites within ±25 % (range) | inertia 90 % coverage | "
            "fitted largest sd/budget, median: shipped → plan (reported; data part) |",
            "|---|---|---|---|"]
    names = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")
    for (shipped,), (plan,), (plan_dir,) in zip(*[iter(args)] * 3, strict=True):
        params = read_json(plan_dir / "summary.json")["plan"]["parameters"]
        budget = [params[n]["budget"] for n in names]
        (ship,), (own,) = read_json(shipped)["results"], read_json(plan)["results"]

        def worst(result: dict, key: str) -> float:
            return median(max(s / b for s, b in zip(fit[key][:6], budget, strict=True))
                          for fit in result["fits"])

        gains = []
        for key in ("sd", "sd_data"):
            a, b = worst(ship, key), worst(own, key)
            gains.append(f"{a:.3f} → {b:.3f} (×{a / b:.2f})")
        med = [s["ratio_median"] for s in own["sites"].values()]
        rows.append(f"| `{plan_dir.name}` against `{ship['scenario']}`, {own['seeds']} seeds | "
                    f"{sum(abs(m - 1) <= 0.25 for m in med)}/{len(med)} "
                    f"({min(med):.2f}–{max(med):.2f}) | {own['coverage90']:.3f} | "
                    f"{'; '.join(gains)} |")
    return "\n".join(rows)


@kind("plan_vs_shipped")
def plan_vs_shipped(args: list[Records]) -> str:
    """A plan against the shipped manoeuvre, predicted and fitted (benchmarks/plan_prediction.py
    records of the shipped scenario and the plan's scenario.toml, in that order; arguments:
    RECORD PLAN_DIR, whose summary.json gives the inertia budgets): the largest sd/budget over
    the six inertia entries, as reported and its data part (the wheels' common scale divided
    out), fitted as the largest of the entries' medians over seeds."""
    (record,), (plan_dir,) = args
    params = read_json(plan_dir / "summary.json")["plan"]["parameters"]
    ship, plan = read_json(record)["results"]
    names = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")
    rows = [f"| largest sd/budget | shipped `{ship['scenario']}` | plan | plan vs shipped |",
            "|---|---|---|---|"]
    for label, part, key in (("predicted, as reported", "sites", "predicted"),
                             (f"fitted, as reported ({plan['seeds']} seeds)", "sites",
                              "fitted_median"),
                             ("predicted, data part", "data_part", "predicted"),
                             (f"fitted, data part ({plan['seeds']} seeds)", "data_part",
                              "fitted_median")):
        cells = []
        for result in (ship, plan):
            worst, name = max((result[part][n][key] / params[n]["budget"], n) for n in names)
            cells.append((worst, f"{worst:.3f}" + (f" ({name})" if part == "data_part" else "")))
        rows.append(f"| {label} | {cells[0][1]} | {cells[1][1]} | "
                    f"×{cells[0][0] / cells[1][0]:.3g} |")
    return "\n".join(rows)


_BODY = {"sun": "Sun", "earth": "Earth", "jupiter": "Jupiter", "saturn": "Saturn",
         "titan": "Titan"}


@kind("ivp_conics")
def ivp_conics(args: list[Records]) -> str:
    """The largest angle (µrad) of a fitted conic per vector and span, and how long the
    osculating conic of ``t = 0`` holds the requirement (the ``ivp_titan_flyby`` experiment's
    results.json)."""
    (path,), = args
    rec = read_json(path)
    res, months = rec["results"], rec["settings"]["months_days"]
    spans = res["conics"][0]["spans_days"]
    rows = ["| vector | " + " | ".join(f"{d:g} d" for d in spans) + " | osculating holds |",
            "|" + "---|" * (len(spans) + 2)]
    for c in res["conics"]:
        holds = (f"> {months:g} d" if c["osculating_holds_days"] is None
                 else f"{c['osculating_holds_days']:.2g} d")
        rows.append(f"| {_BODY[c['base']]} → {_BODY[c['head']]} | "
                    + " | ".join(f"{x:#.3g}" for x in c["fitted_max_urad"]) + f" | {holds} |")
    return "\n".join(rows)


def _sci(x: float) -> str:
    mantissa, exponent = f"{x:.1e}".split("e")
    return f"{mantissa}e{int(exponent)}"


@kind("ivp_flyby")
def ivp_flyby(args: list[Records]) -> str:
    """Spacecraft → Titan over the flyby span: one conic about Titan, one about Saturn, and the
    Chebyshev segments (the ``ivp_titan_flyby`` experiment's results.json)."""
    (path,), = args
    rec = read_json(path)
    res, step = rec["results"], rec["settings"]["dense_step_s"]
    seg, bounds = res["segments"], res["segments"]["bounds_s"]
    hours = [(b - a) / 3600 for a, b in zip(bounds, bounds[1:])]
    conic = res["spacecraft_conic_max_urad"]
    return "\n".join([
        "| model | numbers | largest angle |", "|---|---|---|",
        f"| one conic about Titan (fitted r0, v0) | 7 | {_sci(conic['titan'])} µrad |",
        f"| one conic about Saturn (fitted r0, v0) | 7 | {_sci(conic['saturn'])} µrad |",
        f"| {seg['count']} Chebyshev segments, orders {', '.join(map(str, seg['orders']))} ("
        + ", ".join(f"{h:.0f} h" if h >= 10 else f"{h:.1f} h" for h in hours)
        + f") | {seg['n_coefficients']} | {seg['dense_max_error_urad']:.1f} µrad on a grid "
        f"every {step:g} s off the nodes |"])


def _per_wheel(group: Records, family: str | None = None) -> list[tuple[dict, dict]]:
    """``(record, per-wheel fit)`` of open-world records (coverage_open_world.py), pooled."""
    return [(r, r["fits"]["per_wheel"]) for path in group for r in read_jsonl(path)
            if "per_wheel" in r["fits"] and family in (None, r["family"])]


def _met(fits: list[tuple[dict, dict]], ok=lambda r, f: f["budget"]) -> str:
    return f"{sum(bool(ok(r, f)) for r, f in fits)}/{len(fits)}"


def _share(fits: list[tuple[dict, dict]]) -> float:
    hits = [h for _, f in fits for h in f["hit"]]
    return sum(hits) / len(hits)


@kind("open_world_budgets")
def open_world_budgets(args: list[Records]) -> str:
    """The papers' budgets of the per-wheel model at 1.5 × the stated knowledge and at it
    (coverage_open_world.py records; arguments: inertia, thrust and RWA4 records, each first
    at 1.5 × then at ``--widen 1.0``): budgets met, the worst error at the stated knowledge,
    and the 90 % coverage there."""
    inertia_wide, inertia, thrust_wide, thrust, rwa4_wide, rwa4 = args
    rows = ["| budget | at 1.5 × (above) | at the stated knowledge | 90 % coverage at the "
            "stated knowledge |", "|---|---|---|---|"]
    fits = _per_wheel(inertia)
    moments = max(100 * abs(e) / t for _, f in fits
                  for e, t in zip(f["error"][:3], f["truth"][:3], strict=True))
    products = max(abs(e) for _, f in fits for e in f["error"][3:6])
    families = list(dict.fromkeys(r["family"] for r, _ in fits))
    rows.append(f"| moments ≤ 1 %, products ≤ 75 kg m² | {_met(_per_wheel(inertia_wide))} | "
                f"{_met(fits)} (moments ≤ {moments:.2f} %, products ≤ {products:#.2g} kg m²) | "
                + ", ".join(f"{_share(_per_wheel(inertia, fam)):.2f}" for fam in families)
                + f" ({', '.join(f'`{fam}`' for fam in families)}) |")
    fits = _per_wheel(thrust)
    families = list(dict.fromkeys(r["family"] for r, _ in fits))
    rows.append(f"| F ≤ 10 % | {_met(_per_wheel(thrust_wide))} | {_met(fits)} | "
                + ", ".join(f"{_share(_per_wheel(thrust, fam)):.2f} (`{fam}`)" for fam in families)
                + " |")

    def within_1pct(r: dict, f: dict) -> bool:
        return abs(f["error"][0]) <= 0.01 * f["truth"][0]

    r, f = max(fits, key=lambda rf: abs(rf[1]["error"][0] / rf[1]["truth"][0]))
    worst = (f"worst {100 * f['error'][0] / f['truth'][0]:+.2f} %, `{r['family']}` seed "
             f"{r['seed']}, z {f['z'][0]:+.1f}").replace("-", "−")
    rows.append(f"| F ≤ 1 % | {_met(_per_wheel(thrust_wide), within_1pct)} | "
                f"{_met(fits, within_1pct)} ({worst}) | F alone: "
                + " and ".join(_met(_per_wheel(thrust, fam), lambda r, f: f["hit"][0])
                               for fam in families) + " |")
    for label, family in (("RWA4 by RWA ≤ 1°", "rwa4_rwa"),
                          ("RWA4 by RCS ≤ 3°, with an inertia calibration", "rwa4_rcs_calibrated"),
                          ("RWA4 by RCS ≤ 3°, the file's ±10 % inertia", "rwa4_rcs")):
        fits = _per_wheel(rwa4, family)
        rows.append(f"| {label} | {_met(_per_wheel(rwa4_wide, family))} | {_met(fits)} (worst "
                    f"{max(f['error'][0] for _, f in fits):#.2g}°) | "
                    f"{_met(fits, lambda r, f: f['hit'][0])} |")
    return "\n".join(rows)


@kind("health_model_choice")
def health_model_choice(args: list[Records]) -> str:
    """The log Bayes factor of the change point over a random walk per campaign and seed, then
    its median and range per campaign (benchmarks/health_model_choice.py records, pooled)."""
    from statistics import median

    rows = ["| campaign | seed | log BF (change point − random walk) |", "|---|---|---|"]
    records = [r for group in args for path in group for r in read_json(path)["rows"]]
    rows += [f"| {r['campaign']} | {r['seed']} | {r['log_bf']:.2f} |" for r in records]
    rows += ["| **median, min, max** | | |"]
    for campaign in dict.fromkeys(r["campaign"] for r in records):
        bf = [r["log_bf"] for r in records if r["campaign"] == campaign]
        rows.append(f"| {campaign} | all {len(bf)} | {median(bf):.2f}, {min(bf):.2f}, "
                    f"{max(bf):.2f} |")
    return "\n".join(rows)


@kind("startup_imports")
def startup_imports(args: list[Records]) -> str:
    """Per case of benchmarks/startup_imports.py (a record per argument): the summed self time
    of the imports and the process's wall time (medians of the record's repeats), the watched
    packages it imported, and the 1-minute load average when measured."""
    rows = ["| case | imports | wall | imported (of jax numpy scipy numpyro arviz xarray "
            "matplotlib rich typer) | load |", "|---|---|---|---|---|"]
    for path in (p for group in args for p in group):
        for r in read_json(path)["rows"]:
            rows.append(f"| `{r['case']}` | {r['imports_s']:.2f} s | {r['wall_s']:.2f} s | "
                        f"{' '.join(r['imported']) or '–'} | {r['load_1min']:.1f} |")
    return "\n".join(rows)


@kind("bench_ivp")
def bench_ivp(args: list[Records]) -> str:
    """Vector evaluations per second of the inertial vector propagator, after compilation
    (benchmarks/bench_ivp.py records: the batch over the median time of the repeats)."""
    labels = {"conic": "conic by Goodyear's method (random elliptic/hyperbolic states, each "
                       "solving Kepler's equation)",
              "chebyshev": "Chebyshev, order 12, 5 segments (segment lookup + Eq 16 recurrence)",
              "numpy_chebval": "NumPy `chebval` baseline, same segments"}
    rows = ["| evaluation | vectors/s |", "|---|---|"]
    for path in (p for group in args for p in group):
        rec = read_json(path)
        rows += [f"| {labels[r['evaluation']]} | {_sci(rec['n'] / r['median_s'])} |"
                 for r in rec["rows"]]
    return "\n".join(rows)


@kind("compile_cache")
def compile_cache(args: list[Records]) -> str:
    """Per run of benchmarks/compile_cache.py (records pooled): wall time, start-up, XLA
    compilation (or cache loading), tracing, lowering, the rest, programs, cache hits and
    misses (– with the cache off), and the 1-minute load average at the run's start."""
    rows = ["| run | wall | start-up (imports) | XLA compile / load | trace | lower | rest "
            "(sampling, checks, files, report) | programs | hits | misses | load |",
            "|" + "---|" * 11]
    for path in (p for group in args for p in group):
        for r in read_json(path)["runs"]:
            rest = r["cli_s"] - r["compile_s"] - r["trace_s"] - r["lower_s"]
            cache = (["–", "–"] if r["hits"] is None or " off" in r["run"]
                     else [str(r["hits"]), str(r["misses"])])
            rows.append(f"| {r['run'].removeprefix('fit ')} | {r['wall_s']:.1f} s | "
                        f"{r['wall_s'] - r['cli_s']:.1f} s | {r['compile_s']:.1f} s | "
                        f"{r['trace_s']:.1f} s | {r['lower_s']:.1f} s | {rest:.1f} s | "
                        f"{r['programs']} | {' | '.join(cache)} | {r['load_1min']:.1f} |")
    return "\n".join(rows)


@kind("thrust_design_events")
def thrust_design_events(args: list[Records]) -> str:
    """The per-thruster impulse design of simulated events (benchmarks/thrust_design_events.py
    records): pulses per thruster, rank of the parameters, thrusters identified, identified
    combinations of the others, and the centre of mass's linearised contraction."""
    designs = [d for group in args for path in group for d in read_json(path)["designs"]]
    names = designs[0]["thrusters"]
    rows = [f"| event | pulses per thruster {names[0]}..{names[-1]} | rank | identified | "
            "combinations | centre of mass (linearised contraction x, y, z) |",
            "|---|---|---|---|---|---|"]
    for d in designs:
        ident = d["identified"]
        idcell = f"all {len(ident)}" if len(ident) == len(d["thrusters"]) else ", ".join(ident)
        combos = ", ".join(f"`{c['label']}`" for c in d["combinations"]) or "none"
        if d["not_fired"]:
            combos += f" ({len(d['not_fired'])} never fire)"
        rows.append(f"| `{d['scenario']}` | {' '.join(str(d['pulses'][n]) for n in names)} | "
                    f"{d['rank']} of {d['parameters']} | {idcell or '–'} | {combos} | "
                    + ", ".join(f"{c:.2f}" for c in d["com_contraction"].values()) + " |")
    return "\n".join(rows)


@kind("health_espa")
def health_espa(args: list[Records]) -> str:
    """The ESPA bus's health campaign against its truth, then its control
    (``benchmarks/health_espa.py`` record): the change, its date, the degraded thruster's ratio
    at the last event and the other channels; the control's false alarm; adequacy, fit time."""
    (path,), = args
    rec = read_json(path)
    deg, ctl = rec["degradation"], rec["control"]
    s, truth = deg["summary"], deg["truth"]
    (name,), frac = truth["degradation"]["thrusters"], truth["degradation"]["fraction"]
    chan = s["channels"][f"F[{name}]"]
    others = [c for k, c in s["channels"].items() if k != f"F[{name}]"]
    last = truth["thrust_n"][-1][name] / truth["thrust_n"][0][name]
    date = s["change_date_days"]
    rows = ["| quantity | truth | posterior |", "|---|---|---|",
            f"| P(a change in the span) | a change | {s['p_change']:.6f} |",
            f"| change date, median and 90 % interval (d) | {truth['degradation']['day']:g} | "
            f"{date['median']:.0f}, [{date['interval_90'][0]:.1f}, {date['interval_90'][1]:.1f}] |",
            f"| {name} at the last event / first calibration: mean, 90 % | {1 - frac:.2f} "
            f"(the step; {last:.3f} with the events' scatter) | {chan['ratio_last_mean']:.3f}, "
            f"[{chan['ratio_last_90'][0]:.3f}, {chan['ratio_last_90'][1]:.3f}] |",
            f"| P({name} more than 5 % down at the last event) | down | "
            f"{chan['p_down_last']:.3f} |",
            f"| P(step \\| change), the {len(others)} others | none stepped | "
            f"{min(c['p_step_given_change'] for c in others):.2f}–"
            f"{max(c['p_step_given_change'] for c in others):.2f} |",
            f"| the {len(others)} others at the last event: mean ratio, 90 % upper | 1 (no step) | "
            f"{min(c['ratio_last_mean'] for c in others):.3f}–"
            f"{max(c['ratio_last_mean'] for c in others):.3f}, ≤ "
            f"{max(c['ratio_last_90'][1] for c in others):.3f} |",
            f"| P(more than 5 % down), the {len(others)} others | healthy | ≤ "
            f"{max(c['p_down_last'] for c in others):.1e} |",
            "", "| campaign | P(change) | P(any channel more than 5 % down), last event | "
            "adequacy: inertia_conflict, held_out (threshold 4) | fit |", "|---|---|---|---|---|"]
    for case, r in (("degradation", deg), ("control (no `[degradation]`)", ctl)):
        sm, checks = r["summary"], r["summary"]["adequacy"]["checks"]
        rows.append(f"| {case} | {sm['p_change']:.3g} | {sm['p_down_last']['any']:.2g} | "
                    f"{'ok' if sm['adequacy']['ok'] else 'fails'}: "
                    f"{checks['inertia_conflict']['statistic']:.2f}, "
                    f"{checks['held_out']['statistic']:.2f} | {r['fit_wall_s']:.0f} s |")
    return "\n".join(rows)
