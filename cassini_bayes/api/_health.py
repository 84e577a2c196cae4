"""Thruster health over many biasing events: :func:`fit_health`, :func:`simulate_health_campaign`.

An *event list* is a CSV ``events.csv`` with columns ``date_days`` (days, any origin),
``telemetry`` and ``pulses`` (paths relative to the CSV). A folder stands for its ``events.csv``.
``cassini-bayes simulate-health`` writes such a folder; docs/health.md describes the model.
"""

from __future__ import annotations

import copy
import csv
import json
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, TypeAlias

import numpy as np

from cassini_bayes import __version__
from cassini_bayes._devices import jax_entry
from cassini_bayes.api._inputs import number
from cassini_bayes.errors import InputError, arg, spelled

EventsArg: TypeAlias = ("str | os.PathLike | Sequence[str | os.PathLike | "
                        "tuple[float, str | os.PathLike, str | os.PathLike]]")
"""``events.csv`` files or folders holding one, or ``(date_days, telemetry, pulses)`` tuples."""

if TYPE_CHECKING:
    from cassini_bayes.api._inputs import SpacecraftArg
    from cassini_bayes.inference.health import HealthChannels
    from cassini_bayes.spacecraft import Spacecraft
    from cassini_bayes.inference.adequacy import Adequacy
    from cassini_bayes.inference.health.changepoint import HealthPosterior

__all__ = ["HealthResult", "fit_health", "read_event_list", "simulate_health_campaign",
           "HEALTH_FRACTION"]

HEALTH_FRACTION = 0.05
"""Default loss reported: ``P(thrust more than 5 % below its first calibration)``."""
CHANNEL_RULE = ("thrusters whose per-newton impulse is the same in every event (they always fire "
                "together) share a channel, their mean thrust (Feldman & Lee Eq 21: only their "
                "sum is told by the firings); a thruster fired apart from all others is its own "
                "channel (Eq 19); the split within a channel moves the torque only through the "
                "moment arms and is a nuisance, not reported")


@dataclass(frozen=True)
class HealthResult:
    """A health fit: ``posterior`` (:class:`~cassini_bayes.inference.health.HealthPosterior`),
    the per-event ``summaries``, the event ``files`` ((date, telemetry, pulses) each), the loss
    ``fraction``, the JSON ``summary`` and the ``config``."""

    posterior: HealthPosterior
    summaries: tuple
    files: tuple
    fraction: float
    _summary: dict = field(repr=False)
    config: dict

    def summary(self) -> dict:
        """``summary.json`` as a dict (a copy; the same protocol as :meth:`FitResult.summary`)."""
        return copy.deepcopy(self._summary)

    def save(self, out: str | os.PathLike, *, force: bool = False) -> Path:
        """Write ``summary.json``, ``config.toml``, ``health.csv`` (per event: estimates, their
        sd, ``P(down)`` per channel), ``thrust_bands.csv`` (relative thrust quantiles per channel
        on a date grid), ``health.png`` and ``report.html`` (the answer first, the adequacy
        verdict, self-contained) into ``out`` atomically; returns it."""
        from cassini_bayes.report.figures import png_bytes
        from cassini_bayes.report.health import health_report_html, plot_health
        from cassini_bayes.rundir import RunDir, write_config, write_summary

        png = png_bytes(plot_health(self.posterior, self.fraction), dpi=110)
        page = health_report_html(self, png)
        with RunDir(out, force=force, inputs=[f[1] for f in self.files]) as rd:
            write_summary(rd.path, self._summary)
            write_config(rd.path, self.config)
            _write_csv(rd.path / "health.csv", *health_table(self))
            _write_csv(rd.path / "thrust_bands.csv", *band_table(self.posterior))
            (rd.path / "health.png").write_bytes(png)
            (rd.path / "report.html").write_text(page, encoding="utf-8")
        return rd.final


def _write_csv(path: Path, header: list[str], rows: Iterable[Sequence[object]]) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for r in rows:
            w.writerow([f"{x:.10g}" if isinstance(x, float) else x for x in r])


def read_event_list(events: EventsArg) -> list[tuple[float, Path, Path]]:
    """``(date_days, telemetry, pulses)`` of each event from ``events``: one or more
    ``events.csv`` files or folders holding one, or a list of ``(date_days, telemetry, pulses)``
    tuples."""
    ev = spelled("EVENTS", "events")
    if isinstance(events, (str, os.PathLike)):
        events = [events]
    if not isinstance(events, (list, tuple)):
        raise InputError(f"{ev}: give events.csv files or folders, or "
                         f"(date_days, telemetry, pulses) tuples, not {type(events).__name__}")
    out = []
    for item in events:
        if isinstance(item, tuple):
            if len(item) != 3 or not all(isinstance(x, (str, os.PathLike)) for x in item[1:]):
                raise InputError(f"{ev}: give (date_days, telemetry, pulses) tuples")
            day = number("events", item[0], where=f"{ev} date_days")
            out.append((day, Path(item[1]), Path(item[2])))
            continue
        if not isinstance(item, (str, os.PathLike)):
            raise InputError(f"{ev}: {type(item).__name__} is not an events.csv file, a folder "
                             "or a (date_days, telemetry, pulses) tuple")
        p = Path(item)
        p = p / "events.csv" if p.is_dir() else p
        if not p.exists() and not Path(item).exists():
            raise InputError("not found; give an events.csv file or a folder holding one "
                             "(cassini-bayes simulate-health writes them)", path=str(item))
        if not p.is_file():
            raise InputError("is not an events.csv file or a folder holding one (columns "
                             "date_days, telemetry, pulses)", path=str(item))
        with open(p, newline="") as fh:
            rows = list(csv.DictReader(fh))
        for i, r in enumerate(rows):
            if not r or not {"date_days", "telemetry", "pulses"} <= r.keys():
                raise InputError("needs the columns date_days, telemetry, pulses", path=str(p))
            try:
                day = float(r["date_days"])
            except ValueError:
                raise InputError(f"row {i + 2}: date_days {r['date_days']!r} is not a number "
                                 "of days", path=str(p)) from None
            out.append((day, p.parent / r["telemetry"], p.parent / r["pulses"]))
    if len(out) < 2:
        raise InputError(f"{ev}: {len(out)} event(s); a health fit needs at least 2")
    seen: dict[Path, float] = {}
    for day, tel, _ in out:  # each event is independent evidence: a repeat would count twice
        if tel.resolve() in seen:
            raise InputError(f"{ev}: the event telemetry {tel} is listed twice (days "
                             f"{seen[tel.resolve()]:g} and {day:g}); list each event once")
        seen[tel.resolve()] = day
    return sorted(out, key=lambda e: e[0])


@jax_entry
def fit_health(events: EventsArg, spacecraft: SpacecraftArg, *, fraction: float = HEALTH_FRACTION,
               p_change: float = 0.1, p_channel: float = 0.5, step_sd: float = 0.1,
               tau_sd_frac: float | None = None) -> HealthResult:
    """Posterior of each thrust channel's health over many biasing events; what
    ``cassini-bayes fit health`` computes (exact, no sampling: the same inputs give the same
    numbers).

    Parameters
    ----------
    events : event list(s) (:func:`read_event_list`); event dates in days.
    spacecraft : a :class:`~cassini_bayes.spacecraft.Spacecraft`, model TOML path or name.
    fraction : the loss asked about: ``P(thrust more than fraction below the first
        calibration)`` at each event date.
    p_change, p_channel, step_sd : the change-point prior
        (:class:`~cassini_bayes.inference.health.HealthPrior`): the probability of a change in
        the span, of each channel stepping given a change, and the sd of a step's log thrust
        ratio (dimensionless).
    tau_sd_frac : per-event variation of the pulse time constants propagated into each event's
        summary (default :data:`~cassini_bayes.inference.health.summary.TAU_SD_FRAC`).
    """
    from cassini_bayes.api._inputs import spacecraft_input
    from cassini_bayes.api._result import collect_warnings
    from cassini_bayes.consistency import check_thrust_data
    from cassini_bayes.inference.health import (HealthPrior, event_channels, event_summary,
                                                health_posterior)
    from cassini_bayes.inference.health.adequacy import health_adequacy, inertia_probe
    from cassini_bayes.inference.health.summary import TAU_SD_FRAC, left_out_channels
    from cassini_bayes.rundir import file_record
    from cassini_bayes.telemetry import read_pulses, read_telemetry

    fraction = number("fraction", fraction)
    if not 0.0 < fraction < 1.0:
        raise InputError(f"{arg('fraction')} must lie strictly between 0 and 1, got {fraction}")
    tau_sd = TAU_SD_FRAC if tau_sd_frac is None else number("tau_sd_frac", tau_sd_frac, lo=0.0)
    sc, sc_record, _ = spacecraft_input(spacecraft)
    sc.require_thrusters("fit health")
    files = read_event_list(events)
    summaries, probes, data = [], [], []
    with collect_warnings() as warns:   # (every input left out is one: summary.json says it)
        for day, tel_path, log_path in files:
            tel = read_telemetry(tel_path, spacecraft=sc)
            log = read_pulses(log_path, spacecraft=sc)
            check_thrust_data([(tel, log)], sc)   # as fit thrust: units, pulse log vs on_*
            data.append((tel, log))
        channels = event_channels(data, sc)       # the same channels in every event
        for tel, log in data:
            summaries.append(event_summary(tel, log, sc, channels=channels, tau_sd_frac=tau_sd))
            probes.append(inertia_probe(tel, log, sc, summaries[-1]))
    prior = HealthPrior(p_change=p_change, p_channel=p_channel, step_sd=step_sd,
                        nominal_thrust_n=tuple(float(x) for x in
                                               channels.weights @ sc.thrust_per_thruster)).check()
    post = health_posterior([f[0] for f in files], np.array([s.log_thrust for s in summaries]),
                            np.array([np.sqrt(np.diag(s.cov)) for s in summaries]), prior,
                            channels=channels.names)
    adequacy = health_adequacy([f[0] for f in files], summaries, probes, prior,
                               [_event_label(d, t) for d, t, _ in files])
    summary = health_summary(post, fraction, adequacy, channels=channels, spacecraft=sc)
    summary["warnings"] = (warns + left_out_channels(summaries, [f[0] for f in files])
                           + summary.get("warnings", []))
    config = {"command": "fit health", "version": __version__,
              "inputs": {"events": [{"date_days": d, "telemetry": file_record(t),
                                     "pulses": file_record(p)} for d, t, p in files],
                         "spacecraft": sc_record},
              "settings": {"fraction": fraction, "p_change": p_change, "p_channel": p_channel,
                           "step_sd": step_sd, "tau_sd_frac": tau_sd}}
    return HealthResult(post, tuple(summaries), tuple(files), fraction, summary, config)


def _event_label(day: float, telemetry: Path) -> str:
    """An event as the adequacy checks name it: its folder (or file) and date."""
    name = telemetry.parent.name if telemetry.name == "telemetry.csv" else telemetry.name
    return f"{name} (day {day:g})"


def health_summary(post: HealthPosterior, fraction: float, adequacy: Adequacy | None = None, *,
                   channels: HealthChannels | None = None,
                   spacecraft: Spacecraft | None = None) -> dict:
    """``summary.json`` of a health fit: the change probability and date, per channel (named
    as the thrust fit names thrusts and combinations) the step and ``P(down by more than
    fraction)`` at the last event, the same for any channel and, where the model file names
    more than one thruster ``branch``, for each branch's channels, and the ``adequacy`` verdict
    (:func:`~cassini_bayes.inference.health.adequacy.health_adequacy`) with a warning per
    failed check. ``channels`` and ``spacecraft`` add each channel's thrusters."""
    lo, hi = post.change_date_interval(0.9)
    med = float(post.change_date_quantiles([0.5])[0])
    rng = np.random.default_rng(0)
    dr = post.draws(rng, 4000)
    out = {}
    for k, name in enumerate(post.channels):
        ratio = np.exp(dr["d"][:, k])
        out[name] = {
            "p_down_last": float(post.p_down([k], fraction)[-1]),
            "ratio_last_mean": float(ratio.mean()),
            "ratio_last_90": [float(x) for x in np.quantile(ratio, [0.05, 0.95])],
            "p_step_given_change": float(np.sum(post.interval_prob * post.step_prob[:, k])
                                         / max(post.p_change, 1e-300)),
            "n_events": int(np.isfinite(post.y[:, k]).sum()),
        }
        if channels is not None:
            out[name]["weights"] = {channels.thrusters[s]: 1.0 / len(channels.groups[k])
                                    for s in channels.groups[k]}
        if channels is not None and spacecraft is not None:
            br = {spacecraft.thrusters[s].branch for s in channels.groups[k]}
            out[name]["branch"] = br.pop() if len(br) == 1 else ""
    groups = {"any": list(range(len(post.channels)))}
    branches = sorted({str(c["branch"]) for c in out.values() if c.get("branch")})
    if len(branches) > 1:
        groups.update({f"branch {b}": [k for k, c in enumerate(out.values())
                                       if c.get("branch") == b] for b in branches})
    return {
        "command": "fit health", "version": __version__, "model": "change point",
        "n_events": int(post.dates.size), "first_date_days": float(post.dates[0]),
        "last_date_days": float(post.dates[-1]), "fraction": fraction,
        "p_change": post.p_change,
        "change_date_days": {"median": med, "interval_90": [lo, hi],
                             "note": "given a change; uniform within the interval between "
                                     "the two events around it"},
        "channels": out,
        "channel_rule": CHANNEL_RULE,
        **({} if channels is None else {"not_fired": list(channels.not_fired)}),
        "p_down_last": {b: float(post.p_down(ks, fraction)[-1]) for b, ks in groups.items()},
        "prior": {"p_change": post.prior.p_change, "p_channel": post.prior.p_channel,
                  "step_sd": post.prior.step_sd, "baseline_sd": post.prior.baseline_sd},
        **({} if adequacy is None else {"adequacy": adequacy.to_dict(),
                                        "warnings": adequacy.warnings()}),
    }


def health_table(res: HealthResult) -> tuple[list[str], list[list]]:
    """``health.csv``: per event its date, each channel's estimate (N) and log sd, and the
    posterior ``P(down)`` per channel and per group of ``summary.json``'s ``p_down_last`` (any
    channel, each branch) at its date."""
    post = res.posterior
    names = post.channels
    order = np.argsort([f[0] for f in res.files], kind="stable")
    p = [post.p_down([k], res.fraction) for k in range(len(names))]
    groups = res.summary().get("p_down_last") or {"any": None}
    p_b = {b: post.p_down(list(range(len(names))) if b == "any" else
                          [names.index(c) for c in _branch_members(res.summary(), b)], res.fraction)
           for b in groups}
    header = (["date_days", "telemetry"] + [f"thrust_{c}_n" for c in names]
              + [f"sd_log_{c}" for c in names] + [f"p_down_{c}" for c in names]
              + [f"p_down_{b.replace(' ', '_')}" for b in p_b])
    rows = []
    for e, i in enumerate(order):
        rows.append([float(post.dates[e]), str(res.files[i][1])]
                    + [float(x) for x in np.exp(post.y[e])]
                    + [float(x) for x in post.s[e]]
                    + [float(x[e]) for x in p] + [float(x[e]) for x in p_b.values()])
    return header, rows


def _branch_members(summary: dict, group: str) -> list[str]:
    """The channels of a ``p_down_last`` group (``branch <b>``) of ``summary.json``."""
    b = group.removeprefix("branch ")
    return [c for c, v in summary["channels"].items() if v.get("branch") == b]


def band_table(post: HealthPosterior, n_grid: int = 200,
               n_draws: int = 4000) -> tuple[list[str], list[list]]:
    """``thrust_bands.csv``: on a grid of dates, each channel's thrust relative to its first
    calibration, posterior 5/25/50/75/95 % quantiles (from exact draws, seed 0)."""
    grid = np.linspace(post.dates[0], post.dates[-1], n_grid)
    q = post.relative_thrust_bands(grid, np.random.default_rng(0), n_draws, _QUANTS)
    header = ["date_days"] + [f"{c}_q{int(p * 100):02d}" for c in post.channels for p in _QUANTS]
    rows = [[float(grid[i])] + [float(x) for x in q[:, i].ravel()] for i in range(grid.size)]
    return header, rows


_QUANTS = (0.05, 0.25, 0.5, 0.75, 0.95)


@jax_entry
def simulate_health_campaign(campaign: str | os.PathLike, out: str | os.PathLike, *,
                             seed: int | None = None, force: bool = False) -> Path:
    """Simulate a thruster-health campaign (a campaign TOML path or shipped name, e.g.
    ``"health_degradation"``) into ``out``: one folder per event (``telemetry.csv``,
    ``pulses.csv``, ``truth.json``), ``events.csv`` (the event list :func:`fit_health` reads)
    and ``truth.json`` (dates, true thrusts, the degradation); atomically."""
    from cassini_bayes.api._inputs import check_seed
    from cassini_bayes.api._simulation import simulate_scenario
    from cassini_bayes.rundir import RunDir
    from cassini_bayes.simulate.health_campaign import campaign_events, load_campaign
    from cassini_bayes.telemetry import write_pulses, write_telemetry

    camp = load_campaign(campaign)
    seed = check_seed(camp.seed if seed is None else seed)
    events = campaign_events(camp, seed)
    with RunDir(out, force=force) as rd:
        rows = []
        for k, ev in enumerate(events):
            sim = simulate_scenario(ev.scenario)
            d = rd.path / f"event_{k:03d}"
            d.mkdir()
            if sim.pulses is None:
                raise InputError(f"{camp.source}: event {k} fires no thruster; a health "
                                 "campaign's events are biasing events, each with firings")
            write_telemetry(d / "telemetry.csv", sim.telemetry)
            write_pulses(d / "pulses.csv", sim.pulses)
            (d / "truth.json").write_text(json.dumps(sim.truth(), indent=2) + "\n")
            rows.append([ev.date_days, f"{d.name}/telemetry.csv", f"{d.name}/pulses.csv"])
        _write_csv(rd.path / "events.csv", ["date_days", "telemetry", "pulses"], rows)
        truth = {"scenario": camp.name, "scenario_file": camp.source, "version": __version__,
                 "seed": seed, "description": camp.description,
                 "dates_days": [ev.date_days for ev in events],
                 "thrust_n": [dict(zip(camp.thrusters, map(float, ev.thrust_n)))
                              for ev in events],
                 "degradation": (None if not camp.degraded else
                                 {"thrusters": [camp.thrusters[i] for i in camp.degraded],
                                  "fraction": camp.degradation_fraction,
                                  "day": camp.degradation_day})}
        (rd.path / "truth.json").write_text(json.dumps(truth, indent=2) + "\n")
    return rd.final


def campaign_summaries(campaign: str | os.PathLike, seed: int, *, tau_sd_frac: float | None = None
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """In memory, without files: ``(dates (N,), log thrust (N, K), sd (N, K))`` of a simulated
    campaign's events on the channels of all its events (what the benchmark and the tests feed
    :func:`health_posterior`)."""
    from cassini_bayes.api._simulation import simulate_scenario
    from cassini_bayes.inference.health import event_channels, event_summary
    from cassini_bayes.inference.health.summary import TAU_SD_FRAC
    from cassini_bayes.simulate.health_campaign import campaign_events, load_campaign

    camp = campaign if not isinstance(campaign, (str, os.PathLike)) else load_campaign(campaign)
    ys, ss, ds = [], [], []
    events = campaign_events(camp, seed)
    sims = [simulate_scenario(ev.scenario) for ev in events]
    pairs = [(sim.telemetry, sim.pulses) for sim in sims if sim.pulses is not None]
    if len(pairs) < len(sims):
        raise InputError("every event of a health campaign is a biasing event with firings",
                         path=str(campaign))
    channels = event_channels(pairs, sims[0].prior)
    for ev, sim in zip(events, sims):
        sm = event_summary(sim.telemetry, sim.pulses, sim.prior, channels=channels,
                           tau_sd_frac=TAU_SD_FRAC if tau_sd_frac is None else tau_sd_frac)
        ys.append(sm.log_thrust)
        ss.append(np.sqrt(np.diag(sm.cov)))
        ds.append(ev.date_days)
    return np.array(ds), np.array(ys), np.array(ss)
