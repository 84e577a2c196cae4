"""One small fit per model, run through the CLI, and its summary.json numbers pinned with a
tolerance each.

``tests/data/fit_pins.json`` holds, per model, the ``summary`` a fixed-seed fit wrote and, beside
it, a ``tolerance`` tree of the same shape that says how each leaf is compared on another
machine. Draws are bit-identical on one CPU only: XLA's code differs between instruction sets
(vector widths, fused multiply-add), and NUTS turns a last-bit difference into another chain. So:

* ``exact`` — what no sampler touches (the least-squares baseline, the data's windows,
  configuration strings, and the prior sd, whose prior draws come from the seed's key and are
  marked ``seeded``): relative ``rtol`` 1e-9.
* ``laplace`` — what an optimiser computes (the inertia sensitivity shifts at the posterior
  mode): relative ``rtol`` 1e-6, the optimiser's own convergence scale.
* ``mc`` — sampled summaries: absolute ``atol`` = :data:`K_MCSE` × ArviZ's Monte Carlo standard
  error of that number in the pinned run (``az.mcse``: mean, sd, quantiles). Two independent
  chains differ by √2 MCSE in sd, so the bound is 4.9 sd: about 1e-6 per number, under 0.1 %
  for all ~900 MCSE-compared numbers together (union bound).
* ``coarse`` — sampled figures without an MCSE of their own (R-hat, ESS, divergences, adequacy
  statistics, regression sensitivities on draws): a stated absolute or ratio bound that holds
  between seeds (checked by :func:`check_other_seeds`) and still catches a unit, sign or
  formula error.
* ``verdict`` — a boolean decided by a sampled figure, compared exactly only where that figure
  sits far from its threshold in the pin (else ``skip``).
* ``text`` — a message with its numbers masked; ``skip`` — an arg-max label or a decision too
  near its threshold to be stable, recorded but not compared.

The API-vs-CLI comparison in one process (``tests/test_api.py``) stays exact: same machine, same
seed, same numbers (:func:`assert_same`).

Record with ``python tests/fit_pins.py [MODEL ...]`` (re-record only for a deliberate change of
the numbers, and say why in the commit); ``python tests/fit_pins.py --check-seeds 5 [MODEL ...]``
fits the same inputs with other seeds and compares them with the pins by these rules (the
false-failure check).
"""

from __future__ import annotations

import json
import math
import re
import sys
from pathlib import Path

PINS = Path(__file__).parent / "data" / "fit_pins.json"
SMALL = {"chains": 2, "warmup": 150, "draws": 150}
K_MCSE = 7.0
"""Multiple of the pinned run's Monte Carlo standard error allowed for a sampled number."""

# model -> (scenario, simulation key, spacecraft model, extra CLI options, seed)
RECIPES = {
    "inertia": ("slew_2000_03_15", 21, "models/cassini_2000_03_15.toml", [], 3),
    "thrust": ("fsds_biasing", 31, "models/fsds.toml", [], 4),
    "rwa4": ("rwa4_rcs", 32, "models/cassini_pre_soi.toml",
             ["--method", "rcs", "--prior", "cone"], 5),
}

PRIOR_DRAWS = 500
"""Prior draws of a fit (``cassini_bayes.inference.runner``), whence ``prior_sd``."""
_STATS = ("mean", "sd", "q05", "q50", "q95")
_CONFIG = {"kind", "seed", "version", "model", "mode", "method", "prior", "wheel_errors"}


def write_inputs(model: str, folder: Path) -> dict[str, Path]:
    """Simulate the model's scenario into ``folder``: ``{"telemetry": csv, "pulses": csv?}``."""
    import jax

    from cassini_bayes import setup_jax
    from cassini_bayes.simulate import load_scenario, simulate
    from cassini_bayes.telemetry import write_pulses, write_telemetry

    setup_jax()
    scenario, sim_key = RECIPES[model][:2]
    r = simulate(jax.random.key(sim_key), load_scenario(scenario))
    folder.mkdir(parents=True, exist_ok=True)
    files = {"telemetry": folder / "telemetry.csv"}
    write_telemetry(files["telemetry"], r.telemetry, force=True)
    if r.pulses is not None and model == "thrust":
        files["pulses"] = folder / "pulses.csv"
        write_pulses(files["pulses"], r.pulses, force=True)
    return files


def cli_args(model: str, files: dict[str, Path], out: Path, seed: int | None = None) -> list[str]:
    """``cassini-bayes fit MODEL ...`` arguments of the pinned run (another ``seed`` if given)."""
    _, _, spacecraft, extra, pinned_seed = RECIPES[model]
    args = ["fit", model, "--telemetry", str(files["telemetry"])]
    if "pulses" in files:
        args += ["--pulses", str(files["pulses"])]
    seed = pinned_seed if seed is None else seed
    args += ["--spacecraft", spacecraft, "--out", str(out), "--seed", str(seed), *extra]
    for k, v in SMALL.items():
        args += [f"--{k}", str(v)]
    return args


def numbers(summary: dict) -> dict:
    """The summary without what legitimately differs between runs (warning lines name paths)."""
    return {k: v for k, v in summary.items() if k != "warnings"}


# --- exact comparison (one machine, one process) -------------------------------------------

def assert_same(a, b, where: str = "summary", rtol: float = 1e-9) -> None:
    """Equal structure, equal strings (but for directories)/ints/bools, floats within ``rtol``
    relative: for two runs on the same machine with the same seed."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), f"{where}: keys {set(a) ^ set(b)}"
        for k in a:
            assert_same(a[k], b[k], f"{where}.{k}", rtol)
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), f"{where}: lengths differ"
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{where}[{i}]", rtol)
    elif isinstance(a, float) and not isinstance(b, bool) and isinstance(b, (int, float)):
        assert math.isclose(a, b, rel_tol=rtol, abs_tol=1e-300), f"{where}: {a!r} != {b!r}"
    elif isinstance(a, str):  # messages name the input files: compare their names only
        assert _no_dirs(a) == _no_dirs(b), f"{where}: {a!r} != {b!r}"
    else:
        assert a == b, f"{where}: {a!r} != {b!r}"


def _no_dirs(text) -> str:
    return re.sub(r"\S*/", "", text) if isinstance(text, str) else text


def _masked(text: str) -> str:
    return re.sub(r"[-+]?\d+(\.\d+)?(e[-+]?\d+)?", "#", _no_dirs(text))


# --- comparison by tolerance (any machine) ------------------------------------------------

def assert_within_tolerance(pin: dict, summary: dict, where: str = "summary", *, idata=None,
                            other_seed: bool = False) -> None:
    """``summary`` (a fresh run's numbers) matches the pinned ``{"summary", "tolerance"}`` by
    each leaf's rule (module docstring); the message lists every leaf outside its rule, with
    both values and the rule.

    ``idata``: the fresh run's posterior; a sampled number's bound is then the larger of the
    two runs' (a run that mixed worse than the pin carries a larger MCSE). ``other_seed``: the
    run used another seed, so ``seeded`` numbers are not compared."""
    run_rules = tolerances(summary, idata) if idata is not None else None
    failures: list[str] = []
    _compare(pin["summary"], summary, pin["tolerance"], run_rules, where, other_seed, failures)
    assert not failures, "\n".join(failures)


def _compare(a, b, rule, run_rule, where: str, other_seed: bool, failures: list[str]) -> None:
    if isinstance(a, dict):
        if not (isinstance(b, dict) and set(a) == set(b)):
            failures.append(
                f"{where}: keys differ: {set(a) ^ set(b) if isinstance(b, dict) else b}")
            return
        for k in a:
            _compare(a[k], b[k], rule[k], None if run_rule is None else run_rule[k],
                     f"{where}.{k}", other_seed, failures)
        return
    if isinstance(a, list) and not (isinstance(rule, dict) and "compare" in rule):
        if not (isinstance(b, list) and len(a) == len(b)):
            failures.append(f"{where}: lengths differ")
            return
        for i, (x, y) in enumerate(zip(a, b)):
            _compare(x, y, rule[i], None if run_rule is None else run_rule[i],
                     f"{where}[{i}]", other_seed, failures)
        return
    if run_rule is not None and "atol" in rule and "atol" in run_rule:
        rule = {**rule, "atol": max(rule["atol"], run_rule["atol"])}
    if not _agrees(a, b, rule, other_seed):
        failures.append(f"{where}: {b!r} against the pinned {a!r} ({rule})")


def _agrees(a, b, rule: dict, other_seed: bool) -> bool:
    how = rule["compare"]
    if how == "skip" or (other_seed and rule.get("seeded")):
        return True
    if how == "text":
        return _masked(a) == _masked(b)
    if how in ("exact", "laplace", "verdict") and not isinstance(a, float):
        return (_no_dirs(a) == _no_dirs(b)) if isinstance(a, str) else a == b
    if a is None or b is None:
        return a is None and b is None
    if how in ("exact", "laplace"):
        return math.isclose(a, b, rel_tol=rule["rtol"], abs_tol=1e-300)
    if "ratio" in rule:
        return a > 0 and b > 0 and max(a / b, b / a) <= rule["ratio"]
    return abs(a - b) <= rule["atol"]


# --- the tolerance tree -------------------------------------------------------------------

def tolerances(summary: dict, idata) -> dict:
    """The tolerance tree of a pinned ``summary`` (module docstring), its MCSEs from the run's
    ``idata`` (``posterior.nc``)."""
    import numpy as np

    mcse = _mcse_by_label(idata)
    out = {}
    for key, value in summary.items():
        if key in _CONFIG:
            out[key] = _exact(1e-9)
        elif key in ("baseline", "windows", "wheel", "clock"):
            out[key] = _same_shape(value, _exact(1e-9))
        elif key in ("parameters", "nuisance"):
            out[key] = {label: _stat_rules(entry, mcse[label]) for label, entry in value.items()}
        elif key == "diagnostics":
            out[key] = {"divergences": {"compare": "coarse", "atol": 3,
                                        "why": "a divergence comes and goes with the last bits"},
                        "max_r_hat": {"compare": "coarse", "atol": 0.05,
                                      "why": "split R-hat of 2 short chains"},
                        "min_ess_bulk": _ess_rule(), "min_ess_tail": _ess_rule(),
                        "converged": {"compare": "skip",
                                      "why": "decided by sampled figures at a tiny size"}}
        elif key == "weakly_identified":
            near = [k for k, e in summary["parameters"].items()
                    if e.get("contraction") is not None and abs(e["contraction"] - 0.5) < 0.1]
            out[key] = ({"compare": "skip", "why": f"contraction of {near} near the 0.5 rule"}
                        if near else {"compare": "verdict",
                                      "why": "every contraction >= 0.1 from the 0.5 rule"})
        elif key == "adequacy":
            out[key] = _adequacy_rules(value)
        elif key == "sensitivity":
            out[key] = _sensitivity_rules(summary, value)
        elif key == "flex_mode":
            out[key] = _flex_rules(value)
        elif key == "direction":
            u = np.stack([idata.posterior[n].values.ravel() for n in ("u4_x", "u4_y", "u4_z")])
            axis = u.mean(axis=1) / np.linalg.norm(u.mean(axis=1))
            shape = idata.posterior["u4_x"].shape
            angle = np.degrees(np.arccos(np.clip(axis @ u, -1.0, 1.0))).reshape(shape)
            out[key] = {
                "mean": [_mc(mcse[f"u4_{c}"]["mean"]) for c in "xyz"],
                "cone_deg": {p: _mc(_az_mcse(angle, "quantile", int(p) / 100))
                             for p in value["cone_deg"]}}
        else:
            raise KeyError(f"no tolerance rule for summary key {key!r}: add one to fit_pins.py")
    return out


def _exact(rtol: float) -> dict:
    return {"compare": "exact", "rtol": rtol}


def _mc(mcse: float) -> dict:
    return {"compare": "mc", "atol": K_MCSE * mcse, "mcse": mcse}


def _ess_rule() -> dict:
    return {"compare": "coarse", "ratio": 10.0,
            "why": "ESS of 300 draws varies 7x between seeds (thrust's noise scales: 41 "
                   "against 298); a sampler that stops mixing gives ESS < 10"}


def _same_shape(value, rule):
    if isinstance(value, dict):
        return {k: _same_shape(v, rule) for k, v in value.items()}
    if isinstance(value, list):
        return [_same_shape(v, rule) for v in value]
    return rule


def _stat_rules(entry: dict, mcse: dict) -> dict:
    rules = {s: _mc(mcse[s]) for s in _STATS}
    rules["r_hat"] = {"compare": "coarse", "atol": 0.05, "why": "split R-hat of 2 short chains"}
    rules["ess_bulk"] = rules["ess_tail"] = _ess_rule()
    if "prior_sd" in entry:
        rules["prior_sd"] = {**_exact(1e-9), "seeded": True}
    if "contraction" in entry and entry["prior_sd"]:
        # 1 - c = sd²/prior_sd²: the range the sd's own tolerance allows (not linearised: K MCSE
        # can be a third of the sd), and for another seed the prior sd's spread (PRIOR_DRAWS
        # independent draws: relative sd 1/√(2n) of prior_sd, twice that of 1 - c)
        sd, c = entry["sd"], entry["contraction"]
        through_sd = (1.0 - c) * ((1.0 + K_MCSE * mcse["sd"] / sd) ** 2 - 1.0) if sd else 0.0
        through_prior = K_MCSE * 2.0 * (1.0 - c) / math.sqrt(2.0 * PRIOR_DRAWS)
        rules["contraction"] = {"compare": "mc", "atol": through_sd + through_prior,
                                "why": "through the sd's tolerance and the prior draws"}
    elif "contraction" in entry:
        rules["contraction"] = _exact(1e-9)
    return rules


def _adequacy_rules(adequacy: dict) -> dict:
    checks = {}
    for name, check in adequacy["checks"].items():
        stat, thr = check.get("statistic"), check["threshold"]
        stable = stat is None or abs(stat) <= 0.5 * thr
        rules = {"threshold": _exact(1e-9),
                 "statistic": {"compare": "coarse", "atol": 0.25 * thr,
                               "why": "a posterior-predictive statistic: a quarter of its "
                                      "threshold"},
                 "ok": ({"compare": "verdict", "why": "statistic <= half its threshold"}
                        if stable else {"compare": "skip", "why": "statistic near its threshold"})}
        if "parameter" in check:
            rules["parameter"] = {"compare": "skip", "why": "arg-max over sampled statistics"}
        if "note" in check:
            rules["note"] = {"compare": "text"}
        checks[name] = rules
    stable = all(r["ok"]["compare"] == "verdict" for r in checks.values())
    return {"ok": {"compare": "verdict" if stable else "skip"}, "checks": checks}


def _flex_rules(search: dict | None) -> dict:
    """The flexible-mode search (data only, no sampling): its verdicts exactly; its optimum,
    reached by Nelder-Mead on a likelihood whose last bits differ between CPUs, coarsely; where
    nothing is found the optimum is any local one, and not compared."""
    if search is None:
        return {"compare": "exact", "why": "no search"}
    found = search["found"]
    out = {k: {"compare": "skip", "why": "the best of nothing found"} if not found else
           {"compare": "coarse", "atol": 1e-3 * max(abs(v), 1.0),
            "why": "an optimum: 1e-3 relative"}
           for k, v in search.items() if isinstance(v, float)}
    out.update({k: _exact(1e-9) for k in ("found", "modelled", "prior_sd_kg_m2",
                                           "log_cells_searched")})
    out["rule"] = {"compare": "text"}
    return out


def _sensitivity_rules(summary: dict, sensitivity: dict) -> dict:
    laplace = summary["kind"] == "inertia"   # linearised at the Laplace mode; others on draws
    out = {}
    for effect, block in sensitivity.items():
        params = {}
        for name, entry in block["parameters"].items():
            sd = summary["parameters"][name]["sd"] if name in summary["parameters"] else None
            rules = {}
            for field in entry:
                if field == "units":
                    rules[field] = _exact(1e-9)
                elif field == "shift" and laplace:
                    rules[field] = {"compare": "laplace", "rtol": 1e-6}
                elif field == "shift":
                    scale = sd if sd is not None else abs(entry["shift"])
                    rules[field] = {"compare": "coarse", "atol": 0.5 * scale,
                                    "why": "regression on the draws: half a posterior sd"}
                else:   # shift_in_sd: shift over the sampled posterior sd
                    rules[field] = {"compare": "coarse", "atol": 0.5 + 0.2 * abs(entry[field]),
                                    "why": "over a sampled sd: half a unit plus 20 %"}
            params[name] = rules
        out[effect] = {"modelled": _exact(1e-9), "parameters": params}
    return out


def _az_mcse(x, method: str, prob: float | None = None) -> float:
    import numpy as np

    from cassini_bayes._arviz import load_arviz

    az = load_arviz()    # without numba: ArviZ's numba kernel of mcse(method="sd") fails
    kwargs = {"prob": prob} if prob is not None else {}
    # arviz 0.23 returns a (1,) array for a bare (chain, draw) array
    return float(np.asarray(az.mcse(x, method=method, **kwargs)).reshape(()))


def _mcse_by_label(idata) -> dict[str, dict[str, float]]:
    """ArviZ MCSE of mean, sd and the three quantiles per summary label (``name[i,j]``)."""
    out = {}
    post = idata.posterior
    for name, da in post.data_vars.items():
        extra = [d for d in da.dims if d not in ("chain", "draw")]
        if extra:
            stacked = da.stack(_e=extra).transpose("chain", "draw", "_e")
            items = [
                (f"{name}[{','.join(str(i) for i in (ix if isinstance(ix, tuple) else (ix,)))}]",
                 stacked.values[..., j]) for j, ix in enumerate(stacked["_e"].values)]
        else:
            items = [(name, da.values)]
        for label, x in items:
            out[label] = {"mean": _az_mcse(x, "mean"), "sd": _az_mcse(x, "sd"),
                          "q05": _az_mcse(x, "quantile", 0.05),
                          "q50": _az_mcse(x, "quantile", 0.5),
                          "q95": _az_mcse(x, "quantile", 0.95)}
    return out


# --- recording and the false-failure check -------------------------------------------------

def _fit(model: str, files: dict, out: Path, seed: int | None = None) -> tuple[dict, object]:
    from cassini_bayes._arviz import load_arviz

    from cassini_bayes.cli import main

    code = main(cli_args(model, files, out, seed))
    assert code in (0, 3), f"{model}: exit {code}"
    summary = numbers(json.loads((out / "summary.json").read_text()))
    return summary, load_arviz().from_netcdf(out / "posterior.nc")


def record(models: list[str]) -> None:  # pragma: no cover - run by hand
    """Re-record the pins of ``models`` (all where empty); the others keep theirs."""
    import os
    import tempfile

    os.environ.setdefault("XLA_FLAGS", "--xla_force_host_platform_device_count=4")
    pins = json.loads(PINS.read_text()) if models and PINS.exists() else {}
    pins["about"] = __doc__.split("\n\n")[0].replace("\n", " ")
    with tempfile.TemporaryDirectory() as tmp:
        for model in models or RECIPES:
            files = write_inputs(model, Path(tmp) / model)
            summary, idata = _fit(model, files, Path(tmp) / f"{model}-run")
            pins[model] = {"summary": summary, "tolerance": tolerances(summary, idata)}
            print(model, "recorded", file=sys.stderr)
    PINS.parent.mkdir(exist_ok=True)
    PINS.write_text(json.dumps(pins, indent=1) + "\n")


def check_other_seeds(n: int, models: list[str]) -> int:  # pragma: no cover - run by hand
    """Fit each recipe of ``models`` (all where empty) with ``n`` other seeds and compare with
    the pins: every failure printed; returns their count (the rules' false-failure check)."""
    import os
    import tempfile

    os.environ.setdefault("XLA_FLAGS", "--xla_force_host_platform_device_count=4")
    pins = json.loads(PINS.read_text())
    failures = 0
    with tempfile.TemporaryDirectory() as tmp:
        for model in models or RECIPES:
            files = write_inputs(model, Path(tmp) / model)
            for k in range(1, n + 1):
                seed = RECIPES[model][4] + 100 * k
                summary, idata = _fit(model, files, Path(tmp) / f"{model}-{seed}", seed)
                summary["seed"] = RECIPES[model][4]
                try:
                    assert_within_tolerance(pins[model], summary, f"{model} seed {seed}",
                                            idata=idata, other_seed=True)
                    print(f"{model} seed {seed}: within tolerance", file=sys.stderr)
                except AssertionError as e:
                    failures += 1
                    print(f"{model} seed {seed}: FAILED {e}", file=sys.stderr)
    return failures


if __name__ == "__main__":  # pragma: no cover
    if len(sys.argv) > 2 and sys.argv[1] == "--check-seeds":
        sys.exit(1 if check_other_seeds(int(sys.argv[2]), sys.argv[3:]) else 0)
    record(sys.argv[1:])
