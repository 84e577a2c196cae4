"""Thruster-leak monitoring of one telemetry stretch: :func:`monitor_leak` (docs/leak.md).

The Bayesian monitor (:mod:`cassini_bayes.inference.leak`), for any thruster set of the model
file, and Lee's threshold monitor (:func:`cassini_bayes.estimators.leak.threshold_monitor`) on the
same residual momentum where the thrusters are Cassini's eight of Feldman & Lee Eq 16 (its Eq 11
correction pairs them by name and its 50 N m s threshold is Cassini's); what
``cassini-bayes monitor leak`` runs.
"""

from __future__ import annotations

import copy
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from cassini_bayes import __version__
from cassini_bayes._devices import jax_entry
from cassini_bayes.errors import InputError, spelled

if TYPE_CHECKING:
    from cassini_bayes.api._inputs import PulseLogsArg, SpacecraftArg, TelemetriesArg
    from cassini_bayes.estimators.leak import ThresholdResult
    from cassini_bayes.inference.leak import LeakInputs, LeakPosterior
    from cassini_bayes.spacecraft import Spacecraft

__all__ = ["LeakResult", "monitor_leak", "LEE_LAYOUT_ONLY"]

LEE_LAYOUT_ONLY = ("Lee's threshold monitor applies to Cassini's eight thrusters in the layout "
                   "of Feldman & Lee Eq 16 (its Eq 11 correction pairs Z1..Y4, its R_T is "
                   "Cassini's); only the Bayesian monitor ran")


@dataclass(frozen=True)
class LeakResult:
    """Both monitors on one stretch: the Bayesian ``posterior``
    (:class:`~cassini_bayes.inference.leak.LeakPosterior`), Lee's ``lee``
    (:class:`~cassini_bayes.estimators.leak.ThresholdResult`; ``None`` when the thrusters are not
    Cassini's Eq 16 layout), the ``summary`` (``summary.json``) and ``config`` (``config.toml``)
    dicts, and the input ``files``."""

    posterior: LeakPosterior
    lee: ThresholdResult | None
    _summary: dict = field(repr=False)
    config: dict
    files: tuple

    def summary(self) -> dict:
        """``summary.json`` as a dict (a copy; the same protocol as :meth:`FitResult.summary`)."""
        return copy.deepcopy(self._summary)

    def save(self, out: str | os.PathLike, *, force: bool = False) -> Path:
        """Write ``summary.json``, ``config.toml``, ``probabilities.csv`` (every check's
        probabilities of ``none`` and each of the model's thrusters, e.g. ``none, Z1 … Y4``)
        and ``report.html`` (the answer first, the adequacy verdict, self-contained) into
        ``out`` atomically; returns it. ``force`` replaces only a directory cassini-bayes
        wrote."""
        from cassini_bayes.report.leak import leak_report_html
        from cassini_bayes.rundir import RunDir, write_config, write_summary

        page = leak_report_html(self)
        with RunDir(out, force=force, inputs=list(self.files)) as rd:
            write_summary(rd.path, self._summary)
            write_config(rd.path, self.config)
            table = np.column_stack([self.posterior.t_check, self.posterior.prob])
            np.savetxt(rd.path / "probabilities.csv", table, delimiter=",", fmt="%.10g",
                       header="t_s," + ",".join(f"p_{h}" for h in self.posterior.hypotheses),
                       comments="")
            (rd.path / "report.html").write_text(page, encoding="utf-8")
        return rd.final


def _positive(value: float, option: str, argument: str) -> float:
    if not value > 0:
        raise InputError(f"must be positive, got {value}", path=spelled(option, argument))
    return value


@jax_entry
def monitor_leak(telemetry: TelemetriesArg, spacecraft: SpacecraftArg, *,
                 pulses: PulseLogsArg | None = None, prior_leak: float = 0.01,
                 p_detect: float = 0.99, sample_step_s: float = 60.0,
                 check_step_s: float = 60.0, eta: float = 0.05,
                 threshold_nms: float = 50.0, t_limit_h: float = 10.0) -> LeakResult:
    """Posterior probability of a leak per thruster over one telemetry stretch, for the model's
    thrusters, beside Lee's threshold monitor where they are Cassini's eight (Feldman & Lee
    Eq 16; for another layout ``summary["lee"]`` says it does not apply and ``lee`` is ``None``).

    Parameters
    ----------
    telemetry : a telemetry CSV/Parquet path or a :class:`~cassini_bayes.telemetry.Telemetry`.
    spacecraft : a spacecraft model TOML path, a shipped model's name or a
        :class:`~cassini_bayes.spacecraft.Spacecraft`.
    pulses : a pulse-log CSV path or a :class:`~cassini_bayes.telemetry.PulseLog` (else the
        telemetry's on-times times the model's thrust).
    prior_leak : prior probability of a leak in the stretch (shared by the model's thrusters).
    p_detect : the alarm level of ``P(leak)`` (and of one thruster's probability, isolation).
    sample_step_s, check_step_s : spacing of the residual samples used and of the checks, s.
    eta : thruster-to-thruster thrust variation, fraction (Lee Eq 11).
    threshold_nms, t_limit_h : Lee's ``R_T`` (N m s) and ``T_limit`` (hours); Cassini's layout
        only.
    """
    from cassini_bayes.api._inputs import pulse_inputs, spacecraft_input, telemetry_inputs
    from cassini_bayes.api._result import collect_warnings
    from cassini_bayes.consistency import check_telemetry_data
    from cassini_bayes.inference.leak import leak_inputs, leak_posterior
    from cassini_bayes.inference.leak_adequacy import leak_adequacy

    # the Bayesian monitor checks its own settings (leak_posterior); these are Lee's
    for value, option, argument in ((threshold_nms, "--threshold", "threshold_nms"),
                                    (t_limit_h, "--t-limit", "t_limit_h")):
        _positive(value, option, argument)
    if eta < 0:
        raise InputError(f"must not be negative, got {eta}", path=spelled("--eta", "eta"))
    sc, sc_record, sc_files = spacecraft_input(spacecraft)
    sc.require_thrusters("the leak monitor")
    tels, tel_records, tel_files = telemetry_inputs(telemetry, spacecraft=sc)
    if len(tels) != 1:
        raise InputError(f"got {len(tels)} telemetry inputs; the monitor reads one stretch",
                         path=spelled("TELEMETRY", "telemetry"))
    tel = tels[0]
    logs, log_records, log_files = pulse_inputs(pulses, spacecraft=sc)
    if len(logs) > 1:
        raise InputError(f"got {len(logs)} pulse logs; give one",
                         path=spelled("--pulses", "pulses"))
    log = logs[0] if logs else None
    with collect_warnings() as warns:   # (every input left out is one: summary.json says it)
        check_telemetry_data(tel, sc, log)   # units, conventions, pulse log vs on_* (as `check`)
        inp = leak_inputs(tel, log, sc)
    post = leak_posterior(inp, prior_leak=prior_leak, eta=eta, sample_step_s=sample_step_s,
                          check_step_s=check_step_s, p_detect=p_detect)
    lee, lee_summary = _lee_monitor(inp, sc, threshold_nms, t_limit_h, eta)
    summary = {
        "command": "monitor leak", "version": __version__,
        "t_start_s": float(inp.t[0]), "t_end_s": float(inp.t[-1]),
        "bayes": post.summary(),
        "lee": lee_summary,
        "residual_end_nms": [float(x) for x in inp.residual[-1]],
        "warnings": warns,
    }
    adequacy = leak_adequacy(inp, post, eta=eta, sample_step_s=sample_step_s)
    summary["adequacy"] = adequacy.to_dict()
    summary["warnings"] = warns + adequacy.warnings()
    config = {"command": "monitor leak", "version": __version__,
              "inputs": {"telemetry": tel_records[0], "spacecraft": sc_record,
                         **({"pulses": log_records[0]} if log_records else {})},
              "settings": {"prior_leak": prior_leak, "p_detect": p_detect,
                           "sample_step_s": sample_step_s,
                           "check_step_s": check_step_s,
                           "eta": eta, "threshold_nms": threshold_nms, "t_limit_h": t_limit_h}}
    files = tuple(tel_files + log_files + sc_files)
    return LeakResult(post, lee, summary, config, files)


def _lee_monitor(inp: LeakInputs, sc: Spacecraft, threshold_nms: float, t_limit_h: float,
                 eta: float) -> tuple[ThresholdResult | None, dict]:
    """Lee's threshold monitor (Lee §3.2, Eq 11) on the same residual and its summary entry;
    on a layout other than Cassini's eight thrusters of Eq 16, ``None`` and the reason."""
    from cassini_bayes.estimators.leak import threshold_monitor

    if not sc.eq16_layout:
        return None, {"applies": False, "reason": LEE_LAYOUT_ONLY}
    lee = threshold_monitor(inp.t, inp.residual, inp.impulse, inp.q_matrix,
                            r_t_nms=threshold_nms, t_limit_s=t_limit_h * 3600.0, eta=eta)
    return lee, {
        "applies": True, "detection_time_s": lee.detection_time_s,
        "axis": None if lee.axis is None else "XYZ"[lee.axis],
        "thruster": None if lee.thruster is None else inp.thruster_names[lee.thruster],
        "triggers_s": list(lee.triggers_s), "dismissed_s": list(lee.dismissed_s),
        "threshold_nms": threshold_nms, "t_limit_s": t_limit_h * 3600.0, "eta": eta}
