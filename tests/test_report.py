"""Diagnostic reports: self-contained HTML per run directory, for every kind of run.

The run directories are synthetic but shaped like the fit's (docs/design.md §4.4): ArviZ
InferenceData with posterior (4 chains), prior, sample_stats (diverging, energy), observed_data and
a ``residuals`` group, plus summary.json and config.toml. The numbers are drawn from known normals,
so the report's flags (weak identification, truth in the 90 % interval) have known answers.
"""

from __future__ import annotations

import base64
import dataclasses
import json
import re

import numpy as np
import pytest

from cassini_bayes.report import build_report, html_page, section, table
from cassini_bayes.report.html import Raw, figure
from cassini_bayes.report.rundata import load_run
from cassini_bayes.report.tables import diagnostics, parameter_names, parameter_rows
from pages import first_table
from run_dirs import INERTIA, make_run, summary_stats

RWA1 = np.array([0.0, 0.816497, 0.577350])

# Expected section ids per kind (report/build.py), the answer first
COMMON = ["answer", "adequacy", "residuals", "diagnostics", "configuration"]
SECTIONS = {
    "inertia": COMMON,
    "thrust": COMMON + ["pulses"],
    "rwa4": COMMON,
}
# the answer figure (rwa4: the sky plot), the residuals, trace and rank; thrust: per-pulse impulses
N_FIGURES = {"inertia": 3, "thrust": 4, "rwa4": 3}
# the answer table's columns (issue 31): every fit report's first table
ANSWER_COLUMNS = ["quantity", "unit", "posterior mean", "sd", "90 % interval",
                  "model file (prior mean)", "prior sd", "least squares (papers)",
                  "papers' budget", "verdict"]


@pytest.fixture(scope="module")
def reports(tmp_path_factory):
    """One built report per kind: {kind: (run_dir, html)}."""
    out = {}
    for kind in ("inertia", "thrust", "rwa4"):
        root = tmp_path_factory.mktemp(kind)
        run = make_run(root, kind, draws=1000 if kind == "inertia" else 200)
        path = build_report(run)
        out[kind] = (run, path.read_text(encoding="utf-8"))
    return out


def _section_ids(html: str) -> set[str]:
    return set(re.findall(r'<section id="([^"]+)">', html))


def _assert_self_contained(html: str) -> None:
    # no external resources: nothing loaded over the network, no scripts, no external CSS/fonts
    assert not re.search(r'(src|href)\s*=\s*["\']?\s*(https?:)?//', html, re.I)
    assert "<script" not in html.lower()
    assert "<link" not in html.lower()
    assert "@import" not in html and "url(" not in html
    imgs = re.findall(r'<img[^>]*\ssrc="([^"]*)"', html)
    assert imgs, "no figures embedded"
    for src in imgs:
        assert src.startswith("data:image/png;base64,")
        png = base64.b64decode(src.split(",", 1)[1], validate=True)
        assert png[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("kind", ["inertia", "thrust", "rwa4"])
def test_report_is_self_contained_with_every_section(reports, kind):
    run, html = reports[kind]
    assert (run / "report.html").is_file()
    _assert_self_contained(html)
    assert set(SECTIONS[kind]) <= _section_ids(html)
    assert len(re.findall(r"<img ", html)) == N_FIGURES[kind]
    assert "Not available" not in html  # every group is there in these runs
    assert "could not be drawn" not in html
    # header: kind, run dir, seed, version, converged badge, warnings (escaped)
    assert "CONVERGED" in html and str(run.resolve()) in html
    assert "synthetic &lt;test&gt; run" in html and "<test>" not in html
    # under a few MB even for 4 chains x 1000 draws (inertia)
    assert len(html.encode()) < 3_000_000


@pytest.mark.parametrize("kind", ["inertia", "thrust", "rwa4"])
def test_the_first_table_is_the_answer(reports, kind):
    """Issue 31: a fit's report opens with the answer — the first table holds every calibrated
    quantity with its unit, posterior mean, sd and 90 % interval, the model file's prediction
    and prior sd, the papers' least squares and budget with pass/fail — and the verdicts sit
    above it as badges; the per-variable diagnostics of the nuisance are folded away."""
    run, html = reports[kind]
    headers, rows = first_table(html)
    assert all(c in headers for c in ANSWER_COLUMNS), headers
    assert html.index('<section id="answer">') < html.index('<section id="diagnostics">')
    assert html.index("CONVERGED") < html.index("<table")
    summary = json.loads((run / "summary.json").read_text())
    by_name = {r[0]: dict(zip(headers, r)) for r in rows}
    assert set(summary["parameters"]) <= set(by_name)
    for name, st in summary["parameters"].items():
        row = by_name[name]
        # shown with two significant digits of the sd
        assert float(row["posterior mean"]) == pytest.approx(st["mean"], abs=0.05 * st["sd"])
        assert row["unit"] in ("kg m²", "N", "s", "–")
    per_variable = html.split('<section id="diagnostics">', 1)[1]
    assert "<details><summary>Per-variable diagnostics" in per_variable
    if kind == "inertia":     # the model file's prediction and the budgets of the moments
        assert float(by_name["Ixx"]["model file (prior mean)"]) == 7403.0
        assert by_name["Ixx"]["papers' budget"] == "±1 % (Feldman & Lee §VI)"
        assert by_name["Ixx"]["verdict"] in ("pass", "FAIL")
        assert by_name["Ixy"]["papers' budget"] == "–"
        assert any(k.startswith("worst moment") for k in by_name)
    if kind == "thrust":      # a thrust (N) has the ±10 % budget, a time constant none
        assert by_name["F_Z1"]["papers' budget"].startswith("±10 %")
        assert by_name["tau_fall"]["papers' budget"] == "–"
    if kind == "rwa4":        # the axis's knowledge against Brown's budget; no model value
        assert by_name["u4_x"]["model file (prior mean)"] == "–"
        assert any(k.startswith("spin-axis error") for k in by_name)


def test_answer_budget_verdicts_follow_the_95th_percentile():
    """A moment passes the ±1 % budget when 95 % of its draws lie within 1 % of its mean
    (Feldman & Lee Eq 12 with the draw as the truth); a thrust the ±10 % one likewise."""
    from cassini_bayes.report.tables import budget_check

    rng = np.random.default_rng(0)
    tight = 7400.0 + 7400.0 * 0.004 * rng.standard_normal(4000)   # 95 % within ~0.8 %
    wide = 7400.0 + 7400.0 * 0.008 * rng.standard_normal(4000)    # 95 % within ~1.6 %
    assert budget_check("Ixx", tight).passed and not budget_check("Ixx", wide).passed
    assert budget_check("Ixx", wide).error_q95 == pytest.approx(1.96 * 0.8, rel=0.1)
    assert budget_check("Ixy", wide) is None and budget_check("tau_rise", wide) is None
    thrust = 0.7 + 0.7 * 0.06 * rng.standard_normal(4000)        # 95 % within ~12 %
    assert budget_check("F", thrust).bound == "±10 %" and not budget_check("F", thrust).passed


def test_inertia_report_tables(reports):
    run, html = reports["inertia"]
    for name in ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz", "H0[x]", "sigma_H"):
        assert f"<td class=\"l\">{name}</td>" in html
    assert "energy BFMI" in html and "least squares" in html and "contraction" in html
    loaded = load_run(run)
    names = parameter_names(loaded)
    assert names == list(INERTIA)
    diag = diagnostics(loaded, names)
    assert diag.chains == 4 and diag.draws == 1000 and diag.divergences == 0
    assert diag.bfmi is not None and diag.bfmi.shape == (4,)
    rows = {r.label: r for r in parameter_rows(loaded, names, diag)}
    # posterior sd 8 against prior sd 740: contraction ~ 1 - (8/740)^2, identified
    assert rows["Ixx"].contraction == pytest.approx(1 - (8 / 740.3) ** 2, abs=1e-3)
    assert rows["Ixx"].flag == "" and rows["Ixx"].unit == "kg m²"
    assert rows["Ixx"].baseline == INERTIA["Ixx"] + 1.0 and rows["Ixx"].truth == INERTIA["Ixx"]
    assert "Posterior-mean residual of the momentum model" in html
    # without prior draws, the prior sd stated in constant_data still gives the contraction
    groups = dict(loaded.groups)
    del groups["prior"]
    no_prior = dataclasses.replace(loaded, groups=groups)
    rows = {r.label: r for r in parameter_rows(no_prior, names, diag)}
    assert rows["Ixx"].prior_sd == pytest.approx(740.3)
    assert rows["Ixx"].contraction == pytest.approx(1 - (8 / 740.3) ** 2, abs=1e-3)


def test_thrust_report_flags_prior_dominated_y_thrusters(reports):
    run, html = reports["thrust"]
    loaded = load_run(run)
    names = parameter_names(loaded)
    rows = {r.label: r for r in parameter_rows(loaded, names, diagnostics(loaded, names))}
    # Y thrusters: posterior sd 0.19 against prior sd 0.2 -> contraction ~0.1, flagged;
    # Z thrusters: 0.02 against 0.2 -> contraction ~0.99, identified
    for s in ("Y1", "Y2", "Y3", "Y4"):
        assert rows[f"F_{s}"].flag in ("weakly identified", "prior-dominated")
        assert rows[f"F_{s}"].contraction < 0.5
    for s in ("Z1", "Z2", "Z3", "Z4"):
        assert rows[f"F_{s}"].flag == "" and rows[f"F_{s}"].contraction > 0.9
    assert "weakly identified (posterior/prior contraction &lt; 0.5): F_Y1" in html
    assert "impulse model (Feldman &amp; Lee Eq 17)" in html


def test_rwa4_report_has_axis_plot_and_direction_table(reports):
    run, html = reports["rwa4"]
    assert "RWA1 target" in html and "posterior mean error (angle to truth)" in html
    m = re.search(r"angle to RWA1 target \[0, 0.816497, 0.577350\]</td><td>([0-9.]+)°", html)
    assert m is not None
    summary = json.loads((run / "summary.json").read_text())
    mean = np.array(summary["direction"]["mean"])
    expected = np.degrees(np.arccos(mean @ RWA1 / np.linalg.norm(RWA1)))
    assert float(m.group(1)) == pytest.approx(expected, abs=2e-3)


def test_rwa4_requirement_is_decided_by_the_posterior(reports):
    """Brown's ±2° requirement: "yes"/"no" only at posterior probability ≥ 0.95 / ≤ 0.05; the
    mean axis alone can sit inside while most of the posterior does not (the number audit's
    RCS fit: mean 1.43° from RWA1, probability 0.26, was called "yes")."""
    from cassini_bayes.report._answer import _requirement_verdict

    _, html = reports["rwa4"]      # 3.1° from RWA1, ±0.4°
    assert re.search(r"within ±2° of RWA1 \(reference wheel, spacecraft model\)</td><td>no "
                     r"\(probability 0\.0[0-4]\d\)", html)
    assert _requirement_verdict(0.26).startswith("undecided (probability 0.260")
    assert _requirement_verdict(0.96) == "yes (probability 0.960)"
    assert _requirement_verdict(0.05) == "no (probability 0.050)"


def test_diagnostics_judge_what_the_fit_judged(tmp_path):
    """The report's max R-hat and min ESS cover summary.json's parameters and nuisance, as the
    fit's verdict does; a sampler coordinate (``z``) is listed, last, but not judged."""
    import arviz as az

    run = make_run(tmp_path, "inertia", draws=200)
    idata = az.from_netcdf(str(run / "posterior.nc"))
    post = idata.posterior
    stuck = np.repeat(np.arange(4.0)[:, None], post.sizes["draw"], 1)    # chains disagree
    idata.posterior["z"] = (("chain", "draw"), stuck + 0.01 * np.random.default_rng(1)
                            .standard_normal(stuck.shape))
    (run / "posterior.nc").unlink()
    idata.to_netcdf(str(run / "posterior.nc"))
    summary = json.loads((run / "summary.json").read_text())
    summary["nuisance"] = {"sigma_H": summary["parameters"]["Ixx"]}
    (run / "summary.json").write_text(json.dumps(summary))
    loaded = load_run(run)
    diag = diagnostics(loaded, parameter_names(loaded))
    roles = {r.label: r.role for r in diag.rows}
    assert roles["Ixx"] == "parameter" and roles["sigma_H"] == "nuisance"
    assert "z" not in roles and diag.sampler == {"z": 1, "H0": 3}   # listed, not judged
    assert diag.overall.max_r_hat == max(r.r_hat for r in diag.rows) < 1.05
    html = build_report(run).read_text(encoding="utf-8")
    assert "Sampler coordinates, not judged" in html and "z (1)" in html


def test_cli_report_rebuilds_the_page(tmp_path, run_cli):
    run = make_run(tmp_path, "rwa4", draws=100)
    page = run / "report.html"
    page.write_text("stale")
    code, out, err = run_cli("report", run)
    assert code == 0, err
    html = page.read_text()
    assert html.startswith("<!DOCTYPE html>") and "stale" not in html
    assert out.strip() == str(page.resolve())
    assert not list(run.glob(".report.html.*"))  # no temporary file left behind
    _assert_self_contained(html)


def test_report_refuses_files_of_different_runs(tmp_path, run_cli):
    """Issue 28: a thrust run's posterior.nc copied into an inertia run gave exit 0 and an
    inertia title over thrust variables. ``report`` checks that the run's files belong
    together — summary.json's kind and parameters against posterior.nc's variables,
    config.toml's command and sampler against both — and refuses in one line naming the file;
    nothing is written."""
    import shutil

    def case(name, edit):
        run = make_run(tmp_path / name, "inertia", draws=100)
        edit(run)
        code, _, err = run_cli("report", run)
        assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
        assert "different runs" in err and not (run / "report.html").exists()
        return err

    thrust = make_run(tmp_path / "thrust", "thrust", draws=100)
    err = case("copied", lambda r: shutil.copy(thrust / "posterior.nc", r / "posterior.nc"))
    assert "posterior.nc: holds the draws of a thrust fit, but summary.json is an inertia" in err

    def renamed(run):   # summary.json of the same kind, reporting another parameter
        s = json.loads((run / "summary.json").read_text())
        s["parameters"]["F"] = s["parameters"].pop("Ixx")
        s["kind"] = None
        (run / "summary.json").write_text(json.dumps(s))

    assert "posterior.nc: has no draws of F, which summary.json reports" in case("params",
                                                                                 renamed)

    def command(run):
        (run / "config.toml").write_text('command = "fit thrust"\n')

    assert "config.toml: written by 'cassini-bayes fit thrust', but the run is an inertia" in \
        case("command", command)

    def sampler(run):
        (run / "config.toml").write_text('command = "fit inertia"\n[sampler]\nchains = 4\n'
                                         'draws = 1000\n')

    assert "posterior.nc: holds 100 draw(s), but config.toml asked for draws = 1000" in \
        case("sampler", sampler)
    # the same files of one run pass
    run = make_run(tmp_path / "ok", "inertia", draws=100)
    (run / "config.toml").write_text('command = "fit inertia"\n[sampler]\nchains = 4\n'
                                     'draws = 100\n')
    assert run_cli("report", run)[0] == 0


def test_cli_report_missing_posterior_is_one_line_exit_2(tmp_path, run_cli):
    code, out, err = run_cli("report", tmp_path)
    assert code == 2
    assert err.count("\n") == 1 and "posterior.nc" in err and "Traceback" not in err
    code, _, err = run_cli("report", tmp_path / "nope")
    assert code == 2 and err.count("\n") == 1 and "not found" in err


def test_report_without_prior_residuals_or_energy(tmp_path):
    run = make_run(tmp_path, "rwa4", draws=100, prior=False, residuals=False, energy=False)
    (run / "config.toml").unlink()
    summary = json.loads((run / "summary.json").read_text())
    summary["diagnostics"]["converged"] = False
    (run / "summary.json").write_text(json.dumps(summary))
    # a fit building its run in a temporary directory names the final one
    html = build_report(run, display_dir="/runs/final").read_text()
    assert "/runs/final" in html and str(run) not in html
    _assert_self_contained(html)
    assert set(SECTIONS["rwa4"]) <= _section_ids(html)
    assert "Not available: model residuals" in html
    assert re.search(r"energy BFMI \(per chain\)</td><td>–</td>", html)
    assert "Not available: config.toml" in html
    assert "unknown (no prior)" in html
    assert "could not be drawn" not in html
    assert '<span class="badge fail">NOT CONVERGED</span>' in html


def test_report_shows_the_adequacy_verdict(reports):
    _, html = reports["inertia"]
    assert '<span class="badge fail">ADEQUACY FAILED: prior_data_conflict</span>' in html
    section = html.split('<section id="adequacy">', 1)[1].split("</section>", 1)[0]
    assert "FAILED" in section and "wheel_scale" in section and "6.100" in section
    assert section.count("<tr>") == 4                     # heading + three checks
    _, html = reports["thrust"]
    assert '<span class="badge ok">ADEQUATE</span>' in html
    assert "not applicable" in html and "one event: nothing to hold out" in html


def test_report_out_option_and_missing_summary(tmp_path):
    run = make_run(tmp_path, "rwa4", draws=100, residuals=False)
    (run / "summary.json").unlink()
    out = build_report(run, out=tmp_path / "elsewhere.html")
    html = out.read_text()
    assert out == tmp_path / "elsewhere.html" and not (run / "report.html").exists()
    assert "summary.json not found" in html and "rwa4 run" in html  # kind from the variables
    assert "Not available: model residuals" in html
    assert "ADEQUACY NOT CHECKED" in html and "Not available: this run has no adequacy" in html
    # the direction comes from the draws when summary.json does not give it
    assert "posterior mean direction" in html and "50 % cone radius" in html


def test_page_helpers_escape_and_link():
    page = html_page("A <b> title", [
        section("One & two", table(["x<", "y"], [["<script>", Raw("<em>ok</em>")]])),
        section("Figs", figure(b"\x89PNG\r\n\x1a\nfake", "cap <i>")),
    ])
    assert "<title>A &lt;b&gt; title</title>" in page
    assert "&lt;script&gt;" in page and "<em>ok</em>" in page and "x&lt;" in page
    assert 'href="#one-two"' in page and "cap &lt;i&gt;" in page
    _assert_self_contained(page)


@pytest.mark.parametrize("size_in", [(6.5, 3.8), (6.51, 3.803)])
def test_png_bytes_equals_savefig_at_any_figure_size(size_in):
    """:func:`figures.png_bytes` renders from the canvas's pixels; the PNG is the one the
    savefig path gave (same size, same bytes), also when the size in pixels is fractional."""
    import io

    from matplotlib.figure import Figure
    from PIL import Image

    from cassini_bayes.report import figures

    def draw():
        fig = Figure(figsize=size_in)
        fig.subplots().plot(np.sin(np.arange(100) / 7.0))
        return fig

    buf = io.BytesIO()
    draw().savefig(buf, format="png", dpi=figures.DPI)
    buf.seek(0)
    ref = io.BytesIO()
    Image.open(buf).convert("RGB").quantize(
        colors=256, method=Image.Quantize.FASTOCTREE).save(ref, "PNG")
    assert figures.png_bytes(draw()) == ref.getvalue()


@pytest.mark.parametrize("command", ["budget", "fit health", "monitor leak"])
def test_report_of_a_run_without_a_posterior_names_its_command(tmp_path, command):
    """`report` on a budget, health or leak run (no posterior.nc) says which runs it rebuilds
    instead of "run `cassini-bayes fit ...`"."""
    from cassini_bayes.errors import InputError

    (tmp_path / "summary.json").write_text(json.dumps({"command": command}))
    with pytest.raises(InputError, match=f"a `{command}` run; `report` rebuilds the page of a "
                                         "`fit inertia`, `fit thrust`, `fit wheel-axis` or "
                                         "`fit rwa4` run"):
        load_run(tmp_path)


# ---------------------------------------------------------------------------- figures (issue 31)


def _axes_problems(fig) -> list[str]:
    """Axes of ``fig`` without a unit in their label, and tick labels that overlap (drawn)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    out = []
    for ax in fig.axes:
        if not ax.get_visible() or not ax.axison:
            continue
        for name, axis, label in (("x", ax.xaxis, ax.get_xlabel()),
                                  ("y", ax.yaxis, ax.get_ylabel())):
            boxes = [t.get_window_extent(renderer) for t in axis.get_ticklabels()
                     if t.get_visible() and t.get_text()]
            shared = not boxes and name == "x"     # stacked panels: the bottom one is labelled
            if not shared and not re.search(r"\([^()]+\)\s*$", label):
                out.append(f"{ax.get_title()!r}: {name} label {label!r} has no unit")
            for i, a in enumerate(boxes):
                for b in boxes[i + 1:]:
                    if a.overlaps(b):
                        out.append(f"{ax.get_title()!r}: {name} tick labels overlap")
    return out


def _report_figures(run_dir, monkeypatch) -> dict:
    """Every figure the report of ``run_dir`` draws, caught as the report renders it to PNG,
    named by its position and first panel's title."""
    from cassini_bayes.report import figures, render_report

    drawn = {}
    render = figures.png_bytes

    def keep(fig, **kw):
        drawn[f"{len(drawn)}: {fig.axes[0].get_title() if fig.axes else ''}"] = fig
        return render(fig, **kw)

    monkeypatch.setattr(figures, "png_bytes", keep)
    page = render_report(load_run(run_dir))
    assert "could not be drawn" not in page
    return drawn


@pytest.mark.parametrize("kind", ["inertia", "thrust", "rwa4"])
def test_every_figure_axis_has_a_unit_and_no_tick_labels_overlap(reports, kind, monkeypatch):
    """Issue 31: trace, rank, pair and energy plots carried no units and the pair plot's tick
    labels overlapped ("75006000"). Every axis of every figure of a fit report is labelled
    "name (unit)" and its tick labels are apart; checked on the drawn figures. The check can
    fail: an axis without a unit and crowded ticks are caught."""
    drawn = _report_figures(reports[kind][0], monkeypatch)
    assert len(drawn) >= N_FIGURES[kind], list(drawn)
    for name, fig in drawn.items():
        assert _axes_problems(fig) == [], name
    from matplotlib.figure import Figure

    bad = Figure(figsize=(1.5, 1.5))
    ax = bad.subplots()
    ax.plot([75000.0, 76000.0], [0, 1])
    ax.set_xticks(np.linspace(75000, 76000, 12))
    ax.set_xlabel("Ixx")
    problems = _axes_problems(bad)
    assert any("no unit" in p for p in problems) and any("overlap" in p for p in problems)


def test_health_and_leak_figures_have_units():
    """The health and leak reports' figures, on posteriors built from known numbers."""
    from cassini_bayes.estimators.leak import ThresholdResult
    from cassini_bayes.inference.health import HealthPrior, health_posterior
    from cassini_bayes.inference.leak import HYPOTHESES, LeakPosterior
    from cassini_bayes.report.health import plot_health
    from cassini_bayes.report.leak import leak_figure

    rng = np.random.default_rng(0)
    dates = np.linspace(0.0, 700.0, 12)
    y = np.log(0.7) + 0.01 * rng.standard_normal((12, 6))
    y[7:, 2] += np.log(0.93)                                   # Z3 down 7 % after day 400
    post = health_posterior(dates, y, np.full((12, 6), 0.01), HealthPrior())
    assert _axes_problems(plot_health(post, 0.05)) == []
    t = np.arange(60.0, 1860.0, 60.0)
    prob = np.zeros((t.size, len(HYPOTHESES)))
    prob[:, 0] = np.where(t < 600, 1.0, 0.0)
    prob[:, 1] = 1.0 - prob[:, 0]
    leak = LeakPosterior(t, prob, 0.99, 660.0, 660.0, "Z1", 0.1, 0.002, (0.097, 0.103),
                         np.array([-0.1, 0.08, 0.0]), 600.0, 0.05, np.full(3, 1e-3))
    lee = ThresholdResult(1100.0, 0, 0, (1100.0,), ())
    assert _axes_problems(leak_figure(leak, lee, HYPOTHESES)) == []


def test_a_complete_run_is_reported_without_arviz(tmp_path):
    """The report reads posterior.nc with h5py and takes the sampler diagnostics from
    summary.json: ArviZ (more CPU to import than the whole page) and xarray are not imported
    when summary.json covers every judged variable (docs/performance.md)."""
    import subprocess
    import sys

    run = make_run(tmp_path, "inertia", draws=200)
    s = json.loads((run / "summary.json").read_text())
    stats = summary_stats(np.zeros(10) + np.arange(10.0))
    s["nuisance"] = {k: stats for k in ("sigma_H", "H0[x]", "H0[y]", "H0[z]")}
    (run / "summary.json").write_text(json.dumps(s))
    code = ("import sys; from cassini_bayes.report import build_report; "
            f"build_report({str(run)!r}); "
            "print(sorted(m for m in ('arviz', 'xarray', 'pandas') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]", out.stderr
    html = (run / "report.html").read_text()
    assert "computed here with ArviZ" not in html
    # a run whose summary.json lacks a judged variable gets it from ArviZ, and says so
    del s["nuisance"]["H0[x]"]       # H0 judged (its other components are there)
    (run / "summary.json").write_text(json.dumps(s))
    assert "computed here with ArviZ for 1 components" in build_report(run).read_text()


def test_read_groups_matches_arviz(tmp_path):
    """The h5py reader gives ArviZ's arrays, dimensions and coordinates."""
    import arviz as az

    from cassini_bayes.report.rundata import read_groups

    run = make_run(tmp_path, "thrust", draws=50)
    ours = read_groups(run / "posterior.nc", skip=())
    idata = az.from_netcdf(str(run / "posterior.nc"))
    for group in idata.groups():
        ds = idata[group]
        assert set(ds.data_vars) == set(ours[group].vars), group
        for name, da in ds.data_vars.items():
            var = ours[group][name]
            assert var.dims == da.dims
            if da.dtype.kind in "fib":
                np.testing.assert_array_equal(var.values, da.values)
        for dim in ds.dims:
            if dim in ds.coords:
                assert ours[group].labels(dim) == [x.item() if hasattr(x, "item") else x
                                                   for x in ds.coords[dim].values], dim
