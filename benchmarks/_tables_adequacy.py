"""Table kinds of the adequacy campaigns (``benchmarks/adequacy_false_alarms.py`` and
``benchmarks/adequacy_by_size.py`` records, shown in docs/adequacy.md); registered in
:mod:`_tables` by import."""

from __future__ import annotations

from _tables import Records, kind, read_json


@kind("adequacy_false_alarms")
def adequacy_false_alarms(args: list[Records]) -> str:
    """Each case's check failures (``adequacy_false_alarms.py --json``), one row per case."""
    from adequacy_false_alarms import table

    return table([read_json(p) for group in args for p in group])


@kind("adequacy_by_size")
def adequacy_by_size(args: list[Records]) -> str:
    """Check failures by case and file size (``adequacy_by_size.py --json``), pooled."""
    from adequacy_by_size import table

    return table([read_json(p) for group in args for p in group])
