"""The predicted posterior of a biasing event (``cassini-bayes plan evaluate`` / ``plan thrust``)
against NUTS fits of open-world replicates.

For each case (a scenario name or path, and the thrust fit's mode): the predicted posterior sd
of every thrust site (Laplace on the event flown without noise, made once on the nominal
scenario, :func:`cassini_bayes.plan.thrust.evaluate_thrust`); then ``--seeds`` replicates, each
an open-world truth (:func:`cassini_bayes.simulate.open_world.draw_open_world` with the inertia
drawn: non-Normal sensor and wheel errors 1.5× wider than the robust priors, external torques
1.5× the prior's and a drift, a flexible mode, time-tag errors and stale samples), simulated with
noise and fitted by the default robust ``fit thrust`` (NUTS). Per site: the fitted sd over the
predicted (median over the seeds, range) and the 90 % coverage of the truth; per fit, each
site's ``z`` (posterior mean less the truth, over the posterior sd) and the learned noise
levels (``sigma_omega``, ``sigma_rho``, posterior median) over the scenario's sensors', and the
learned time-tag sd beside the sd of the tag errors flown.
``--nominal``: the scenario itself simulated with its noise, no open-world error (the
prediction's own assumptions). Not a test.

    python benchmarks/plan_thrust.py --case biasing_day028:mean --case PLAN/scenario.toml:thruster
        [--seeds 10] [--nominal] [--chains 4] [--warmup 300] [--draws 300] [--json out.json]
        [--without flex ...] [--resume] [--truths 8] [--fits-from RECORD ...] [--matched]
        [--first-seed K] [--regular-clock]

``--truths N``: the prediction is the median over the nominal truth and N truths drawn from the
model file's knowledge (``plan evaluate --truths``). ``--fits-from RECORD ...``: each case's fits
are those of other records (same case, settings and truths; their fits joined in seed order),
only the prediction is made. ``--first-seed K``: fit seeds K .. ``--seeds`` − 1 only (two
processes share a campaign; ``--fits-from`` joins their records).
``--matched``: also the prediction at each seed's own open-world truth (its noise-free flight,
its own pulses), each fit's ``predicted_matched``.
``--regular-clock``: the model file states the telemetry's clock regular (``[telemetry_knowledge]
regular_clock``), in the prediction and the fits alike. ``--tag-sd-s X`` (with ``--fits-from``):
the prediction as if the model file stated a time-tag sd of X s (the open world flies 1.5 × the
statement; on a regular clock the fits take the labels' scatter, so only the prediction moves).
``--without``: those open-world effects switched off (:func:`cassini_bayes.simulate.open_world.
without`; every other draw unchanged). ``--resume`` keeps the fits of an interrupted ``--json``
record (same options; the prediction is re-made, noise-free and deterministic) and fits the seeds
it lacks.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _fitted(post, names: list[str], thrusters) -> tuple[list[float], object]:
    """Posterior sd of each site and the draws (S, sites)."""
    import numpy as np

    cols = []
    for n in names:
        if n.startswith("F["):
            v = np.asarray(post["F"].values)
            v = v.reshape(-1, v.shape[-1])[:, list(thrusters).index(n[2:-1])]
        else:
            v = np.asarray(post[n].values).ravel()
        cols.append(v)
    d = np.stack(cols, 1)
    return d.std(0).tolist(), d


def _tag_sds(post, flown_s: float) -> dict:
    """The learned time-tag sd (posterior median, s) beside the sd of the tag errors flown
    ``flown_s``, where the fit learns it."""
    import numpy as np

    if "time_tag_sd" not in post:
        return {}
    return {"tag_sd_learned_s": float(np.median(np.asarray(post["time_tag_sd"].values))),
            "tag_sd_flown_s": float(flown_s)}


CLOCK: dict = {"regular": False, "tag_sd_s": None}
"""Whether the model file is taken to state a regular clock (``--regular-clock``), and the
time-tag sd it is taken to state (``--tag-sd-s``; ``None``: its own)."""


def _stated(s):
    """Scenario ``s`` with its model file's clock as ``--regular-clock`` and ``--tag-sd-s``
    state it."""
    from dataclasses import replace

    tag = {} if CLOCK["tag_sd_s"] is None else {"time_tag_sd_s": CLOCK["tag_sd_s"]}
    k = replace(s.prior.knowledge, regular_clock=CLOCK["regular"], **tag)
    return replace(s, prior=replace(s.prior, knowledge=k))


def _open_world(name: str, seed: int, off: tuple, src: str):
    """The open-world truth of ``seed`` (its draw and its scenario)."""
    import numpy as np

    from cassini_bayes.simulate import scenario_from_dict
    from cassini_bayes.simulate.open_world import draw_open_world, without

    ow = draw_open_world(name, np.random.default_rng([seed, 3232]), draw_inertia=True)
    ow = without(ow, off) if off else ow
    return ow, _stated(scenario_from_dict(ow.scenario, src=src))


def matched(fits: list, name: str, mode: str, off: tuple, src: str) -> None:
    """Add to each fit the prediction at its own truth (``predicted_matched``: the noise-free
    flight of that truth, its own pulses)."""
    from cassini_bayes.plan.thrust import evaluate_thrust

    for f in fits:
        if "predicted_matched" not in f:
            f["predicted_matched"] = evaluate_thrust(_open_world(name, f["seed"], off, src)[1],
                                                     mode).site_sd.tolist()
            print(f"{name} seed {f['seed']}: predicted at its own truth", file=sys.stderr,
                  flush=True)


def run(case: str, seeds: int, settings, partial=None, nominal: bool = False,
        fits: list | None = None, off: tuple = (), truths: int = 0,
        match: bool = False, first: int = 0) -> dict:
    """One case: the prediction, then the fits of the seeds ``first .. seeds - 1`` that ``fits``
    (those of a resumed or joined record, kept) lacks."""
    import jax
    import numpy as np

    from cassini_bayes._devices import release_compiled_programs
    from cassini_bayes.inference.thrust import fit_thrust
    from cassini_bayes.plan.thrust import _truth, evaluate_thrust
    from cassini_bayes.plan.wheel_axis import scenario_noise
    from cassini_bayes.simulate import load_scenario, simulate
    from cassini_bayes.simulate.open_world import apply_time_tags

    name, mode = case.rsplit(":", 1) if ":" in case else (case, "mean")
    s = _stated(load_scenario(name))
    t0 = time.perf_counter()
    pred = evaluate_thrust(s, mode, truths=truths)
    t_pred = time.perf_counter() - t0
    names = list(pred.sites)
    print(f"{name} ({mode}): predicted in {t_pred:.0f} s: " + ", ".join(
        f"{n} {sd:.3g}" for n, sd in zip(names, pred.site_sd)), file=sys.stderr, flush=True)
    fits = list(fits or [])
    have = {f["seed"] for f in fits}
    for seed in (k for k in range(first, seeds) if k not in have):
        k_sim, k_fit = jax.random.split(jax.random.key(3200 + seed))
        if nominal:
            si = s
            sim = simulate(k_sim, si)
            tel = sim.telemetry
        else:
            ow, si = _open_world(name, seed, off, s.source)
            sim = simulate(k_sim, si)
            tel = apply_time_tags(sim.telemetry, ow)
        sensor = np.asarray(scenario_noise(si)[:2], float)
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            post = fit_thrust(k_fit, [(tel, sim.pulses)], s.prior, mode=mode, settings=settings,
                              prior_draws=0)
        sd, draws = _fitted(post.idata.posterior, names, post.problem.thrusters)
        truth = _truth(si, post.problem, names)
        lo, hi = np.quantile(draws, [0.05, 0.95], axis=0)
        z = (draws.mean(0) - truth) / np.asarray(sd)
        fits.append({"seed": seed, "sd": sd, "hit90": ((lo <= truth) & (truth <= hi)).tolist(),
                     "z": z.tolist(),
                     "noise_over_sensor": [
                         float(np.median(np.asarray(post.idata.posterior[k].values)) / sensor[j])
                         for j, k in enumerate(("sigma_omega", "sigma_rho"))],
                     **_tag_sds(post.idata.posterior, si.noise.time_tag_jitter_s if nominal
                                else np.std(ow.time_tag_error_s)),
                     "r_hat": float(post.diagnostics.max_r_hat),
                     "divergences": int(post.diagnostics.divergences),
                     "seconds": time.perf_counter() - t0})
        print(f"{name} seed {seed}: {fits[-1]['seconds']:.0f} s, R-hat {fits[-1]['r_hat']:.3f}, "
              f"div {fits[-1]['divergences']}, noise/sensor "
              + "/".join(f"{x:.2f}" for x in fits[-1]["noise_over_sensor"])
              + (f", tag sd {1e3 * fits[-1]['tag_sd_learned_s']:.3g} ms learned, "
                 f"{1e3 * fits[-1]['tag_sd_flown_s']:.3g} flown"
                 if "tag_sd_learned_s" in fits[-1] else ""),
              file=sys.stderr, flush=True)
        release_compiled_programs()   # docs/limits.md: mappings of compiled programs
        if partial is not None:
            partial(_summary(case, s, mode, pred, t_pred, names, fits, nominal, off))
    if match and not nominal:
        matched(fits, name, mode, off, s.source)
    return _summary(case, s, mode, pred, t_pred, names, fits, nominal, off)


def _summary(case, s, mode, pred, t_pred, names, fits, nominal=False, off=()) -> dict:
    import numpy as np

    sd = np.array([f["sd"] for f in fits])
    ratio = sd / pred.site_sd[None, :]
    hits = np.array([f["hit90"] for f in fits], float)
    sites = {n: {"predicted": float(pred.site_sd[i]), "prior": float(pred.site_prior_sd[i]),
                 **({"predicted_nominal": float(pred.site_sd_nominal[i]),
                     "predicted_range": [float(x[i]) for x in pred.site_sd_range],
                     "predicted_truths": pred.site_sd_truths[:, i].tolist(),
                     "predicted_interval90": [float(x[i]) for x in pred.site_sd_interval]}
                    if pred.truths else {}),
                 "budget": float(pred.budget[i]),
                 "fitted_median": float(np.median(sd[:, i])),
                 "ratio_median": float(np.median(ratio[:, i])),
                 "ratio_min": float(ratio[:, i].min()), "ratio_max": float(ratio[:, i].max()),
                 "coverage90": float(hits[:, i].mean())}
             for i, n in enumerate(names)}
    med = np.median(ratio, 0)
    if fits and all("predicted_matched" in f for f in fits):
        own = sd / np.array([f["predicted_matched"] for f in fits])
        for i, n in enumerate(names):
            sites[n]["ratio_matched_median"] = float(np.median(own[:, i]))
    return {"case": case, "scenario": s.name, "mode": mode, "seeds": len(fits),
            "truths": "nominal" if nominal else "open_world", "without": sorted(off),
            "predicted_over_truths": int(pred.truths),
            "floored": int(pred.floored),
            "predict_seconds": t_pred, "predicted_max_ratio": pred.max_ratio,
            "predicted_worst": pred.worst, "n_pulses": pred.n_pulses,
            "pulse_widths_s": list(pred.pulse_widths_s), "sites": sites, "fits": fits,
            "within_25pct": int(np.sum(np.abs(med - 1) <= 0.25)), "n_sites": len(names),
            "coverage90": float(hits.mean()),
            "max_r_hat": float(max(f["r_hat"] for f in fits)),
            "divergences": int(sum(f["divergences"] for f in fits))}


def _settings(a) -> dict:
    """The record's sampler settings, and the clock where stated regular."""
    out = {"chains": a.chains, "warmup": a.warmup, "draws": a.draws}
    return {**out, "regular_clock": True} if a.regular_clock else out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", action="append", required=True,
                    help="SCENARIO[:MODE] (mode mean, branch or thruster; default mean)")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--nominal", action="store_true",
                    help="the scenario's own truth and noise, no open-world error")
    ap.add_argument("--without", nargs="+", default=[], metavar="EFFECT",
                    help="open-world effects to switch off (open_world.EFFECTS_OFF)")
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--warmup", type=int, default=300)
    ap.add_argument("--draws", type=int, default=300)
    ap.add_argument("--json", type=Path)
    ap.add_argument("--resume", action="store_true",
                    help="keep the fits of the --json record and fit the seeds it lacks")
    ap.add_argument("--truths", type=int, default=0,
                    help="predict as the median over the nominal truth and N drawn from the "
                         "model file's knowledge (plan evaluate --truths)")
    ap.add_argument("--matched", action="store_true",
                    help="also predict at each seed's own open-world truth")
    ap.add_argument("--fits-from", type=Path, nargs="+", metavar="RECORD",
                    help="take the fits of each case from these records (same settings; joined "
                         "in seed order): only the prediction is made")
    ap.add_argument("--first-seed", type=int, default=0,
                    help="fit seeds from this one (another process fits the ones before)")
    ap.add_argument("--regular-clock", action="store_true",
                    help="the model file states the telemetry's clock regular")
    ap.add_argument("--tag-sd-s", type=float,
                    help="predict as if the model file stated this time-tag sd, s (with "
                         "--fits-from: the fits are not re-made)")
    a = ap.parse_args(argv)
    if a.tag_sd_s is not None and not (a.fits_from and a.tag_sd_s > 0):
        sys.exit("--tag-sd-s: give a positive sd, s, with --fits-from (it moves the prediction "
                 "only)")
    CLOCK.update(regular=a.regular_clock, tag_sd_s=a.tag_sd_s)
    before = {}
    if a.fits_from:
        for path in a.fits_from:
            rec = json.loads(path.read_text())
            if rec["settings"] != _settings(a):
                sys.exit(f"--fits-from {path}: made with sampler settings {rec['settings']}")
            for r in rec["results"]:
                if (r["truths"] == ("nominal" if a.nominal else "open_world")
                        and r["without"] == sorted(a.without)):
                    before.setdefault(r["case"], []).extend(r["fits"])
        for case, fits in before.items():
            fits.sort(key=lambda f: f["seed"])
            if len({f["seed"] for f in fits}) < len(fits):
                sys.exit(f"--fits-from: {case} has a seed in two records")
    if a.resume:
        if not (a.json and a.json.is_file()):
            sys.exit("--resume: give --json with the record to resume")
        before = {r["case"]: r["fits"] for r in json.loads(a.json.read_text())["results"]}
    if a.json:
        from _provenance import start

        a.json.parent.mkdir(parents=True, exist_ok=True)
        start(a.json, {k: v for k, v in vars(a).items()
                       if k != "resume" and not (k == "first_seed" and v == 0)}, argv,
              replace=not a.resume)
    sys.path.insert(0, str(ROOT))
    import cassini_bayes
    from cassini_bayes.files import write_text
    from cassini_bayes.inference.runner import SamplerSettings

    cassini_bayes.setup_jax()
    settings = SamplerSettings(chains=a.chains, warmup=a.warmup, draws=a.draws,
                               chain_method="vectorized")
    out = {"settings": _settings(a), "results": []}
    def write(results):
        if a.json:
            write_text(a.json, json.dumps({**out, "results": results}, indent=1))

    for case in a.case:
        done = list(out["results"])
        r = run(case, 0 if a.fits_from else a.seeds, settings,
                partial=lambda r: write(done + [r]), nominal=a.nominal, fits=before.get(case),
                off=tuple(a.without), truths=a.truths, first=a.first_seed, match=a.matched)
        if a.tag_sd_s is not None:
            r["predicted_tag_sd_s"] = a.tag_sd_s
        out["results"].append(r)
        kind = "nominal" if a.nominal else "open-world"
        print(f"\n{case}: fitted sd / predicted sd, median over {r['seeds']} {kind} seeds "
              f"(min–max); {r['within_25pct']}/{r['n_sites']} sites within 25 %; 90 % "
              f"coverage {r['coverage90']:.3f}; R-hat <= {r['max_r_hat']:.3f}, "
              f"{r['divergences']} divergences")
        for lab, v in r["sites"].items():
            print(f"  {lab:10s} pred {v['predicted']:10.4g}  fit {v['fitted_median']:10.4g}  "
                  f"ratio {v['ratio_median']:.3f} ({v['ratio_min']:.3f}–{v['ratio_max']:.3f})"
                  f"  cover90 {v['coverage90']:.2f}  prior {v['prior']:.4g}"
                  + (f"  own truth {v['ratio_matched_median']:.3f}"
                     if "ratio_matched_median" in v else ""), flush=True)
        write(out["results"])


if __name__ == "__main__":
    main()
