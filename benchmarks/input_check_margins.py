"""Margins of the wheel-axes and gyro-bias checks (``consistency.check_wheel_units``,
``consistency.check_gyro_bias``) on open-world data.

For every open-world family of ``coverage_open_world.py`` and seeds ``0 … N−1``: draw the
open-world truth (errors 1.5× wider than the robust priors, per wheel and per axis, a flexible
mode, drifting torques, time-tag errors, the true inertia anywhere in the model file's ±10 % box
for thrust and RWA4), simulate, apply the time tags, and fit the momentum balance of
:func:`cassini_bayes.consistency.wheel_momentum_scale` with the nominal spacecraft model: the
common scale ``κ`` and the free-axis fit (:class:`~cassini_bayes.consistency.WheelAxes`).

Then the same telemetry damaged, one mistake at a time: each known wheel's sign flipped, each pair
of known wheels' columns swapped, one wheel's column in rad/s. Prints per family how often the
free-axis fit is judged (conditioning ≥ ``AXES_CONDITION_MIN``), the largest angle and the scale
range on clean data (false alarms: clean files refused), and per mistake how often it is refused;
then the gyro bias the data show against the drawn one and the model's ``[gyro]`` sd, and how often
a file is warned about it (each warned file with its drawn bias). Not a test: the numbers are in
docs/input_checks.md.

    python benchmarks/input_check_margins.py [--seeds 20] [--families post_probe rwa4_rwa …]
"""

from __future__ import annotations

import argparse
import itertools
import sys
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from coverage_open_world import FAMILIES  # noqa: E402


def _telemetry(family: str, seed: int):
    """The open-world telemetry of (family, seed) and its nominal spacecraft model."""
    import jax

    from cassini_bayes.simulate import scenario_from_dict, simulate
    from cassini_bayes.simulate.open_world import apply_time_tags, draw_open_world

    kind, name = FAMILIES[family]
    fam = list(FAMILIES).index(family)
    ow = draw_open_world(name, np.random.default_rng([seed, fam]), widen=1.5,
                         draw_inertia=kind != "inertia",
                         solved_wheel="RWA4" if kind == "rwa4" else None)
    scenario = scenario_from_dict(ow.scenario, src=name)
    sim = simulate(jax.random.key(50_000 * (fam + 1) + seed), scenario)
    tel = apply_time_tags(sim.telemetry, ow)
    on = tel.on_times
    if on is None and sim.pulses is not None:
        from cassini_bayes.consistency import _derived_on_times

        on = _derived_on_times(tel, sim.pulses)
    return tel, on, scenario.prior, ow.record


def _damaged(tel, known: list[str]):
    """(label, telemetry) per mistake: a flipped sign, two swapped columns, one in rad/s."""
    from cassini_bayes.telemetry import RPM_TO_RAD_S

    def with_rates(edit):
        rates = np.array(tel.wheel_rates, float)
        edit(rates)
        return replace(tel, wheel_rates=rates)

    idx = {n: tel.wheel_names.index(n) for n in known}
    for n in known:
        yield "flip", with_rates(lambda r, i=idx[n]: r.__setitem__((slice(None), i), -r[:, i]))
        yield "rad/s", with_rates(
            lambda r, i=idx[n]: r.__setitem__((slice(None), i), r[:, i] * RPM_TO_RAD_S))
    for a, b in itertools.combinations(known, 2):
        yield "swap", with_rates(lambda r, i=idx[a], j=idx[b]: r.__setitem__(
            (slice(None), [i, j]), r[:, [j, i]]))


def main(argv=None) -> None:
    from cassini_bayes.consistency import (AXES_CONDITION_MIN, GyroBiasWarning,
                                           check_gyro_bias, check_wheel_units,
                                           wheel_momentum_scale)
    from cassini_bayes.errors import InputError

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--families", nargs="+", default=list(FAMILIES))
    a = ap.parse_args(argv)
    print(f"{'family':20s} {'judged':>7s} {'cond (min–max)':>15s} {'max angle':>9s} "
          f"{'scales':>13s} {'clean refused':>13s} {'flip':>7s} {'swap':>7s} {'rad/s':>7s} "
          f"{'gyro |b|/sd':>11s} {'gyro warned':>11s}")
    for family in a.families:
        judged, conds, angles, scales, refused = 0, [], [], [], 0
        gyro, warned = [], 0
        caught = {"flip": [0, 0], "swap": [0, 0], "rad/s": [0, 0]}
        for seed in range(a.seeds):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                tel, on, sc, drawn = _telemetry(family, seed)
            with warnings.catch_warnings(record=True) as seen:
                warnings.simplefilter("always")
                est = check_gyro_bias(tel, sc)
            sd = sc.knowledge.gyro_bias_sd_rad_s
            if any(issubclass(w.category, GyroBiasWarning) for w in seen):
                warned += 1
                truth = np.asarray(drawn["gyro_bias_rad_s"]["values"])
                print(f"  warned: {family} seed {seed}: drawn |b| up to "
                      f"{np.max(np.abs(truth)) / sd:.2f} prior sd, estimate off by at most "
                      f"{np.max(np.abs(est.bias - truth)) / sd:.2f} ({est.window_s:g}-s windows)")
            if est is not None:
                gyro.append(float(np.max(np.abs(est.bias))) / sd)
            fit = wheel_momentum_scale(tel, sc, on)
            axes = fit.axes if fit is not None else None
            if axes is None:
                continue
            conds.append(axes.conditioning)
            if axes.judged:
                judged += 1
                angles += [axes.angle_deg(n, sc.wheel(n).axis) for n in axes.vectors]
                scales += [axes.scale(n) for n in axes.vectors]
            try:
                check_wheel_units(tel, sc, on)
            except InputError:
                refused += 1
            known = [n for n in tel.active_wheels() if n not in sc.articulated_wheels]
            for label, bad in _damaged(tel, known):
                caught[label][1] += 1
                try:
                    check_wheel_units(bad, sc, on)
                except InputError:
                    caught[label][0] += 1
        n = a.seeds
        cond = f"{min(conds):.3f}–{max(conds):.3f}" if conds else "–"
        ang = f"{max(angles):.2f}°" if angles else "–"
        sc_txt = f"{min(scales):.3f}–{max(scales):.3f}" if scales else "–"
        hits = {k: f"{c}/{t}" for k, (c, t) in caught.items()}
        g_txt = f"{max(gyro):.2f} ({len(gyro)})" if gyro else "–"
        print(f"{family:20s} {judged:>3d}/{n:<3d} {cond:>15s} {ang:>9s} {sc_txt:>13s} "
              f"{refused:>9d}/{n:<3d} {hits['flip']:>7s} {hits['swap']:>7s} "
              f"{hits['rad/s']:>7s} {g_txt:>11s} {warned:>7d}/{n:<3d}")
    print(f"(judged: conditioning ≥ {AXES_CONDITION_MIN}; flip/swap/rad-s: damaged copies "
          "refused / made; gyro: the largest estimated |bias| over the model's [gyro] sd, and "
          "the files with an estimate)")


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    main()
