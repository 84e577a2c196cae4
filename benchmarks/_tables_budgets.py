"""Table kinds of the error budgets that ``cassini-bayes reproduce`` writes (its
``error_budgets`` experiment, shown in docs/budgets.md); registered in :mod:`_tables` by
import."""

from __future__ import annotations

from _tables import Records, kind, read_json

# (budget, line) of a posterior row -> (calibration, source) of the least-squares budget that
# estimates the same quantity; source None: every source on together.
_LEAST_SQUARES = {
    ("inertia", "inertia knowledge, worst moment (Eq 12)"): ("inertia", None),
    ("thrust", "thrust knowledge"): ("thrust", None),
    ("thrust", "mass properties (least-squares Eq 23)"): ("thrust", "mass properties"),
    ("rwa4 (rwa)", "RWA4 axis knowledge"): ("rwa4_rwa", None),
    ("rwa4 (rcs)", "RWA4 axis knowledge"): ("rwa4_rcs", None),
    ("rwa4 mass properties", "extra RCS-method error (Brown Eq 1)"): ("rwa4_rcs",
                                                                      "mass properties"),
}


def _g(x: float) -> str:
    """Three significant digits (trailing zeros kept: 0.0400, 1.19)."""
    return f"{x:#.3g}".rstrip(".")


def _least_squares(results: dict, budget: str, line: str) -> str:
    if line.startswith("pulse time constants"):
        key = ("thrust", "pulse time constants")
    else:
        key = _LEAST_SQUARES.get((budget, line))
    if key is None:
        return "–"
    b = results[key[0]]
    rms, worst = ((b["total_rms"], b["total_worst"]) if key[1] is None
                  else (b["lines"][key[1]]["rms"], b["lines"][key[1]]["worst"]))
    what = "all sources" if key[1] is None else key[1]
    return f"{_g(rms)} / {_g(worst)} ({what}, `{b['scenario']}`)"


@kind("budget_from_posteriors")
def budget_from_posteriors(args: list[Records]) -> str:
    """The budget lines propagated from the reproduce run's posteriors (median and 90 %
    interval; the papers' pointing lines without a calibrated input left out), the papers'
    bound, the least squares' error on the same quantity (RMS / worst over the one-source
    budget's keys) and the sum of the one-at-a-time variance shares (1: the inputs act
    independently; above 1: they compensate each other)."""
    (path,), = args
    r = read_json(path)["results"]
    rows = ["| budget | line | ours: median [90 %] | paper | least squares: RMS / worst | "
            "Σ shares |", "|---|---|---|---|---|---|"]
    for row in r["from_posteriors"]["rows"]:
        iv = row["interval"]
        if iv is None:
            continue
        unit = {"%": " %", "deg": "°", "mrad": " mrad"}[row["unit"]]
        shares = (f"{iv['share_sum']:,.0f}" if iv["share_sum"] >= 100
                  else f"{iv['share_sum']:.2f}")
        rows.append(f"| {row['budget']} | {row['line']} | {_g(iv['median'])}{unit} "
                    f"[{_g(iv['low'])}, {_g(iv['high'])}] | {row['paper'] or '–'} | "
                    f"{_least_squares(r, row['budget'], row['line'])} | {shares} |")
    return "\n".join(rows)


@kind("bench_budget")
def bench_budget(args: list[Records]) -> str:
    """Wall seconds of each step of the budgets from posteriors in a warm process: the first
    call (with compilation) and the median after it (``benchmarks/bench_budget.py`` record)."""
    (path,), = args
    r = read_json(path)
    rows = ["| step | first call | after (median of " + str(r["repeat"]) + ") |", "|---|---|---|"]
    for step, t in r["steps"].items():
        rows.append(f"| {step} | {t['first_s']:.2f} s | {t['after_s']:.2f} s |")
    return "\n".join(rows)
