"""Benchmark: inertia posterior, NumPyro (``fit_inertia``) against a plain PyMC model.

One process, one data set: the ``slew_2000_03_15`` scenario simulated once (0.25 Hz for 4 h, 3600
samples), its ``[prior]`` spacecraft model as the prior. Both samplers target the same posterior:

* the likelihood is the one :func:`cassini_bayes.inference.inertia.prepare_inertia` builds — the
  Gaussian momentum residual with the empirical-Bayes noise covariance ``s² B̂_t``, written as the
  per-file sufficient statistics ``Σ_t e_tᵀ B̂_t⁻¹ e_t = δᵀFδ + 2gᵀδ + Q*`` (``δ = θ − θ*``,
  ``θ = (Ixx … Iyz, H_0, T_N)``) plus ``−N_obs log s``;
* the prior: ``(Ixx … Iyz) ~ Normal(predicted, knowledge sd)`` truncated to physical tensors,
  ``H_0 ~ N(0, 100 N m s)``, ``T_N ~ N(0, 15 µN m)`` per axis, ``log s ~ N(0, 1)``.

NumPyro samples this through ``fit_inertia`` (whitened log-Cholesky coordinates, dense mass
matrix). The PyMC model is what a practitioner would write: scalar ``pm.Normal`` priors on the
six entries in kg m², ``H0``/``T_N`` in SI units, ``log s``, the truncation as a ``pm.Potential``
that is ``−inf`` unless ``Σ = ½ tr(I) 1 − I`` is positive definite (Sylvester's criterion: the
same set as the Cholesky map), the likelihood as a ``pm.Potential``, and PyMC's default NUTS
(``jitter+adapt_diag``, target_accept 0.8, pytensor C backend). The truncation constant differs
by a constant only, so the two posteriors are identical.

Each sampler runs twice (4 chains × 1000 warmup + 1000 draws): the first run includes
compilation (XLA / pytensor C; pytensor also caches its C modules on disk across processes), the
second does not. ESS and R-hat come from ArviZ for both. Not a test: nothing is asserted.

    python benchmarks/bench_inertia_pymc.py [--chains 4] [--draws 1000] [--warmup 1000] [--cores 2]
        [--pymc-param physical|standardised] [--pymc-warmup N] [--pymc-draws N]

PyMC's default NUTS hits its tree-depth limit on this posterior (tiny, strongly correlated
posterior scales: docs/design.md §7.4), about 0.15 s per iteration on 2 shared cores,
so 4 × 2000 iterations take tens of minutes: ``--pymc-warmup/--pymc-draws`` shorten
its runs so the comparison finishes; ESS/s stays comparable (ESS per second of sampling).
"""

from __future__ import annotations

import argparse
import os
import time


def _numpyro_runs(args, tel, prior_sc):
    """Two ``fit_inertia`` runs and one sampler-only run; times (s), InferenceData, problem."""
    import jax

    from cassini_bayes.inference.inertia import fit_inertia, inertia_model, prepare_inertia
    from cassini_bayes.inference.runner import SamplerSettings, run_nuts

    s = SamplerSettings(chains=args.chains, warmup=args.warmup, draws=args.draws)
    t0 = time.perf_counter()
    fit_inertia(jax.random.key(10), [tel], prior_sc, robust=False, settings=s)
    t_first = time.perf_counter() - t0
    t0 = time.perf_counter()
    res = fit_inertia(jax.random.key(11), [tel], prior_sc, robust=False, settings=s)
    t_second = time.perf_counter() - t0
    problem = prepare_inertia([tel], prior_sc)
    t0 = time.perf_counter()
    idata_s = run_nuts(jax.random.key(12), inertia_model(True, False),
                       model_kwargs=problem.model_kwargs, settings=s, prior_draws=0)
    t_sampler = time.perf_counter() - t0
    return dict(first=t_first, second=t_second, sampler=t_sampler, idata=res.idata,
                idata_sampler=idata_s, problem=problem)


def pymc_model(problem, param: str = "standardised"):
    """The plain PyMC model of the same posterior (one telemetry file, torque on, idealised).

    ``param="physical"``: ``Ixx … Iyz``, ``H0``, ``T_N`` are the sampled variables in kg m²,
    N m s, N m. ``param="standardised"`` (PyMC's usual non-centred idiom): each is
    ``prior mean + prior sd × z`` with ``z ~ N(0, 1)`` sampled, the entries kept as
    ``pm.Deterministic``. Same prior, same likelihood.
    """
    import numpy as np
    import pymc as pm
    import pytensor.tensor as pt

    from cassini_bayes.inference.inertia import (H0_PRIOR_SD_NMS, NOISE_PRIOR_LOG_SD,
                                                 TORQUE_PRIOR_SD_NM)
    from cassini_bayes.physics.momentum import INERTIA_NAMES

    kw = problem.model_kwargs
    fmat = np.asarray(kw["fmat"])[0]          # (12, 12), θ = (π, H_0, T_N)
    gvec = np.asarray(kw["gvec"])[0]
    q_star = float(np.asarray(kw["q_star"])[0])
    n_obs = float(np.asarray(kw["n_obs"])[0])
    theta_star = np.asarray(kw["theta_star"])
    if theta_star.size != 12:
        raise ValueError("the PyMC benchmark model is written for one file with torque")
    mean, sd = problem.prior.mean, problem.prior.sd

    with pm.Model() as model:
        if param == "physical":
            ent = [pm.Normal(n, mu=mean[i], sigma=sd[i]) for i, n in enumerate(INERTIA_NAMES)]
            h0 = pm.Normal("H0", mu=0.0, sigma=H0_PRIOR_SD_NMS, shape=3)
            tq = pm.Normal("T_N", mu=0.0, sigma=TORQUE_PRIOR_SD_NM, shape=3)
        elif param == "standardised":
            z_i = pm.Normal("z_inertia", 0.0, 1.0, shape=6)
            ent = [pm.Deterministic(n, mean[i] + sd[i] * z_i[i])
                   for i, n in enumerate(INERTIA_NAMES)]
            h0 = pm.Deterministic("H0", H0_PRIOR_SD_NMS * pm.Normal("z_H0", 0.0, 1.0, shape=3))
            tq = pm.Deterministic("T_N", TORQUE_PRIOR_SD_NM * pm.Normal("z_T_N", 0.0, 1.0,
                                                                        shape=3))
        else:
            raise ValueError(f"param must be 'physical' or 'standardised', not {param!r}")
        log_s = pm.Normal("log_noise_scale", mu=0.0, sigma=NOISE_PRIOR_LOG_SD)
        ixx, iyy, izz, ixy, ixz, iyz = ent
        # Physical inertia: Σ = ½ tr(I) 1 − I positive definite (leading minors > 0).
        half_tr = 0.5 * (ixx + iyy + izz)
        s00, s11, s22 = half_tr - ixx, half_tr - iyy, half_tr - izz
        s01, s02, s12 = -ixy, -ixz, -iyz
        m2 = s00 * s11 - s01**2
        det = (s00 * (s11 * s22 - s12**2) - s01 * (s01 * s22 - s12 * s02)
               + s02 * (s01 * s12 - s11 * s02))
        physical = pt.and_(pt.and_(pt.gt(s00, 0), pt.gt(m2, 0)), pt.gt(det, 0))
        pm.Potential("physical", pt.switch(physical, 0.0, -np.inf))
        delta = pt.concatenate([pt.stack(ent), h0, tq]) - theta_star
        quad = pt.dot(delta, pt.dot(fmat, delta)) + 2.0 * pt.dot(gvec, delta) + q_star
        pm.Potential("loglik", -0.5 * quad * pt.exp(-2.0 * log_s) - n_obs * log_s)
    return model


def _pymc_runs(args, problem):
    import pymc as pm

    draws = args.pymc_draws or args.draws
    tune = args.pymc_warmup or args.warmup
    common = dict(draws=draws, tune=tune, chains=args.chains, cores=args.cores,
                  progressbar=False, compute_convergence_checks=False,
                  mp_ctx="forkserver" if args.cores > 1 else None)
    t0 = time.perf_counter()
    model = pymc_model(problem, args.pymc_param)
    with model:
        pm.sample(random_seed=20, **common)
    t_first = time.perf_counter() - t0
    t0 = time.perf_counter()
    with model:
        idata = pm.sample(random_seed=21, **common)
    t_second = time.perf_counter() - t0
    return dict(first=t_first, second=t_second,
                sampler=float(idata.posterior.attrs.get("sampling_time", float("nan"))),
                idata=idata)


def _diag(idata):
    import arviz as az
    import numpy as np

    from cassini_bayes.physics.momentum import INERTIA_NAMES

    ess = az.ess(idata, var_names=list(INERTIA_NAMES), method="bulk")
    rhat = az.rhat(idata, var_names=list(INERTIA_NAMES))
    div = int(np.sum(idata.sample_stats["diverging"].values))
    return (min(float(ess[n]) for n in INERTIA_NAMES), max(float(rhat[n]) for n in INERTIA_NAMES),
            div, {n: float(idata.posterior[n].mean()) for n in INERTIA_NAMES},
            {n: float(idata.posterior[n].std()) for n in INERTIA_NAMES})


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--warmup", type=int, default=1000)
    ap.add_argument("--draws", type=int, default=1000)
    ap.add_argument("--cores", type=int, default=min(2, os.cpu_count() or 1),
                    help="PyMC worker processes")
    ap.add_argument("--pymc-param", choices=("physical", "standardised"), default="physical",
                    help="PyMC parameterisation (see pymc_model)")
    ap.add_argument("--pymc-warmup", type=int, default=None,
                    help="PyMC tuning iterations (default: --warmup)")
    ap.add_argument("--pymc-draws", type=int, default=None,
                    help="PyMC draws per chain (default: --draws)")
    args = ap.parse_args(argv)

    import jax

    jax.config.update("jax_num_cpu_devices", os.cpu_count() or 1)
    import numpy as np
    import pymc as pm

    from cassini_bayes.physics.momentum import INERTIA_NAMES, inertia_vector
    from cassini_bayes.simulate import load_scenario, simulate

    scenario = load_scenario("slew_2000_03_15")
    tel = simulate(jax.random.key(0), scenario).telemetry
    print(f"slew_2000_03_15: {tel.n} samples; {args.chains} chains × ({args.warmup} warmup + "
          f"{args.draws} draws); {os.cpu_count()} CPUs, {jax.local_device_count()} JAX host "
          f"devices; PyMC {pm.__version__} cores={args.cores}, {args.pymc_param} parameters, "
          f"{args.pymc_warmup or args.warmup} tune + {args.pymc_draws or args.draws} draws")

    npy = _numpyro_runs(args, tel, scenario.prior)
    pmc = _pymc_runs(args, npy["problem"])

    rows = []
    for name, r, idata in (("NumPyro fit_inertia", npy, npy["idata"]),
                           ("PyMC default NUTS", pmc, pmc["idata"])):
        ess, rhat, div, mean, sd = _diag(idata)
        rows.append(dict(name=name, ess=ess, rhat=rhat, div=div, mean=mean, sd=sd, **{
            k: r[k] for k in ("first", "second", "sampler")}))
    ess_s, rhat_s, div_s, _, _ = _diag(npy["idata_sampler"])

    print()
    print(f"{'':22s}{'1st run s':>10s}{'2nd run s':>10s}{'sampler s':>10s}{'min ESS':>9s}"
          f"{'ESS/s 2nd':>10s}{'ESS/s smp':>10s}{'max R-hat':>10s}{'div':>5s}")
    for r in rows:
        print(f"{r['name']:22s}{r['first']:10.2f}{r['second']:10.2f}{r['sampler']:10.2f}"
              f"{r['ess']:9.0f}{r['ess'] / r['second']:10.0f}{r['ess'] / r['sampler']:10.0f}"
              f"{r['rhat']:10.4f}{r['div']:5d}")
    n, p = rows
    print(f"NumPyro sampler-only run (run_nuts, 3rd run): min ESS {ess_s:.0f}, max R-hat "
          f"{rhat_s:.4f}, divergences {div_s}")
    ratio_wall = (n["ess"] / n["second"]) / (p["ess"] / p["second"])
    ratio_smp = (n["ess"] / n["sampler"]) / (p["ess"] / p["sampler"])
    print(f"ratio NumPyro/PyMC ESS/s: 2nd-run wall {ratio_wall:.1f}×, sampler only {ratio_smp:.1f}×")
    print("  2nd run: NumPyro = fit_inertia end to end (data prep, sampling, prior draws, residuals,"
          " diagnostics); PyMC = pm.sample (function compilation from the warm C cache, sampling)")
    print("  sampler: NumPyro = run_nuts alone (compiled); PyMC = its 'sampling_time' attribute")
    print()
    print(f"{'posterior mean ± sd':22s}" + "".join(f"{k:>18s}" for k in INERTIA_NAMES))
    for r in rows:
        print(f"{r['name']:22s}" + "".join(f"{r['mean'][k]:10.1f} ±{r['sd'][k]:6.2f}"
                                           for k in INERTIA_NAMES))
    truth = np.asarray(inertia_vector(scenario.truth.inertia))
    print(f"{'truth':22s}" + "".join(f"{v:18.1f}" for v in truth))

if __name__ == "__main__":
    main()
