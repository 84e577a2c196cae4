"""SBC of the default robust thrust model (``cassini-bayes sbc thrust --set robust=true``).

What ``cassini-bayes fit thrust`` runs by default (:func:`~cassini_bayes.inference.thrust.
fit_thrust` with ``robust=True``, the inertia sampled from the model file's knowledge, per-wheel
spin-inertia errors) is checked here in a closed world: every parameter that fit states a prior
for is drawn from that prior and flown by the simulator (:func:`robust_thrust_truth`), and the
fit's posterior ranks them (Talts et al. 2018).

Drawn per replicate, for the scenario's ``[prior]`` spacecraft and its running wheels:

* the thrust of the mode: ``log F ~ Normal(log F_pred, THRUST_PRIOR_LOG_SD)`` per thrust
  parameter (``mean``: one for all thrusters; ``branch``: Cassini's ``F_Z``, ``F_Y``;
  ``thruster``: one per thruster about its own nominal), flown as each thruster's
  ``TruthParams.thrust_n``;
* mode ``thruster`` only: the centre-of-mass offset ``δ ~ Normal(0, [center_of_mass] sd_m)`` per
  axis, flown as the truth model's centre of mass ``e + δ`` (the thrusters' torques
  ``(r_s − e − δ) × d_s``, Feldman & Lee Eq 16);
* the pulse time constants from :func:`~cassini_bayes.inference.thrust.draw_tau_prior`;
* the inertia from the model file's Gaussian knowledge
  (:func:`~cassini_bayes.inference.inertia.knowledge.inertia_prior_gaussian`, the fit's prior);
* the nuisance vector ``ν`` of the layout :func:`~cassini_bayes.inference.thrust.prepare_thrust`
  builds for one event (gyro bias and scale factor, each running wheel's spin-inertia scale with
  the shared part, the wheels' axis tilts, a body-fixed torque and its rate), ``layout.sd ·
  N(0, 1)``, flown by :func:`~cassini_bayes.simulate.with_errors`, ``TruthParams.torque_body_nm``
  and, turned to inertial axes at the initial attitude (the dead band holds it),
  ``torque_inertial_rate_nm_s``;
* the time tags' sd from the fit's prior about the model's ``[telemetry_knowledge]
  time_tag_sd_s`` (:func:`~cassini_bayes.inference.thrust.prior.tag_log_scale`), the telemetry's
  time tags jittered with it (the fit reads the jittered times).

The noise levels stay the scenario's: the fit's noise scale is centred on the data's own
white-noise levels (empirical Bayes), which no prior draw can be made from.

Ranked: the thrusts (``F``; mode ``thruster``: ``F[<name>]`` of each thruster the scenario's
reference event identifies, and each identified combination of the others, labelled as the fit
labels them; :func:`reference_design`), ``com_x com_y com_z`` (mode ``thruster``), ``tau_delay
tau_rise tau_fall``, with ``rank_inertia`` (default True) ``Ixx … Iyz``, and with
``rank_nuisance`` (default True) the gyro scale factors and biases and each wheel's scale
``c_k`` (the nuisance sites the fit draws from their exact conditional) and ``time_tag_sd``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes._paths import SCENARIOS_DIR
from cassini_bayes.analysis.sbc_models._contract import ModelSpec, SbcFit, SbcModel
from cassini_bayes.analysis.sbc_models._common import (
    IDEAL_PULSE_TAU_S,
    check_options,
    nuisance_names,
    nuisance_scalars,
    quiet,
    sampler_settings,
    truth_nuisance_scalars,
)
from cassini_bayes.analysis.sbc_models._thrust import thrust_scenario
from cassini_bayes.errors import InputError

if TYPE_CHECKING:
    from cassini_bayes.inference.thrust import ThrustDesign
    from cassini_bayes.simulate.scenario import Scenario
    from cassini_bayes.spacecraft import Spacecraft

__all__ = ["THRUST_ESPA_SCENARIO", "robust_thrust_truth", "simulate_robust_thrust",
           "reference_design", "robust_thrust_model"]

THRUST_ESPA_SCENARIO = SCENARIOS_DIR / "sbc" / "sbc_thrust_espa_bus.toml"
"""The ESPA bus's short biasing event for the per-thruster robust SBC (the file's header)."""

_KEYS = {"num_warmup", "num_draws", "num_chains", "thin", "robust", "mode", "pulse_dynamics",
         "thrust_factor", "rank_inertia", "rank_nuisance"}


def robust_thrust_truth(key: jax.Array, spacecraft: Spacecraft, wheels: Sequence[str],
                        mode: str) -> dict[str, Any]:
    """One draw of every parameter of the robust thrust model from its own prior (module
    docstring), for ``spacecraft`` (the ``[prior]`` model), the running ``wheels`` of one event
    and the thrust ``mode``.

    Returns ``thrust`` (n_f,) N, one per thrust parameter of the mode; ``thrust_n`` (M,) N, each
    thruster's; ``com`` (3,) m (zero unless mode ``thruster``); ``tau`` (3,) s; ``inertia`` (6,)
    kg m²; the one event's nuisance sites of :func:`~cassini_bayes.inference.nuisance.
    split_nuisance` (``gyro_bias`` (3,), ``gyro_scale`` (3,), ``wheel_scale`` (K,) each wheel's
    total ``c_k``, ``wheel_scale_common``, ``wheel_tilt`` (K, 2) rad, ``T_body`` (3,) N m,
    ``T_N_rate`` (3,) N m/s, the body torque's rate);
    ``time_tag_sd`` s (0 where the model states none); and ``wheels``, the K wheel names in the
    layout's order.
    """
    from cassini_bayes.inference.inertia.knowledge import inertia_prior_gaussian
    from cassini_bayes.inference.nuisance import nuisance_layout, split_nuisance
    from cassini_bayes.inference.thrust import THRUST_PRIOR_LOG_SD, draw_tau_prior, tau_prior
    from cassini_bayes.inference.thrust.prior import tag_log_scale, thrust_index, thrust_names

    k_f, k_c, k_t, k_i, k_n = jax.random.split(key, 5)
    n_thr = len(spacecraft.thrusters)
    index = thrust_index(mode, n_thr)
    if mode == "thruster":
        f_pred = np.asarray(spacecraft.thrust_per_thruster, float)
    else:
        f_pred = np.full(len(thrust_names(mode)), float(spacecraft.thrust))
    thrust = np.exp(np.log(f_pred) + THRUST_PRIOR_LOG_SD
                    * np.asarray(jax.random.normal(k_f, f_pred.shape)))
    com = (float(spacecraft.com_sd_m) * np.asarray(jax.random.normal(k_c, (3,)))
           if mode == "thruster" else np.zeros(3))
    tau = np.asarray(draw_tau_prior(k_t, tau_prior(spacecraft)))
    gauss = inertia_prior_gaussian(spacecraft)
    chol = np.linalg.cholesky(np.asarray(gauss.cov) + 1e-9 * np.eye(6))   # as sample_thrust_prior
    inertia = np.asarray(gauss.mean, float) + chol @ np.asarray(jax.random.normal(k_i, (6,)))
    layout = nuisance_layout(spacecraft, 1, tuple(wheels), wheel_errors="per_wheel",
                             torque_rate=True)
    nu = layout.sd * np.asarray(jax.random.normal(k_n, (layout.size,)))
    out = split_nuisance(nu, layout)
    for site in ("gyro_bias", "T_body", "T_N_rate"):
        out[site] = np.asarray(out[site])[0]                    # the one event
    z_tag = jax.random.normal(jax.random.fold_in(key, 6), ())
    tag_sd = float(spacecraft.knowledge.time_tag_sd_s) * float(jnp.exp(tag_log_scale(z_tag)))
    out.update(thrust=thrust, thrust_n=thrust[index], com=com, tau=tau, inertia=inertia,
               wheels=layout.wheels, time_tag_sd=tag_sd)
    return out


def reference_design(scenario: Scenario, seed: int = 0) -> ThrustDesign:
    """The per-thruster design (:class:`~cassini_bayes.inference.thrust.ThrustDesign`) of the
    scenario's event flown at the prior's centre (nominal thrusts and centre of mass, the
    ``[pulse]`` prior's medians, the predicted inertia, no sensor or wheel error): which
    thrusters the event identifies and which combinations of the others. The ranked thrust
    quantities are fixed from it for the whole campaign (any fixed function of the parameters
    ranks uniformly under a calibrated model; a replicate's own design may differ a little).
    ``seed``: the key of the reference event's sensor noise."""
    from cassini_bayes.inference.inertia.knowledge import inertia_prior_gaussian
    from cassini_bayes.inference.thrust import prepare_thrust, tau_prior
    from cassini_bayes.physics.momentum import inertia_vector
    from cassini_bayes.simulate.run import (measured_telemetry, pulse_log, simulate_arrays,
                                            truth_params)

    sc = scenario.prior
    tp = truth_params(scenario)._replace(
        inertia=jnp.asarray(inertia_vector(sc.inertia)),
        thrust_n=jnp.asarray(sc.thrust_per_thruster, float),
        tau_s=jnp.asarray(tau_prior(sc).median()))
    arrays = simulate_arrays(jax.random.key(seed), scenario, tp)
    log = pulse_log(arrays, scenario)
    if log is None:
        raise InputError("the thrust SBC scenario fires no thruster at the prior's centre; "
                         "give a biasing event that needs the thrusters",
                         path=scenario.source or None)
    tel = measured_telemetry(arrays, scenario, "<sbc thrust reference event>")
    problem = quiet(prepare_thrust)([(tel, log)], sc, mode="thruster",
                                     inertia=inertia_prior_gaussian(sc), robust=True)
    return problem.design


def simulate_robust_thrust(prior_keys: jax.Array, sim_keys: jax.Array, scenario: Scenario,
                           mode: str, *, pulse_dynamics: bool = True,
                           thrust_factor: float = 1.0) -> tuple[list[dict[str, Any]], Any]:
    """Draw one truth per ``prior_keys`` (:func:`robust_thrust_truth`, the scenario's running
    wheels sorted as :func:`~cassini_bayes.inference.thrust.prepare_thrust` sorts them) and fly
    each with its ``sim_keys`` noise: the thrusts (times ``thrust_factor``), time constants (1 µs
    each without ``pulse_dynamics``: ideal rectangular pulses), inertia and body torque into
    :class:`~cassini_bayes.simulate.run.TruthParams` (the torque's rate in inertial axes at the
    initial attitude, no constant inertial torque), the wheel and gyro
    errors by :func:`~cassini_bayes.simulate.with_errors`, the time tags jittered with the
    drawn ``time_tag_sd``, and the centre-of-mass offset as the truth model's centre of mass
    (a scenario of its own per replicate: the thrusters' torques are the simulator's
    per-scenario arrays; one compiled program serves them all). Returns the drawn truths and the
    runs' :class:`~cassini_bayes.simulate.run.SimArrays` stacked along a leading batch axis."""
    from cassini_bayes.frames import dcm_body_to_inertial
    from cassini_bayes.simulate.run import noise_params, simulate_arrays, truth_params
    from cassini_bayes.simulate.run import with_errors

    spacecraft = scenario.prior
    wheels = tuple(sorted(n for n, on in zip(scenario.wheel_names, scenario.wheels_on) if on))
    base = truth_params(scenario)
    base_noise = noise_params(scenario)
    to_inertial = dcm_body_to_inertial(jnp.asarray(scenario.q0))
    drawn, runs = [], []
    for p_key, s_key in zip(prior_keys, sim_keys):
        d = robust_thrust_truth(p_key, spacecraft, wheels, mode)
        tau = d["tau"] if pulse_dynamics else np.full(3, IDEAL_PULSE_TAU_S)
        tp = base._replace(inertia=jnp.asarray(d["inertia"]),
                           thrust_n=jnp.asarray(d["thrust_n"] * thrust_factor),
                           tau_s=jnp.asarray(tau), torque_body_nm=jnp.asarray(d["T_body"]),
                           torque_inertial_nm=jnp.zeros(3),
                           torque_inertial_rate_nm_s=to_inertial @ jnp.asarray(d["T_N_rate"]))
        noise = base_noise._replace(time_tag_jitter_s=jnp.asarray(d["time_tag_sd"]))
        tp, nz = with_errors(scenario, tp, noise,
                             wheel_scale=dict(zip(d["wheels"], d["wheel_scale"])),
                             wheel_tilt_rad=dict(zip(d["wheels"], d["wheel_tilt"])),
                             gyro_bias_rad_s=d["gyro_bias"], gyro_scale_factor=d["gyro_scale"])
        sc = scenario
        if np.any(d["com"]):
            truth = dataclasses.replace(scenario.truth, com_m=np.asarray(spacecraft.com_m, float)
                                        + d["com"])
            sc = dataclasses.replace(scenario, truth=truth)
        drawn.append(d)
        runs.append(simulate_arrays(s_key, sc, tp, nz))
    return drawn, jax.tree.map(lambda *xs: jnp.stack(xs), *runs)


def _thrust_quantities(mode: str, design, thrusters) -> tuple[tuple[str, ...], np.ndarray]:
    """The ranked thrust names and their weights (Q, n_f) on the mode's thrust vector: ``F``
    (mean), ``F_Z F_Y`` (branch), or per thruster the identified thrusters ``F[<name>]`` and the
    identified combinations of the others (:func:`reference_design`)."""
    from cassini_bayes.inference.thrust.design import combination_label
    from cassini_bayes.inference.thrust.prior import thrust_names

    if mode != "thruster":
        names = thrust_names(mode)
        return names, np.eye(len(names))
    m = len(thrusters)
    rows = [np.eye(m)[i] for i in np.flatnonzero(design.identified)]
    names = [f"F[{thrusters[i]}]" for i in np.flatnonzero(design.identified)]
    for w in design.combinations:
        rows.append(np.asarray(w, float))
        names.append(combination_label(w, thrusters))
    return tuple(names), np.array(rows).reshape(len(rows), m)


def _robust_options(spec: ModelSpec, scenario: Scenario) -> dict[str, Any]:
    """The adapter's options: the defaults overridden by ``spec``'s, checked; the scenario must
    fly the prior model's thrusters (one model for ``[truth]`` and ``[prior]``)."""
    from cassini_bayes.inference.thrust import MODES

    opts = {"num_warmup": 300, "num_draws": 300, "num_chains": 2, "thin": 3, "robust": True,
            "mode": "mean", "pulse_dynamics": True, "thrust_factor": 1.0,
            "rank_inertia": True, "rank_nuisance": True, **dict(spec.options)}
    check_options("thrust", opts, _KEYS)
    mode = str(opts["mode"])
    if mode not in MODES:
        raise InputError(f"thrust SBC option mode={mode!r}: choose one of {', '.join(MODES)}")
    if [t.name for t in scenario.truth.thrusters] != list(scenario.prior.thruster_names):
        raise InputError("the robust thrust SBC flies the prior model's thrusters: give the "
                         "scenario one model for [truth] and [prior]", path=spec.scenario_source)
    return opts


@dataclass(frozen=True, eq=False)
class _RobustReplicates:
    """Truth, simulation and fit of the robust thrust adapter's replicates: the ranked thrust
    quantities ``f_names`` are ``f_weights`` (Q, n_f) times the mode's thrust vector."""

    scenario: Any
    opts: dict[str, Any]
    wheels: tuple[str, ...]
    f_names: tuple[str, ...]
    f_weights: np.ndarray
    settings: Any

    @property
    def mode(self) -> str:
        return str(self.opts["mode"])

    @property
    def names(self) -> tuple[str, ...]:
        """The ranked scalars, in order (module docstring)."""
        from cassini_bayes.inference.inertia import INERTIA_NAMES
        from cassini_bayes.inference.thrust import COM_NAMES, TAU_NAMES

        return (self.f_names + (tuple(COM_NAMES) if self.mode == "thruster" else ())
                + tuple(TAU_NAMES) + (tuple(INERTIA_NAMES) if self.opts["rank_inertia"] else ())
                + (nuisance_names(self.wheels) + self._tag if self.opts["rank_nuisance"]
                   else ()))

    @property
    def _tag(self) -> tuple[str, ...]:
        """``time_tag_sd`` where the fit learns it (the model states a time-tag sd)."""
        return ("time_tag_sd",) if self.scenario.prior.knowledge.time_tag_sd_s > 0 else ()

    def ranked(self, d: dict[str, Any]) -> dict[str, Any]:
        """The ranked scalars of a drawn truth (:func:`robust_thrust_truth`)."""
        from cassini_bayes.inference.inertia import INERTIA_NAMES
        from cassini_bayes.inference.thrust import COM_NAMES, TAU_NAMES

        out = dict(zip(self.f_names, self.f_weights @ d["thrust"]))
        if self.mode == "thruster":
            out.update(zip(COM_NAMES, d["com"]))
        out.update(zip(TAU_NAMES, d["tau"]))
        if self.opts["rank_inertia"]:
            out.update(zip(INERTIA_NAMES, d["inertia"]))
        if self.opts["rank_nuisance"]:
            out.update(truth_nuisance_scalars(d, self.wheels))
            out.update({n: d[n] for n in self._tag})
        return out

    def prior_sample(self, key) -> dict[str, Any]:
        """``(key) -> {name: scalar}``: the ranked scalars of one prior draw."""
        return self.ranked(robust_thrust_truth(key, self.scenario.prior, self.wheels, self.mode))

    def simulate_batch(self, prior_keys, sim_keys):
        """The truths drawn and flown by :func:`simulate_robust_thrust`, ranked."""
        drawn, arrays = simulate_robust_thrust(
            prior_keys, sim_keys, self.scenario, self.mode,
            pulse_dynamics=bool(self.opts["pulse_dynamics"]),
            thrust_factor=float(self.opts["thrust_factor"]))
        params = [self.ranked(d) for d in drawn]
        return {n: np.array([p[n] for p in params]) for n in self.names}, arrays

    def fit(self, key, arrays) -> SbcFit:
        """The robust :func:`~cassini_bayes.inference.thrust.fit_thrust` of one replicate's
        telemetry and commanded pulses, its draws ranked."""
        from cassini_bayes.inference.thrust import fit_thrust
        from cassini_bayes.simulate.run import measured_telemetry, pulse_log

        log = pulse_log(arrays, self.scenario)
        if log is None:
            raise RuntimeError("no thruster fired in this replicate")
        tel = measured_telemetry(arrays, self.scenario, "<sbc thrust replicate, robust>")
        post = fit_thrust(key, [(tel, log)], self.scenario.prior, mode=self.mode,
                          settings=self.settings, prior_draws=0, robust=True)
        if post.problem.layout.wheels != self.wheels:
            raise RuntimeError(f"replicate's active wheels {post.problem.layout.wheels} are not "
                               f"the scenario's {self.wheels}")
        n_div = int(post.idata.sample_stats["diverging"].values.sum())
        draws = self.posterior_ranked(post.idata.posterior)
        return SbcFit({n: jnp.asarray(draws[n]) for n in self.names}, jnp.asarray(n_div))

    def posterior_ranked(self, p) -> dict[str, np.ndarray]:
        """The ranked quantities' ``(chain, draw)`` draws from the posterior group ``p``: the
        thrust quantities as ``f_weights`` times the thrust draws, the nuisance split."""
        if self.mode == "thruster":
            f = np.asarray(p["F"].values, float)                          # (chain, draw, M)
        else:
            f = np.stack([np.asarray(p[n].values, float) for n in self.f_names], -1)
        draws = dict(zip(self.f_names, np.moveaxis(f @ self.f_weights.T, -1, 0)))
        scalars = [n for n in self.names if n not in draws and "[" not in n]
        draws.update({n: np.asarray(p[n].values, float) for n in scalars})
        if self.opts["rank_nuisance"]:
            draws.update(nuisance_scalars({s: np.asarray(p[s].values, float)
                                           for s in ("gyro_scale", "gyro_bias", "wheel_scale")},
                                          self.wheels))
        return draws


def _robust_record(reps: _RobustReplicates, design) -> dict[str, Any]:
    """The settings recorded in the run: the options, the scenario, the time-tag sd, the wheels
    and, per thruster, the reference design's rank and identified thrusters."""
    scenario, spacecraft = reps.scenario, reps.scenario.prior
    record = {**reps.opts, "scenario": scenario.name, "prior_model": scenario.prior_model_path,
              "time_tag_sd_s": float(spacecraft.knowledge.time_tag_sd_s),
              "wheels": list(reps.wheels)}
    if design is not None:
        record.update(reference_rank=int(design.rank), reference_thrust_rank=int(
            design.thrust_rank), reference_identified=[
            t for t, ok in zip(spacecraft.thruster_names, design.identified) if ok],
            reference_combinations=[n for n in reps.f_names if not n.startswith("F[")])
    return record


def robust_thrust_model(spec: ModelSpec) -> SbcModel:
    """The ``thrust`` SBC adapter with ``robust=True`` (module docstring).

    Options: ``num_warmup, num_draws, num_chains, thin`` (default 300, 300, 2, 3), ``mode``
    (``mean``, ``branch`` or ``thruster``; default ``mean``, ``fit thrust``'s), ``rank_inertia``
    and ``rank_nuisance`` (True), and the idealised adapter's two deliberate mis-specifications:
    ``pulse_dynamics=False`` (ideal rectangular pulses flown) and ``thrust_factor`` (the flown
    thrust times this factor, the recorded truth the drawn one).
    """
    scenario = thrust_scenario(spec)
    opts = _robust_options(spec, scenario)
    mode = str(opts["mode"])
    wheels = tuple(sorted(n for n, on in zip(scenario.wheel_names, scenario.wheels_on) if on))
    design = reference_design(scenario) if mode == "thruster" else None
    f_names, f_weights = _thrust_quantities(mode, design, scenario.prior.thruster_names)
    reps = _RobustReplicates(scenario, opts, wheels, f_names, f_weights, sampler_settings(opts))
    return SbcModel("thrust", reps.names, reps.prior_sample, None, quiet(reps.fit),
                    vectorized=False, settings=_robust_record(reps, design), rhat_max=1.05,
                    simulate_batch=reps.simulate_batch)
