"""The RWA4 fit: NUTS on the prepared problem, the axis summary and the InferenceData
(:func:`fit_rwa4`), and the axis's sensitivity to the robust effects (:func:`axis_sensitivity`).
"""

from __future__ import annotations

from typing import Any, NamedTuple, Sequence

import jax
import numpy as np

from cassini_bayes.diagnostics import Diagnostics
from cassini_bayes.inference.idata import replace_groups
from cassini_bayes.inference.inertia import InertiaGaussian
from cassini_bayes.inference.rwa4.data import N_COORDS, Rwa4Problem, prepare_rwa4
from cassini_bayes.inference.rwa4.likelihood import DATA_KEYS, rows
from cassini_bayes.inference.rwa4.model import LOG_DENSITY, PHYSICAL, rwa4_model
from cassini_bayes.inference.rwa4.prior import sample_rwa4_prior
from cassini_bayes.inference.rwa4.window_means import no_nuisance
from cassini_bayes.inference.rwa4.windows import WHEEL, Window
from cassini_bayes.inference.sphere import direction_summary
from cassini_bayes.names import INERTIA_NAMES, U4_NAMES
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import Telemetry

__all__ = ["axis_sensitivity", "Rwa4Posterior", "fit_rwa4"]


def axis_sensitivity(problem: Rwa4Problem) -> dict[str, float]:
    """RMS shift of the axis (deg) each nuisance effect of prior size would cause in a model that
    leaves it out (Lee §4.1 made quantitative, as :mod:`~cassini_bayes.inference.sensitivity`).

    Linearised at the Laplace centre ``θ*``: the data ``d`` (:func:`rows`) gain ``D_e ν_e``
    from effect ``e``, which moves the idealised model's mode by
    ``Δθ = H⁻¹ Jᵀ C⁻¹ D_e ν_e`` (``H`` the idealised log density's negative Hessian, ``J`` =
    ∂d/∂θ, ``C`` the noise covariance); with ``ν_e ~ N(0, diag sd_e²)`` the axis shift ``U Δθ``
    (``U`` = ∂u/∂θ) has covariance ``U K diag(sd_e²) Kᵀ Uᵀ``, reported as √trace in degrees.
    """
    kw = problem.data
    centre = kw.centre
    ideal = kw._replace(**no_nuisance(len(problem.pairs), kw.n_s.shape[0]))
    physical = PHYSICAL[problem.chart]
    log_density = LOG_DENSITY[problem.chart]
    data = {k: getattr(kw, k) for k in DATA_KEYS}
    data.update({k: problem.nuisance[k] for k in ("nu_cols", "nu_cols_s", "nu_pi", "nu_pi_s",
                                                  "nu_sd", "nu_wheel")})

    def rows_at(theta):
        u, pi, _, _ = physical(theta, kw)
        return rows(u, pi, kw.log_noise_hat, **data)

    hess = -np.asarray(jax.hessian(lambda th: log_density(th, ideal))(centre))
    jac = np.asarray(jax.jacfwd(lambda th: rows_at(th)[0])(centre))
    jac_u = np.asarray(jax.jacfwd(lambda th: physical(th, kw)[0])(centre))
    _, noise, cols = (np.asarray(x) for x in rows_at(centre))        # cols: D diag(sd)
    gain = jac_u @ np.linalg.solve(hess, jac.T @ np.linalg.solve(np.asarray(noise), cols))
    out = {}
    for effect, sl in problem.layout.slices.items():
        k = gain[:, sl]
        if k.size:
            out[effect] = float(np.degrees(np.sqrt(np.sum(k * k))))
    return out


class Rwa4Posterior(NamedTuple):
    """Result of :func:`fit_rwa4`: InferenceData, diagnostics, problem and the direction summary
    (``{"mean": [x, y, z], "cone_deg": {"50": …, "90": …, "95": …}}``)."""

    idata: Any
    """ArviZ InferenceData (its groups are attributes ArviZ sets at run time)."""
    diagnostics: Diagnostics
    problem: Rwa4Problem
    direction: dict


def fit_rwa4(key, tel: Telemetry, spacecraft: Spacecraft, *, method: str = "rcs",
             pairs: Sequence[tuple[Window, Window]] | None = None, prior: str = "uniform",
             inertia: InertiaGaussian | None = None, settings=None,
             prior_draws: int = 500, wheel: str = WHEEL, robust: bool = True,
             wheel_errors: str = "per_wheel") -> Rwa4Posterior:
    """Posterior of a wheel's spin axis (unit vector, body axes; default RWA4) with the inertia
    sampled jointly.

    Parameters
    ----------
    key : jax.random key.
    tel : the calibration telemetry.
    spacecraft : wheels and the inertia prior (the solved wheel's axis is not used).
    method : ``"rcs"`` (Brown Eq 1) or ``"rwa"`` (Brown Eq 3).
    pairs : ``[(A, B), …]`` windows (s); detected from quiet periods when ``None``.
    prior : ``"uniform"`` on the sphere or ``"cone"`` (articulation cone).
    inertia : Gaussian inertia prior (e.g. :func:`~cassini_bayes.inference.thrust.
        inertia_from_run`); default the spacecraft model's knowledge requirements.
    settings : :class:`~cassini_bayes.inference.runner.SamplerSettings`.
    wheel : the wheel solved for (``u4_*`` is its axis), e.g. ``"RWA1"`` for Brown's flight
        test with RWA2 and RWA3 known.
    robust : the robust model (default: gyro bias and scale factor, wheel spin-inertia scales,
        the known wheels' axis tilts and a body-fixed torque integrated out; module docstring)
        or, ``False``, Brown's idealised model.
    wheel_errors : ``"per_wheel"`` (default: one spin-inertia scale per wheel, the solved one
        included) or ``"common"`` (one scale for every wheel).

    Returns
    -------
    Rwa4Posterior
        ``idata`` groups ``posterior`` (``u4_*``, ``Ixx … Iyz``, sampler coordinates ``w``),
        ``sample_stats``, ``prior``, ``observed_data`` (window means: ``h_known_mean`` N m s,
        ``rho4_attitude_mean`` rad/s, ``n_samples``), ``constant_data`` (baseline axis,
        windows, spin change, inertia prior).
    """
    from cassini_bayes.inference.progress import step
    from cassini_bayes.inference.runner import SamplerSettings, diagnostics, run_nuts

    settings = settings or SamplerSettings()
    with step("preparing: windows, Laplace approximation (mode and curvature)"):
        problem = prepare_rwa4(tel, spacecraft, method=method, pairs=pairs, prior=prior,
                               inertia=inertia, wheel=wheel, robust=robust,
                               wheel_errors=wheel_errors)
    coords = {"w_dim": np.arange(N_COORDS)}
    dims = {"w": ["w_dim"]}
    idata = run_nuts(key, rwa4_model(problem.chart), model_kwargs={"data": problem.data},
                     settings=settings, coords=coords, dims=dims,
                     prior=lambda k, n: sample_rwa4_prior(k, problem, n), prior_draws=prior_draws)
    post = idata.posterior
    draws = np.stack([post[n].values.ravel() for n in U4_NAMES], -1)
    direction = direction_summary(draws)
    replace_groups(idata, _data_groups(problem))
    names = list(U4_NAMES) + list(INERTIA_NAMES)
    return Rwa4Posterior(idata, diagnostics(idata, names), problem, direction)


def _data_groups(problem: Rwa4Problem) -> dict:
    """The ``observed_data`` (window means) and ``constant_data`` groups of :func:`fit_rwa4`."""
    import xarray as xr

    kw = problem.data
    observed = xr.Dataset(
        {"h_known_mean": (("window", "axis"), np.asarray(kw.k_h), {"units": "N m s",
                          "description": "window mean of A(q)ᵀ h_known (inertial)"}),
         "rho4_attitude_mean": (("window", "axis", "axis2"), np.asarray(kw.r_u),
                                {"units": "rad/s", "description": "window mean of ρ4 A(q)ᵀ"}),
         "n_samples": ("window", np.asarray(kw.n_w))},
        coords={"window": np.arange(np.asarray(kw.n_w).shape[0]), "axis": ["x", "y", "z"],
                "axis2": ["x", "y", "z"]}, attrs={"source": problem.source})
    win = np.array([[a[0], a[1], b[0], b[1]] for a, b in problem.pairs], float)
    constant = xr.Dataset(
        {"baseline": ("axis", problem.baseline),
         "windows": (("pair", "edge"), win, {"units": "s"}),
         "spin_change_rpm": ("pair", problem.spin_change_rpm),
         "prior_inertia_mean": ("param", np.asarray(problem.inertia.mean)),
         "prior_inertia_sd": ("param", np.sqrt(np.diag(np.asarray(problem.inertia.cov))))},
        coords={"axis": ["x", "y", "z"], "pair": np.arange(win.shape[0]),
                "edge": ["a0", "a1", "b0", "b1"], "param": list(INERTIA_NAMES)})
    return {"observed_data": observed, "constant_data": constant}
