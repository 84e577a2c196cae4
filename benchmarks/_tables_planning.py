"""Table kinds of the planning benchmarks' records (docs/planning/); registered in
:mod:`_tables` by import."""

from __future__ import annotations

from pathlib import Path

from _tables import Records, kind, read_json, share_cell


def _results(args: list[Records]) -> list[dict]:
    """Every result of the records, each marked ``regular_clock`` where its record's settings
    state the clock regular (``plan_thrust.py --regular-clock``)."""
    out = []
    for path in (p for group in args for p in group):
        rec = read_json(path)
        clock = bool(rec.get("settings", {}).get("regular_clock"))
        out += [{**r, "regular_clock": True} if clock else r for r in rec["results"]]
    return out


def _ratios(result: dict) -> list[float]:
    return [site["ratio_median"] for site in result["sites"].values()]


@kind("plan_prediction")
def plan_prediction(args: list[Records]) -> str:
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


@kind("plan_prediction_open_world")
def plan_prediction_open_world(args: list[Records]) -> str:
    """The same over open-world truths (plan_prediction.py --open-world): sites whose median
    ratio is within 25 %, and the inertia's 90 % coverage."""
    rows = ["| scenario, open-world seeds | sites within ±25 % (median fitted/predicted) | "
            "median ratio, range over sites | inertia 90 % coverage (per entry) |",
            "|---|---|---|---|"]
    for r in _results(args):
        med = _ratios(r)
        k = sum(abs(m - 1.0) <= 0.25 for m in med)
        within = f"**{k}/{len(med)}**" if k == len(med) else f"{k}/{len(med)}"
        per = " ".join(share_cell(x) for x in r["coverage90_per_entry"])
        rows.append(f"| `{r['scenario']}`, {r['seeds']} seeds | {within} | "
                    f"{min(med):.3f}–{max(med):.3f} | {r['coverage90']:.3f} ({per}) |")
    return "\n".join(rows)


@kind("plan_wheel_axis")
def plan_wheel_axis(args: list[Records]) -> str:
    """Fitted over predicted sd of the wheel's axis and the inertia, median over open-world
    seeds (range), and the 90 % cone's coverage (benchmarks/plan_wheel_axis.py records)."""
    rows = ["| scenario | u4_x | u4_y | u4_z | Ixx…Iyz | largest angular sd | 90 % cone radius | "
            "90 % cone coverage | per-component coverage |", "|" + "---|" * 9]
    axis = ("u4_x", "u4_y", "u4_z")
    for r in (read_json(path) for group in args for path in group):
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


def _ratio(x: float) -> str:
    return f"{x:.2f}" if x < 10 else f"{x:.0f}"


@kind("plan_thrust")
def plan_thrust(args: list[Records]) -> str:
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
            f"| `{r['scenario']}`{', regular clock' if r.get('regular_clock') else ''}"
            + (f", median over {r['predicted_over_truths'] + 1} truths"
               if r.get("predicted_over_truths") else "") + " | "
            f"{_ratio(f['ratio_median'])} ({_ratio(f['ratio_min'])}–"
            f"{_ratio(f['ratio_max'])}) | "
            + " | ".join(_ratio(med[t]) for t in ("tau_delay", "tau_rise", "tau_fall")) + " | "
            + " | ".join(f"{_ratio(min(med[e] for e in es))}–{_ratio(max(med[e] for e in es))}"
                         for es in (("Ixx", "Iyy", "Izz"), ("Ixy", "Ixz", "Iyz")))
            + f" | {f'**{within}**' if k == len(med) else within} | {r['coverage90']:.2f} "
            f"(F {cov['F']['coverage90']:.2f}, τ "
            + "/".join(f"{cov[t]['coverage90']:.1f}" for t in ("tau_delay", "tau_rise", "tau_fall"))
            + f") | ≤ {r['max_r_hat']:.3f}, {r['divergences']} |")
    return "\n".join(rows)


@kind("plan_thrust_thruster")
def plan_thrust_thruster(args: list[Records]) -> str:
    """Mode ``thruster`` records of benchmarks/plan_thrust.py: fitted over predicted sd, median
    over the seeds (range over the sites of a group), 90 % coverage, the learned noise
    levels over the sensors' and the learned time-tag sd over the flown (median over the fits;
    — where a record predates the learned tag sd)."""
    from statistics import median

    groups = (("F[…]", lambda n: n.startswith("F[")), ("com", lambda n: n.startswith("com_")),
              ("τd/τr/τf", lambda n: n.startswith("tau_")),
              ("Ixx…Izz", lambda n: n in ("Ixx", "Iyy", "Izz")),
              ("Ixy…Iyz", lambda n: n in ("Ixy", "Ixz", "Iyz")))
    rows = ["| scenario | truths, seeds | " + " | ".join(g for g, _ in groups)
            + " | sites within ±25 % | 90 % coverage: all (least site) | learned σ_ω, σ_ρ / "
            "sensors' | learned tag sd / flown | R-hat, divergences |", "|" + "---|" * 12]
    for r in _results(args):
        sites = r["sites"]
        cells = []
        for _, pick in groups:
            med = [v["ratio_median"] for n, v in sites.items() if pick(n)]
            cells.append(" / ".join(_ratio(m) for m in med) if len(med) <= 3
                         else f"{_ratio(min(med))}–{_ratio(max(med))}")
        k = sum(abs(v["ratio_median"] - 1.0) <= 0.25 for v in sites.values())
        within = f"{k}/{len(sites)}"
        least = min(sites, key=lambda n: sites[n]["coverage90"])
        noise = [median(f["noise_over_sensor"][j] for f in r["fits"]) for j in (0, 1)]
        tags = [f["tag_sd_learned_s"] / f["tag_sd_flown_s"] for f in r["fits"]
                if f.get("tag_sd_flown_s")]
        tag = f"{median(tags):.2f}" if tags else "—"
        truths = (r["truths"].replace("_", "-") + "".join(f", no {e}" for e in r.get("without", []))
                  + (", regular clock" if r.get("regular_clock") else ""))
        rows.append(f"| `{_scenario_label(r['scenario'])}` | {truths}, {r['seeds']} | "
                    + " | ".join(cells)
                    + f" | {f'**{within}**' if k == len(sites) else within} | "
                    f"{r['coverage90']:.2f} ({least} {sites[least]['coverage90']:.2f}) | "
                    f"{noise[0]:.2f}, {noise[1]:.2f} | {tag} | ≤ {r['max_r_hat']:.3f}, "
                    f"{r['divergences']} |")
    return "\n".join(rows)


@kind("thrust_noise_at_truth")
def thrust_noise_at_truth(args: list[Records]) -> str:
    """The noise scale the thrust fit's density puts at an open-world truth, over the sensors'
    (benchmarks/thrust_noise_at_truth.py records): every effect, none, and each alone."""
    paths = [path for group in args for path in group]
    recs = [read_json(path) for path in paths]
    cols = list(recs[0]["seeds"][0]["noise_over_sensor"])
    many = len(recs) > 1                    # then a column names each row's record
    rows = [("| record " if many else "") + "| case, seed | "
            + " | ".join(c.replace("_", " ") for c in cols) + " |",
            "|" + "---|" * (len(cols) + 1 + many)]
    for path, r in zip(paths, recs):
        for row in r["seeds"]:
            v = row["noise_over_sensor"]
            flex = ", mode modelled" if r.get("flex") == "model" else ""
            rows.append((f"| `{Path(path).name}` " if many else "")
                        + f"| `{_scenario_label(r['case'])}`{flex}, {row['seed']} | "
                        + " | ".join(f"**{v[c]:.2f}**" if v[c] > 1.25 else f"{v[c]:.2f}"
                                     for c in cols) + " |")
    return "\n".join(rows)


@kind("thrust_scale_ridge")
def thrust_scale_ridge(args: list[Records]) -> str:
    """The thrust fit's density along the common-scale ridge of ``F``, ``I`` and the wheels'
    spin inertias (benchmarks/thrust_scale_ridge.py records): the sd of the scale it implies and
    the offset of its maximum, per variant, beside the wheel prior's own sd along the ridge (two
    significant digits: the fixed density's width is hundredths of a per cent)."""
    rows = ["| case | variant | sd of the scale | its maximum at | the wheel prior's sd |",
            "|---|---|---|---|---|"]
    for path in (p for group in args for p in group):
        for case in read_json(path)["cases"]:
            for r in case["rows"]:
                sd, peak = r["sd"], r["peak_offset"]
                rows.append(f"| `{case['case']}` | {r['variant']} | "
                            + (f"{100 * sd:.2g} %" if sd is not None else "flat") + " | "
                            + (f"{100 * peak:+.2g} %" if peak is not None else "—")
                            + f" | {100 * case['prior_sd']:.2f} % |")
    return "\n".join(rows)


def _scenario_label(scenario: str) -> str:
    """A scenario's name, or the folder of a written scenario.toml."""
    return Path(scenario).parent.name if scenario.endswith(".toml") else scenario


@kind("plan_wheel_axis_vs_baseline")
def plan_wheel_axis_vs_baseline(args: list[Records]) -> str:
    """A planned wheel-axis calibration against the baseline slews, both fitted on the same
    open-world seeds (two benchmarks/plan_wheel_axis.py records: baseline, plan)."""
    from statistics import median

    (base,), (plan,) = args
    recs = [read_json(base), read_json(plan)]
    fits = [r["fits"] for r in recs]

    def med(key: str, sub: str | None = None) -> list[float]:
        return [median(f[key][sub] if sub else f[key] for f in fs) for fs in fits]

    head = (f"| {recs[1]['wheel']} axis, {recs[1]['seeds']} open-world seeds, fitted (median) | "
            f"`{_scenario_label(recs[0]['scenario'])}` | `{_scenario_label(recs[1]['scenario'])}`"
            " | plan vs baseline |")
    rows = [head, "|---|---|---|---|"]
    for label, (b, p) in (("largest angular sd", med("sd_direction_deg")),
                          ("90 % cone", med("cone_deg", "90")),
                          ("error of the posterior mean", med("error_deg"))):
        rows.append(f"| {label} | {b:.4f}° | {p:.4f}° | ×{b / p:.2f} |")
    rows.append(f"| 90 % cone coverage | {recs[0]['coverage_cone90']:.2f} | "
                f"{recs[1]['coverage_cone90']:.2f} | |")
    axis = ("u4_x", "u4_y", "u4_z")
    cells = []
    for r in recs:
        m = r["ratio_median"]
        inertia = [v for k, v in m.items() if k not in axis]
        cells.append(", ".join(f"{m[k]:.2f}" for k in axis)
                     + f" ({min(inertia):.2f}–{max(inertia):.2f})")
    rows.append(f"| fitted / predicted sd: u4_x, u4_y, u4_z (inertia) | {cells[0]} | "
                f"{cells[1]} | |")
    return "\n".join(rows)


@kind("plan_wheel_axis_predicted")
def plan_wheel_axis_predicted(args: list[Records]) -> str:
    """A wheel-axis plan's prediction against its baseline's (a ``plan wheel-axis`` run
    directory's summary.json): sd, cone, the three largest variance shares, limits used."""
    ((run,),) = args
    s = read_json(run / "summary.json")
    b, p = s["baseline"], s["plan"]
    rows = [f"| {s['wheel']} axis, predicted | baseline, same limits | plan | plan vs baseline |",
            "|---|---|---|---|",
            f"| largest angular sd | {b['sd_direction_deg']:.4f}° | {p['sd_direction_deg']:.4f}° "
            f"| ×{s['improvement']['sd_direction']:.2f} |",
            f"| 90 % cone | {b['cone_deg']['90']:.4f}° | {p['cone_deg']['90']:.4f}° | "
            f"×{s['improvement']['cone90']:.2f} |"]
    share = [", ".join(f"{k.replace('_', ' ')} {v:.2f}" for k, v in sorted(
        r["variance_shares"].items(), key=lambda kv: -kv[1])[:3]) for r in (b, p)]
    rows.append(f"| largest variance shares | {share[0]} | {share[1]} | |")
    used = [", ".join(f"{r['usage'][k]:.2f}" for k in ("body_rate", "wheel_speed",
                                                         "wheel_torque")) for r in (b, p)]
    rows.append(f"| limits used: body rate, wheel speed, wheel torque | {used[0]} | {used[1]} | |")
    return "\n".join(rows)


@kind("plan_thrust_vs_shipped")
def plan_thrust_vs_shipped(args: list[Records]) -> str:
    """A planned biasing event against the shipped one, predicted and fitted on open-world
    seeds (two benchmarks/plan_thrust.py records: shipped, plan): the largest sd/budget over
    the sites (which site) and F's sd."""
    (shipped,), (plan,) = args
    rows = ["| | predicted: largest sd/budget | predicted F sd (N) | fitted (open-world seeds, "
            "median): largest sd/budget | fitted F sd (N) |", "|---|---|---|---|---|"]
    cells = []
    for path in (shipped, plan):
        (r,) = read_json(path)["results"]
        site, worst = max(((k, v["fitted_median"] / v["budget"]) for k, v in r["sites"].items()),
                          key=lambda kv: kv[1])
        cells.append((r["scenario"], r["predicted_max_ratio"], r["predicted_worst"],
                      r["sites"]["F"]["predicted"], worst, site,
                      r["sites"]["F"]["fitted_median"], r["seeds"]))
    for scenario, pmax, pworst, pf, fmax, fworst, ff, n in cells:
        rows.append(f"| `{scenario}` | {pmax:.2f} ({pworst}) | {pf:.5f} | {fmax:.2f} ({fworst}), "
                    f"{n} seeds | {ff:.5f} |")
    (_, pa, _, fa, wa, _, ga, _), (_, pb, _, fb, wb, _, gb, _) = cells
    rows.append(f"| plan vs shipped | ×{pa / pb:.2f} | ×{fa / fb:.2f} | ×{wa / wb:.2f} | "
                f"×{ga / gb:.2f} |")
    return "\n".join(rows)


@kind("plan_weak_z")
def plan_weak_z(args: list[Records]) -> str:
    """Predicted sd of the weak manoeuvre over the strong one per inertia entry, the data part
    and as a fit reports it (benchmarks/plan_weak_z.py records); bold where an entry loses at
    least 1.5× what the better of Ixx and Iyy loses."""
    entries = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")
    rows = ["| | " + " | ".join(entries) + " |", "|---" * 7 + "|"]
    for path in (p for group in args for p in group):
        r = read_json(path)
        for part, label in (("sd_data", "data part (common wheel scale known)"),
                            ("sd", "as the fit reports it")):
            ratio = r["ratio"][part]
            floor = 1.5 * max(ratio["Ixx"], ratio["Iyy"])
            cells = [f"**{ratio[e]:.3g}**" if ratio[e] >= floor else f"{ratio[e]:.3g}"
                     for e in entries]
            rows.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(rows)


@kind("plan_thrust_truths")
def plan_thrust_truths(args: list[Records]) -> str:
    """Fitted over predicted sd (median over the open-world seeds) against the predictions
    of benchmarks/plan_thrust.py's records made with ``--truths`` and ``--matched``: at the
    nominal truth, the median over the nominal and the drawn knowledge truths (what a plan can
    know before it flies; a record made without ``--truths`` has none), that median's ≥ 90 %
    interval where the record keeps it and, against that median, the fits' own median's over
    the seeds (a site counts when its interval reaches ±25 %), and at each seed's own truth.
    Mode ``thruster`` records add the centre of mass (x / y / z); a row that repeats one above
    (the nominal truth of records joining the same fits) is shown once."""
    with_com = any("com_x" in r["sites"] for r in _results(args))
    rows = ["| scenario, seeds | prediction | F | " + ("com | " if with_com else "")
            + "tau_delay | tau_rise | tau_fall | Ixx…Izz | Ixy…Iyz | sites within ±25 % |",
            "|" + "---|" * (10 if with_com else 9)]
    for r in _results(args):
        for label, span in _truth_rows(r).items():
            row = f"| `{_scenario_label(r['scenario'])}`, {len(r['fits'])} | {label} | " \
                + _span_cells(span, with_com)
            if row not in rows:
                rows.append(row)
    return "\n".join(rows)


def _truth_rows(r: dict) -> dict[str, dict[str, tuple[float, float]]]:
    """Each prediction of record ``r`` (label → site → (low, high) fitted/predicted median;
    equal but for the median's interval)."""
    from statistics import median

    from cassini_bayes.plan.truths import median_interval

    names, sites, fits = list(r["sites"]), r["sites"], r["fits"]
    preds = {"nominal truth": [[sites[n].get("predicted_nominal", sites[n]["predicted"])
                                for n in names]] * len(fits)}
    if r["predicted_over_truths"]:
        preds[f"median over {r['predicted_over_truths'] + 1} truths"] = \
            [[sites[n]["predicted"] for n in names]] * len(fits)
    if all("predicted_matched" in f for f in fits):
        preds["each seed's own truth"] = [f["predicted_matched"] for f in fits]
    out = {}
    for label, pred in preds.items():
        med = {n: median(f["sd"][i] / p[i] for f, p in zip(fits, pred))
               for i, n in enumerate(names)}
        out[label] = {n: (m, m) for n, m in med.items()}
    if r["predicted_over_truths"] and all("predicted_interval90" in sites[n] for n in names):
        out["that median's 90 % interval"] = {
            n: tuple(median(f["sd"][i] for f in fits) / p
                     for p in sites[n]["predicted_interval90"][::-1])
            for i, n in enumerate(names)}
        lo, hi = median_interval([f["sd"] for f in fits])
        out["the fits' median's 90 % interval, against that median"] = {
            n: (lo[i] / sites[n]["predicted"], hi[i] / sites[n]["predicted"])
            for i, n in enumerate(names)}
    if "predicted_tag_sd_s" in r:
        tags = f", the file's tag sd taken as {r['predicted_tag_sd_s'] * 1e3:g} ms"
        out = {label + tags: v for label, v in out.items()}
    return out


def _span_cells(span: dict[str, tuple[float, float]], with_com: bool) -> str:
    """The cells of one :func:`plan_thrust_truths` row from its sites' (low, high) ratios."""
    def cell(lo: float, hi: float) -> str:
        return _ratio(lo) if lo == hi else f"{_ratio(lo)}–{_ratio(hi)}"

    def group(names) -> str:
        los, his = [span[n][0] for n in names], [span[n][1] for n in names]
        if len(names) == 1:
            return cell(*span[names[0]])
        if all(lo == hi for lo, hi in zip(los, his)):
            return f"{_ratio(min(los))}–{_ratio(max(los))}"
        return cell(min(los), max(his))

    k = sum(lo <= 1.25 and hi >= 0.75 for lo, hi in span.values())
    thrusts = [n for n in span if n == "F" or n.startswith("F[")]
    com = ([" / ".join(cell(*span[c]) if c in span else "—" for c in ("com_x", "com_y", "com_z"))]
           if with_com else [])
    within = f"{k}/{len(span)}"
    return " | ".join([group(thrusts), *com]
                      + [cell(*span[t]) for t in ("tau_delay", "tau_rise", "tau_fall")]
                      + [group(es) for es in (("Ixx", "Iyy", "Izz"), ("Ixy", "Ixz", "Iyz"))]
                      + [f"**{within}**" if k == len(span) else within]) + " |"


_PROBE_TAGS = {"all": "every sample", "none": "none (the true times)",
               "near": "the {n} within 0.2 s of a pulse's command or end",
               "far": "the {n} 0.2 s or more from a pulse's command or end",
               "start": "the {n} at a pulse's command", "end": "the {n} at a pulse's end",
               "grid": "every sample, the labels then on their fitted grid (its error: mean "
                       "{mean:.2f}, largest {largest:.1f} ms)",
               "clock": "every sample, on a stated regular clock (the grid's errors integrated "
                        "out)"}


@kind("thrust_mode_probe")
def thrust_mode_probe(args: list[Records]) -> str:
    """The thrust fit's Laplace mode on one open-world flight (benchmarks/thrust_mode_probe.py
    records): the time constants (± their Laplace sd where the record has it) and the tag scale,
    per variant of the effects and the samples that keep their time-tag errors."""
    from cassini_bayes.simulate.open_world import EFFECTS_OFF

    rows = ["| case, seed | time tags kept on (largest) | other open-world effects | "
            "τd, τr, τf at the mode [± Laplace sd], ms (truth) | tag scale |",
            "|---|---|---|---|---|"]
    for path in (p for group in args for p in group):
        rec = read_json(path)
        for r in rec["results"]:
            off = set(r["without"]) - {"time_tags"}
            others = ("none" if off == set(EFFECTS_OFF) - {"time_tags"} else
                      "all but " + ", ".join(sorted(off)) if off else "all")
            tags = _PROBE_TAGS[r["tags"]].format(n=r["tagged"], mean=1e3 * r.get("mean_tag_s", 0.0),
                                                 largest=1e3 * r["largest_tag_s"])
            if r["tags"] not in ("none", "grid"):
                factor = "" if r["tag_factor"] == 1.0 else f" × {r['tag_factor']:g}"
                tags += f"{factor} ({1e3 * r['largest_tag_s']:.1f} ms)"
            sds = r.get("tau_laplace_sd_s", [None] * 3)
            tau = ", ".join(f"{1e3 * m:.1f}" + ("" if d is None else f" ± {1e3 * d:.1f}")
                            for m, d in zip(r["tau_mode_s"], sds))
            truth = ", ".join(f"{1e3 * x:g}" for x in r["tau_truth_s"])
            rows.append(f"| `{_scenario_label(rec['case'].rsplit(':', 1)[0])}`, {r['seed']} | "
                        f"{tags} | {others} | {tau} ({truth}) | "
                        + ("— |" if r["tags"] == "clock" else f"{r['tag_scale_mode']:.2g} |"))
    return "\n".join(rows)


@kind("thrust_probe_com")
def thrust_probe_com(args: list[Records]) -> str:
    """The centre of mass at the thrust fit's Laplace mode, per set of open-world effects left
    on (benchmarks/thrust_mode_probe.py records with ``com_mode_m``), with the fit's nuisance
    prior factor and inertia, and its mode of the first gyro-scale and wheel-tilt terms."""
    import numpy as np

    from cassini_bayes.simulate.open_world import EFFECTS_OFF

    rows = ["| seed | open-world effects on | fit's nuisance priors, inertia | com x, y, z at the "
            "mode ± Laplace sd, mm (truth) | largest \\|error\\|/sd | gyro scale y at the mode "
            "(truth) | wheel 1 tilt at the mode, ° (truth) |",
            "|---|---|---|---|---|---|---|"]
    for path in (p for group in args for p in group):
        for r in read_json(path)["results"]:
            on = [e for e in EFFECTS_OFF if e not in r["without"]]
            m, d, x = (1e3 * np.asarray(r[k], float) for k in
                       ("com_mode_m", "com_laplace_sd_m", "com_truth_m"))
            com = ", ".join(f"{a:.1f} ± {b:.1f}" for a, b in zip(m, d))
            nu = r["nuisance"]
            gyro = [nu["gyro_scale"][k][1] * ("gyro" in on or k == "mode") + 0.0
                    for k in ("mode", "truth")]
            tilt = [", ".join(f"{a * ('tilts' in on or k == 'mode') + 0.0:.2f}"
                              for a in nu["wheel_axes"][k][:2]) for k in ("mode", "truth")]
            rows.append(f"| {r['seed']} | {', '.join(on) or 'none'} | "
                        f"× {r['knowledge_factor']:g}, {r['inertia']} | {com} "
                        f"({', '.join(f'{a:.1f}' for a in x)}) | {np.max(np.abs(m - x) / d):.1f} | "
                        f"{1e3 * gyro[0]:.1f}e-3 ({1e3 * gyro[1]:.1f}e-3) | "
                        f"{tilt[0]} ({tilt[1]}) |")
    return "\n".join(rows)
