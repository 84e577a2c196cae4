"""Table kinds of the robust models' single-case benchmarks (``docs/robust/``)."""

from __future__ import annotations

import statistics

from _tables import Records, kind, read_json

ENTRIES = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")
Z99 = 2.576   # the 99 % interval's edge in sd (a Normal posterior)


def _signed(x: float, digits: int) -> str:
    """``x`` with its sign, the minus as the typographic one (the docs' tables)."""
    return f"{x:+.{digits}f}".replace("-", "\u2212")


def _fit(path, case: str, model: str) -> dict:
    """One fit of a ``benchmarks/per_wheel_inertia.py`` record."""
    return next(f for f in read_json(path)["fits"] if f["case"] == case and f["model"] == model)


@kind("per_wheel_errors")
def per_wheel_errors(args: list[Records]) -> str:
    """Per entry, the per-wheel and common models on the wheels-off case of one
    ``benchmarks/per_wheel_inertia.py`` record: z (posterior mean − truth in posterior sd), the
    sd (kg m²), and how far beyond its 99 % interval the common model puts an entry."""
    path = args[0][0]
    per, com = (_fit(path, "per-wheel errors", m)["entries"] for m in ("per_wheel", "common"))
    rows = ["| entry | per-wheel z | per-wheel sd | common z | common sd "
            "| common: outside 99 % by |", "|---|---|---|---|---|---|"]
    for n in ENTRIES:
        p, c = per[n], com[n]
        out = "—" if c["in99"] else f"{abs(c['z']) - Z99:.1f} sd"
        z_common = _signed(c["z"], 1) if c["in99"] else f"**{_signed(c['z'], 1)}**"
        rows.append(f"| {n} | {_signed(p['z'], 2)} | {p['sd']:.3g} | {z_common} | "
                    f"{c['sd']:.3g} | {out} |")
    return "\n".join(rows)


@kind("per_wheel_models")
def per_wheel_models(args: list[Records]) -> str:
    """A row per model on the wheels-off case of each record: z per entry, the largest R-hat
    and the divergences (``benchmarks/per_wheel_inertia.py``)."""
    rows = ["| model | " + " | ".join(ENTRIES) + " | R-hat | divergences |",
            "|---" * (len(ENTRIES) + 3) + "|"]
    for path in (p for group in args for p in group):
        for model in ("per_wheel", "common"):
            f = _fit(path, "per-wheel errors", model)
            zs = " | ".join(_signed(f["entries"][n]["z"], 2) for n in ENTRIES)
            rows.append(f"| {model.replace('_', '-')} z | {zs} | {f['max_r_hat']:.4f} | "
                        f"{f['divergences']} |")
    return "\n".join(rows)


@kind("per_wheel_clean")
def per_wheel_clean(args: list[Records]) -> str:
    """Per entry, the posterior sd (kg m²) of the per-wheel and common models on the clean case
    of one ``benchmarks/per_wheel_inertia.py`` record, and their ratio: the per-wheel model's
    price where the wheels are as the model file says."""
    path = args[0][0]
    per, com = (_fit(path, "clean", m)["entries"] for m in ("per_wheel", "common"))
    rows = ["| entry | per-wheel sd | common sd | per-wheel / common |", "|---|---|---|---|"]
    rows += [f"| {n} | {per[n]['sd']:.3g} | {com[n]['sd']:.3g} | "
             f"{per[n]['sd'] / com[n]['sd']:.2f} |" for n in ENTRIES]
    return "\n".join(rows)


@kind("closed_world_thrust_log")
def closed_world_thrust_log(args: list[Records]) -> str:
    """The closed-world thrust campaign's summary per model, read from the printed log of
    benchmarks/coverage_robust_thrust.py (``MODEL : 90 % coverage F …, tau_delay …; … max R-hat
    …, min bulk ESS …, divergences …``): covered seeds per parameter, R-hat, ESS, divergences."""
    import re

    rows = ["| model | F | τd | τr | τf | max R-hat | min bulk ESS | divergences |",
            "|" + "---|" * 8]
    line = re.compile(r"^(?P<model>\w+)\s*: 90 % coverage F (?P<F>[\d.]+), "
                      r"tau_delay (?P<d>[\d.]+), tau_rise (?P<r>[\d.]+), "
                      r"tau_fall (?P<f>[\d.]+).*max R-hat (?P<rhat>[\d.]+), "
                      r"min bulk ESS (?P<ess>\d+), divergences (?P<div>\d+)")
    for path in (p for group in args for p in group):
        text = path.read_text()
        n = len(re.findall(r"^seed \d+:", text, re.MULTILINE))
        for m in filter(None, map(line.match, text.splitlines())):
            cells = [f"{round(float(m[k]) * n)}/{n}" for k in ("F", "d", "r", "f")]
            rows.append(f"| {m['model']} | " + " | ".join(cells)
                        + f" | {m['rhat']} | {m['ess']} | {m['div']} |")
    return "\n".join(rows)


@kind("thrust_shipped_fits")
def thrust_shipped_fits(args: list[Records]) -> str:
    """One row per ``benchmarks/thrust_shipped_fits.py`` record: the thrust's error and sd (% of
    the truth), whether its 90 % interval covers, the rise and fall time constants' posterior
    means (truth), the delay's contraction, max R-hat, divergences and the least bulk ESS (the
    simulation key beside the scenario where it is not 0)."""
    rows = ["| scenario | F error | sd(F) | 90 % covers | τr (ms) | τf (ms) | τd contraction | "
            "max R-hat | divergences | min bulk ESS |", "|" + "---|" * 10]
    for r in (r for group in args for p in group for r in read_json(p)):
        d, tau, true = r["diagnostics"], r["tau"], r["tau_true_ms"]
        rows.append(
            f"| `{r['scenario']}`" + (f", key {r['key']}" if r.get("key") else "")
            + f" | {_signed(r['F_error_pct'], 2)} % | {r['F_sd_pct']:.2f} % | "
            f"{'yes' if r['F_covered_90'] else 'no'} | "
            f"{1e3 * tau['tau_rise']['mean']:.1f} ({true['tau_rise']:.0f}) | "
            f"{1e3 * tau['tau_fall']['mean']:.1f} ({true['tau_fall']:.0f}) | "
            f"{tau['tau_delay']['contraction']:.2f} | {d['max_r_hat']:.3f} | "
            f"{d['divergences']} | {d['min_ess_bulk']:.0f} |")
    return "\n".join(rows)


@kind("robust_price")
def robust_price(args: list[Records]) -> str:
    """The price of the robust models on clean data (``benchmarks/robust_price.py`` record): the
    thrust's sd (% of its mean) and the rise and fall time constants' sd per model, the RWA4
    axis's 90 % cone and error by either method, and each column's largest R-hat and
    divergences."""
    r = read_json(next(p for group in args for p in group))
    models = (("idealised", "thrust idealised (inertia fixed)"), ("common", "thrust common"),
              ("per_wheel", "thrust per_wheel"))

    def f_sd(rec):
        return f"{100 * rec['F']['sd'] / rec['F']['mean']:#.2g} %"

    def axis(method, m):
        rec = r[f"rwa4_{method} {m}"]
        return f"{rec['cone90_deg']:#.2g}° ({rec['error_deg']:#.2g}°)"

    fixed = r["thrust per_wheel (inertia fixed)"]
    rows = ["| fit | idealised | common | per-wheel (default) |", "|---|---|---|---|",
            f"| thrust sd(F), clean `biasing_day028` | {f_sd(r[models[0][1]])} (inertia fixed) "
            f"| {f_sd(r[models[1][1]])} | {f_sd(r[models[2][1]])} "
            f"(inertia sampled; {f_sd(fixed)} with `--fix-inertia`) |",
            "| thrust sd(τr), sd(τf) | " + " | ".join(
                f"{1e3 * r[k]['tau_rise']['sd']:.2f}, {1e3 * r[k]['tau_fall']['sd']:.1f} ms"
                for _, k in models) + " |"]
    for method, label in (("rwa", "RWA method"), ("rcs", "RCS method (±10 % inertia)")):
        rows.append(f"| RWA4 90 % cone (axis error), {label} | "
                    + " | ".join(axis(method, m) for m, _ in models) + " |")
    fits = {m: [r[k] for k in r if k.endswith(m) or k.endswith(f"{m} (inertia fixed)")]
            for m, _ in models}
    rows.append("| largest R-hat, divergences | " + " | ".join(
        f"{max(f['r_hat'] for f in fits[m]):.3f}, {sum(f['divergences'] for f in fits[m])}"
        for m, _ in models) + " |")
    return "\n".join(rows)


@kind("thrust_thruster_fits")
def thrust_thruster_fits(args: list[Records]) -> str:
    """Per-thruster thrust fits by seed (benchmarks/thrust_thruster_fits.py records): the
    largest thrust error, the thrusts' median sd, the centre of mass's error, the 90 %
    intervals that cover (the ones that miss named), R-hat, divergences and the fit's wall."""
    rows = ["| seed | max \\|thrust error\\| | thrust sd (posterior, median) | offset error "
            "x, y, z (mm) | 90 % intervals covering | max R-hat | divergences | wall time |",
            "|---|---|---|---|---|---|---|---|"]
    for r in (r for group in args for p in group for r in read_json(p)):
        th, com, tau = r["thrusts"], r["com"], r["tau"]
        hits = {f"F[{n}]": t["covered_90"] for n, t in th.items()}
        hits.update({f"com_{a}": c["covered_90"] for a, c in com.items()})
        hits.update({n: t["covered_90"] for n, t in tau.items()})
        missed = [n for n, h in hits.items() if not h]
        cover = f"{len(hits) - len(missed)}/{len(hits)}" + (
            f" ({', '.join(missed)} out)" if missed else "")
        d = r["diagnostics"]
        err = max(abs(t["error_pct"]) for t in th.values())
        sd = sorted(t["sd_pct"] for t in th.values())[len(th) // 2]
        offs = ", ".join(f"{1e3 * c['error_m']:+.2f}" for c in com.values())
        rows.append(f"| {r['seed']} | {err:.2f} % | {sd:.2f} % | {offs} | {cover} | "
                    f"{d['max_r_hat']:.4f} | {d['divergences']} | {r['seconds']:.0f} s |")
    return "\n".join(rows)


@kind("per_wheel_events")
def per_wheel_events(args: list[Records]) -> str:
    """The per-wheel model beside the common one on one thrust event and one RWA4 run
    (``benchmarks/per_wheel_events.py --json`` records): F's 90 % interval against the truth,
    its z and sd, the time constants' sds; the axis error and cone; R-hat, divergences, wall."""
    recs = [r for group in args for p in group for r in read_json(p)]
    models = list(dict.fromkeys(r["model"] for r in recs))
    rows = ["| fit | " + " | ".join(m.replace("_", "-") for m in models) + " |",
            "|---|" + "---|" * len(models)]

    def diag(r: dict) -> str:
        return f"R-hat {r['max_r_hat']:.4f}, {r['divergences']} div., {r['wall_s']:.0f} s"

    for scenario in dict.fromkeys(r["scenario"] for r in recs):
        by = {r["model"]: r for r in recs if r["scenario"] == scenario}
        first = by[models[0]]
        if "error_deg" in first:
            cells = [f"error {r['error_deg']:.3f}°, 90 % cone {r['cone90_deg']:.3f}°: "
                     f"{'covers' if r['covered'] else '**misses**'}; {diag(r)}"
                     for r in (by[m] for m in models)]
            rows.append(f"| RWA4 axis (`{scenario}`) | " + " | ".join(cells) + " |")
            continue
        cells = [f"90 % [{r['q05']:.5f}, {r['q95']:.5f}] "
                 f"{'covers' if r['covered'] else '**misses**'}, z {r['z']:+.2f}, sd "
                 f"{r['sd_pct']:.3f} %; {diag(r)}" for r in (by[m] for m in models)]
        rows.append(f"| thrust `F` (`{scenario}`, truth {first['truth']:.5f} N) | "
                    + " | ".join(cells) + " |")
        rows.append("| thrust sd(τd, τr, τf) | " + " | ".join(
            ", ".join(f"{v:.2f}" for v in by[m]["tau_sd_ms"].values()) + " ms"
            for m in models) + " |")
    return "\n".join(rows)


@kind("thrust_inertia_off")
def thrust_inertia_off(args: list[Records]) -> str:
    """The robust thrust fit of an event whose moments are 3 % above the model's prediction,
    the inertia sampled and fixed (``benchmarks/thrust_inertia_off.py`` records): F against
    the truth, its z, Ixx's posterior where sampled, R-hat and divergences."""
    recs = [r for group in args for p in group for r in read_json(p)]
    rows = [f"| robust model | F (truth {recs[0]['F_true']:.3f} N) | z | Ixx (truth "
            f"{recs[0]['Ixx_true']:.0f}, predicted {recs[0]['Ixx_pred']:.0f} kg m²) | "
            "max R-hat, divergences |", "|---|---|---|---|---|"]
    label = {"sampled": "inertia sampled from the ±10 % prior (default)",
             "fixed": "inertia fixed at the prediction (`--fix-inertia`)"}
    for r in recs:
        ixx = f"{r['Ixx_mean']:.0f} ± {r['Ixx_sd']:.0f}" if "Ixx_mean" in r else "—"
        rows.append(f"| {label[r['inertia']]} | {r['F_mean']:.4f} ± {r['F_sd']:.4f} | "
                    f"{_signed(r['z'], 1)} | {ixx} | {r['max_r_hat']:.3f}, {r['divergences']} |")
    return "\n".join(rows)


@kind("coverage_robust_inertia")
def coverage_robust_inertia(args: list[Records]) -> str:
    """Per family (``coverage_robust_inertia.py --json``): each model's 90 % coverage of the six
    inertia entries with its binomial sd and its seed-clustered sd (the sd of the per-seed
    coverage over the seeds, /√seeds: one seed's six intervals are correlated), the error-budget
    pass rate, the drawn common wheel error of the seeds whose robust fit fails the budget (where
    the record has it), the largest R-hat and the divergences."""
    (path,), = args
    rec = read_json(path)
    models = [m for m in ("robust", "idealised") if m in rec["options"]["models"]]
    head = ["family", "seeds"] + [f"{m}: {c}" for m in models for c in
                                  ("90 % coverage; seed-clustered sd", "budget")]
    drawn = all("wheel_error_mean" in r for r in rec["results"])
    if drawn:
        head.append("drawn common wheel error where the robust budget fails")
    lines = ["| " + " | ".join(head) + " | R-hat (largest), divergences |",
             "|" + "---|" * (len(head) + 1)]
    for family in dict.fromkeys(r["family"] for r in rec["results"]):
        rows = [r for r in rec["results"] if r["family"] == family]
        cells, worst, div = [], 0.0, 0
        for m in models:
            per_seed = [sum(r[m]["hit"]) / len(r[m]["hit"]) for r in rows]
            n = sum(len(r[m]["hit"]) for r in rows)
            p = sum(per_seed) / len(per_seed)
            clustered = statistics.stdev(per_seed) / len(per_seed) ** 0.5 if len(rows) > 1 else 0
            cells += [f"{p:.3f} ± {(p * (1 - p) / n) ** 0.5:.3f}; {clustered:.3f}",
                      f"{sum(r[m]['budget'] for r in rows)}/{len(rows)}"]
            worst = max(worst, *(r[m]["r_hat"] for r in rows))
            div += sum(r[m]["divergences"] for r in rows)
        if drawn:
            cells.append(", ".join(f"{_signed(100 * r['wheel_error_mean'], 2)} %" for r in rows
                                   if "robust" in r and not r["robust"]["budget"]) or "–")
        lines.append(f"| `{family}` | {len(rows)} | " + " | ".join(cells)
                     + f" | {worst:.4f}, {div} |")
    return "\n".join(lines)


@kind("thrust_tag_statement")
def thrust_tag_statement(args: list[Records]) -> str:
    """The single-width event's thrusts against the stated and the flown time-tag sd
    (``benchmarks/thrust_time_tag_statement.py --json``)."""
    from thrust_time_tag_statement import table

    return table([r for group in args for p in group for r in read_json(p)])
