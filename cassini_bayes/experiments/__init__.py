"""Experiments: one registered library function per kind, one short TOML file per experiment.

``experiments/NAME.toml`` names a ``kind`` and its ``[settings]``; ``cassini-bayes experiment``
runs it into a run directory (``results.json``, ``report.html``, ``config.toml``, figures) and
``cassini-bayes reproduce`` runs every file whose kind is registered and writes one summary page
with the papers' numbers beside ours.

To add a kind, add a module here (discovered automatically) with one decorated function::

    from cassini_bayes.experiments import ExperimentOutput, check_fact, register

    @register("thrust_table2", defaults={"draws": 1000}, quick={"draws": 50}, order=30)
    def thrust_table2(key, settings, ctx) -> ExperimentOutput:
        ...
        return ExperimentOutput(summary={...}, checks=(check_fact("table2_day028_tf65", x),))

and a file ``experiments/thrust_table2.toml`` with ``kind = "thrust_table2"``.
"""

from cassini_bayes.experiments._registry import ExperimentKind, register, registered_kinds
from cassini_bayes.experiments._reproduce import ReproduceResult, discover_experiments, reproduce
from cassini_bayes.experiments._results import (
    Check,
    ExperimentContext,
    ExperimentOutput,
    FigureOut,
    Table,
    check_fact,
    convergence_check,
    coverage_check,
    png,
)
from cassini_bayes.experiments._run import RunRecord, experiment_key, run_experiment, run_into
from cassini_bayes.experiments._schema import Experiment, experiment_from_dict, load_experiment

__all__ = [
    "Check",
    "Experiment",
    "ExperimentContext",
    "ExperimentKind",
    "ExperimentOutput",
    "FigureOut",
    "ReproduceResult",
    "RunRecord",
    "Table",
    "check_fact",
    "convergence_check",
    "coverage_check",
    "discover_experiments",
    "experiment_from_dict",
    "experiment_key",
    "load_experiment",
    "png",
    "register",
    "registered_kinds",
    "reproduce",
    "run_experiment",
    "run_into",
]
