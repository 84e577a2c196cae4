"""Where the robust thrust fit's mode lies on one open-world flight, without sampling: a probe of
which error moves the time constants, about a minute a variant where a NUTS fit takes 10-20.

    python benchmarks/thrust_mode_probe.py --case biasing_espa_bus_mixed_widths:thruster
        --seed 4 [--variant OFF:TAGS ...] [--json PATH]

Each variant flies the open-world truth of ``--seed`` (the draw of ``plan_thrust.py``, the same
keys) with the effects ``OFF`` switched off (comma-separated, ``open_world.EFFECTS_OFF``;
``none``) and the telemetry's time-tag errors (times ``--tag-factor``) kept only on the samples
``TAGS`` names:

- ``all``: every sample (the open world); ``none``: the true sample times;
- ``near`` / ``far``: the samples within / beyond :data:`NEAR_S` of a pulse's command or end;
- ``start`` / ``end``: the samples at a pulse's command / end time (to a microsecond);
- ``grid``: every sample's tag, then the labels put on their least-squares regular grid (a
  straight line in the sample index): what a fit could do if it knew the clock regular, with
  the grid's own error (an offset and a rate, about ``σ_t/√n``) left;
- ``clock``: every sample's tag, and the model file stating a regular clock
  (``[telemetry_knowledge] regular_clock``): the fit puts the labels on their grid itself and
  integrates the grid's offset and period errors out.

``--knowledge-factor`` multiplies the fit's prior sds of the robust nuisance (the model file's
gyro, wheel-scale, wheel-tilt and torque knowledge; the open world is drawn from the file's own);
``--inertia truth`` fixes the inertia at the flight's true one in place of sampling it.

It prints the time constants and the time tags' learned scale at the mode of the fit's density
(the Laplace mode its preparation finds, ``ThrustProblem.data.centre``), with the fit's default
model (robust, inertia sampled). The mode moves as the posterior does; where the posterior is
not Gaussian the two can differ by several of its sds (the NUTS fits of the same seeds are in
``plan_thrust.py``'s records). Not a test.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NEAR_S = 0.2
TAGS = ("all", "none", "near", "far", "start", "end", "grid", "clock")


def _kept(t, pulses, which: str):
    """(n,) bool: the samples of true times ``t`` whose time-tag error is kept."""
    import numpy as np

    t_on = np.asarray(pulses.t_on, float)
    t_off = t_on + np.asarray(pulses.width, float)
    gap = {k: np.min(np.abs(e[None, :] - t[:, None]), 1)
           for k, e in (("start", t_on), ("end", t_off))}
    near = np.minimum(gap["start"], gap["end"]) < NEAR_S
    every = np.ones(t.size, bool)
    return {"all": every, "grid": every, "clock": every, "none": ~every, "near": near,
            "far": ~near, "start": gap["start"] < 1e-6, "end": gap["end"] < 1e-6}[which]


_KNOWLEDGE = ("gyro_bias_sd_rad_s", "gyro_scale_factor_sd", "wheel_inertia_sd_frac",
              "wheel_common_inertia_sd_frac", "wheel_axis_sd_deg", "torque_sd_nm",
              "torque_rate_sd_nm_per_h")
_NUISANCE = {"gyro_scale": ("gyro_scale_factor", 1.0, "gyro"),
             "wheel_inertia": ("wheel_inertia_errors", 1.0, "wheels"),
             "wheel_axes": ("wheel_axis_tilt_deg", 57.29577951308232, "tilts")}


def _nuisance_at_mode(p, at, record: dict) -> dict:
    """Per block of ``ν`` (gyro scale, wheel scales, wheel tilts in degrees): its conditional
    mean and sd at the mode, and the open world's draw (zeros where that effect is off)."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    from cassini_bayes.inference.gaussian import nuisance_marginal
    from cassini_bayes.inference.thrust.model import _event_stats, nuisance_sd

    st = _event_stats(at, p.data)
    sd = nuisance_sd(at, p.data)
    _, mean, chol = nuisance_marginal(jnp.sum(st.info, 0), jnp.sum(st.score, 0), sd)
    cov = jax.scipy.linalg.cho_solve((chol, True), jnp.eye(chol.shape[0]))
    nu, nu_sd = np.asarray(sd * mean), np.asarray(sd) * np.sqrt(np.diag(np.asarray(cov)))
    out = {}
    for block, (effect, unit, switch) in _NUISANCE.items():
        sl = p.layout.slices[block]
        drawn = np.ravel(record.get(effect, {}).get("values", []))
        out[block] = {"mode": (unit * nu[sl]).tolist(), "sd": (unit * nu_sd[sl]).tolist(),
                      "prior_sd": (unit * np.asarray(sd)[sl]).tolist(),
                      "truth": (0.0 * drawn if switch in record.get("off", ()) else drawn).tolist()}
    return out


def probe(case: str, seed: int, off: tuple, tags: str, factor: float = 1.0,
          knowledge_factor: float = 1.0, inertia: str = "sampled") -> dict:
    """One variant: the mode's time constants (s) and tag scale, the truth's, the kept count."""
    import jax
    import numpy as np
    from plan_thrust import _open_world

    from cassini_bayes.inference.thrust import prepare_thrust, resolve_inertia
    from cassini_bayes.inference.thrust.coords import physical
    from cassini_bayes.simulate import load_scenario, simulate
    from cassini_bayes.simulate.open_world import apply_time_tags

    name, mode = case.rsplit(":", 1) if ":" in case else (case, "mean")
    s = load_scenario(name)
    k_sim, _ = jax.random.split(jax.random.key(3200 + seed))   # plan_thrust.py's keys
    ow, si = _open_world(name, seed, off, s.source)
    sim = simulate(k_sim, si)
    tel = apply_time_tags(sim.telemetry, ow)
    t = np.asarray(sim.telemetry.t, float)
    keep = _kept(t, sim.pulses, tags)
    tel = replace(tel, t=t + factor * (np.asarray(tel.t, float) - t) * keep)
    if tags == "grid":
        k = np.arange(t.size)
        tel = replace(tel, t=np.polyval(np.polyfit(k, np.asarray(tel.t, float), 1), k))
    prior = s.prior
    if tags == "clock":
        prior = replace(prior, knowledge=replace(prior.knowledge, regular_clock=True))
    kn = prior.knowledge
    prior = replace(prior, knowledge=replace(kn, **{k: knowledge_factor * getattr(kn, k)
                                                    for k in _KNOWLEDGE}))
    sample = inertia == "sampled"
    if not sample:
        prior = replace(prior, inertia=np.asarray(si.truth.inertia, float))
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p = prepare_thrust([(tel, sim.pulses)], prior, mode=mode, robust=True,
                           inertia=resolve_inertia(None, prior, sample))
    at = physical(p.data.centre, p.data, p.n_f, p.n_c, sample)
    jac = np.asarray(jax.jacfwd(lambda x: physical(x, p.data, p.n_f, p.n_c, sample).tau)(
        p.data.centre)) @ np.asarray(p.data.tril)
    com = {}
    if p.n_c:                                   # mode thruster: the centre-of-mass offset too
        j_com = np.asarray(jax.jacfwd(lambda x: physical(x, p.data, p.n_f, p.n_c, sample).com)(
            p.data.centre)) @ np.asarray(p.data.tril)
        com = {"com_mode_m": np.asarray(at.com, float).tolist(),
               "com_laplace_sd_m": np.sqrt(np.sum(j_com**2, 1)).tolist(),
               "com_truth_m": (np.asarray(si.truth.com_m, float)
                               - np.asarray(prior.com_m, float)).tolist()}
    return {"seed": seed, "without": sorted(off), "tags": tags, "tag_factor": factor,
            "knowledge_factor": knowledge_factor, "inertia": inertia,
            "nuisance": _nuisance_at_mode(p, at, ow.record),
            "tagged": int(keep.sum()),
            "largest_tag_s": float(np.max(np.abs(np.asarray(tel.t, float) - t))),
            "mean_tag_s": float(np.mean(np.asarray(tel.t, float) - t)),
            "samples": int(t.size), "tau_mode_s": np.asarray(at.tau, float).tolist(),
            "tau_laplace_sd_s": np.sqrt(np.sum(jac**2, 1)).tolist(),
            "tau_truth_s": np.asarray(sim.params.tau_s, float).tolist(),
            "tag_scale_mode": float(at.tag_scale), **com, "seconds": time.perf_counter() - t0}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", required=True, help="SCENARIO[:MODE]")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--variant", nargs="+", default=["flex:all"], metavar="OFF:TAGS")
    ap.add_argument("--tag-factor", type=float, default=1.0,
                    help="the kept time-tag errors times this factor")
    ap.add_argument("--knowledge-factor", type=float, default=1.0,
                    help="the fit's nuisance prior sds times this factor")
    ap.add_argument("--inertia", choices=("sampled", "truth"), default="sampled")
    ap.add_argument("--json", type=Path)
    a = ap.parse_args(argv)
    variants = []
    for v in a.variant:
        off, _, tags = v.partition(":")
        if tags not in TAGS:
            sys.exit(f"--variant {v}: TAGS is one of {', '.join(TAGS)}")
        variants.append((tuple(x for x in off.split(",") if x and x != "none"), tags))
    if a.json:
        from _provenance import start

        start(a.json, vars(a), argv)
    sys.path.insert(0, str(ROOT))
    import cassini_bayes
    from cassini_bayes.files import write_text

    cassini_bayes.setup_jax()
    out = []
    for off, tags in variants:
        r = probe(a.case, a.seed, off, tags, a.tag_factor, a.knowledge_factor, a.inertia)
        out.append(r)
        ms = ", ".join(f"{1e3 * m:.2f} ± {1e3 * d:.2f} ({1e3 * x:g})" for m, d, x in
                       zip(r["tau_mode_s"], r["tau_laplace_sd_s"], r["tau_truth_s"]))
        print(f"seed {a.seed}, without {','.join(r['without']) or 'none'}, tags on {tags} "
              f"({r['tagged']}/{r['samples']}, largest {1e3 * r['largest_tag_s']:.3g} ms): "
              f"tau_delay, rise, fall at the mode ± Laplace sd (truth) ms "
              f"{ms}; tag scale {r['tag_scale_mode']:.3g} ({r['seconds']:.0f} s)"
              + ("" if "com_mode_m" not in r else "; com at the mode ± sd (truth) mm " + ", ".join(
                  f"{1e3 * m:.3f} ± {1e3 * d:.3f} ({1e3 * x:.3f})" for m, d, x in
                  zip(r["com_mode_m"], r["com_laplace_sd_m"], r["com_truth_m"]))), flush=True)
        if a.json:
            write_text(a.json, json.dumps({"case": a.case, "results": out}, indent=1))


if __name__ == "__main__":
    main()
