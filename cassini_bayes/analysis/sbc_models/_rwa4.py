"""The ``rwa4`` SBC adapter: a wheel's spin axis by Brown's RCS or RWA method."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes._paths import SCENARIOS_DIR
from cassini_bayes.analysis.sbc_models._common import (
    check_options,
    posterior_draws,
    quiet,
    sampler_settings,
    scenario_of,
    stacked,
)
from cassini_bayes.analysis.sbc_models._contract import ModelSpec, SbcFit, SbcModel, register
from cassini_bayes.errors import InputError

__all__ = ["RWA4_SCENARIO", "robust_rwa4_truth", "draw_rwa4_truth"]

# default scenario: Brown's RCS-method calibration cut to 450 s (the file's header says more)
RWA4_SCENARIO = SCENARIOS_DIR / "sbc" / "sbc_rwa4_rcs.toml"

_RWA4_KEYS = {"num_warmup", "num_draws", "num_chains", "thin", "prior", "rank_inertia",
              "rwa4_inertia_factor", "robust", "wheel", "method"}


def robust_rwa4_truth(key, spacecraft, wheel: str, known) -> dict[str, Any]:
    """One draw of the robust spin-axis model's nuisance vector ``ν`` from its own prior, split
    into named effects (:func:`~cassini_bayes.inference.nuisance.split_nuisance`).

    The layout is the one :func:`~cassini_bayes.inference.rwa4.prepare_rwa4` builds for one file
    with the ``known`` running wheels and the solved ``wheel`` (each with its own spin-inertia
    scale, tilts for the known ones, body-fixed and inertial torques and the inertial torque's
    rate); its prior is independent zero-mean Normal with sds ``layout.sd``, so the draw is
    ``layout.sd · N(0, 1)``. Returns the sites of :func:`split_nuisance` of the one file (the
    file axis dropped) plus ``scale_wheels`` and ``tilt_wheels``, the wheel names of
    ``wheel_scale`` and ``wheel_tilt``.
    """
    import numpy as np

    from cassini_bayes.inference.nuisance import nuisance_layout, split_nuisance

    known = tuple(known)
    layout = nuisance_layout(spacecraft, 1, known, wheel_errors="per_wheel",
                             scaled=known + (wheel,), inertial_torque=True, torque_rate=True)
    nu = layout.sd * np.asarray(jax.random.normal(key, (layout.size,)))
    out = split_nuisance(nu, layout)
    for site in ("gyro_bias", "T_body", "T_inertial", "T_N_rate"):
        out[site] = np.asarray(out[site])[0]                    # the one file
    out["scale_wheels"], out["tilt_wheels"] = layout.scale_wheels, layout.wheels
    return out


def draw_rwa4_truth(key, mean, sd, cone):
    """One draw of ``u4`` (3,) and ``π`` (6,) from the RWA4 fit's prior (NumPy, by rejection).

    Same distribution as :func:`cassini_bayes.inference.rwa4.sample_rwa4_prior`: ``u4`` uniform
    on the sphere (a normalised standard normal), times the articulation-cone factor of
    ``cone`` (the prior model's :class:`~cassini_bayes.spacecraft.WheelCone`; ``None``: none)
    by rejection; ``π`` from ``Normal(mean, diag sd²)`` times the model's smooth
    physical factor, by the model's own sampler
    (:func:`~cassini_bayes.inference.rwa4.sample_inertia_prior`).
    """
    import numpy as np

    from cassini_bayes.inference.rwa4 import cone_log_factor, sample_inertia_prior

    k_u, k_i = jax.random.split(key)
    for r in range(10_000):
        k_x, k_a = jax.random.split(jax.random.fold_in(k_u, r))
        x = np.asarray(jax.random.normal(k_x, (3,)))
        u = x / np.linalg.norm(x)
        if cone is None or float(jax.random.uniform(k_a)) < np.exp(cone_log_factor(u, cone)):
            break
    return u, sample_inertia_prior(k_i, mean, np.diag(np.asarray(sd, float) ** 2), 1)[0]


def _rwa4_options(spec: ModelSpec, scenario) -> dict[str, Any]:
    """The adapter's options: the defaults overridden by ``spec``'s, checked against the fit's
    priors and methods and the scenario (the solved wheel must exist and run; the cone prior
    needs the model's articulation cone)."""
    from cassini_bayes.inference.rwa4 import METHODS, PRIORS

    opts = {"num_warmup": 300, "num_draws": 300, "num_chains": 2, "thin": 3,
            "prior": "uniform", "rank_inertia": True, "rwa4_inertia_factor": 1.0,
            "robust": False, "wheel": "RWA4", "method": "rcs", **dict(spec.options)}
    check_options("rwa4", opts, _RWA4_KEYS)
    if opts["prior"] not in PRIORS:
        raise InputError(f"rwa4 SBC option prior={opts['prior']!r}: choose one of "
                         f"{', '.join(PRIORS)}")
    if opts["method"] not in METHODS:
        raise InputError(f"rwa4 SBC option method={opts['method']!r}: choose one of "
                         f"{', '.join(METHODS)}")
    wheel = str(opts["wheel"])
    if wheel not in scenario.wheel_names:
        raise InputError(f"rwa4 SBC option wheel={wheel!r}: the scenario has no such wheel "
                         f"(its wheels: {', '.join(scenario.wheel_names)})",
                         path=spec.scenario_source)
    if not scenario.wheels_on[scenario.wheel_names.index(wheel)]:
        raise InputError(f"the rwa4 SBC scenario must run {wheel} ([initial] wheels_on)",
                         path=spec.scenario_source)
    if opts["prior"] == "cone" and scenario.prior.wheel(wheel).cone is None:
        raise InputError(f"rwa4 SBC option prior='cone': the prior model gives {wheel} no "
                         "articulation cone ('cone_axis', 'cone_deg')", path=spec.scenario_source)
    return opts


@dataclass(frozen=True, eq=False)
class _Rwa4Replicates:
    """Truth, simulation and fit of the rwa4 adapter's replicates (``opts`` checked by
    :func:`_rwa4_options`)."""

    scenario: Any
    opts: dict[str, Any]
    settings: Any

    @property
    def wheel(self) -> str:
        return str(self.opts["wheel"])

    @property
    def robust(self) -> bool:
        return bool(self.opts["robust"])

    @cached_property
    def k4(self) -> int:
        """The solved wheel's index in the scenario."""
        return self.scenario.wheel_names.index(self.wheel)

    @cached_property
    def known(self) -> tuple[str, ...]:
        """The other running wheels, in the scenario's order."""
        return tuple(n for n, on in zip(self.scenario.wheel_names, self.scenario.wheels_on)
                     if on and n != self.wheel)

    @cached_property
    def names(self) -> tuple[str, ...]:
        """The ranked scalars: ``u4_x u4_y u4_z`` and, with ``rank_inertia``, ``Ixx … Iyz``."""
        from cassini_bayes.inference.inertia import INERTIA_NAMES
        from cassini_bayes.inference.rwa4 import U4_NAMES

        return tuple(U4_NAMES) + (tuple(INERTIA_NAMES) if self.opts["rank_inertia"] else ())

    @cached_property
    def base(self):
        """The scenario's truth and noise."""
        from cassini_bayes.simulate.run import noise_params, truth_params

        return truth_params(self.scenario), noise_params(self.scenario)

    @cached_property
    def inertia_prior(self):
        """The inertia prior of the scenario's ``[prior]`` model."""
        from cassini_bayes.inference.inertia import inertia_prior

        return inertia_prior(self.scenario.prior)

    def draw(self, key) -> dict[str, Any]:
        """One replicate's truth: ``u4`` and ``π`` (:func:`draw_rwa4_truth`), robust also the
        nuisance (:func:`robust_rwa4_truth`)."""
        from cassini_bayes.inference.inertia import INERTIA_NAMES
        from cassini_bayes.inference.rwa4 import U4_NAMES

        cone = (self.scenario.prior.wheel(self.wheel).cone if self.opts["prior"] == "cone"
                else None)
        # the idealised model's truths keep their key (its campaign in docs/sbc/rwa4/ reruns)
        k_a, k_n = jax.random.split(key) if self.robust else (key, None)
        u, pi = draw_rwa4_truth(k_a, self.inertia_prior.mean, self.inertia_prior.sd, cone)
        d = dict(zip(U4_NAMES + tuple(INERTIA_NAMES), np.concatenate([u, pi])))
        if self.robust:
            d["nuisance"] = robust_rwa4_truth(k_n, self.scenario.prior, self.wheel, self.known)
        return d

    def prior_sample(self, key) -> dict[str, Any]:
        """``(key) -> {name: scalar}``: the ranked scalars of one prior draw."""
        d = self.draw(key)
        return {n: d[n] for n in self.names}

    def flown(self, d: dict[str, Any]):
        """The simulator's truth and noise of one drawn replicate: the drawn inertia and axis
        (the solved wheel's spin inertia times ``rwa4_inertia_factor``), robust also the
        torques and sensor and wheel errors (:func:`~cassini_bayes.simulate.with_errors`)."""
        from cassini_bayes.inference.inertia import INERTIA_NAMES
        from cassini_bayes.inference.rwa4 import U4_NAMES
        from cassini_bayes.simulate.run import with_errors

        base, nz = self.base
        tp = base._replace(inertia=jnp.asarray([d[n] for n in INERTIA_NAMES]))
        if self.robust:
            nu = d["nuisance"]
            tp = tp._replace(torque_body_nm=jnp.asarray(nu["T_body"]),
                             torque_inertial_nm=jnp.asarray(nu["T_inertial"]),
                             torque_inertial_rate_nm_s=jnp.asarray(nu["T_N_rate"]))
            tp, nz = with_errors(self.scenario, tp, nz,
                                 wheel_scale=dict(zip(nu["scale_wheels"], nu["wheel_scale"])),
                                 wheel_tilt_rad=dict(zip(nu["tilt_wheels"], nu["wheel_tilt"])),
                                 gyro_bias_rad_s=nu["gyro_bias"],
                                 gyro_scale_factor=nu["gyro_scale"])
        u = jnp.asarray([d[n] for n in U4_NAMES])
        factor = float(self.opts["rwa4_inertia_factor"])
        return tp._replace(wheel_axes=jnp.asarray(tp.wheel_axes).at[self.k4].set(u),
                           wheel_inertias=jnp.asarray(tp.wheel_inertias).at[self.k4].multiply(
                               factor)), nz

    def simulate_batch(self, prior_keys, sim_keys):
        """Truths drawn replicate by replicate (rejection in NumPy), flown in one batch; an
        RWA-controlled scenario's controller allocates with each drawn axis."""
        from cassini_bayes.inference.rwa4 import U4_NAMES
        from cassini_bayes.simulate.run import simulate_batch

        drawn = [self.draw(k) for k in prior_keys]
        flown = [self.flown(d) for d in drawn]
        believed = None
        if self.scenario.control == "rwa":   # the controller allocates with the drawn axis
            base = np.asarray(self.scenario.rwa.believed_axes, float)
            believed = np.stack([base] * len(drawn))
            believed[:, self.k4] = [[d[n] for n in U4_NAMES] for d in drawn]
        arrays = simulate_batch(sim_keys, self.scenario, stacked([f[0] for f in flown]),
                                stacked([f[1] for f in flown]), noise_batched=True,
                                believed_axes=believed)
        params = {n: np.array([d[n] for d in drawn]) for n in self.names}
        return params, arrays

    def fit(self, key, arrays) -> SbcFit:
        """:func:`~cassini_bayes.inference.rwa4.fit_rwa4` of one replicate, the scenario's
        ``A``/``B`` windows as the pair (detected from quiet periods when it names none)."""
        from cassini_bayes.inference.rwa4 import fit_rwa4
        from cassini_bayes.simulate.run import measured_telemetry

        wins = {w.name: (w.t0_s, w.t1_s) for w in self.scenario.windows}
        pairs = [(wins["A"], wins["B"])] if {"A", "B"} <= set(wins) else None
        tel = measured_telemetry(arrays, self.scenario, f"<sbc rwa4 replicate, {self.wheel}>")
        post = fit_rwa4(key, tel, self.scenario.prior, method=str(self.opts["method"]),
                        pairs=pairs, prior=self.opts["prior"], settings=self.settings,
                        prior_draws=0, wheel=self.wheel, robust=self.robust)
        if self.robust and post.problem.layout.wheels != self.known:
            raise RuntimeError(f"replicate's known wheels {post.problem.layout.wheels} are not "
                               f"the scenario's {self.known}")
        return posterior_draws(post.idata, self.names)


@register("rwa4")
def _rwa4(spec: ModelSpec) -> SbcModel:
    """A wheel's spin axis by Brown's RCS or RWA method: prior truth, simulator, NUTS.

    Truth per replicate, from the prior :func:`~cassini_bayes.inference.rwa4.fit_rwa4` states:
    ``u4`` (the solved wheel's axis) uniform on the sphere (option ``prior="cone"``: the
    articulation-cone prior) and the inertia ``π ~ Normal(predicted, knowledge sd²)`` times the
    model's smooth physical factor (:func:`~cassini_bayes.inference.inertia.inertia_prior` of the
    ``[prior]`` model; see :func:`draw_rwa4_truth`). They go into ``TruthParams.wheel_axes``
    (the wheel's row) and ``inertia``; the rest is the scenario's. Data: the scenario (default
    :data:`RWA4_SCENARIO`) through :func:`~cassini_bayes.simulate.run.simulate_batch`; in an
    RWA-controlled scenario (Brown's RWA method) the controller allocates with the drawn axis,
    so the slews are flown whatever the draw. Fit:
    ``fit_rwa4(method=method, wheel=wheel, robust=robust)`` with the scenario's ``A``/``B``
    windows as the pair (detected from quiet periods when the scenario names none).

    ``robust=True`` checks the robust model (``fit wheel-axis``'s default): each replicate also
    draws every nuisance effect that model integrates out from its prior
    (:func:`robust_rwa4_truth`: gyro bias and scale factor, each running wheel's spin-inertia
    scale, the solved wheel's included, the known wheels' axis tilts, body-fixed and inertial
    torques, the inertial torque's rate) and flies them (:func:`~cassini_bayes.simulate.
    with_errors`, the torques into the truth). Every other truth (noise levels, the known wheels'
    nominal axes) is the scenario's, so a scenario used here must not add errors of its own
    beyond those the prior draws (they are all replaced).

    Ranked: ``u4_x u4_y u4_z`` and, with ``rank_inertia`` (default True), ``Ixx … Iyz`` (the
    nuisance is integrated out analytically, so it has no draws to rank).
    Options: ``num_warmup, num_draws, num_chains, thin`` (default 300, 300, 2, 3), ``prior``
    (``uniform``), ``robust`` (False), ``wheel`` (``RWA4``), ``method`` (``rcs``), and a
    deliberate mis-specification SBC must detect: ``rwa4_inertia_factor`` multiplies the solved
    wheel's spin inertia in the simulator while the fit keeps the model's (the spin-up momentum
    ``J4 Δρ4`` is then mis-stated, which the fit can only absorb in the inertia).
    """
    scenario = scenario_of(spec, RWA4_SCENARIO)
    opts = _rwa4_options(spec, scenario)
    reps = _Rwa4Replicates(scenario, opts, sampler_settings(opts))
    record = {**opts, "scenario": scenario.name, "prior_model": scenario.prior_model_path}
    return SbcModel("rwa4", reps.names, reps.prior_sample, None, quiet(reps.fit),
                    vectorized=False, settings=record, rhat_max=1.05,
                    simulate_batch=reps.simulate_batch)
