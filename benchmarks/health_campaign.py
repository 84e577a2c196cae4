"""Thruster-health campaigns: detection delay, false alarms and change-date coverage.

For each seed, both campaign files (``experiments/scenarios/health_degradation.toml``: Z3/Z4
lose 7 % on day 400; ``health_control.toml``: no change; 32 events over 730 days, event dates,
wheel targets, per-event thrust scatter, time-constant scatter, spacecraft and wheel inertia
errors drawn per seed, docs/health.md) are simulated and each event reduced to its summary; the
change-point posterior is then run *sequentially*, on the events up to each one, as an operator
would after each biasing event. Decision rules, fixed before the runs:

- alarm when ``P(Z3 or Z4 more than 5 % below the first calibration) ≥ 0.95`` at the latest
  event; the delay is counted in events after the change (1 = the first event after it);
- a false alarm is ``P > 0.05`` at any event from the third on (control campaign; and before the
  change on the degradation campaign);
- the change date's 90 % (and 50 %) interval (given a change) from all 32 events covers the true
  date or not. With ``--uniform-date`` the degradation day is drawn per seed uniformly in
  [150, 650] instead of the file's day 400: the truth then falls anywhere between two events, as
  the model's uniform prior on the date assumes (with a fixed day and bounded date jitter it sits
  near one event's nominal date, which central intervals cover less often).

    python benchmarks/health_campaign.py [--seeds 40] [--first-seed 0] [--uniform-date]
        [--wheel-inertia-sd 0.01] [--out FILE.json]

``--wheel-inertia-sd`` overrides both files' per-wheel spin-inertia error (a stress test: the
files draw the model's stated 0.5 %).

Prints a Markdown table (docs/health.md carries the measured one). Never a timed test. The
defaults of the model (``p_change`` 0.1, …) were set on seeds 100-179; seeds 0-39 and 200-239
are reported (docs/health.md).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time

import numpy as np

from cassini_bayes.api._health import campaign_summaries
from cassini_bayes.inference.health import HealthPrior, health_posterior
from cassini_bayes.simulate.health_campaign import load_campaign

ALARM, QUIET, FRACTION, FIRST_LOOK = 0.95, 0.05, 0.05, 3
Z3_Z4 = [2, 3]


def sequential(dates, y, s, prior):
    """``P(Z3 or Z4 down)`` at event ``n`` from events ``0..n`` (NaN before ``FIRST_LOOK``)."""
    out = np.full(dates.size, np.nan)
    for n in range(FIRST_LOOK, dates.size + 1):
        out[n - 1] = health_posterior(dates[:n], y[:n], s[:n], prior).p_down(Z3_Z4,
                                                                              FRACTION)[-1]
    return out


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=40)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--uniform-date", action="store_true")
    ap.add_argument("--wheel-inertia-sd", type=float, default=None)
    ap.add_argument("--out", default=None)
    args = ap.parse_args(argv)
    if args.out:
        from _provenance import start

        start(args.out, vars(args), argv, replace=True)
    prior = HealthPrior()
    deg, ctl = load_campaign("health_degradation"), load_campaign("health_control")
    if args.wheel_inertia_sd is not None:
        deg = dataclasses.replace(deg, wheel_inertia_error_sd=args.wheel_inertia_sd)
        ctl = dataclasses.replace(ctl, wheel_inertia_error_sd=args.wheel_inertia_sd)
    t0 = time.time()
    rows = []
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        if args.uniform_date:
            day = float(np.random.default_rng([seed, 99]).uniform(150.0, 650.0))
            deg = dataclasses.replace(deg, degradation_day=day)
        d, y, s = campaign_summaries(deg, seed)
        p = sequential(d, y, s, prior)
        after = np.flatnonzero(d >= deg.degradation_day)
        hits = np.flatnonzero(p[after] >= ALARM)
        full = health_posterior(d, y, s, prior)
        lo, hi = full.change_date_interval(0.9)
        lo50, hi50 = full.change_date_interval(0.5)
        dc, yc, sc = campaign_summaries(ctl, seed)
        pc = sequential(dc, yc, sc, prior)
        rows.append({
            "seed": seed, "change_day": deg.degradation_day,
            "delay_events": int(hits[0] + 1) if hits.size else None,
            "delay_days": float(d[after[hits[0]]] - deg.degradation_day) if hits.size else None,
            "pre_change_max_p": float(np.nanmax(p[:after[0]])) if after[0] >= FIRST_LOOK
            else None,
            "p_change_end": full.p_change,
            "interval_90": [lo, hi], "covered_90": bool(lo <= deg.degradation_day <= hi),
            "covered_50": bool(lo50 <= deg.degradation_day <= hi50),
            "control_max_p": float(np.nanmax(pc)), "control_p_change_end":
                health_posterior(dc, yc, sc, prior).p_change,
        })
        print(f"seed {seed}: delay {rows[-1]['delay_events']} events, control max "
              f"{rows[-1]['control_max_p']:.3f}, covered {rows[-1]['covered_90']} "
              f"({time.time() - t0:.0f} s)", flush=True)
    n = len(rows)
    delays = np.array([r["delay_events"] if r["delay_events"] is not None else np.inf
                       for r in rows])
    ctl_max = np.array([r["control_max_p"] for r in rows])
    pre = np.array([r["pre_change_max_p"] for r in rows if r["pre_change_max_p"] is not None])
    cov90 = np.mean([r["covered_90"] for r in rows])
    cov50 = np.mean([r["covered_50"] for r in rows])
    result = {
        "seeds": n, "first_seed": args.first_seed, "wall_s": time.time() - t0,
        "uniform_date": args.uniform_date, "wheel_inertia_sd": args.wheel_inertia_sd,
        "rules": {"alarm": ALARM, "quiet": QUIET, "fraction": FRACTION,
                  "first_look_event": FIRST_LOOK},
        "delay_events": {"median": float(np.median(delays)),
                         "q90": float(np.quantile(delays, 0.9)), "max": float(delays.max()),
                         "detected": int(np.isfinite(delays).sum()),
                         "within": {str(k): int(np.sum(delays <= k)) for k in (1, 2, 3, 5, 8,
                                                                             10)}},
        "control_quiet_fraction": float(np.mean(ctl_max < QUIET)),
        "control_max_p_quantiles": [float(x) for x in np.quantile(ctl_max, [0.5, 0.9, 1.0])],
        "pre_change_quiet_fraction": float(np.mean(pre < QUIET)) if pre.size else None,
        "coverage_90": float(cov90), "coverage_90_sd": float(np.sqrt(0.9 * 0.1 / n)),
        "coverage_50": float(cov50), "coverage_50_sd": float(np.sqrt(0.25 / n)),
        "runs": rows,
    }
    print(f"\n| seeds | detected | delay median / 90 % / max (events) | control quiet "
          f"(max P < 0.05) | pre-change quiet | cov 90 % (sd) | cov 50 % (sd) |\n|---|---|---|"
          f"---|---|---|---|\n| {n} | {result['delay_events']['detected']}/{n} | "
          f"{np.median(delays):g} / {np.quantile(delays, 0.9):g} / {delays.max():g} | "
          f"{np.mean(ctl_max < QUIET):.3f} | {result['pre_change_quiet_fraction']} | "
          f"{cov90:.3f} ({result['coverage_90_sd']:.3f}) | {cov50:.3f} "
          f"({result['coverage_50_sd']:.3f}) |")
    if args.out:
        with open(args.out, "w") as fh:
            json.dump(result, fh, indent=1)
    return result


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    main()
