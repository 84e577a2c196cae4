"""Table kinds of the Basilisk flights' records (validation/results/; validation/basilisk_espa.py
writes one ``results.json`` per seed); registered in :mod:`_tables` by import."""

from __future__ import annotations

from _tables import Records, kind, read_json


def _flights(args: list[Records]) -> list[tuple[int, dict]]:
    """``(seed, results)`` of each record, the seed from its name (``…_seedN.json``)."""
    out = []
    for path in (p for group in args for p in group):
        out.append((int(path.stem.rsplit("seed", 1)[1]), read_json(path)))
    return out


@kind("basilisk_inertia")
def basilisk_inertia(args: list[Records]) -> str:
    """Per seed and inertia entry: truth, posterior mean and 90 % interval, error, and the
    seed's convergence and adequacy (the ``slews`` case)."""
    flights = _flights(args)
    rows = ["| seed | param | truth | mean [90 %] | error | covered |", "|---|---|---|---|---|---|"]
    for seed, res in flights:
        for r in res["slews"]["rows"]:
            err = (f"{r['error']:+.3g} ({100 * r['rel_error']:+.2f} %)"
                   if r["param"] in ("Ixx", "Iyy", "Izz") else f"{r['error']:+.3g}")
            rows.append(f"| {seed} | {r['param']} | {r['truth']:.6g} | {r['mean']:.5g} "
                        f"[{r['q05']:.5g}, {r['q95']:.5g}] | {err} | "
                        f"{'yes' if r['covered'] else 'no'} |")
    rows += ["", "| seed | covered | divergences | max R-hat | min bulk ESS | adequacy |",
             "|---|---|---|---|---|---|"]
    for seed, res in flights:
        s = res["slews"]
        d, n = s["diagnostics"], len(s["rows"])
        k = sum(bool(r["covered"]) for r in s["rows"])
        rows.append(f"| {seed} | {k}/{n} | {d['divergences']} | {d['max_r_hat']:.3f} | "
                    f"{d['min_ess_bulk']:.0f} | {'ok' if s['adequacy']['ok'] else 'fails'} |")
    return "\n".join(rows)


@kind("basilisk_wheel_axis")
def basilisk_wheel_axis(args: list[Records]) -> str:
    """Per seed: the fitted wheel axis's angle to the truth, its 90 % cone, and the fit's
    convergence and adequacy (the ``wheel-axis`` case, RWA method)."""
    rows = ["| seed | angle to truth | model file to truth | 90 % cone | covered | ≤ 0.5° | "
            "divergences | max R-hat | min bulk ESS | adequacy |", "|" + "---|" * 10]
    for seed, res in _flights(args):
        a = res["wheel-axis"]["axis"]
        rows.append(f"| {seed} | {a['error_deg']:.3f}° | {a['file_to_truth_deg']:.3f}° | "
                    f"{a['cone90_deg']:.3f}° | {'yes' if a['covered'] else 'no'} | "
                    f"{'yes' if a['within_0p5_deg'] else 'no'} | {a['divergences']} | "
                    f"{a['max_r_hat']:.3f} | {a['min_ess_bulk']:.0f} | "
                    f"{'ok' if a['adequacy_ok'] else 'fails'} |")
    return "\n".join(rows)
