"""Table kinds of the speed and convergence benchmarks' records (docs/performance/,
docs/quick_settings/); registered in :mod:`_tables` by import."""

from __future__ import annotations

import re

from _tables import Records, kind, read_json


@kind("quick_settings")
def quick_settings(args: list[Records]) -> str:
    """Converged fits per sampler setting (benchmarks/quick_settings.py's records, pooled)."""
    from quick_settings import table

    return table([p for group in args for p in group])


@kind("bench_samplers")
def bench_samplers(args: list[Records]) -> str:
    """The package's warm robust fit against nutpie (benchmarks/bench_samplers.py records): a
    row per argument, its label the letter that ends the record's name (``A+B``: pooled)."""
    from statistics import median

    rows = ["| run | `fit inertia` (robust, warm, run directory and report) | nutpie, plain "
            "model | ratio of medians | per round |", "|---|---|---|---|---|"]
    for group in args:
        walls: dict[str, list[float]] = {"pkg_robust_warm": [], "nutpie": []}
        for path in group:
            runs = sorted(read_json(path)["runs"], key=lambda r: r["round"])
            for system, w in walls.items():
                w += [r["wall_s"] for r in runs if r["system"] == system]
        pkg, nut = walls["pkg_robust_warm"], walls["nutpie"]
        per_round = [a / b for a, b in zip(pkg, nut, strict=True)]
        ratio = f"{median(pkg) / median(nut):.2f} | {min(per_round):.2f}–{max(per_round):.2f}"
        if len(group) > 1:
            rows.append(f"| all {len(pkg)} | median {median(pkg):.2f} s | median "
                        f"{median(nut):.2f} s | {ratio} |")
            continue
        label = re.search(r"[a-z]*$", group[0].stem)[0]
        cells = [", ".join(f"{w:.2f}" for w in ws) + f" s (median {median(ws):.2f})"
                 for ws in (pkg, nut)]
        rows.append(f"| {label} ({len(pkg)} rounds) | {cells[0]} | {cells[1]} | {ratio} |")
    return "\n".join(rows)


@kind("bench_samplers_medians")
def bench_samplers_medians(args: list[Records]) -> str:
    """Every system's medians of a benchmarks/bench_samplers.py record (its ``medians``)."""
    from bench_samplers import table

    (path,), = args
    return table(read_json(path)["medians"])


@kind("api_vs_cli")
def api_vs_cli(args: list[Records]) -> str:
    """The API's first example against ``fit inertia`` (benchmarks/api_vs_cli.py records): the
    wall and CPU medians of the counted runs, the ratio, the chain method and the load."""
    rows = ["| settings | API wall | CLI wall | API/CLI | API cpu | CLI cpu | chains (API, CLI) | "
            "load |", "|" + "---|" * 8]
    for r in (read_json(p) for group in args for p in group):
        st, med = r["settings"], r["median"]
        loads = [x["load_1min"] for rs in r["runs"].values() for x in rs]
        rows.append(f"| {st['chains']} × ({st['warmup']} + {st['draws']}), {st['pairs']} pairs | "
                    f"{med['api']['wall_s']:.1f} s | {med['cli']['wall_s']:.1f} s | "
                    f"{r['api_over_cli']:.2f} | {med['api']['cpu_s']:.1f} s | "
                    f"{med['cli']['cpu_s']:.1f} s | {r['chain_method_used']['api']}, "
                    f"{r['chain_method_used']['cli']} | {min(loads):.1f}–{max(loads):.1f} |")
    return "\n".join(rows)


@kind("bench_thrust")
def bench_thrust(args: list[Records]) -> str:
    """A robust ``fit thrust`` of one long event by phase (benchmarks/bench_thrust.py record): a
    column per run (the cold one, then the warm ones), wall and CPU seconds, the sampler's
    leapfrog steps and step sizes, the gradient's cost, the bulk ESS and the load."""
    (path,), = args
    runs = read_json(path)["runs"]
    head = [f"{r['kind']}" + (f" {i}" if r["kind"] == "warm" else "")
            for i, r in enumerate(runs)]
    rows = ["| | " + " | ".join(head) + " |", "|---|" + "---|" * len(runs)]

    def row(label, fn):
        rows.append(f"| {label} | " + " | ".join(fn(r) for r in runs) + " |")

    row("whole fit, wall s", lambda r: f"{r['total_wall']:.1f}")
    row("whole fit, CPU s", lambda r: f"{r['total_cpu']:.1f}")
    for phase in ("sampler", "laplace", "nuisance draws, residuals"):
        row(f"{phase}, wall / CPU s", lambda r, p=phase: f"{r['wall'][p]:.1f} / {r['cpu'][p]:.1f}")
    row("leapfrog steps per iteration", lambda r: f"{r['leapfrog_per_iteration']:.2f}")
    row("step sizes", lambda r: f"{min(r['step_size']):.2f}–{max(r['step_size']):.2f}")
    row("value and gradient of the log density, CPU ms", lambda r: f"{r['gradient_cpu_ms']:.2f}")
    row("bulk ESS of F, τd, τr, τf", lambda r: ", ".join(
        f"{r['summary_parameters'][n]['ess_bulk']:.0f}"
        for n in ("F", "tau_delay", "tau_rise", "tau_fall")))
    row("divergences", lambda r: f"{r['divergences']}")
    row("load average (start, end)", lambda r: f"{r['load_start']:.1f}, {r['load_end']:.1f}")
    return "\n".join(rows)


@kind("bench_thrust_commits")
def bench_thrust_commits(args: list[Records]) -> str:
    """One row per benchmarks/bench_thrust.py record, in the order given, named by the commit
    of its manifest's run: the last warm run's wall and CPU seconds, its preparation's and its
    sampler's CPU, the gradient's CPU ms and the leapfrog steps per iteration."""
    from _provenance import manifest_path

    rows = ["| code | warm fit, wall | warm fit, CPU | preparation, CPU | sampler, CPU | "
            "value and gradient, CPU | leapfrog steps per iteration |", "|" + "---|" * 7]
    for path in (p for group in args for p in group):
        r = read_json(path)["runs"][-1]
        commit = read_json(manifest_path(path))["runs"][0]["commit"][:7]
        rows.append(f"| `{commit}` | {r['total_wall']:.1f} s | {r['total_cpu']:.1f} s | "
                    f"{r['cpu']['preparation']:.1f} s | {r['cpu']['sampler']:.1f} s | "
                    f"{r['gradient_cpu_ms']:.2f} ms | {r['leapfrog_per_iteration']:.2f} |")
    return "\n".join(rows)


@kind("memory_telemetry")
def memory_telemetry(args: list[Records]) -> str:
    """Peak memory by file size (benchmarks/memory_telemetry.py's record): a row per size, a
    column per stage, the wall time beside the prepare stages."""
    from memory_telemetry import STAGES

    res = [r for group in args for p in group for r in read_json(p)["results"]]
    rows = ["| rows | `read_telemetry` | + `prepare_inertia` (idealised) | + `prepare_inertia` "
            "(robust) |", "|---|---|---|---|"]
    for n in sorted({r["rows"] for r in res}):
        by = {r["stage"]: r for r in res if r["rows"] == n}
        cells = [f"{by[s]['peak_mb']:.0f} MB" + (f" ({by[s]['seconds']:.0f} s)" if s != "read"
                                                  else "") if s in by else "—"
                 for s in STAGES]
        rows.append(f"| {n:,} | " + " | ".join(cells) + " |")
    return "\n".join(rows)


COMPILE_TOP = 6
"""Programs a ``compile_programs`` table lists by name; the rest are one row."""


@kind("compile_programs")
def compile_programs(args: list[Records]) -> str:
    """What a cold fit compiles (benchmarks/compile_cache.py's record: its first run, cache
    off): the :data:`COMPILE_TOP` slowest programs with their count and seconds, then the rest."""
    runs = [r for group in args for p in group for r in read_json(p)["runs"]]
    per = sorted(runs[0]["per_program"], key=lambda x: -x[2])
    rows = ["| program | count | seconds |", "|---|---|---|"]
    rows += [f"| `{name}` | {n} | {s:.1f} |" for name, n, s in per[:COMPILE_TOP]]
    rest = per[COMPILE_TOP:]
    if rest:
        count, secs = sum(n for _, n, _ in rest), sum(s for *_, s in rest)
        rows.append(f"| {len(rest)} other programs (eager array operations outside `jit` "
                    f"among them) | {count} | {secs:.1f} |")
    rows.append(f"| all ({runs[0]['run']}) | {runs[0]['programs']} | "
                f"{sum(s for *_, s in per):.1f} |")
    return "\n".join(rows)


@kind("bench_sbc")
def bench_sbc(args: list[Records]) -> str:
    """Warm SBC throughput per model and batch (benchmarks/bench_sbc.py records)."""
    rows = ["| model | batch | replicates/min (wall) | CPU s/replicate | replicates per "
            "CPU-minute | load average |", "|---|---|---|---|---|---|"]
    for r in (r for group in args for p in group for r in read_json(p)):
        how = "vectorised" if r["vectorized"] else "one by one"
        lo, hi = r["load"]
        rows.append(f"| {r['model']} | {r['batch']}, {how} | "
                    f"{60 / r['wall_s_per_replicate']:.0f} | {r['cpu_s_per_replicate']:.3f} | "
                    f"{60 / r['cpu_s_per_replicate']:.0f} | {lo:.1f}–{hi:.1f} |")
    return "\n".join(rows)


@kind("bench_report")
def bench_report(args: list[Records]) -> str:
    """CPU cost of a fit's report (benchmarks/bench_report.py records): ``report DIR`` in a
    fresh process, and ``build_report`` in a warm one with its figures and the run's reading."""
    rows = ["| run | `cassini-bayes report DIR`, CPU (wall), median | `build_report` warm, CPU "
            "| of it: figures and PNG | reading the run | load |", "|---|---|---|---|---|---|"]
    for r in (r for group in args for p in group for r in read_json(p)):
        w = r["warm_cpu_s"]
        figs = sum(v for k, v in w.items() if k.endswith(("_figure", "png_bytes")))
        rows.append(f"| {r['kind']} (`{r['run']}`) | {r['report_cpu_s']:.2f} s "
                    f"({r['report_wall_s']:.2f} s), {r['repeat']} runs | "
                    f"{w['build_report (total)']:.2f} s | {figs:.2f} s | "
                    f"{w.get('load_run', float('nan')):.2f} s | {r['load']:.1f} |")
    return "\n".join(rows)
