"""Table kinds of the SBC, thruster-health and adequacy-verdict records (docs/sbc/, docs/health/,
docs/verdicts/); registered in :mod:`_tables` by import."""

from __future__ import annotations

from _tables import Records, kind, read_json


def _p(p: float) -> str:
    """A p-value as the SBC tables print it: three decimals, two significant digits below 0.01."""
    return f"{p:.3f}" if p >= 0.01 else f"{p:.2g}"


def _sbc_row(name: str, chi2_p: float, ecdf_p: float, cov: list[float]) -> str:
    return (f"| {name} | {_p(chi2_p)} | {_p(ecdf_p)} | "
            + " | ".join(f"{c:.3f}" for c in cov) + " |")


_SBC_HEAD = ("| parameter | χ² p | ECDF p | cov 50 | cov 80 | cov 90 | cov 95 |\n"
             "|-----------|------|--------|--------|--------|--------|--------|")


@kind("sbc")
def sbc(args: list[Records]) -> str:
    """Rank uniformity and coverage per parameter of a ``cassini-bayes sbc`` summary.json, or
    of ``benchmarks/health_sbc.py``'s (the health and leak models)."""
    ((path,),) = args
    rows = [_SBC_HEAD]
    for name, par in read_json(path)["parameters"].items():
        if "chi2" in par:                                   # cassini-bayes sbc
            cov = [par["coverage"][k]["observed"] for k in ("50", "80", "90", "95")]
            rows.append(_sbc_row(name, par["chi2"]["p_value"], par["ecdf"]["p_value"], cov))
        else:                                               # benchmarks/health_sbc.py
            cov = [par["coverage"][k] for k in ("0.5", "0.8", "0.9", "0.95")]
            rows.append(_sbc_row(name, par["chi2_p"], par["ecdf_p"], cov))
    return "\n".join(rows)


def _calibration(args: list[Records], key: str, label: str) -> str:
    ((path,),) = args
    bins = read_json(path)[key]
    rows = [f"| {label} | n | mean P | observed rate | sd |", "|---|---|---|---|---|"]
    for i, b in enumerate(bins):
        lo, hi = (f"{x:g}" for x in b["bin"])
        close = "]" if i == len(bins) - 1 else ")"
        rows.append(f"| [{lo}, {hi}{close} | {b['n']} | {b['mean_p']:.2g} | {b['rate']:.2g} | "
                    f"{b['sd']:.2g} |")
    return "\n".join(rows)


@kind("leak_p_calibration")
def leak_p_calibration(args: list[Records]) -> str:
    """Calibration of the leak monitor's ``P(leak)`` (health_sbc.py's leak summary.json)."""
    return _calibration(args, "p_leak_calibration", "P(leak) bin")


@kind("leak_hypothesis_calibration")
def leak_hypothesis_calibration(args: list[Records]) -> str:
    """Calibration of every leak hypothesis' probability (the same summary.json)."""
    return _calibration(args, "p_hypothesis_calibration", "P bin")


@kind("health_campaign")
def health_campaign(args: list[Records]) -> str:
    """The thruster-health acceptance campaign per record (benchmarks/health_campaign.py):
    detection, delay, quiet controls and the change date's interval coverage."""
    rows = ["| seeds | detected | delay, events: median / 90 % / max | control quiet (every look "
            "< 0.05) | before the change quiet | 90 % interval covers (binomial sd) | 50 % "
            "covers (sd) |", "|" + "---|" * 7]
    for r in (read_json(path) for group in args for path in group):
        n, d = r["seeds"], r["delay_events"]
        rows.append(f"| {r['first_seed']}-{r['first_seed'] + n - 1} | {d['detected']}/{n} | "
                    f"{d['median']:g} / {d['q90']:g} / {d['max']:g} | "
                    f"{round(r['control_quiet_fraction'] * n)}/{n} | "
                    f"{round(r['pre_change_quiet_fraction'] * n)}/{n} | "
                    f"{r['coverage_90']:.3f} ({r['coverage_90_sd']:.3f}) | "
                    f"{r['coverage_50']:.3f} ({r['coverage_50_sd']:.3f}) |")
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
def verdict_health(args: list[Records]) -> str:
    """The health campaign's adequacy verdict per model, control and degraded campaigns
    pooled (benchmarks/verdict_false_alarms.py health records; ``A+B``: seeds pooled)."""
    from cassini_bayes.inference.adequacy import PRIOR_CONFLICT_SD, Z_THRESHOLD

    thresholds = {"inertia_conflict": PRIOR_CONFLICT_SD, "held_out": Z_THRESHOLD}
    rows = ["| events | seeds | model | `inertia_conflict` | `held_out` | any check |",
            "|" + "---|" * 6]
    for group in args:
        records = [read_json(path) for path in group]
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
def verdict_leak(args: list[Records]) -> str:
    """The leak monitor's adequacy verdict per model, on stretches without and with a leak
    (benchmarks/verdict_false_alarms.py leak records)."""
    from cassini_bayes.inference.adequacy import AUTOCORR_MAX, PRIOR_CONFLICT_SD, Z_THRESHOLD

    thresholds = {"residual_fit": Z_THRESHOLD, "prior_data_conflict": PRIOR_CONFLICT_SD,
                  "residual_autocorrelation": AUTOCORR_MAX}
    rows = ["| stretches | model | `residual_fit` | `prior_data_conflict` | "
            "`residual_autocorrelation` | any check |", "|" + "---|" * 6]
    for group in args:
        stretches = [s for path in group for s in read_json(path)["raw"]["stretches"]]
        for leak in (False, True):
            sel = [s for s in stretches if s["leak"] == leak]
            models = [k for k, v in sel[0].items() if isinstance(v, dict) and "residual_fit" in v]
            cases = {f"{len(sel)} {'with' if leak else 'without'} a leak | `{m}`":
                     [s[m] for s in sel] for m in models}
            rows += _verdict_rows(cases, thresholds)
    return "\n".join(rows)


@kind("verdict_budget")
def verdict_budget(args: list[Records]) -> str:
    """The budget's ``shared_inertia`` check on clean and epoch-mixed pairs of runs
    (benchmarks/verdict_false_alarms.py budget records; ``A+B``: seeds pooled)."""
    from cassini_bayes.inference.adequacy import Z_THRESHOLD

    rows = []
    for group in args:
        records = [read_json(path) for path in group]
        pairs = [p for rec in records for p in rec["raw"]["pairs"]]
        rows += [f"| seeds {_seeds(records)} | `shared_inertia` (median, largest) | any check |",
                 "|" + "---|" * 3]
        rows += _verdict_rows({f"`{case}`": [{"shared_inertia": p[case]} for p in pairs]
                               for case in ("clean", "epochs")},
                              {"shared_inertia": Z_THRESHOLD})
    return "\n".join(rows)


@kind("sbc_trial_noise")
def sbc_trial_noise(args: list[Records]) -> str:
    """The noise centre of a few thrust SBC replicates (benchmarks/sbc_thrust_trial.py)."""
    ((path,),) = args
    rows = ["| replicate | pulses / samples | pulse-free 2nd differences | σ̂_ω / gyro noise | "
            "σ̂_ρ / tach noise |", "|---|---|---|---|---|"]
    for r in read_json(path)["replicates"]:
        w, t = r["noise_over_sensor"]
        rows.append(f"| {r['replicate']} | {r['pulses']} / {r['samples']} | {r['unbent']} of "
                    f"{r['differences']} | {w:.2f} | {t:.2f} |")
    return "\n".join(rows)


@kind("sbc_trial_common_scale")
def sbc_trial_common_scale(args: list[Records]) -> str:
    """The drawn common scale of a few thrust SBC replicates and where their posteriors put the
    truth (benchmarks/sbc_thrust_trial.py, with ``--fit``)."""
    ((path,),) = args
    rows = ["| replicate | mean `c_k` | z of the common scale | Φ(z) (its rank if the data add "
            "nothing) | fraction of draws below the truth: moments, wheel scales |",
            "|---|---|---|---|---|"]
    for r in read_json(path)["replicates"]:
        below = r["fraction_below"]
        groups = [[v for k, v in below.items() if k.startswith("I")],
                  [v for k, v in below.items() if k.startswith("wheel_scale")]]
        rows.append(f"| {r['replicate']} | {100 * r['mean_wheel_scale']:+.2f} % | "
                    f"{r['z_common']:+.2f} | {r['phi_z_common']:.3g} | "
                    + ", ".join(f"{min(g):.2f}–{max(g):.2f}" for g in groups) + " |")
    return "\n".join(rows)
