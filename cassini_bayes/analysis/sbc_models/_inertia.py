"""The ``inertia`` SBC adapter: the inertia tensor from RWA slews."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import jax.numpy as jnp
import numpy as np

from cassini_bayes._paths import SCENARIOS_DIR
from cassini_bayes.analysis.sbc_models._common import (
    active_wheels,
    check_options,
    nuisance_names,
    nuisance_scalars,
    sampler_settings,
    scenario_of,
    stacked,
    truth_nuisance_scalars,
)
from cassini_bayes.analysis.sbc_models._contract import ModelSpec, SbcFit, SbcModel, register
from cassini_bayes.analysis.sbc_models._nuts import nuts_fit
from cassini_bayes.errors import InputError

__all__ = ["INERTIA_SCENARIO", "robust_inertia_truth"]

# default scenario: one hour of RWA slews about Y, X and Z (the file's header says more)
INERTIA_SCENARIO = SCENARIOS_DIR / "sbc" / "sbc_inertia_slews.toml"

_INERTIA_KEYS = {"num_warmup", "num_draws", "num_chains", "thin", "torque",
                 "wheel_inertia_factor", "robust", "rank_nuisance"}


def robust_inertia_truth(key, scenario, *, torque: bool = True) -> dict[str, Any]:
    """One draw of every parameter of the robust inertia model from its own prior, for
    ``scenario``'s ``[prior]`` spacecraft and active wheels (one telemetry file).

    :func:`~cassini_bayes.inference.inertia.sample_prior` with the model's nuisance layout
    (:func:`~cassini_bayes.inference.nuisance.nuisance_layout`, as
    :func:`~cassini_bayes.inference.inertia.prepare_inertia` builds it): ``Ixx … Iyz``, ``T_N``
    and, for the one file, ``gyro_bias`` (3,) rad/s, ``gyro_scale`` (3,), ``wheel_scale`` (K,)
    each wheel's total ``c_k = c_s + d_k``, ``wheel_scale_common`` (the shared ``c_s``, when the
    model has it), ``wheel_tilt`` (K, 2) rad, ``T_body`` (3,) N m and, with ``torque``,
    ``T_N_rate`` (3,) N m/s; and ``wheels``, the K wheel names. The same function the fit's
    ``prior`` group uses, so the truth's prior is the model's.
    """
    import numpy as np

    from cassini_bayes.inference.inertia import inertia_prior, sample_prior
    from cassini_bayes.inference.nuisance import nuisance_layout

    layout = nuisance_layout(scenario.prior, 1, active_wheels(scenario), torque_rate=torque)
    d = sample_prior(key, inertia_prior(scenario.prior), 1, torque=torque, layout=layout)
    out = {n: np.asarray(v)[0] for n, v in d.items()}
    for site in ("gyro_bias", "T_body", "T_N_rate", "T_N", "H0"):
        if site in out:
            out[site] = out[site][0]                        # the one file
    out["wheels"] = layout.wheels
    return out


def _inertia_options(spec: ModelSpec) -> dict[str, Any]:
    """The adapter's options: the defaults overridden by ``spec``'s, checked; ``rank_nuisance``
    defaults to True for the robust model and is an error for the idealised one (it has no
    nuisance parameters)."""
    opts = {"num_warmup": 300, "num_draws": 300, "num_chains": 2, "thin": 3, "torque": True,
            "wheel_inertia_factor": 1.0, "robust": False, **dict(spec.options)}
    check_options("inertia", opts, _INERTIA_KEYS)
    if opts["robust"]:
        opts.setdefault("rank_nuisance", True)
    elif opts.get("rank_nuisance"):
        raise InputError("inertia SBC option rank_nuisance needs robust=true (the idealised "
                         "model has no nuisance parameters)")
    return opts


def _inertia_numpyro_model(scenario, robust: bool, torque: bool):
    """The inertia posterior's NumPyro model: the robust one with the scenario's nuisance
    layout for one file, else the idealised one."""
    from cassini_bayes.inference.inertia import inertia_model
    from cassini_bayes.inference.nuisance import nuisance_layout

    if not robust:
        return inertia_model(torque, False)
    layout = nuisance_layout(scenario.prior, 1, active_wheels(scenario), torque_rate=torque)
    return inertia_model(torque, True, layout.wheel_errors, common=layout.has_common,
                         torque_rate=torque)


@dataclass(frozen=True, eq=False)
class _InertiaReplicates:
    """Truth, simulation and data preparation of the inertia adapter's replicates.

    ``extra`` are the ranked nuisance names (empty unless robust with ``rank_nuisance``);
    ``factor`` multiplies the simulator's wheel spin inertias (the fit keeps the model's).
    """

    scenario: Any
    robust: bool
    torque: bool
    factor: float
    wheels: tuple[str, ...]
    extra: tuple[str, ...]

    @cached_property
    def base(self):
        """The scenario's truth and noise (:func:`~cassini_bayes.simulate.run.truth_params`,
        :func:`~cassini_bayes.simulate.run.noise_params`)."""
        from cassini_bayes.simulate.run import noise_params, truth_params

        return truth_params(self.scenario), noise_params(self.scenario)

    @cached_property
    def prior(self):
        """The inertia prior of the scenario's ``[prior]`` model."""
        from cassini_bayes.inference.inertia import inertia_prior

        return inertia_prior(self.scenario.prior)

    @property
    def names(self) -> tuple[str, ...]:
        """The ranked scalars: ``Ixx … Iyz`` and the ranked nuisance."""
        from cassini_bayes.inference.inertia import INERTIA_NAMES

        return tuple(INERTIA_NAMES) + self.extra

    def draw_truth(self, key) -> dict[str, Any]:
        """One replicate's truth from the fitted model's own prior."""
        from cassini_bayes.inference.inertia import INERTIA_NAMES, sample_prior

        if self.robust:
            return robust_inertia_truth(key, self.scenario, torque=self.torque)
        d = sample_prior(key, self.prior, 1, torque=self.torque)
        return {**{n: d[n][0] for n in INERTIA_NAMES},
                "T_N": d["T_N"][0, 0] if self.torque else np.zeros(3)}

    def ranked(self, d: dict[str, Any]) -> dict[str, Any]:
        """The ranked scalars of a drawn truth."""
        from cassini_bayes.inference.inertia import INERTIA_NAMES

        out = {n: d[n] for n in INERTIA_NAMES}
        if self.extra:
            out.update(truth_nuisance_scalars(d, self.wheels))
        return out

    def prior_sample(self, key) -> dict[str, Any]:
        """``(key) -> {name: scalar}``: the ranked scalars of one prior draw."""
        return self.ranked(self.draw_truth(key))

    def flown(self, d: dict[str, Any]):
        """The simulator's truth and noise of one drawn replicate: the drawn inertia and
        inertial torque, with robust the body torque, its rate and the sensor and wheel errors
        (:func:`~cassini_bayes.simulate.with_errors`)."""
        from cassini_bayes.inference.inertia import INERTIA_NAMES
        from cassini_bayes.simulate.run import with_errors

        zero = np.zeros(3)
        base, nz = self.base
        tp = base._replace(
            inertia=jnp.asarray([d[n] for n in INERTIA_NAMES]),
            torque_inertial_nm=jnp.asarray(d.get("T_N", zero)))
        if self.robust:
            tp = tp._replace(torque_body_nm=jnp.asarray(d["T_body"]),
                             torque_inertial_rate_nm_s=jnp.asarray(d.get("T_N_rate", zero)))
            tp, nz = with_errors(self.scenario, tp, nz,
                                 wheel_scale=dict(zip(d["wheels"], d["wheel_scale"])),
                                 wheel_tilt_rad=dict(zip(d["wheels"], d["wheel_tilt"])),
                                 gyro_bias_rad_s=d["gyro_bias"], gyro_scale_factor=d["gyro_scale"])
        return tp._replace(wheel_inertias=tp.wheel_inertias * self.factor), nz

    def simulate_batch(self, prior_keys, sim_keys):
        """``(prior_keys, sim_keys) -> ({name: (B,)}, batched data)``: truths drawn replicate
        by replicate (the prior sampler rejects in NumPy), flown in one simulator batch."""
        from cassini_bayes.simulate.run import simulate_batch

        drawn = [self.draw_truth(k) for k in prior_keys]
        pairs = [self.flown(d) for d in drawn]
        truth = stacked([p[0] for p in pairs])
        if self.robust:
            arrays = simulate_batch(sim_keys, self.scenario, truth, stacked([p[1] for p in pairs]),
                                    noise_batched=True)
        else:
            arrays = simulate_batch(sim_keys, self.scenario, truth)
        params = [self.ranked(d) for d in drawn]
        return {n: np.array([p[n] for p in params]) for n in self.names}, arrays

    def prepare(self, arrays) -> dict[str, Any]:
        """One replicate's fit data: the package's own preparation
        (:func:`~cassini_bayes.inference.inertia.prepare_inertia`) of its noisy telemetry."""
        from cassini_bayes.inference.inertia import prepare_inertia
        from cassini_bayes.simulate.run import measured_telemetry

        tel = measured_telemetry(arrays, self.scenario, "<sbc inertia replicate>")
        problem = prepare_inertia([tel], self.scenario.prior, torque=self.torque,
                                  robust=self.robust)
        if self.robust and problem.layout.wheels != self.wheels:
            raise RuntimeError(f"replicate's active wheels {problem.layout.wheels} are not the "
                               f"scenario's {self.wheels}")
        return {"data": problem.data}


def _inertia_fit(reps: _InertiaReplicates, settings):
    """The vectorisable fit: :func:`nuts_fit` on the inertia model's sites, the nuisance sites
    split into the ranked scalars when ``reps.extra`` ranks them."""
    from cassini_bayes.inference.inertia import INERTIA_NAMES

    extra = ("gyro_scale", "gyro_bias", "wheel_scale") if reps.extra else ()
    site_fit = nuts_fit(_inertia_numpyro_model(reps.scenario, reps.robust, reps.torque),
                        tuple(INERTIA_NAMES) + extra, settings)
    if not reps.extra:
        return site_fit

    def fit(key, kwargs):
        out = site_fit(key, kwargs)
        draws = {n: out.draws[n] for n in INERTIA_NAMES}
        draws.update(nuisance_scalars(out.draws, reps.wheels))
        return SbcFit(draws, out.n_divergent)

    return fit


@register("inertia")
def _inertia(spec: ModelSpec) -> SbcModel:
    """Inertia tensor from RWA slews: truth from the model's own prior, the slew simulator, NUTS.

    Truth per replicate: ``Ixx … Iyz`` from :func:`cassini_bayes.inference.inertia.sample_prior`
    (the stated prior of the posterior, rejection of non-physical tensors) with the scenario's
    ``[prior]`` spacecraft, and a constant inertial torque from its ``T_N`` prior; the rest of the
    truth (wheels, noise levels) is the scenario's. Data: the scenario's slews through
    :func:`cassini_bayes.simulate.run.simulate_batch` (one vmapped call per batch). Fit: the
    idealised model of :func:`cassini_bayes.inference.inertia.fit_inertia` (``robust=False``: the
    simulator draws no sensor or wheel errors), in its two steps: per replicate the package's own
    data preparation :func:`~cassini_bayes.inference.inertia.prepare_inertia` (empirical-Bayes GLS,
    sufficient statistics, Laplace whitening; NumPy), then one ``jax.vmap`` over the batch of the
    package's NUTS program on those statistics (:func:`nuts_fit` on
    :func:`~cassini_bayes.inference.inertia.inertia_model`): the same draws ``fit_inertia`` gives
    with the same key, all replicates of a batch in one compiled call.

    ``robust=True`` checks the robust model instead (``fit inertia``'s default): each replicate
    also draws every nuisance parameter from that model's prior (:func:`robust_inertia_truth`:
    gyro bias and scale factor, each wheel's spin-inertia scale with the shared part, wheel-axis
    tilts, body-fixed torque, the inertial torque's rate), flies the slews with them
    (:func:`~cassini_bayes.simulate.with_errors`, the torques into the truth) and fits the robust
    model; with ``rank_nuisance`` (default True) the gyro scale factors and biases and each
    wheel's scale ``c_k`` are ranked beside the inertia.

    Options: ``num_warmup, num_draws, num_chains, thin`` (default 300, 300, 2, 3), ``torque``
    (True), ``robust`` (False), ``rank_nuisance`` (True), and ``wheel_inertia_factor`` (1.0): the
    simulator's wheel spin inertias times this factor while the fit keeps the model's — a
    deliberate mis-specification (the wheel/spacecraft inertia scale, Psiaki 2005) that SBC must
    detect.
    """
    scenario = scenario_of(spec, INERTIA_SCENARIO)
    opts = _inertia_options(spec)
    robust = bool(opts["robust"])
    wheels = active_wheels(scenario)
    reps = _InertiaReplicates(
        scenario, robust, bool(opts["torque"]), float(opts["wheel_inertia_factor"]), wheels,
        nuisance_names(wheels) if robust and opts["rank_nuisance"] else ())
    record = {**opts, "scenario": scenario.name, "prior_model": scenario.prior_model_path}
    return SbcModel("inertia", reps.names, reps.prior_sample, None,
                    _inertia_fit(reps, sampler_settings(opts)), vectorized=True,
                    settings=record, rhat_max=1.05, simulate_batch=reps.simulate_batch,
                    prepare=reps.prepare)
