"""Budgets whose inputs are posteriors: every line a credible interval with its attribution.

:func:`posterior_budget` takes the posteriors of an inertia, a thrust and an RWA4 fit (any of them;
:func:`load_posterior` reads a run directory's ``posterior.nc``) and propagates their draws through
the lines of :mod:`cassini_bayes.analysis.budget_lines` with
:func:`~cassini_bayes.analysis.propagation.propagate`:

* the calibrations' own budgets (Feldman & Lee ±1 % inertia and ±10 % thrust, Brown 3° RCS / 1°
  RWA), the thrust's pulse-time-constant line and Brown's mass-property line (≤ 1.5°);
* Lee's pointing budget (003 Table 2, 3σ, X and Z): the reaction-wheel control line combined, by
  root-sum-square, with the part due to inertia and RWA4-axis knowledge; the six lines without a
  calibrated input keep the paper's values (and say so); the RSS then becomes an interval.

Posteriors of different fits are independent: their draws are resampled (with replacement, from
the caller's key) to ``n_draws`` joint draws.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import numpy as np

from cassini_bayes.analysis import budget_lines as bl
from cassini_bayes.analysis.mass_property import RWA1_PHI_RAD, axis_on_cone
from cassini_bayes.analysis.paper_facts import LEE_POINTING_TABLE2, TABLE1, fact
from cassini_bayes.analysis.propagation import LineInterval, propagate
from cassini_bayes.errors import InputError
from cassini_bayes.names import F_NAMES, INERTIA_NAMES, TAU_NAMES, U4_NAMES, a_kind
from cassini_bayes.units import RPM_TO_RAD_S

__all__ = ["Posterior", "load_posterior", "posterior_from_idata", "BudgetRow", "budget_table",
           "budget_csv", "TABLE_COLUMNS",
           "PosteriorBudget", "DEFAULT_MANEUVER", "posterior_budget", "LEE_CONTROL_LINE"]

KINDS = ("inertia", "thrust", "rwa4")
LEE_CONTROL_LINE = "Reaction wheel-based attitude control error"


class Posterior(NamedTuple):
    """Draws of one fit's calibrated parameters.

    Attributes
    ----------
    kind : ``"inertia"``, ``"thrust"`` or ``"rwa4"``.
    source : where the draws came from (a run directory), for the report.
    draws : parameter → (n,) draws; the RWA4 axis as ``"u4"`` (n, 3). Inertia entries kg m²,
        thrust N, time constants s.
    method : the RWA4 calibration method (``"rcs"``/``"rwa"``), ``None`` otherwise or unknown.
    """

    kind: str
    source: str
    draws: dict[str, np.ndarray]
    method: str | None = None

    def estimate(self) -> dict[str, np.ndarray]:
        """The calibration's point estimate: posterior means (the mean axis, normalised)."""
        est = {k: np.mean(v, axis=0) for k, v in self.draws.items()}
        if "u4" in est:
            est["u4"] = est["u4"] / np.linalg.norm(est["u4"])
        return est


def posterior_from_idata(idata, kind: str, source: str, method: str | None = None) -> Posterior:
    """The :class:`Posterior` of ``kind`` from an InferenceData (``source`` names it in errors)."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    post = getattr(idata, "posterior", None)
    names = set(post.data_vars) if post is not None else set()
    need = {"inertia": INERTIA_NAMES, "thrust": ("F",), "rwa4": U4_NAMES}[kind]
    missing = [n for n in need if n not in names]
    if missing:
        raise InputError(f"{source}: no {kind} draws ({', '.join(missing)} missing); give the run "
                         f"directory of {a_kind(kind)} fit")
    keep = {"inertia": INERTIA_NAMES, "thrust": ("F",) + TAU_NAMES, "rwa4": U4_NAMES}[kind]
    draws = {n: np.asarray(post[n].values, float).reshape(-1) for n in keep if n in names}
    if kind == "rwa4":
        draws = {"u4": np.stack([draws.pop(n) for n in U4_NAMES], -1)}
    for n, v in draws.items():
        if v.shape[0] < 10 or not np.all(np.isfinite(v)):
            raise InputError(f"{source}: too few or non-finite draws of {n}; re-run the fit")
    if kind == "thrust" and any(n in names for n in F_NAMES[1:]):
        raise InputError(f"{source}: per-thruster thrust draws; the budget takes a fit of the "
                         "mean thrust F (fit thrust with the default mode)")
    return Posterior(kind, source, draws, method)


def load_posterior(run_dir, kind: str, *, option: str | None = None) -> Posterior:
    """The :class:`Posterior` of ``kind`` in a run directory (``posterior.nc``).

    ``option`` names the argument in errors (``--inertia``); the RWA4 method is read from the
    run's ``config.toml`` (``[options] method``) when it is there.
    """
    from cassini_bayes.rundir import read_posterior, read_run_file

    where = f"{option} {run_dir}" if option else str(run_dir)
    idata = read_posterior(run_dir, kind, where)
    method = None
    if kind == "rwa4":
        cfg = read_run_file(run_dir, "config.toml") or {}
        m = (cfg.get("options") or {}).get("method", cfg.get("method"))
        method = m if m in ("rcs", "rwa") else None
    return posterior_from_idata(idata, kind, where, method)


def _resample(key, draws: dict[str, np.ndarray], n: int) -> dict[str, np.ndarray]:
    m = len(next(iter(draws.values())))
    idx = np.asarray(jax.random.choice(key, m, (n,), replace=True))
    return {k: v[idx] for k, v in draws.items()}


class BudgetRow(NamedTuple):
    """One line of a budget.

    Attributes
    ----------
    budget : which budget (``"inertia"``, ``"thrust"``, ``"rwa4"``, ``"pointing X"`` …).
    line : the line, in words.
    unit : unit of the values.
    paper : the paper's number as printed ("" when it prints none for this line).
    interval : the posterior-propagated line, ``None`` when no posterior enters it.
    inputs : what the line was computed from (the posteriors, or the paper's assumed value).
    value : the paper's value used when ``interval`` is ``None``, else ``None``.
    fact_id : the :data:`~cassini_bayes.analysis.paper_facts.PAPER_FACTS` row, if any.
    """

    budget: str
    line: str
    unit: str
    paper: str
    interval: LineInterval | None
    inputs: str
    value: float | None = None
    fact_id: str | None = None

    def to_dict(self) -> dict:
        return {"budget": self.budget, "line": self.line, "unit": self.unit, "paper": self.paper,
                "interval": None if self.interval is None else self.interval.to_dict(),
                "inputs": self.inputs, "value": self.value, "fact_id": self.fact_id}


class PosteriorBudget(NamedTuple):
    """Every budget line computed from the given posteriors (:func:`posterior_budget`)."""

    rows: tuple[BudgetRow, ...]
    n_draws: int
    level: float
    sources: dict[str, str]
    maneuver: bl.Maneuver

    def to_dict(self) -> dict:
        m = self.maneuver
        return {"n_draws": self.n_draws, "level": self.level, "sources": dict(self.sources),
                "maneuver": {"rate_rad_s": np.asarray(m.rate_rad_s).tolist(),
                             "accel_rad_s2": np.asarray(m.accel_rad_s2).tolist(),
                             "wheel_momentum_nms": np.asarray(m.wheel_momentum_nms).tolist(),
                             "bandwidth_rad_s": float(m.bandwidth_rad_s)},
                "rows": [r.to_dict() for r in self.rows]}


def _default_maneuver() -> bl.Maneuver:
    """A multi-axis turn at the Post-Probe slews' 3 mrad/s and 0.03 mrad/s² about (1, 1, 1)/√3,
    with RWA2, RWA3 and RWA4 (believed at RWA1) at Brown's −600, −800, −850 rpm and the
    scenarios' PD bandwidth of 0.1 rad/s."""
    from cassini_bayes.spacecraft import CASSINI_WHEEL_AXES

    axes = np.stack([CASSINI_WHEEL_AXES[1], CASSINI_WHEEL_AXES[2], CASSINI_WHEEL_AXES[0]])
    direction = np.ones(3) / math.sqrt(3.0)
    h = (0.16 * RPM_TO_RAD_S * np.array([-600.0, -800.0, -850.0])) @ axes
    return bl.Maneuver(3e-3 * direction, 3e-5 * direction, h, 0.1, axes)


DEFAULT_MANEUVER = _default_maneuver()
# believed (and true) inertia of the control line when no inertia posterior is given, kg m²
_POST_PROBE_INERTIA = np.asarray(TABLE1["post_probe"]["est"], float)


def _fmt_fact(fact_id: str) -> str:
    return fact(fact_id).printed


def posterior_budget(key, *, inertia: Posterior | None = None, thrust: Posterior | None = None,
                     rwa4: Posterior | None = None, extra_axes: tuple[Posterior, ...] = (),
                     n_draws: int = 4000, level: float = 0.9,
                     maneuver: bl.Maneuver = DEFAULT_MANEUVER,
                     pulse_widths_s=(0.125,), pulse_counts=None,
                     thrust_inertia_sensitivity=None) -> PosteriorBudget:
    """The budget lines computed from the given posteriors (module docstring).

    Parameters
    ----------
    key : jax.random key (the resampling of the independent posteriors' draws).
    inertia, thrust, rwa4 : posteriors (:func:`load_posterior`); any may be ``None``.
    n_draws : joint draws propagated.
    level : credible level of the intervals.
    maneuver : the turn Lee's control line is evaluated on.
    pulse_widths_s, pulse_counts : pulse mix of the thrust's pulse-time-constant line (default:
        125 ms pulses, as Feldman & Lee Table 2).
    thrust_inertia_sensitivity : (name, (6,) % of thrust per kg m² of ``Ixx … Iyz``) of the
        least-squares thrust on a biasing event; with an inertia posterior it adds the thrust's
        mass-property line (it needs the event's telemetry, so only the caller can give it).
    """
    if n_draws < 10:
        raise InputError(f"n_draws must be at least 10, got {n_draws}")
    k_i, k_t, k_r = jax.random.split(key, 3)
    post = {"inertia": inertia, "thrust": thrust, "rwa4": rwa4}
    for name, p in post.items():
        if p is not None and p.kind != name:
            raise InputError(f"{p.source}: {a_kind(p.kind)} posterior given as the {name} "
                             "posterior")
    d_i = _resample(k_i, inertia.draws, n_draws) if inertia else None
    d_t = _resample(k_t, thrust.draws, n_draws) if thrust else None
    d_r = _resample(k_r, rwa4.draws, n_draws) if rwa4 else None
    rows: list[BudgetRow] = []

    def add(budget, line, unit, fid, fn, draws, inputs, paper=None) -> BudgetRow:
        _, iv = propagate(fn, draws, level=level)
        row = BudgetRow(budget, line, unit, paper if paper is not None else _fmt_fact(fid), iv,
                        inputs, None, fid)
        rows.append(row)
        return row

    est = np.array([inertia.estimate()[n] for n in INERTIA_NAMES]) if inertia else None
    if inertia:
        add("inertia", "inertia knowledge, worst moment (Eq 12)", "%", "inertia_accuracy_pct",
            lambda d: bl.inertia_worst_moment_pct(d, est), d_i, "posterior: inertia")
    if thrust:
        est_t = thrust.estimate()
        add("thrust", "thrust knowledge", "%", "thrust_accuracy_pct",
            lambda d: bl.thrust_error_pct({"F": d["F"]}, est_t["F"]), {"F": d_t["F"]},
            "posterior: thrust")
        if all(n in d_t for n in TAU_NAMES):
            tau_hat = np.array([est_t[n] for n in TAU_NAMES])
            add("thrust", "pulse time constants (F / R, "
                + ", ".join(f"{1e3 * w:g}" for w in np.atleast_1d(pulse_widths_s)) + " ms)",
                "%", "thrust_accuracy_pct",
                lambda d: bl.tau_thrust_error_pct(d, tau_hat, pulse_widths_s, pulse_counts),
                {n: d_t[n] for n in TAU_NAMES}, "posterior: thrust time constants")
    if inertia and thrust_inertia_sensitivity is not None:
        event, sens = thrust_inertia_sensitivity
        add("thrust", "mass properties (least-squares Eq 23)", "%", "thrust_accuracy_pct",
            lambda d: bl.thrust_mass_property_pct(d, est, sens), d_i,
            f"posterior: inertia; sensitivity on {event}")
    axis_hat = rwa4.estimate()["u4"] if rwa4 else np.asarray(axis_on_cone(RWA1_PHI_RAD))
    for i, p in enumerate(((rwa4,) if rwa4 else ()) + tuple(extra_axes)):
        if p.kind != "rwa4":
            raise InputError(f"{p.source}: {a_kind(p.kind)} posterior given as an RWA4 "
                             "posterior")
        fid = "rwa4_rwa_expected_deg" if p.method == "rwa" else "rwa4_rcs_total_deg"
        d = d_r if i == 0 else _resample(jax.random.fold_in(k_r, i), p.draws, n_draws)
        add(f"rwa4 ({p.method or 'method not recorded'})", "RWA4 axis knowledge", "deg", fid,
            lambda d, a=p.estimate()["u4"]: bl.axis_error_deg(d, a), d, "posterior: RWA4")
    if inertia:
        draws = dict(d_i) | (dict(d_r) if rwa4 else {})
        add("rwa4 mass properties", "extra RCS-method error (Brown Eq 1)", "deg",
            "rwa4_mass_property_deg", lambda d: bl.rcs_mass_property_deg(d, est, axis_hat),
            draws, "posterior: inertia" + (", RWA4 axis" if rwa4 else "; axis at RWA1"))
    _pointing_rows(add, rows, d_i, d_r, est, axis_hat, maneuver)
    sources = {k: p.source for k, p in post.items() if p is not None}
    sources |= {f"rwa4 ({p.method})": p.source for p in extra_axes}
    return PosteriorBudget(tuple(rows), n_draws, level, sources, maneuver)


def _pointing_rows(add, rows, d_i, d_r, i_hat, axis_hat, maneuver) -> None:
    """Lee Table 2 per axis: the paper's lines, the control line with the knowledge part, RSS
    (``i_hat`` the believed inertia entries, ``None`` without an inertia posterior)."""
    knowledge = (d_i or {}) | (d_r or {})
    which = ", ".join(n for n, d in (("inertia", d_i), ("RWA4 axis", d_r)) if d is not None)
    inputs = f"posterior: {which}" if which else ""
    for col, axis in ((0, "X"), (1, "Z")):
        budget = f"pointing {axis} (Lee Table 2, 3σ)"
        others = [(name, vals[col]) for name, *vals in LEE_POINTING_TABLE2]
        assumed_sq = sum(v * v for name, v in others if name != LEE_CONTROL_LINE)
        paper_control = dict(others)[LEE_CONTROL_LINE]
        for name, v in others:
            if name != LEE_CONTROL_LINE or not knowledge:
                rows.append(BudgetRow(budget, name, "mrad", f"{v:g} mrad", None,
                                      "paper's value (no calibrated input)"
                                      if name != LEE_CONTROL_LINE else "paper's value",
                                      float(v)))
        fid = f"lee_pointing_rss_{axis.lower()}_mrad"
        if not knowledge:
            rss = math.sqrt(sum(v * v for _, v in others))
            rows.append(BudgetRow(budget, "root-sum-square", "mrad", _fmt_fact(fid), None,
                                  "paper's values", rss, fid))
            continue
        k = 0 if axis == "X" else 2
        i_est = i_hat if i_hat is not None else _POST_PROBE_INERTIA

        def part(d, k=k, i_est=i_est):
            return np.abs(bl.rwa_control_error_mrad(d, i_est, axis_hat, maneuver)[:, k])

        add(budget, "control error from inertia and RWA4-axis knowledge", "mrad", None, part,
            knowledge, inputs, paper="")
        add(budget, f"{LEE_CONTROL_LINE} (paper ⊕ knowledge)", "mrad", None,
            lambda d, part=part, p=paper_control: np.hypot(p, part(d)), knowledge, inputs,
            paper=f"{paper_control:g} mrad")
        add(budget, "root-sum-square", "mrad", fid,
            lambda d, part=part, p=paper_control, a=assumed_sq: np.sqrt(a + p * p + part(d) ** 2),
            knowledge, inputs + "; other lines the paper's")


TABLE_COLUMNS = ("budget", "line", "paper", "posterior: median [5 %, 95 %]",
                 "attribution (one at a time)", "inputs")


def _attribution_text(iv: LineInterval) -> str:
    shown = sorted(((v, k) for k, v in iv.shares.items() if v >= 0.005), reverse=True)
    if len(iv.shares) > 1 and not 0.5 <= iv.share_sum <= 2.0:
        # correlated parameters that compensate each other (or a strongly non-additive line):
        # the one-at-a-time spreads are shown relative to each other
        text = ", ".join(f"{k} {100 * v / iv.share_sum:.0f} %" for v, k in shown)
        return f"{text} (relative; alone they spread the line {iv.share_sum:.3g}× its variance)"
    text = ", ".join(f"{k} {100 * v:.0f} %" for v, k in shown) or "—"
    if len(iv.shares) > 1 and abs(iv.share_sum - 1.0) > 0.05:
        text += f" (sum {100 * iv.share_sum:.0f} %)"
    return text


def budget_table(budget: PosteriorBudget) -> tuple[tuple[str, ...], list[tuple[str, ...]]]:
    """Columns and text rows of the budget: each line's paper value beside its posterior
    interval (or the paper's value it keeps) and its attribution."""
    rows = []
    for r in budget.rows:
        if r.interval is None:
            ours, attr = f"{r.value:.4g} {r.unit} (kept)", "—"
        else:
            ours, attr = f"{r.interval.text(3)} {r.unit}", _attribution_text(r.interval)
        rows.append((r.budget, r.line, r.paper or "—", ours, attr, r.inputs))
    return TABLE_COLUMNS, rows


def budget_csv(budget: PosteriorBudget) -> str:
    """The budget as CSV text: one row per line, the shares as ``name=share`` pairs."""
    import csv
    import io

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["budget", "line", "unit", "paper", "median", "low", "high", "level", "value",
                "share_sum", "shares", "inputs"])
    for r in budget.rows:
        iv = r.interval
        nums = (["", "", "", ""] if iv is None else
                [f"{iv.median:.6g}", f"{iv.low:.6g}", f"{iv.high:.6g}", f"{iv.level:g}"])
        shares = "" if iv is None else ";".join(f"{k}={v:.4g}" for k, v in iv.shares.items())
        w.writerow([r.budget, r.line, r.unit, r.paper, *nums,
                    "" if r.value is None else f"{r.value:.6g}",
                    "" if iv is None else f"{iv.share_sum:.4g}", shares, r.inputs])
    return buf.getvalue()
