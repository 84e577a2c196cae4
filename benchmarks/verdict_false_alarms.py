"""Adequacy verdicts of ``fit health``, ``monitor leak`` and ``budget``: false alarms on correctly
specified data and power against a spacecraft model of another epoch (``cassini_pre_soi``, whose
moments are 16-24 % above the Post-Probe truth and whose thrust is 0.75 N against 0.699 N).

Parts (each seed simulates fresh data; the statistic of every check is recorded):

* ``health`` — ``health_control`` and ``health_degradation`` (``--events`` events each; the
  shipped files have 32) per seed, fitted with ``cassini_post_probe`` (the model the events were
  simulated from: clean) and with ``cassini_pre_soi`` (mismatched); exactly what ``fit health``
  computes, from in-memory summaries.
* ``leak`` — ``leak_cruise`` stretches of ``--hours`` (thrusts and body torque drawn from the
  monitor's own priors as in ``benchmarks/leak_detection.py``), half without a leak and half with
  a 10 % leak of a random thruster, monitored with both models; a second table sets the
  monitor's answers against the truth (thruster, the fraction's 90 % interval, CPU time).
* ``budget`` — ``shared_inertia`` of an inertia fit and a thrust fit (robust models, small
  sampler settings): clean = ``slews_post_probe_real`` and ``biasing_day028_real`` (both
  Post-Probe truths), both fitted with ``cassini_post_probe``; epochs mixed = the slews of
  ``slews_pre_soi_real`` (Pre-SOI truth) fitted with the same model file, so only the runs'
  inertia can tell (the other three checks count flags in the runs' own files: no false-alarm
  rate to measure).

Prints one Markdown table per part (rate of each check's failure, median and largest
statistic). Not a test; the tables go to docs/health.md, docs/leak.md and docs/budgets.md.

    python benchmarks/verdict_false_alarms.py health --seeds 10 [--events 32]
    python benchmarks/verdict_false_alarms.py leak --seeds 12 [--hours 4] [--check-step 60]
    python benchmarks/verdict_false_alarms.py budget --seeds 4
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

MODELS = ("cassini_post_probe", "cassini_pre_soi")


def _health(seed: int, campaign: str, n_events: int) -> dict:
    """{model: {check: statistic}} of one campaign."""
    from cassini_bayes.api import simulate_scenario
    from cassini_bayes.inference.health import HealthPrior, event_channels, event_summary
    from cassini_bayes.inference.health.adequacy import health_adequacy, inertia_probe
    from cassini_bayes.simulate.health_campaign import campaign_events, load_campaign
    from cassini_bayes.spacecraft import load_spacecraft

    camp = dataclasses.replace(load_campaign(campaign), n_events=n_events)
    events = campaign_events(camp, seed)
    sims = [simulate_scenario(ev.scenario) for ev in events]
    dates = [ev.date_days for ev in events]
    out = {}
    for model in MODELS:
        sc = load_spacecraft(model)
        channels = event_channels([(s.telemetry, s.pulses) for s in sims], sc)
        summaries = [event_summary(s.telemetry, s.pulses, sc, channels=channels) for s in sims]
        probes = [inertia_probe(s.telemetry, s.pulses, sc, m) for s, m in zip(sims, summaries)]
        ad = health_adequacy(dates, summaries, probes, HealthPrior(nominal_thrust_n=sc.thrust),
                             [f"event_{k:03d}" for k in range(len(sims))])
        out[model] = {c.name: c.statistic for c in ad.checks}
    return out


def leak_stretches(seed: int, hours: float, n: int):
    """Yield ``(leak, scenario, true thrusts (8,) N, telemetry, pulse log)`` for the ``n``
    ``leak_cruise`` stretches of ``hours`` of one seed: ``n/2`` without a leak, then ``n/2`` with
    a 10 % leak of a random thruster from a random onset in [600, 3600] s; thrusts and body
    torque drawn from the monitor's own priors (``leak_detection.py``). Shared with
    ``leak_quadrature.py`` so both see the same draws."""
    import jax

    from leak_detection import _truths
    from cassini_bayes.simulate import load_scenario, pulse_log, simulate_batch
    from cassini_bayes.simulate.scenario import Leak
    from cassini_bayes.telemetry import Telemetry

    rng = np.random.default_rng(seed)
    base = dataclasses.replace(load_scenario("leak_cruise"), duration_s=hours * 3600.0)
    for leak in (False, True):
        s = dataclasses.replace(base, leak=Leak(int(rng.integers(8)), 0.1,
                                                float(rng.uniform(600.0, 3600.0)))
                                if leak else None)
        b = n // 2
        truths = _truths(s, rng, b)
        arr = simulate_batch(jax.random.split(jax.random.PRNGKey(seed + 7 * leak), b), s,
                             truths)
        arr = jax.tree_util.tree_map(np.asarray, arr)
        for i in range(b):
            a = jax.tree_util.tree_map(lambda x, i=i: x[i], arr)
            tel = Telemetry(t=a.t_meas, q=a.q_meas, omega=a.omega_meas,
                            wheel_rates=a.wheel_rates_meas, wheel_names=s.wheel_names,
                            on_times=a.on_times, source=f"<{s.name}>")
            yield leak, s, np.asarray(truths.thrust_n)[i], tel, pulse_log(a, s)


def _leak(seed: int, hours: float, n: int, check_step_s: float, true_inertia: bool = False
          ) -> list[dict]:
    """[{model: {check: statistic, monitor's answer}, "leak": bool, "truth": {…}}] of the ``n``
    stretches of :func:`leak_stretches` (``true_inertia``: each model's inertia replaced by the
    simulation's). The monitor's answer: the thruster it isolated (``None``: none), its last
    probability, the fraction's mean, sd and 90 % interval (``mean ± 1.645 sd`` where the
    monitor reports no interval), the onset and the monitor's CPU seconds; the truth's fraction
    is in each model's thrust (the leak is 10 % of the true thrust)."""
    from cassini_bayes.inference.leak import leak_inputs, leak_posterior
    from cassini_bayes.inference.leak_adequacy import leak_adequacy
    from cassini_bayes.physics.impulse import THRUSTER_NAMES
    from cassini_bayes.spacecraft import load_spacecraft

    out = []
    for leak, s, thrust_n, tel, pulses in leak_stretches(seed, hours, n):
        row = {"leak": leak}
        if leak:
            row["truth"] = {"thruster": THRUSTER_NAMES[s.leak.thruster],
                            "onset_s": s.leak.t_start_s,
                            "thrust_n": float(thrust_n[s.leak.thruster])}
        for model in MODELS:
            sc = load_spacecraft(model)
            if true_inertia:
                sc = dataclasses.replace(sc, inertia=np.asarray(s.truth.inertia))
            inp = leak_inputs(tel, pulses, sc)
            cpu = time.process_time()
            post = leak_posterior(inp, check_step_s=check_step_s)
            cpu = time.process_time() - cpu
            ad = leak_adequacy(inp, post, eta=0.05, sample_step_s=60.0)
            row[model] = {c.name: c.statistic for c in ad.checks}
            interval = getattr(post, "fraction_interval", None) or (
                post.fraction_mean - 1.645 * post.fraction_sd,
                post.fraction_mean + 1.645 * post.fraction_sd)
            row[model].update(
                p_leak=float(post.p_leak[-1]), thruster=post.thruster,
                p_thruster=float(post.prob[-1][1:].max()),
                detection_time_s=post.detection_time_s,
                fraction_mean=post.fraction_mean, fraction_sd=post.fraction_sd,
                fraction_interval=[float(x) for x in interval], onset_s=post.onset_s,
                cpu_s=cpu)
            if leak:
                row[model]["fraction_truth"] = (s.leak.fraction * row["truth"]["thrust_n"]
                                                / float(sc.thrust))
        out.append(row)
    return out


def _answers(rows: list[dict]) -> str:
    """Markdown: per case and model, the monitor's answers against the truth."""
    lines = ["| case | model | n | alarms | right thruster | wrong thruster | none isolated "
             "| 90 % interval covers | fraction error median / max (% of thrust) "
             "| monitor CPU s median / max |", "|---|---|---|---|---|---|---|---|---|---|"]
    for leak in (False, True):
        for model in MODELS:
            sel = [r for r in rows if r["leak"] == leak]
            ans = [r[model] for r in sel]
            cpu = np.array([a["cpu_s"] for a in ans])
            alarms = sum(a["detection_time_s"] is not None for a in ans)
            if leak:
                right = sum(a["thruster"] == r["truth"]["thruster"] for r, a in zip(sel, ans))
                none = sum(a["thruster"] is None for a in ans)
                cover = sum(a["fraction_interval"][0] <= a["fraction_truth"]
                            <= a["fraction_interval"][1] for a in ans)
                err = 100 * np.abs([a["fraction_mean"] - a["fraction_truth"] for a in ans])
                cells = (f"{right}/{len(ans)} | {len(ans) - right - none} | {none} | "
                         f"{cover}/{len(ans)} | {np.median(err):.3g} / {err.max():.3g}")
            else:
                cells = "– | – | – | – | –"
            lines.append(f"| {'10 % leak' if leak else 'no leak'} | {model} | {len(ans)} | "
                         f"{alarms} | {cells} | {np.median(cpu):.2f} / {cpu.max():.2f} |")
    return "\n".join(lines)


def _budget(seed: int, settings: dict) -> dict:
    """{"clean": z, "epochs": z} of shared_inertia for one seed."""
    import cassini_bayes as cb
    from cassini_bayes.analysis.budget_adequacy import run_inertia_draws, shared_inertia

    with tempfile.TemporaryDirectory() as d, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        runs = {}
        for name, scenario in (("post", "slews_post_probe_real"), ("pre", "slews_pre_soi_real")):
            sim = cb.simulate_scenario(scenario, seed=seed)
            runs[name] = cb.fit_inertia(sim.telemetry, "cassini_post_probe", seed=seed,
                                        **settings).save(Path(d) / name)
        ev = cb.simulate_scenario("biasing_day028_real", seed=seed)
        runs["thrust"] = cb.fit_thrust(ev.telemetry, ev.pulses, "cassini_post_probe", seed=seed,
                                       **settings).save(Path(d) / "thrust")
        draws = run_inertia_draws(runs)
    return {"clean": shared_inertia({"inertia": draws["post"],
                                     "thrust": draws["thrust"]}).statistic,
            "epochs": shared_inertia({"inertia": draws["pre"],
                                      "thrust": draws["thrust"]}).statistic}


def _table(title: str, rows: dict[str, list[dict]], thresholds: dict[str, float]) -> str:
    """Markdown: per case and check, failures/n, median and largest statistic."""
    lines = [f"{title}\n", "| case | n | " + " | ".join(f"`{c}`" for c in thresholds)
             + " | any |", "|---|---|" + "---|" * (len(thresholds) + 1)]
    for case, stats in rows.items():
        cells, anyf = [], np.zeros(len(stats), bool)
        for c, thr in thresholds.items():
            x = np.array([s[c] if s[c] is not None else np.nan for s in stats], float)
            fail = np.nan_to_num(x, nan=-np.inf) > thr
            anyf |= fail
            ok = x[np.isfinite(x)]
            cells.append(f"{fail.sum()}/{len(x)} ({np.median(ok):.2f}, {ok.max():.2f})"
                         if ok.size else "n/a")
        lines.append(f"| {case} | {len(stats)} | " + " | ".join(cells)
                     + f" | **{anyf.sum()}/{len(stats)}** |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("part", choices=("health", "leak", "budget"))
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--events", type=int, default=32, help="health: events per campaign")
    ap.add_argument("--hours", type=float, default=4.0, help="leak: hours per stretch")
    ap.add_argument("--check-step", type=float, default=60.0,
                    help="leak: seconds between the monitor's checks (the verdict reads the "
                         "last)")
    ap.add_argument("--true-inertia", action="store_true",
                    help="leak: give each model the simulation's true inertia (a diagnostic)")
    ap.add_argument("--json", default=None, help="write the raw statistics here")
    args = ap.parse_args()
    if args.json:
        from _provenance import start

        start(args.json, vars(args), None, replace=True)
    seeds = range(args.first_seed, args.first_seed + args.seeds)
    t0, raw = time.time(), {}
    if args.part == "health":
        from cassini_bayes.inference.adequacy import PRIOR_CONFLICT_SD, Z_THRESHOLD

        rows: dict[str, list[dict]] = {}
        for seed in seeds:
            for camp in ("health_control", "health_degradation"):
                res = _health(seed, camp, args.events)
                raw.setdefault(camp, []).append({"seed": seed, **res})
                for model, st in res.items():
                    rows.setdefault(f"{camp}, {model}", []).append(st)
            print(f"seed {seed}: {time.time() - t0:.0f} s", file=sys.stderr, flush=True)
        print(_table(f"health, {args.events} events, seeds {seeds.start}-{seeds.stop - 1}", rows,
                     {"inertia_conflict": PRIOR_CONFLICT_SD, "held_out": Z_THRESHOLD}))
    elif args.part == "leak":
        from cassini_bayes.inference.adequacy import AUTOCORR_MAX, PRIOR_CONFLICT_SD, Z_THRESHOLD

        rows = {}
        for seed in seeds:
            for r in _leak(seed, args.hours, 2, args.check_step, args.true_inertia):
                raw.setdefault("stretches", []).append({"seed": seed, **r})
                for model in MODELS:
                    rows.setdefault(f"{'10 % leak' if r['leak'] else 'no leak'}, {model}",
                                    []).append(r[model])
            print(f"seed {seed}: {time.time() - t0:.0f} s", file=sys.stderr, flush=True)
        print(_table(f"leak monitor, {args.hours:g} h stretches, seeds {seeds.start}-"
                     f"{seeds.stop - 1}" + (", models with the true inertia"
                                            if args.true_inertia else ""), rows,
                     {"residual_fit": Z_THRESHOLD, "prior_data_conflict": PRIOR_CONFLICT_SD,
                      "residual_autocorrelation": AUTOCORR_MAX}))
        print("\n" + _answers(raw["stretches"]))
    else:
        from cassini_bayes.inference.adequacy import Z_THRESHOLD

        settings = {"chains": 2, "warmup": 200, "draws": 200}
        rows = {"clean (both Post-Probe)": [], "epochs mixed (Pre-SOI slews)": []}
        for seed in seeds:
            res = _budget(seed, settings)
            raw.setdefault("pairs", []).append({"seed": seed, **res})
            rows["clean (both Post-Probe)"].append({"shared_inertia": res["clean"]})
            rows["epochs mixed (Pre-SOI slews)"].append({"shared_inertia": res["epochs"]})
            print(f"seed {seed}: {time.time() - t0:.0f} s", file=sys.stderr, flush=True)
        print(_table(f"budget, inertia + thrust fits (2 x 200 + 200), seeds {seeds.start}-"
                     f"{seeds.stop - 1}", rows, {"shared_inertia": Z_THRESHOLD}))
    print(f"\n{time.time() - t0:.0f} s")
    if args.json:
        Path(args.json).write_text(json.dumps({"args": vars(args), "raw": raw}, indent=1))


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    main()
