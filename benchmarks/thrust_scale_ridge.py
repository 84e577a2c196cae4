"""Does the robust thrust fit's likelihood keep the common-scale ridge flat?

Scaling the inertia, every thrust and every wheel's spin inertia by one factor ``s`` leaves the
measured rates and wheel speeds of a biasing event unchanged (Feldman & Lee Eq 17 is
homogeneous in them), so the data cannot tell ``s``: only the priors can (the wheels' spin
inertias, about 0.5 %). The fit samples the inertia and the thrusts and integrates the wheel
scales out as the linear nuisance ``ν``; this script puts its own log density
(``inference/thrust/model.py::log_density``) on the event flown without noise at its truth and
moves along the ridge (``F`` and ``I`` × ``s``, the wheel scales following in ``ν``), and
reports the curvature as an sd of ``s`` and the slope as the offset of the maximum:

* ``as fitted`` — the fit's density;
* ``wheel noise follows`` — the white wheel-rate noise of the left side, ``σ_ρ² Σ J_k² g_k
  g_kᵀ``, taken at ``s J_k`` (the fit holds it at the model file's ``J_k``);
* ``wheel momentum follows`` — and the wheel momentum of the rate-step corrections (``h_mid``,
  ``d_h``) at ``s J_k`` too;
* the same three with the wheel scales' prior sds × 30 (``no wheel prior``): what is left is
  what the likelihood itself says about ``s``.

A ridge the likelihood keeps flat gives, with the wheel prior, the prior's own sd along it
(``prior_sd``) and, without it, an sd set only by the inertia and thrust priors (tens of per
cent). No sampling.

    python benchmarks/thrust_scale_ridge.py --case biasing_espa_bus:thruster [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import sys
from functools import partial
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STEP = 0.005            # the ridge's step, a fraction of s; evaluated at ±STEP and ±2 STEP
WIDE = 30.0             # the wheel scales' prior sd multiplier of the ``no wheel prior`` rows
VARIANTS = {"as fitted": "", "wheel noise follows": "w", "wheel momentum follows": "wh"}


def ridge(case: str, variants: dict = VARIANTS, wides=(False, True)) -> dict:
    """The log density along the ridge for each variant (module docstring); ``prior_sd`` the
    wheel prior's sd of the common scale (``NuisanceLayout.scale_weights``)."""
    import jax
    import jax.numpy as jnp
    import numpy as np

    from cassini_bayes.inference.thrust.model import log_density
    from cassini_bayes.plan.thrust import (_site_names, _truth, _truth_vector,
                                           noise_free_problem, representable)
    from cassini_bayes.simulate import load_scenario

    name, mode = case.rsplit(":", 1)
    sc = load_scenario(name)
    _, problem, _ = noise_free_problem(sc, mode)
    names = _site_names(problem)
    truth = _truth(representable(sc, mode), problem, names)
    scaled = np.array([n.startswith("F") or n in ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")
                       for n in names])
    k = problem.n_f + problem.n_c + 3
    layout = problem.layout
    wheel_idx = np.arange(layout.size)[layout.wheel_block]      # c_0 … c_{S−1} and c_s

    def theta(factor: float) -> np.ndarray:
        x = _truth_vector(problem, names, np.where(scaled, truth * factor, truth))
        return np.r_[x[:k], 0.0, x[k:]]                          # the noise at the sensors'

    @partial(jax.jit, static_argnames="mods")
    def density(thetas, factors, kw, mods: str):
        def one(t, f):
            ev, rep = kw.events, {}
            if "w" in mods:
                rep["wheel_cov"] = ev.wheel_cov * f**2
            if "h" in mods:
                rep.update(h_mid=ev.h_mid * f, d_h=ev.d_h * f)
            return log_density(t, kw._replace(events=ev._replace(**rep)), problem.n_f,
                               problem.n_c, True)
        return jax.vmap(one)(thetas, factors)

    steps = STEP * np.array([-2.0, -1.0, 1.0, 2.0])
    factors = 1.0 + np.r_[0.0, steps]
    thetas = jnp.asarray(np.stack([theta(f) for f in factors]), float)
    rows = []
    for wide in wides:
        data = problem.data
        if wide:
            data = data._replace(nu_sd=data.nu_sd.at[wheel_idx].multiply(WIDE))
        for label, mods in variants.items():
            dens = np.asarray(density(thetas, jnp.asarray(factors), data, mods))
            lp = dens[1:] - dens[0]
            coef = np.polyfit(steps, lp, 2)              # lp ≈ −b d² + a d
            b, a = -coef[0], coef[1]
            rows.append({"variant": label + (", no wheel prior" if wide else ""),
                         "log_density": lp.tolist(),
                         "sd": float(1.0 / np.sqrt(2.0 * b)) if b > 0 else None,
                         "peak_offset": float(a / (2.0 * b)) if b > 0 else None})
            print(f"{case} {rows[-1]['variant']:40s} sd {rows[-1]['sd']}, peak at "
                  f"{rows[-1]['peak_offset']}", file=sys.stderr, flush=True)
    weights = layout.scale_weights
    prior_sd = float(np.sqrt(weights**2 @ np.asarray(layout.sd)[layout.wheel_block]**2))
    return {"case": case, "steps": steps.tolist(), "prior_sd": prior_sd, "rows": rows}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", nargs="+", required=True, help="SCENARIO:MODE ...")
    ap.add_argument("--json", type=Path)
    a = ap.parse_args(argv)
    if a.json:
        from _provenance import start
        start(a.json, vars(a), argv, replace=True)
    sys.path.insert(0, str(ROOT))
    import cassini_bayes
    from cassini_bayes.files import write_text

    cassini_bayes.setup_jax()
    out = {"step": STEP, "wide": WIDE, "cases": [ridge(c) for c in a.case]}
    if a.json:
        write_text(a.json, json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
