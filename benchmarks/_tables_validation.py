"""Table kinds of the cross-checks against other simulators (validation/results/, shown in
docs/robust/basilisk.md); registered in :mod:`_tables` by import."""

from __future__ import annotations

from _tables import Records, kind, read_json


def _adequacy(adequacy: dict | None) -> str:
    if not adequacy:
        return "–"
    failed = [k for k, c in adequacy["checks"].items() if not c.get("ok", True)]
    return "ok" if adequacy["ok"] else f"fails ({', '.join(failed)})"


@kind("basilisk_espa_bias")
def basilisk_espa_bias(args: list[Records]) -> str:
    """One row per ``validation/basilisk_espa.py --cases bias`` record (its ``bias`` block):
    the thrust errors per thruster (% of the truth), the largest, the largest posterior sd (% of
    the thrust), the centre-of-mass offset's error (mm; posterior sd), the entries their 90 %
    interval covers, max R-hat, divergences, the adequacy verdict, the fit's wall time, and the
    125 ms impulse bits' largest error (% of Basilisk's) and how many of the eight their 90 %
    interval covers (``impulse_bits``, validation/espa_bias_record.py)."""
    rows = ["| RW2 tilt | telemetry (s) | seed | thrust error A1..F4 (%) | max \\|err\\| | "
            "thrust sd | offset error (mm) | covered | max R-hat | div. | adequacy | fit time | "
            "impulse bit max \\|err\\| | bits covered | record |", "|" + "---|" * 15]
    for path in (p for group in args for p in group):
        b = read_json(path)["bias"]
        t, dg = b["truth"], b["diagnostics"]
        thrust = [r for r in b["rows"] if "rel_error_pct" in r]
        com = [r for r in b["rows"] if r["kind"] == "com"]
        errs = ", ".join(f"{r['rel_error_pct']:+.2f}" for r in thrust)
        sd = max(100 * r["sd"] / r["truth"] for r in thrust)
        off = (", ".join(f"{1e3 * r['error']:+.1f}" for r in com) + " (sd "
               + ", ".join(f"{1e3 * r['sd']:.1f}" for r in com) + ")")
        cov = sum(r["covered"] for r in b["rows"])
        bits = b.get("impulse_bits") or []
        bit_err = (f"{max(abs(r['rel_error_pct']) for r in bits):.2f} %" if bits else "–")
        bit_cov = f"{sum(r['covered'] for r in bits)}/{len(bits)}" if bits else "–"
        rows.append(f"| {t['tilt_angle_deg']:.1f}° | {t['sample_period_s']:g} | {b['seed']} | "
                    f"{errs} | {b['max_abs_thrust_error_pct']:.2f} % | {sd:.2f} % | {off} | "
                    f"{cov}/{len(b['rows'])} | {dg['max_r_hat']:.4f} | {dg['divergences']} | "
                    f"{_adequacy(b['adequacy'])} | {b['fit_wall_s']:.0f} s | {bit_err} | "
                    f"{bit_cov} | `{path.name}` |")
    return "\n".join(rows)


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


def _fits(args: list[Records], method: str) -> list[dict]:
    return [r for group in args for p in group for r in read_json(p) if r["method"] == method]


@kind("wheel_axis_rwa")
def wheel_axis_rwa(args: list[Records]) -> str:
    """One row per RWA-method record of ``benchmarks/wheel_axis_fits.py``: the posterior mean's
    and the least squares' angle from the true axis, the 90 % cone, the diagnostics and the
    adequacy verdict."""
    rows = ["| spacecraft, wheel | posterior mean error | least squares error | 90 % cone | "
            "max R-hat | divergences | min bulk ESS | adequacy |", "|" + "---|" * 8]
    for r in _fits(args, "rwa"):
        d = r["diagnostics"]
        rows.append(f"| `{r['model']}`, {r['wheel']} | {r['error_deg']:.3f}° | "
                    f"{r['least_squares_error_deg']:.3f}° | {r['cone_deg']['90']:#.3g}° | "
                    f"{d['max_r_hat']:.3f} | {d['divergences']} | {d['min_ess_bulk']:.0f} | "
                    f"{'passed' if r['adequacy_ok'] else 'FAILED'} |")
    return "\n".join(rows)


@kind("wheel_axis_rcs")
def wheel_axis_rcs(args: list[Records]) -> str:
    """One row per RCS-method record of ``benchmarks/wheel_axis_fits.py``: the inertia knowledge,
    the windows (given or detected, s), the errors as ``wheel_axis_rwa``, the 95 % cone (with the
    budget warning where the fit gave one), the diagnostics and the adequacy verdict."""
    rows = ["| inertia knowledge | windows A, B (s) | posterior mean error | least squares error | "
            "95 % cone | max R-hat | divergences | adequacy |", "|" + "---|" * 8]
    for r in _fits(args, "rcs"):
        d = r["diagnostics"]
        knowledge = ("`--inertia-posterior` of a `slews_espa_bus` fit" if r["inertia_posterior"]
                     else "the model file's (±10 % moments)")
        w = r["windows"][0]
        windows = (f"{'given' if r['windows_given'] else 'detected'} "
                   f"{w['a'][0]:.0f}–{w['a'][1]:.0f}, {w['b'][0]:.0f}–{w['b'][1]:.0f}")
        warned = " (with the budget warning)" if any("budget" in w for w in r["warnings"]) else ""
        rows.append(f"| {knowledge} | {windows} | {r['error_deg']:.3f}° | "
                    f"{r['least_squares_error_deg']:.3f}° | {r['cone_deg']['95']:.2f}°{warned} | "
                    f"{d['max_r_hat']:.3f} | {d['divergences']} | "
                    f"{'passed' if r['adequacy_ok'] else 'FAILED'} |")
    return "\n".join(rows)
