"""The plain inertia model a user would write, in PyMC, nutpie and NumPyro (benchmark helper).

Run as a child process by ``benchmarks/bench_samplers.py``::

    python benchmarks/plain_inertia.py SYSTEM DATA.npz OUT.npz [--chains 4] [--warmup 1000]
        [--draws 1000] [--seed 0] [--noise plain|package]

``SYSTEM`` is ``pymc``, ``nutpie`` or ``numpyro``. Each process imports only NumPy and its own
framework (never ``cassini_bayes``), builds the model, samples once, and writes the draws of the
six inertia entries and its own timings to ``OUT.npz``.

The model (Feldman & Lee 2006 Eq 3, the momentum regression with ``H_N`` unknown): in inertial axes
the total angular momentum ``A(q_t)ᵀ (I ω_t + H_w,t)`` (N m s) is ``H_0 + T_N (t − t_0)``, up to
Gaussian noise. With the wheel momentum on the data side, per sample and axis::

    A_tᵀ H_w,t = H_0 + T_N (t − t_0) − A_tᵀ I ω_t + ε,   ε ~ Normal(0, σ²)

a linear regression in ``π = (Ixx, Iyy, Izz, Ixy, Ixz, Iyz)`` (kg m²), ``H_0`` (N m s) and ``T_N``
(N m). Priors — the ones ``cassini-bayes fit inertia`` states: ``π ~ Normal(predicted, knowledge
sd)`` from the spacecraft model (``DATA.npz``: ``prior_mean``, ``prior_sd``), ``H_0 ~ Normal(0, 100
N m s)``, ``T_N ~ Normal(0, 15 µN m)`` per axis, sampled in µN m (in N m its scale, 1e-5, is
10⁸ times smaller than the inertia's and the samplers' initial points land ~10⁵ prior sd out: PyMC
and NumPyro then did not converge in 300 warm-up steps); the noise, which the package models per
sensor, is one ``σ ~ HalfNormal(1 N m s)`` here (a user's first model). The package's prior also
truncates ``π`` to physical tensors; the posterior lies far inside, so that changes nothing here.

``--noise package`` keeps everything else and replaces the single σ by the noise model of
``cassini-bayes fit inertia --idealised``: the body residual ``e_t = I ω_t + H_w,t − A_t H_N,t``
of each sample has covariance ``s² B̂_t``, ``B̂_t`` (errors in variables of gyro, wheel-rate and
attitude noise, fixed by the package's empirical-Bayes step) given in ``DATA.npz`` as its inverse
Cholesky factor ``W_t``, and ``log s ~ Normal(0, 1)``. The same posterior as the package's, written
plainly: the check that the package's speed is not bought with a different answer.

Samplers at their defaults: PyMC ``pm.sample`` (NUTS, ``jitter+adapt_diag``, target acceptance
0.8; chains in ``cores = os.cpu_count()`` processes — PyMC's own default takes half the CPUs,
one on a 2-core machine, and would run the chains one after the other); nutpie
``compile_pymc_model`` + ``sample`` (numba backend, chains in threads); NumPyro
``MCMC(NUTS(model))`` (diagonal mass matrix, target 0.8, ``init_to_uniform``), chains in
parallel on four host devices and 64-bit floats (a careful user's two lines: without them the
chains run one after the other in float32).

Timings written: ``t_import`` (process start of the script to the framework imported),
``t_fit`` (the sampling call, including whatever it compiles), ``t_sample`` (the sampling loop,
compilation excluded: PyMC's own ``sampling_time``; nutpie's ``sample`` after
``compile_pymc_model``; NumPyro's ``run`` minus the JAX trace, lower and compile durations
recorded by ``jax.monitoring`` during it), ``t_compile`` where it is a step of its own.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

T0 = time.perf_counter()

import numpy as np  # noqa: E402

NAMES = ("Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz")
H0_SD_NMS = 100.0
TORQUE_SD_UNM = 15.0          # µN m: the torque is sampled in the unit of its prior
SIGMA_SCALE_NMS = 1.0


def load(path: str) -> dict:
    """``a`` (n, 3, 3) DCMs inertial → body, ``omega`` (n, 3) rad/s, ``h_wheels`` (n, 3) N m s
    body, ``dt`` (n,) s, ``prior_mean``/``prior_sd`` (6,) kg m²; and ``y = A_tᵀ H_w,t``."""
    with np.load(path) as z:
        d = {k: np.asarray(z[k], dtype=np.float64) for k in z.files}
    d["y"] = np.einsum("nji,nj->ni", d["a"], d["h_wheels"])
    if "whiten" in d:
        d["wy"] = -np.einsum("nij,nj->ni", d["whiten"], d["h_wheels"])  # −W_t H_w,t
    return d


def _pymc_parameters(d: dict):
    """The shared priors inside a ``pm.Model`` context: the inertia matrix (kg m²), ``H_0``
    (N m s) and ``T_N`` (N m)."""
    import pymc as pm
    import pytensor.tensor as pt

    xx, yy, zz, xy, xz, yz = (pm.Normal(n, mu=m, sigma=s)
                              for n, m, s in zip(NAMES, d["prior_mean"], d["prior_sd"]))
    h0 = pm.Normal("H0", 0.0, H0_SD_NMS, shape=3)
    t_n = 1e-6 * pm.Normal("T_N_uNm", 0.0, TORQUE_SD_UNM, shape=3)
    inertia = pt.stack([pt.stack([xx, xy, xz]), pt.stack([xy, yy, yz]), pt.stack([xz, yz, zz])])
    return inertia, h0, t_n


def pymc_model(d: dict):
    """The plain PyMC model (module docstring)."""
    import pymc as pm
    import pytensor.tensor as pt

    a, omega, dt = (pt.as_tensor(d[k]) for k in ("a", "omega", "dt"))
    with pm.Model() as model:
        inertia, h0, t_n = _pymc_parameters(d)
        sigma = pm.HalfNormal("sigma", SIGMA_SCALE_NMS)
        body = pt.dot(omega, inertia)                               # I ω_t, (n, 3)
        inertial = (a * body[:, :, None]).sum(axis=1)               # A_tᵀ I ω_t
        mu = h0[None, :] + dt[:, None] * t_n[None, :] - inertial
        pm.Normal("h", mu=mu, sigma=sigma, observed=d["y"])
    return model


def pymc_model_package_noise(d: dict):
    """The same regression with the package's noise model (``--noise package``): per sample, the
    body residual ``e_t = I ω_t + H_w,t − A_t (H_0 + T_N (t − t_0))`` whitened by ``W_t`` is
    ``Normal(0, s²)``, ``log s ~ Normal(0, 1)``."""
    import pymc as pm
    import pytensor.tensor as pt

    a, omega, dt, w = (pt.as_tensor(d[k]) for k in ("a", "omega", "dt", "whiten"))
    with pm.Model() as model:
        inertia, h0, t_n = _pymc_parameters(d)
        scale = pm.LogNormal("s", 0.0, 1.0)
        h_n = h0[None, :] + dt[:, None] * t_n[None, :]              # inertial, (n, 3)
        part = pt.dot(omega, inertia) - (a * h_n[:, None, :]).sum(axis=2)  # I ω_t − A_t H_N
        pm.Normal("e", mu=(w * part[:, None, :]).sum(axis=2), sigma=scale,
                  observed=d["wy"])
    return model


def _numpyro_parameters(d: dict):
    """The shared priors inside a NumPyro model: the inertia matrix (kg m²), ``H_0`` (N m s)
    and ``T_N`` (N m)."""
    import jax.numpy as jnp
    import numpyro
    import numpyro.distributions as dist

    xx, yy, zz, xy, xz, yz = (numpyro.sample(n, dist.Normal(m, s))
                              for n, m, s in zip(NAMES, d["prior_mean"], d["prior_sd"]))
    h0 = numpyro.sample("H0", dist.Normal(0.0, H0_SD_NMS).expand([3]).to_event(1))
    t_n = 1e-6 * numpyro.sample("T_N_uNm",
                                dist.Normal(0.0, TORQUE_SD_UNM).expand([3]).to_event(1))
    inertia = jnp.stack([jnp.stack([xx, xy, xz]), jnp.stack([xy, yy, yz]),
                         jnp.stack([xz, yz, zz])])
    return inertia, h0, t_n


def numpyro_model(d: dict):
    """The plain NumPyro model (module docstring)."""
    import jax.numpy as jnp
    import numpyro
    import numpyro.distributions as dist

    a, omega, dt, y = (jnp.asarray(d[k]) for k in ("a", "omega", "dt", "y"))

    def model():
        inertia, h0, t_n = _numpyro_parameters(d)
        sigma = numpyro.sample("sigma", dist.HalfNormal(SIGMA_SCALE_NMS))
        inertial = jnp.einsum("nji,nj->ni", a, omega @ inertia)
        mu = h0 + dt[:, None] * t_n - inertial
        numpyro.sample("h", dist.Normal(mu, sigma), obs=y)

    return model


def numpyro_model_package_noise(d: dict):
    """:func:`pymc_model_package_noise` in NumPyro."""
    import jax.numpy as jnp
    import numpyro
    import numpyro.distributions as dist

    a, omega, dt, w, wy = (jnp.asarray(d[k]) for k in ("a", "omega", "dt", "whiten", "wy"))

    def model():
        inertia, h0, t_n = _numpyro_parameters(d)
        scale = numpyro.sample("s", dist.LogNormal(0.0, 1.0))
        part = omega @ inertia - jnp.einsum("nij,nj->ni", a, h0 + dt[:, None] * t_n)
        numpyro.sample("e", dist.Normal(jnp.einsum("nij,nj->ni", w, part), scale), obs=wy)

    return model


def run_pymc(d, args) -> dict:
    import pymc as pm

    t = time.perf_counter()
    model = (pymc_model_package_noise if args.noise == "package" else pymc_model)(d)
    with model:
        idata = pm.sample(draws=args.draws, tune=args.warmup, chains=args.chains,
                          cores=min(args.chains, os.cpu_count() or 1), random_seed=args.seed,
                          progressbar=False, compute_convergence_checks=False)
    t_fit = time.perf_counter() - t
    return {"idata": idata, "t_fit": t_fit,
            "t_sample": float(idata.posterior.attrs["sampling_time"])}


def run_nutpie(d, args) -> dict:
    import nutpie

    t = time.perf_counter()
    build = pymc_model_package_noise if args.noise == "package" else pymc_model
    compiled = nutpie.compile_pymc_model(build(d))
    t_compile = time.perf_counter() - t
    t1 = time.perf_counter()
    idata = nutpie.sample(compiled, draws=args.draws, tune=args.warmup, chains=args.chains,
                          seed=args.seed, progress_bar=False)
    t_sample = time.perf_counter() - t1
    return {"idata": idata, "t_fit": time.perf_counter() - t, "t_sample": t_sample,
            "t_compile": t_compile}


def run_numpyro(d, args) -> dict:
    import jax
    from jax import monitoring
    from numpyro.infer import MCMC, NUTS

    compile_events = ("/jax/core/compile/backend_compile_duration",
                      "/jax/core/compile/jaxpr_trace_duration",
                      "/jax/core/compile/jaxpr_to_mlir_module_duration")
    spent = []
    monitoring.register_event_duration_secs_listener(
        lambda event, secs, **kw: spent.append(secs) if event in compile_events else None)
    t = time.perf_counter()
    build = numpyro_model_package_noise if args.noise == "package" else numpyro_model
    mcmc = MCMC(NUTS(build(d)), num_warmup=args.warmup, num_samples=args.draws,
                num_chains=args.chains, progress_bar=False)
    mcmc.run(jax.random.key(args.seed))
    samples = jax.block_until_ready(mcmc.get_samples(group_by_chain=True))
    t_fit = time.perf_counter() - t
    import arviz as az

    idata = az.from_dict(posterior={k: np.asarray(v) for k, v in samples.items()})
    return {"idata": idata, "t_fit": t_fit, "t_sample": t_fit - sum(spent),
            "t_compile": sum(spent)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("system", choices=("pymc", "nutpie", "numpyro"))
    ap.add_argument("data")
    ap.add_argument("out")
    ap.add_argument("--chains", type=int, default=4)
    ap.add_argument("--warmup", type=int, default=1000)
    ap.add_argument("--draws", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--noise", choices=("plain", "package"), default="plain",
                    help="plain: one σ on the inertial residual; package: the idealised fit's "
                         "per-sample noise covariance (DATA.npz 'whiten')")
    args = ap.parse_args(argv)
    if args.system == "numpyro":
        import numpyro

        numpyro.set_host_device_count(args.chains)
        numpyro.enable_x64()
        run = run_numpyro
    elif args.system == "pymc":
        import pymc  # noqa: F401

        run = run_pymc
    else:
        import nutpie  # noqa: F401
        import pymc  # noqa: F401

        run = run_nutpie
    t_import = time.perf_counter() - T0
    res = run(load(args.data), args)
    post = res.pop("idata").posterior
    draws = np.stack([np.asarray(post[n].values, dtype=float) for n in NAMES])  # (6, C, D)
    np.savez(args.out, draws=draws, names=np.asarray(NAMES), t_import=t_import,
             **{k: float(v) for k, v in res.items()})
    return 0


if __name__ == "__main__":
    from cassini_bayes import setup_jax

    setup_jax()  # 64-bit, the compilation cache, CPU devices: this script uses modules directly
    os.environ.setdefault("MPLBACKEND", "Agg")
    sys.exit(main())
