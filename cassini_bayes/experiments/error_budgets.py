"""Experiment kind ``error_budgets``: one error budget per calibration, in the style of Lee's
pointing budget (003 Table 2).

For each calibration (inertia from slews, thrust from biasing, RWA4 axis by the RCS and by the
RWA method) every error source the simulator models is switched on *alone* and the paper's
least-squares estimate is computed over ``n_seeds`` keys; the source's contribution is the RMS
error of the estimate. The contributions are root-sum-squared and compared with a run with every
source on together and with the papers' budgets (±1 % inertia, ±10 % thrust, 3° RCS / 1° RWA).

Sources:

* sampling — no noise at all: what the discrete telemetry and the method leave (the floor, part
  of every other line too);
* rate noise (gyro), attitude noise (star tracker), wheel-rate noise and wheel quantization
  (tachometers) — each at the scenario's level, through :func:`cassini_bayes.simulate.sensors.
  measure` applied to the one noise-free trajectory (the sensors do not act on the dynamics);
* external torque — a constant inertial torque of ``external_torque_nm`` in a random direction
  per key (Brown: ≈ 3e-6 N m), simulated (vmapped over keys);
* mass properties — the estimate computed with the predicted inertia instead of the true one
  (thrust and RWA4; the inertia calibration estimates it);
* pulse time constants — true τ drawn uniformly over the manufacturer's ranges, the estimate
  assuming the nominal values (thrust only), simulated (vmapped over keys).

Least squares keeps the budget cheap (no sampling); its numbers are the papers' method's.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.analysis.paper_facts import fact
from cassini_bayes.estimators.baseline import fit_thrust_baseline
from cassini_bayes.experiments import (
    Check,
    ExperimentOutput,
    FigureOut,
    Table,
    check_fact,
    png,
    register,
)
from cassini_bayes.experiments._posteriors import find_posterior

__all__ = ["SOURCES", "CALIBRATIONS", "BudgetLine", "Budget", "calibration_budget",
           "error_budgets"]

SOURCES = ("sampling", "rate noise", "attitude noise", "wheel-rate noise", "wheel quantization",
           "external torque", "mass properties", "pulse time constants")
CALIBRATIONS = ("inertia", "thrust", "rwa4_rcs", "rwa4_rwa")
_TITLE = {"inertia": "Inertia (worst moment, Eq 12)", "thrust": "Thrust (Eq 23, τ-adjusted)",
          "rwa4_rcs": "RWA4 axis, RCS method (Eq 1)", "rwa4_rwa": "RWA4 axis, RWA method (Eq 3)"}
_UNIT = {"inertia": "%", "thrust": "%", "rwa4_rcs": "deg", "rwa4_rwa": "deg"}
_FACT = {"inertia": "inertia_accuracy_pct", "thrust": "thrust_accuracy_pct",
         "rwa4_rcs": "rwa4_rcs_total_deg", "rwa4_rwa": "rwa4_rwa_expected_deg"}


class BudgetLine(NamedTuple):
    """One source of a budget: RMS and worst error over the keys (in the budget's unit)."""

    source: str
    rms: float
    worst: float


class Budget(NamedTuple):
    """A calibration's budget: its lines, their root-sum-square and the all-sources total."""

    calibration: str
    unit: str
    lines: tuple[BudgetLine, ...]
    rss: float
    total_rms: float
    total_worst: float


def _rms(x) -> float:
    x = np.asarray(x, float)
    return float(np.sqrt(np.mean(x * x)))


# --- telemetry from arrays ------------------------------------------------------------------


def _noisy(tel, key, noise):
    """Noise-free telemetry ``tel`` through the sensors with ``noise`` (NoiseParams)."""
    from dataclasses import replace

    from cassini_bayes.simulate.sensors import measure

    q, w, rho = measure(key, jnp.asarray(tel.q), jnp.asarray(tel.omega),
                        jnp.asarray(tel.wheel_rates), noise)
    return replace(tel, q=np.asarray(q), omega=np.asarray(w), wheel_rates=np.asarray(rho))


def _batch_results(keys, scenario, truth):
    """``SimResult``-like views of a vmapped batch (noise-free telemetry, pulse logs)."""
    from cassini_bayes.simulate import pulse_log, simulate_batch
    from cassini_bayes.simulate.sensors import NoiseParams

    zero = NoiseParams(*(jnp.asarray(0.0) for _ in range(4)))
    arr = jax.tree_util.tree_map(np.asarray, simulate_batch(keys, scenario, truth, zero))
    out = []
    for b in range(keys.shape[0]):
        ab = jax.tree_util.tree_map(lambda x, b=b: x[b], arr)
        tel = _Tel(scenario, ab)
        out.append((tel, pulse_log(ab, scenario) if scenario.uses_thrusters else None))
    return out


def _Tel(scenario, a):
    from cassini_bayes.telemetry import Telemetry

    return Telemetry(t=np.asarray(a.t), q=np.asarray(a.q), omega=np.asarray(a.omega),
                     wheel_rates=np.asarray(a.wheel_rates), wheel_names=scenario.wheel_names,
                     on_times=np.asarray(a.on_times) if scenario.uses_thrusters else None,
                     source=f"<simulated {scenario.name}>")


# --- estimators per calibration -----------------------------------------------------------------


def _estimator(calibration: str, scenario, sim) -> Callable:
    """``error(tel, pulses, truth_params, assumed_inertia) -> float`` for a calibration."""
    from cassini_bayes.estimators.baseline import (
        fit_inertia_baseline,
        fit_rwa4_baseline,
        fit_thrust_baseline,
    )
    from cassini_bayes.estimators.inertia import table1_errors

    prior = scenario.prior
    if calibration == "inertia":
        def err(tel, pulses, tp, assumed):
            pi = fit_inertia_baseline([tel], prior, method="all_axes").pi
            return float(np.max(np.abs(table1_errors(np.asarray(tp.inertia), pi)[:3])))
        return err
    if calibration == "thrust":
        p = prior.pulse
        tau_nominal = (p.tau_delay, p.tau_rise, p.tau_fall)

        def err(tel, pulses, tp, assumed):
            f = fit_thrust_baseline(tel, prior, pulses, tau=tau_nominal, inertia=assumed)
            f_true = float(np.mean(np.asarray(tp.thrust_n)))
            return 100.0 * abs(float(f.estimate[0]) - f_true) / f_true
        return err
    from cassini_bayes.inference.rwa4 import detect_windows

    method = "rcs" if calibration == "rwa4_rcs" else "rwa"
    pairs = detect_windows(sim.truth, method)
    k4 = list(scenario.wheel_names).index("RWA4")

    def err(tel, pulses, tp, assumed):
        fit = fit_rwa4_baseline(tel, prior, method, [a for a, _ in pairs], [b for _, b in pairs],
                                inertia=assumed)
        truth = np.asarray(tp.wheel_axes)[k4]
        c = float(np.dot(fit.axis, truth) / np.linalg.norm(fit.axis) / np.linalg.norm(truth))
        return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))
    return err


def calibration_budget(key, calibration: str, scenario_name: str, n_seeds: int, *,
                       external_torque_nm: float = 3e-6) -> Budget:
    """The error budget of one calibration on one scenario (module docstring).

    Parameters
    ----------
    key : jax.random key.
    calibration : one of :data:`CALIBRATIONS`.
    scenario_name : scenario under ``experiments/scenarios/`` (or a path).
    n_seeds : keys per source.
    external_torque_nm : magnitude of the external-torque source, N m.
    """
    from cassini_bayes.physics.momentum import inertia_matrix
    from cassini_bayes.simulate import load_scenario, noise_params, simulate, truth_params
    from cassini_bayes.simulate.sensors import NoiseParams

    scenario = load_scenario(scenario_name)
    k_nom, k_noise, k_dir, k_tau, k_tot = jax.random.split(key, 5)
    sim = simulate(k_nom, scenario)
    tp0 = truth_params(scenario)
    i_true = np.asarray(inertia_matrix(tp0.inertia))
    i_pred = np.asarray(scenario.prior.inertia)
    estimate = _estimator(calibration, scenario, sim)
    nominal = noise_params(scenario)
    zero = NoiseParams(*(jnp.asarray(0.0) for _ in range(4)))
    keys = jax.random.split(k_noise, n_seeds)
    pulses0 = sim.pulses

    def noise_only(field: str | None) -> list[float]:
        noise = zero if field is None else zero._replace(**{field: getattr(nominal, field)})
        return [estimate(_noisy(sim.truth, k, noise), pulses0, tp0, i_true) for k in keys]

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        errors: dict[str, list[float]] = {
            "sampling": noise_only(None),
            "rate noise": noise_only("gyro_rad_s"),
            "attitude noise": noise_only("star_tracker_rad"),
            "wheel-rate noise": noise_only("tach_noise_rpm"),
            "wheel quantization": noise_only("tach_quantum_rpm"),
        }
        # external torque: random direction per key, simulated
        b = n_seeds
        dirs = jax.random.normal(k_dir, (b, 3))
        dirs = dirs / jnp.linalg.norm(dirs, axis=1, keepdims=True)   # (b, 3) / (b, 1)
        batch = jax.tree_util.tree_map(lambda x: jnp.broadcast_to(x, (b,) + x.shape), tp0)
        torque = batch._replace(torque_inertial_nm=external_torque_nm * dirs)
        runs = _batch_results(jax.random.split(k_dir, b), scenario, torque)
        errors["external torque"] = [
            estimate(tel, pl, jax.tree_util.tree_map(lambda x, i=i: x[i], torque), i_true)
            for i, (tel, pl) in enumerate(runs)]
        if calibration != "inertia":
            errors["mass properties"] = [estimate(sim.truth, pulses0, tp0, i_pred)]
        tau_batch = None
        if calibration == "thrust":
            p = scenario.truth.pulse
            ranges = np.array([p.tau_delay_range, p.tau_rise_range, p.tau_fall_range], float)
            u = jax.random.uniform(k_tau, (b, 3))
            tau_batch = batch._replace(tau_s=jnp.asarray(ranges[None, :, 0])
                                       + u * jnp.asarray(ranges[None, :, 1] - ranges[None, :, 0]))
            runs = _batch_results(jax.random.split(k_tau, b), scenario, tau_batch)
            errors["pulse time constants"] = [
                estimate(tel, pl, jax.tree_util.tree_map(lambda x, i=i: x[i], tau_batch), i_true)
                for i, (tel, pl) in enumerate(runs)]
        # every source together: torque (and τ) runs through all the sensors; thrust and RWA4
        # with the predicted inertia
        together = torque
        if tau_batch is not None:
            together = tau_batch._replace(torque_inertial_nm=torque.torque_inertial_nm)
            runs = _batch_results(jax.random.split(k_tot, b), scenario, together)
        assumed = i_true if calibration == "inertia" else i_pred
        total = [estimate(_noisy(tel, jax.random.fold_in(k_tot, i), nominal), pl,
                          jax.tree_util.tree_map(lambda x, i=i: x[i], together), assumed)
                 for i, (tel, pl) in enumerate(runs)]
    lines = tuple(BudgetLine(s, _rms(errors[s]), float(np.max(errors[s])))
                  for s in SOURCES if s in errors)
    rss = float(math.sqrt(sum(line.rms ** 2 for line in lines)))
    return Budget(calibration, _UNIT[calibration], lines, rss, _rms(total),
                  float(np.max(total)))


@register(
    "error_budgets",
    defaults={"calibrations": list(CALIBRATIONS),
              "scenarios": {"inertia": "slews_post_probe", "thrust": "biasing_day028",
                            "rwa4_rcs": "rwa4_rcs", "rwa4_rwa": "rwa4_rwa"},
              "n_seeds": 6, "external_torque_nm": 3.0e-6,
              "posteriors": {"inertia": "auto", "thrust": "auto", "rwa4_rcs": "auto",
                             "rwa4_rwa": "auto"},
              "posterior_draws": 4000},
    quick={"calibrations": ["thrust"], "n_seeds": 2, "posterior_draws": 1000},
    order=80,
    description="Error budgets of the four calibrations, one source at a time (Lee Table 2 style)",
)
def error_budgets(key, settings, ctx) -> ExperimentOutput:
    """Each calibration's error budget: sources on one at a time, RSS, total, paper budget.

    Settings: ``calibrations`` (any of ``inertia``, ``thrust``, ``rwa4_rcs``, ``rwa4_rwa``),
    ``scenarios`` (scenario per calibration), ``n_seeds`` (keys per source),
    ``external_torque_nm`` (magnitude of the external-torque source, N m), ``posteriors``
    (run directories of the inertia, thrust, RWA4-RCS and RWA4-RWA fits whose draws the
    posterior-propagated budgets take; ``"auto"``: the fits of ``inertia_table1``,
    ``thrust_table2`` and the RWA4 campaigns earlier in the same ``reproduce`` run; ``""``: none),
    ``posterior_draws`` (joint draws propagated).
    """
    cals = _calibrations(settings, ctx)
    posteriors = {w: find_posterior(v, w, f"posteriors.{w}", ctx)
                  for w, v in settings["posteriors"].items()}
    budgets = []
    for i, c in enumerate(cals):
        ctx.progress(i / len(cals), f"{c}: budget")
        budgets.append(calibration_budget(jax.random.fold_in(key, i), c,
                                          settings["scenarios"][c], settings["n_seeds"],
                                          external_torque_nm=settings["external_torque_nm"]))
    checks, tables, summary = [], [], {}
    for bud in budgets:
        _budget_lines(bud, settings, checks, tables, summary)
    notes = _NOTES
    ctx.progress(0.95, "budgets from posteriors")
    sensitivity = None
    if "thrust" in cals and posteriors["inertia"] is not None:
        k_nom = jax.random.split(jax.random.fold_in(key, cals.index("thrust")), 5)[0]
        name = settings["scenarios"]["thrust"]
        sensitivity = (name, thrust_inertia_sensitivity(k_nom, name))
    post_checks, post_table, post_summary, post_note = _from_posteriors(
        jax.random.fold_in(key, 0x6275), posteriors, settings["posterior_draws"], sensitivity)
    checks += post_checks
    tables.append(post_table)
    summary["from_posteriors"] = post_summary
    notes += (post_note,)
    fig = _plot(budgets)
    ctx.progress(1.0, "done")
    return ExperimentOutput(summary=summary, checks=tuple(checks), tables=tuple(tables),
                            notes=notes,
                            figures=(FigureOut("error_budgets", png(fig),
                                               "RMS contribution of each source (log scale) "
                                               "with the RSS, the all-sources total and the "
                                               "paper's budget (dashed)."),))


def _calibrations(settings, ctx) -> list[str]:
    """The calibrations to budget, in order without repeats; ``ctx.error`` on a bad setting."""
    cals = list(dict.fromkeys(settings["calibrations"]))
    for c in cals:
        if c not in CALIBRATIONS:
            raise ctx.error(f"'settings.calibrations' has unknown calibration {c!r}; known: "
                            f"{', '.join(CALIBRATIONS)}")
    if settings["n_seeds"] < 1:
        raise ctx.error("'settings.n_seeds' must be at least 1")
    if settings["external_torque_nm"] < 0:
        raise ctx.error("'settings.external_torque_nm' must be non-negative (N m)")
    if settings["posterior_draws"] < 10:
        raise ctx.error("'settings.posterior_draws' must be at least 10")
    return cals


def _budget_lines(bud, settings, checks, tables, summary) -> None:
    """One calibration's budget: its RSS and all-sources checks, its table and its summary
    entry (appended to ``checks``, ``tables`` and ``summary``)."""
    f = fact(_FACT[bud.calibration])
    checks.append(check_fact(_FACT[bud.calibration], bud.rss,
                             label=f"{_TITLE[bud.calibration]}: RSS of the sources",
                             decimals=3, note=f"{settings['n_seeds']} keys per source"))
    checks.append(check_fact(_FACT[bud.calibration], bud.total_worst,
                             label=f"{_TITLE[bud.calibration]}: worst with all sources on",
                             decimals=3, note=f"RMS {bud.total_rms:.3g} {bud.unit}"))
    rows = [(line.source, f"{line.rms:.4g}", f"{line.worst:.4g}",
             f"{100 * line.rms ** 2 / bud.rss ** 2:.0f} %" if bud.rss > 0 else "—")
            for line in bud.lines]
    rows += [("RSS", f"{bud.rss:.4g}", "", "100 %"),
             ("all sources on", f"{bud.total_rms:.4g}", f"{bud.total_worst:.4g}", ""),
             ("paper's budget", f.printed, "", "")]
    tables.append(Table(f"{_TITLE[bud.calibration]}: error budget ({bud.unit})",
                        ("source", "RMS", "worst", "share of RSS²"), tuple(rows),
                        note=f"scenario {settings['scenarios'][bud.calibration]}; "
                             f"least-squares estimate; {settings['n_seeds']} keys per source"))
    summary[bud.calibration] = {
        "unit": bud.unit, "scenario": settings["scenarios"][bud.calibration],
        "lines": {line.source: {"rms": line.rms, "worst": line.worst} for line in bud.lines},
        "rss": bud.rss, "total_rms": bud.total_rms, "total_worst": bud.total_worst,
        "paper_budget": f.value}


_NOTES = (
    "Each source is switched on alone (the others off) and the papers' least-squares "
    "estimate is computed for every key; a line is the RMS (and worst) error over the keys. "
    "Sensor noise acts on the telemetry only, so those lines re-measure one noise-free "
    "trajectory; external torque and pulse time constants change the dynamics and are "
    "simulated, vmapped over the keys. 'Sampling' (no noise) is the method's own floor and "
    "is inside every other line. Mass properties: the estimate with the predicted instead of "
    "the true inertia (deterministic).",
    "Like Lee's pointing budget (Table 2), contributions are combined by root-sum-square, "
    "which assumes independent sources; the 'all sources on' row checks that assumption.",
)


def thrust_inertia_sensitivity(key, scenario_name: str) -> np.ndarray:
    """(6,) change of the least-squares thrust (% of the true thrust) per kg m² of each assumed
    inertia entry ``Ixx … Iyz``, on the noise-free biasing event ``scenario_name`` simulated with
    ``key`` (the estimate is linear in the assumed inertia: one difference per entry is exact)."""
    from cassini_bayes.analysis.budget_lines import inertia_of
    from cassini_bayes.simulate import load_scenario, simulate, truth_params

    scenario = load_scenario(scenario_name)
    sim = simulate(key, scenario)
    tp = truth_params(scenario)
    p = scenario.prior.pulse
    tau = (p.tau_delay, p.tau_rise, p.tau_fall)
    f_true = float(np.mean(np.asarray(tp.thrust_n)))
    entries = np.asarray(tp.inertia, float)

    def thrust(e):
        fit = fit_thrust_baseline(sim.truth, scenario.prior, sim.pulses, tau=tau,
                                  inertia=inertia_of(e))
        return float(fit.estimate[0])

    f0 = thrust(entries)
    return np.array([100.0 * (thrust(entries + np.eye(6)[k]) - f0) / f_true for k in range(6)])


def _from_posteriors(key, posteriors, n_draws, sensitivity=None):
    """Checks, table, summary and note of the budgets propagated from the fits' posteriors."""
    from cassini_bayes.analysis.posterior_budgets import budget_table, posterior_budget

    rwa4 = posteriors["rwa4_rwa"] or posteriors["rwa4_rcs"]
    extra = tuple(p for p in (posteriors["rwa4_rcs"],) if p is not None and p is not rwa4)
    bud = posterior_budget(key, inertia=posteriors["inertia"], thrust=posteriors["thrust"],
                           rwa4=rwa4, extra_axes=extra, n_draws=n_draws,
                           thrust_inertia_sensitivity=sensitivity)
    checks = []
    for r in bud.rows:
        if r.fact_id is None:
            continue
        f = fact(r.fact_id)
        iv = r.interval
        label = f"{r.budget}: {r.line}"
        if f.kind == "budget" and iv is not None:
            checks.append(check_fact(r.fact_id, iv.high, decimals=4,
                                     label=f"{label}: from posteriors, median [5 %, 95 %] "
                                           f"{iv.text(3)} {r.unit}; 95th percentile",
                                     note=f"median [5 %, 95 %] {iv.text(3)} {r.unit}; "
                                          f"{r.inputs}"))
        elif f.kind == "value":  # Lee's RSS: the paper's own entries give 1.186 / 0.244
            ours = iv.median if iv is not None else r.value
            checks.append(Check(
                f"{label}" + (", posterior median" if iv is not None else ""), ours, f.unit,
                fact_id=f.id, paper=f.printed, passed=None, decimals=3,
                note=(f"[5 %, 95 %] {iv.text(3)} {r.unit}; {r.inputs}. " if iv is not None
                      else "the paper's entries; ")
                     + "no verdict: Table 2's own entries root-sum-square to 1.186 / 0.244, the "
                       "paper prints 1.18 / 0.23"))
    columns, rows = budget_table(bud)
    used = ", ".join(f"{k}: {v}" for k, v in bud.sources.items()) or "none found"
    table = Table("Budgets from posteriors, beside the papers' numbers", columns,
                  tuple(rows), note=f"{bud.n_draws} joint draws; posteriors {used}. "
                                    "docs/budgets.md describes each line.")
    note = ("Budgets from posteriors: each line's physics evaluated at every joint draw of the "
            "fits' posteriors (independent fits resampled together), the draw read as the truth "
            "and the posterior mean as what the spacecraft believes; a line is its median and "
            "90 % credible interval. Attribution: the share of the line's variance each "
            "calibrated parameter causes when it alone varies, the others at their posterior "
            "medians. Lines with no calibrated input (most of Lee's pointing budget) keep the "
            "paper's values. The inertia and thrust posteriors found by 'auto' are the "
            "idealised fits of the clean Table 1/2 scenarios, so their lines are the "
            "noise-limited part only; docs/budgets.md gives a robust fit's budget for "
            "comparison. The per-source budgets above are the least-squares method's; the "
            "posterior already holds the noise sources, so its knowledge lines replace them.")
    return tuple(checks), table, bud.to_dict(), note


def _plot(budgets):
    from matplotlib.figure import Figure

    n = len(budgets)
    fig = Figure(figsize=(4.2 * min(n, 2), 3.2 * math.ceil(n / 2)))
    axes = np.atleast_1d(fig.subplots(math.ceil(n / 2), min(n, 2))).ravel()
    for ax, bud in zip(axes, budgets):
        labels = [line.source for line in bud.lines] + ["RSS", "all on"]
        vals = [max(line.rms, 1e-12) for line in bud.lines] + [bud.rss, bud.total_rms]
        y = np.arange(len(labels))
        ax.barh(y, vals, color=["C0"] * len(bud.lines) + ["C1", "C2"])
        ax.axvline(fact(_FACT[bud.calibration]).value, ls="--", color="C3")
        ax.set_xscale("log")
        ax.set_yticks(y, labels, fontsize=7)
        ax.invert_yaxis()
        ax.set_xlabel(bud.unit)
        ax.set_title(_TITLE[bud.calibration], fontsize=8)
    for ax in axes[n:]:
        ax.set_visible(False)
    fig.tight_layout()
    return fig
