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
            rel = r.get("rel_error", r["error"] / r["truth"])
            err = (f"{r['error']:+.3g} ({100 * rel:+.2f} %)"
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


@kind("basilisk_rwa4_rcs")
def basilisk_rwa4_rcs(args: list[Records]) -> str:
    """Per seed and inertia prior: RWA4's fitted axis against the Basilisk truth, its 90 % cone,
    Brown's 3° and the fit's diagnostics (``validation/basilisk_crosscheck.py``'s ``rcs`` case)."""
    rows = ["| seed | inertia prior | angle to truth | 90 % cone | covered | ≤ 3° | divergences | "
            "max R-hat | adequacy |", "|" + "---|" * 9]
    for seed, res in _flights(args):
        for r in res["rcs"]["rows"]:
            prior = ("the Basilisk slews' posterior (`--inertia-posterior`)"
                     if "slews" in r["prior"] else "the model file's knowledge (±10 %, ±75 kg m²)")
            rows.append(f"| {seed} | {prior} | {r['error_deg']:.3f}° | {r['cone90_deg']:.3f}° | "
                        f"{'yes' if r['covered'] else 'no'} | "
                        f"{'yes' if r['within_budget'] else 'no'} | {r['divergences']} | "
                        f"{r['max_r_hat']:.3f} | {'ok' if r['adequacy_ok'] else 'fails'} |")
    return "\n".join(rows)


@kind("basilisk_thrust")
def basilisk_thrust(args: list[Records]) -> str:
    """Per seed: the thrust and the pulse time constants against Basilisk's (its ramp table's
    constants; the τf for which Feldman & Lee §V delivers Basilisk's impulses beside them), then
    the fit's diagnostics (``basilisk_crosscheck.py``'s ``bias`` case)."""
    rows = ["| seed | param | Basilisk | mean [90 %] | error | covered |", "|" + "---|" * 6]
    flights = _flights(args)
    for seed, res in flights:
        b = res["bias"]
        for r in b["rows"]:
            if r["param"] == "F":
                truth, est = f"{r['truth']:.5f} N", (f"{r['mean']:.5f} [{r['q05']:.5f}, "
                                                     f"{r['q95']:.5f}] N")
                err = f"{r['error']:+.5f} N ({100 * r['error'] / r['truth']:+.2f} %)"
            else:
                ms = {k: 1e3 * r[k] for k in ("truth", "mean", "q05", "q95", "error")}
                truth = f"{ms['truth']:.1f} ms"
                if r["param"] == "tau_fall":
                    truth += f" (§V equivalent {1e3 * b['truth']['tau_fall_fl_equivalent']:.1f})"
                est = f"{ms['mean']:.2f} [{ms['q05']:.2f}, {ms['q95']:.2f}] ms"
                err = f"{ms['error']:+.2f} ms"
            rows.append(f"| {seed} | {r['param']} | {truth} | {est} | {err} | "
                        f"{'yes' if r['covered'] else 'no'} |")
    rows += ["", "| seed | pulses | divergences | max R-hat | min bulk ESS | converged | "
             "adequacy |", "|" + "---|" * 7]
    for seed, res in flights:
        b = res["bias"]
        d = b["diagnostics"]
        rows.append(f"| {seed} | {b['truth']['n_pulses']} | {d['divergences']} | "
                    f"{d['max_r_hat']:.3f} | {d['min_ess_bulk']:.0f} | "
                    f"{'yes' if d['converged'] else 'no'} | {_adequacy(b['adequacy'])} |")
    return "\n".join(rows)


@kind("basilisk_impulse")
def basilisk_impulse(args: list[Records]) -> str:
    """Per commanded width: the impulse per newton of one pulse Basilisk's thrusters delivered
    (their output messages), the first-order ramp without delay, and Feldman & Lee §V at
    Basilisk's table constants (the first record's ``bias`` case)."""
    _, res = _flights(args)[0]
    rows = ["| commanded width | pulses | Basilisk delivered | first-order rise + decay, "
            "no delay | Feldman & Lee §V at the table's constants |", "|" + "---|" * 5]
    for width, v in res["bias"]["truth"]["impulse_per_newton_by_width"].items():
        rows.append(f"| {float(width):.3f} s | {v['count']} | {v['basilisk_s']:.4f} | "
                    f"{v['ramp_no_delay_s']:.4f} | {v['feldman_lee_s']:.4f} |")
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
