"""Table kinds of the closed- and open-world coverage campaigns (docs/robust/); registered in
:mod:`_tables` by import."""

from __future__ import annotations

from _tables import Records, coverage_cell, kind, read_json, read_jsonl, share_cell


def _families(records: list[dict]):
    """``(family, i, model, seeds, fits)`` per family and model of open-world records, in their
    order: ``seeds`` the family's records, ``fits`` the model's fit in each (``i`` the model's
    index within the family)."""
    for family in dict.fromkeys(r["family"] for r in records):
        seeds = [r for r in records if r["family"] == family]
        for i, model in enumerate(dict.fromkeys(m for r in seeds for m in r["fits"])):
            yield family, i, model, seeds, [r["fits"][model] for r in seeds if model in r["fits"]]


def _axis_fit_cells(fits: list[dict]) -> str:
    """The axis tables' last cells: budget met, adequacy ok, max R-hat and divergences."""
    n = len(fits)
    return (f"{sum(f['budget'] for f in fits)}/{n} | {sum(f['adequacy_ok'] for f in fits)}/{n} | "
            f"{max(f['r_hat'] for f in fits):.3f}, {sum(f['divergences'] for f in fits)} |")


@kind("closed_world_inertia")
def closed_world_inertia(args: list[Records]) -> str:
    """Closed-world coverage of the robust inertia model per family
    (benchmarks/coverage_robust_inertia.py records' ``summary``)."""
    rows = ["| family, model | 90 % coverage (seeds × 6) | per entry Ixx … Iyz | moments within "
            "1 % | largest moment error | max R-hat | divergences |", "|" + "---|" * 7]
    for group in args:
        for path in group:
            for key, r in read_json(path)["summary"].items():
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
def closed_world_rwa4(args: list[Records]) -> str:
    """Closed-world RWA4 axis coverage per family and model
    (benchmarks/coverage_robust_rwa4.py records)."""
    from statistics import median

    rows = ["| family, model | record | 90 % cone covers (binomial sd at 0.9) | axis error median "
            "/ worst | median cone90 | max R-hat | divergences |", "|---|---|---|---|---|---|---|"]
    for group in args:
        for path in group:
            for family, models in read_json(path).items():
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


@kind("open_world_inertia")
def open_world_inertia(args: list[Records]) -> str:
    """Open-world inertia coverage per family and model (benchmarks/coverage_open_world.py
    records): all entries' 90 % coverage with its binomial and seed-clustered sd (the sd of
    the per-seed coverage over the seeds, / √seeds), per entry, budget, adequacy, max |z|."""
    from statistics import stdev

    rows = ["| family | model | 90 % coverage (binomial sd; seed-clustered sd) | per entry Ixx "
            "Iyy Izz Ixy Ixz Iyz | budget | adequacy ok | max \\|z\\| |", "|" + "---|" * 7]
    records = [r for group in args for path in group for r in read_jsonl(path)]
    for family, i, model, seeds, fits in _families(records):
        n_seeds, per_entry = len(fits), list(zip(*(f["hit"] for f in fits), strict=True))
        hits = [h for f in fits for h in f["hit"]]
        k, n = sum(hits), len(hits)
        cov = k / n
        se = (cov * (1 - cov) / n) ** 0.5 if 0 < cov < 1 else (0.09 / n) ** 0.5
        clustered = stdev(sum(f["hit"]) / len(f["hit"]) for f in fits) / n_seeds ** 0.5
        z = max(abs(x) for f in fits for x in f["z"])
        first = f"| `{family}` |" if i == 0 else "| |"
        rows.append(f"{first} {model} | {cov:.3f} ± {se:.3f}; {clustered:.3f} ({k}/{n}) | "
                    + " ".join(share_cell(sum(e) / n_seeds) for e in per_entry)
                    + f" | {sum(f['budget'] for f in fits)}/{n_seeds} | "
                    f"{sum(f['adequacy_ok'] for f in fits)}/{n_seeds} | "
                    + (f"{z:.1f}" if z < 10 else f"{z:.0f}") + " |")
    return "\n".join(rows)


@kind("open_world_rwa4")
def open_world_rwa4(args: list[Records]) -> str:
    """Open-world RWA4 axis per family and model (benchmarks/coverage_open_world.py records):
    90 % cone coverage, axis error, cone, budget, adequacy, R-hat and divergences."""
    from statistics import median

    rows = ["| family | model | 90 % cone covers | axis error median / worst | median 90 % cone "
            "| budget | adequacy ok | max R-hat, divergences |", "|" + "---|" * 8]
    records = [r for group in args for path in group for r in read_jsonl(path)]
    for family, i, model, seeds, fits in _families(records):
        n, err = len(fits), [f["error"][0] for f in fits]
        first = f"| `{family}` |" if i == 0 else "| |"
        rows.append(f"{first} {model} | {coverage_cell(sum(f['hit'][0] for f in fits), n)} | "
                    f"{median(err):#.3g}° / {max(err):#.3g}° | "
                    f"{median(f['cone90_deg'] for f in fits):#.3g}° | "
                    + _axis_fit_cells(fits))
    return "\n".join(rows)


@kind("open_world_thrust")
def open_world_thrust(args: list[Records]) -> str:
    """Open-world thrust coverage per record, family and model (coverage_open_world.py
    records): all entries' 90 % coverage, per entry, F's error and sd relative to its truth
    (sd = error / z), the worst z of F, budget, R-hat and divergences."""
    from statistics import median, quantiles

    rows = ["| family | model, seeds | 90 % coverage | per entry F τd τr τf | \\|F error\\| "
            "median / 90th pct / worst | worst z(F) | median sd(F) | budget (10 %) | max R-hat, "
            "divergences |", "|" + "---|" * 9]
    for group in args:
        records = [r for path in group for r in read_jsonl(path)]
        for family, i, model, seeds, fits in _families(records):
            n = len(fits)
            hits = [h for f in fits for h in f["hit"]]
            per = " ".join(share_cell(sum(e) / n)
                           for e in zip(*(f["hit"] for f in fits), strict=True))
            err = [100 * abs(f["error"][0]) / f["truth"][0] for f in fits]
            sd = [100 * abs(f["error"][0] / f["z"][0]) / f["truth"][0] for f in fits]
            zcell = f"{max((f['z'][0] for f in fits), key=abs):+.1f}".replace("-", "−")
            rows.append(
                f"| `{family}` | {model}, {n} | {coverage_cell(sum(hits), len(hits))} | "
                f"{per} | "
                f"{median(err):.2f} % / {quantiles(err, n=10, method='inclusive')[-1]:.2f} % "
                f"/ {max(err):.2f} % | {zcell} | {median(sd):.2f} % | "
                f"{sum(f['budget'] for f in fits)}/{n} | "
                f"{max(f['r_hat'] for f in fits):.3f}, {sum(f['divergences'] for f in fits)} |")
    return "\n".join(rows)


@kind("rcs_family")
def rcs_family(args: list[Records]) -> str:
    """The RWA4 RCS slow-spin-up family per argument (benchmarks/rcs_slow_spinup.py family
    records; the chart is the record's name, ``family_before…`` or ``family_after…``)."""
    from statistics import median

    rows = ["| chart | seeds | converged | divergences (fits) | max R-hat | min / median bulk ESS "
            "| axis error median / worst | median cone90 |", "|" + "---|" * 8]
    for group in args:
        fits = [f for path in group for f in read_json(path)["records"]
                if group.seeds is None or f["seed"] in group.seeds]
        seeds = sorted(f["seed"] for f in fits)
        chart = group[0].stem.split("_")[1]
        div = [f for f in fits if f["divergences"]]
        each = ", ".join(f"{f['seed']}" + (f": {f['divergences']}" if f["divergences"] > 1 else "")
                         for f in div)
        err, ess = [f["err_deg"] for f in fits], [f["ess_bulk"] for f in fits]
        rows.append(f"| {chart} | {seeds[0]}–{seeds[-1]} | {sum(f['converged'] for f in fits)}/"
                    f"{len(fits)} | {sum(f['divergences'] for f in fits)}"
                    + (f" ({len(div)} fits: seeds {each})" if div else "")
                    + f" | {max(f['r_hat'] for f in fits):.4f} | {min(ess):.0f} / "
                    f"{median(ess):.0f} | {median(err):.2f}° / {max(err):.2f}° | "
                    f"{median(f['cone90_deg'] for f in fits):.2f}° |")
    return "\n".join(rows)


def _setting(opts: dict, thrust: bool = True) -> str:
    """A campaign record's open-world setting in words: the widening, the effects switched off,
    the fits' stated torque knowledge, the drawn time tags' scale and, for a thrust family,
    what the thrust fit did with a flexible mode (coverage_open_world.py options; ``flex``
    ``auto`` is today's ``model``; the other fits have no such option)."""
    parts = [f"widen {opts.get('widen', 1.5):g}"]
    if opts.get("off"):
        parts.append("off " + " ".join(opts["off"]))
    if opts.get("torque_sd_nm"):
        parts.append(f"torque prior {opts['torque_sd_nm']:g} N m")
    if opts.get("time_tag_scale", 1.0) != 1.0:
        parts.append(f"time tags × {opts['time_tag_scale']:.3g}")
    flex = {"auto": "mode modelled", "model": "mode modelled", "check": "mode checked",
            "off": "no mode search"}.get(opts.get("flex"))
    if flex and thrust:
        parts.append(flex)
    return ", ".join(parts)


@kind("open_world_wheel_axis")
def open_world_wheel_axis(args: list[Records]) -> str:
    """Open-world wheel axis of any spacecraft per record, family and model
    (coverage_open_world.py records with ``component_hit``): the setting, the 90 % cone's
    coverage, each axis component's and inertia entry's 90 % interval coverage, all components
    pooled, the axis error (and within 0.5°, the issue-29 criterion), the cone, Brown's budget,
    adequacy, R-hat and divergences."""
    from statistics import median

    rows = ["| family (wheel) | setting | 90 % cone covers | per component u_x u_y u_z Ixx Iyy "
            "Izz Ixy Ixz Iyz | all components | axis error median / worst | within 0.5° | "
            "median 90 % cone | budget (1°) | adequacy ok | max R-hat, divergences |",
            "|" + "---|" * 11]
    for group in args:
        records = [r for path in group for r in read_jsonl(path)]
        for family, i, model, seeds, fits in _families(records):
            n, err = len(fits), [f["error"][0] for f in fits]
            comp = [h for f in fits for h in f["component_hit"]]
            per = " ".join(share_cell(sum(e) / n)
                           for e in zip(*(f["component_hit"] for f in fits), strict=True))
            setting = _setting(seeds[0]["options"], False)
            rows.append(f"| `{family}` ({fits[0]['wheel']}) | {setting}"
                        f"{'' if model == 'per_wheel' else ', ' + model} | "
                        f"{coverage_cell(sum(f['hit'][0] for f in fits), n)} | "
                        f"{per} | {coverage_cell(sum(comp), len(comp))} | "
                        f"{median(err):#.3g}° / {max(err):#.3g}° | "
                        f"{sum(e <= 0.5 for e in err)}/{n} | "
                        f"{median(f['cone90_deg'] for f in fits):#.3g}° | "
                        + _axis_fit_cells(fits))
    return "\n".join(rows)


@kind("open_world_wheel_axis_settings")
def open_world_wheel_axis_settings(args: list[Records]) -> str:
    """The open-world wheel axis's 90 % cone coverage per setting (rows, in record order) and
    family (columns): the same records as :func:`open_world_wheel_axis`, one cell each, bold
    at 0.8 or more."""
    cells: dict[str, dict[str, str]] = {}
    families: dict[str, str] = {}
    for group in args:
        records = [r for path in group for r in read_jsonl(path)]
        for family, _, model, seeds, fits in _families(records):
            setting = _setting(seeds[0]["options"], False) + ("" if model == "per_wheel"
                                                              else ", " + model)
            k, n = sum(f["hit"][0] for f in fits), len(fits)
            families.setdefault(family, f"`{family}` ({fits[0]['wheel']})")
            cells.setdefault(setting, {})[family] = (f"**{k}/{n}**" if k >= 0.8 * n
                                                     else f"{k}/{n}")
    rows = ["| setting | " + " | ".join(families.values()) + " |",
            "|" + "---|" * (len(families) + 1)]
    for setting, row in cells.items():
        rows.append(f"| {setting} | " + " | ".join(row.get(f, "–") for f in families) + " |")
    return "\n".join(rows)


def _axis_stats(group: Records) -> dict[str, dict]:
    """Per family, the per-wheel fits' cone hits, axis errors (°) and cones (°) of one record
    argument (its seeds only, where given)."""
    records = [r for path in group for r in read_jsonl(path)
               if group.seeds is None or r["seed"] in group.seeds]
    out = {}
    for family, _, model, seeds, fits in _families(records):
        if model == "per_wheel":
            out[family] = {"wheel": fits[0].get("wheel", "RWA4"), "n": len(fits),
                           "hit": sum(f["hit"][0] for f in fits),
                           "error": [f["error"][0] for f in fits],
                           "cone": [f["cone90_deg"] for f in fits],
                           "setting": _setting(seeds[0]["options"], False)}
    return out


@kind("open_world_wheel_axis_change")
def open_world_wheel_axis_change(args: list[Records]) -> str:
    """The open-world wheel axis before → after a change of the fit, per family: arguments in
    pairs ``BEFORE AFTER`` of coverage_open_world.py records (the same seeds); the per-wheel
    model's cone coverage, axis error, cone and fits within 0.5°."""
    from statistics import median

    if len(args) % 2:
        raise ValueError("open_world_wheel_axis_change takes records in pairs: BEFORE AFTER")
    rows = ["| family (wheel), setting | cone covers, before → after | axis error median / worst "
            "| median 90 % cone | within 0.5° |", "|" + "---|" * 5]
    for before, after in zip(args[::2], args[1::2]):
        old, new = _axis_stats(before), _axis_stats(after)
        for family in (f for f in new if f in old):
            a, b = old[family], new[family]
            err = [f"{median(x['error']):#.2g}° / {max(x['error']):#.2g}°" for x in (a, b)]
            within = [sum(e <= 0.5 for e in x["error"]) for x in (a, b)]
            rows.append(f"| `{family}` ({b['wheel']}), {b['setting']} | {a['hit']}/{a['n']} → "
                        f"{coverage_cell(b['hit'], b['n'])} | {err[0]} → {err[1]} | "
                        f"{median(a['cone']):#.2g}° → {median(b['cone']):#.2g}° | "
                        f"{within[0]}/{a['n']} → {within[1]}/{b['n']} |")
    return "\n".join(rows)


@kind("open_world_per_thruster")
def open_world_per_thruster(args: list[Records]) -> str:
    """Open-world per-thruster thrust coverage per record (coverage_open_world.py records of
    ``espa_bias*``): the setting (effects switched off), seeds, 90 % coverage over all entries
    and per group (thrusts, impulse bits, centre of mass, time constants), every thrust within
    the 3 % budget, converged fits (R-hat ≤ 1.01, no divergence), adequacy, and whether every
    fit covering under half its entries was flagged (not converged or adequacy failed). In
    pooled records (``A+B``) a later record's seed replaces an earlier one's: a re-fit."""
    import json as _json

    from _provenance import manifest_path

    groups = (("F[", "thrusts"), ("bit[", "bits"), ("com_", "com"), ("tau_", "τ"))
    rows = ["| record | setting | seeds | all entries | thrusts | impulse bits | centre of mass "
            "| time constants | thrusts within 3 % | converged | adequacy ok | bad fits flagged "
            "|", "|" + "---|" * 12]
    for group in args:
        by_seed = {r["seed"]: r for path in group for r in read_jsonl(path)
                   if group.seeds is None or r["seed"] in group.seeds}
        records = [by_seed[s] for s in sorted(by_seed)]
        opts = _json.loads(manifest_path(group[0]).read_text())["options"]
        fits = [r["fits"]["per_wheel"] for r in records]
        seeds = sorted(r["seed"] for r in records)
        cells = []
        for prefix, _ in groups:
            hits = [h for f in fits for e, h in zip(f["entries"], f["hit"], strict=True)
                    if e.startswith(prefix)]
            cells.append(coverage_cell(sum(hits), len(hits)) if hits else "—")
        hits = [h for f in fits for h in f["hit"]]
        ok = [f["r_hat"] <= 1.01 and not f["divergences"] for f in fits]
        bad = [i for i, f in enumerate(fits) if sum(f["hit"]) < len(f["hit"]) / 2]
        flagged = sum(not ok[i] or not fits[i]["adequacy_ok"] for i in bad)
        span = f"{seeds[0]}–{seeds[-1]}" if len(seeds) > 1 else f"{seeds[0]}"
        n = len(fits)
        rows.append(f"| `{'+'.join(p.name for p in group)}` | {_setting(opts)} | {span} ({n}) | "
                    f"{coverage_cell(sum(hits), len(hits))} | " + " | ".join(cells)
                    + f" | {sum(f['budget'] for f in fits)}/{n} | {sum(ok)}/{n} | "
                    f"{sum(f['adequacy_ok'] for f in fits)}/{n} | {flagged}/{len(bad)} |")
    return "\n".join(rows)
