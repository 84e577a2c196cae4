"""Data preparation of the thrust model: the events checked, padded to common lengths and
turned into the prepared :class:`ThrustProblem` (:func:`prepare_thrust`)."""

from __future__ import annotations

from typing import NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from cassini_bayes.errors import InputError, spelled
from cassini_bayes.estimators.leak import interval_means
from cassini_bayes.inference.inertia.knowledge import InertiaGaussian, inertia_mean_tril
from cassini_bayes.inference.gaussian import ColumnStatistics, column_statistics
from cassini_bayes.inference.laplace import laplace
from cassini_bayes.inference.noise import pulse_bent, rate_noise_levels
from cassini_bayes.inference.nuisance import (nuisance_layout, with_clock_errors,
                                              with_time_tag_steps)
from cassini_bayes.inference.thrust.clock import (ClockGrid, events_clock_columns,
                                                  events_on_grid)
from cassini_bayes.inference.thrust.columns import (events_nuisance_columns, rotation_errors,
                                                    wheel_momentum)
from cassini_bayes.inference.thrust.coords import (bit_widths, long_pulse_excess, n_tag,
                                                  rise_deficit)
from cassini_bayes.inference.thrust.design import ThrustDesign, thrust_design
from cassini_bayes.inference.thrust.flex import ModeSearch, flex_mode_columns
from cassini_bayes.inference.thrust.likelihood import (EventData, PulseLayout, events_impulse,
                                                       events_time_tag_rates, noise_covariances,
                                                       pulse_layout)
from cassini_bayes.inference.thrust.model import laplace_density, thrust_sizes
from cassini_bayes.inference.thrust.prior import (THRUST_PRIOR_LOG_SD, TauPrior, thrust_index,
                                                  tau_prior, thrust_names)
from cassini_bayes.inference.thrust.time_tags import (events_tag_sensitivity, events_tag_steps,
                                                      gyro_tag_terms, rank_one_rows,
                                                      tag_scale_fields,
                                                      with_pre_command_rates, with_tag_expectation)
from cassini_bayes.physics.impulse import impulse_lhs, impulse_lhs_basis
from cassini_bayes.physics.momentum import inertia_matrix
from cassini_bayes.physics.rate_step_moments import StepPairs, interval_moments, step_pairs
from cassini_bayes.spacecraft import Spacecraft
from cassini_bayes.telemetry import PulseLog, Telemetry, pulses_in_span, without_stale_samples

__all__ = ["ThrustData", "ThrustProblem", "prepare_thrust"]

_TAIL_S = 1.5   # a pulse's thrust 1.5 s after its command ends: e^{-1.5 s / 90 ms} < 1e-7
_PULSE_BUCKET = 64
_NOISE_SCAN = np.arange(-15.0, 41.0, 2.5)   # noise coordinate (prior.NOISE_STEP): σ/σ̂ 0.2-55
SPAN_MISS_SHARE = 0.3
"""An event's momentum change outside the torques its fired thrusters can make, as a share of
the change: above it (and above :data:`SPAN_MISS_NOISE` noise sd) the model's thrusters cannot
be what moved the spacecraft."""
SPAN_MISS_NOISE = 10.0


class ThrustData(NamedTuple):
    """The arrays of :func:`~cassini_bayes.inference.thrust.model.thrust_model` (a pytree:
    problems of the same shapes share one compiled sampler). ``E`` events.

    Attributes
    ----------
    events : :class:`~cassini_bayes.inference.thrust.likelihood.EventData`, each field with a
        leading event axis (E), padded to common lengths.
    log_noise_hat : (E, 2) log data noise levels (σ_ω, σ_ρ rad/s).
    q_matrix : (3, M) m, torque per newton of each of the M thrusters about the model file's
        centre of mass (Feldman & Lee Eq 16).
    tau_delay_scale, tau_mu, tau_sd, a_mu, c_mu : the pulse time constants' prior and the
        sampler's centres of the rise deficit and the long-pulse excess, s (coords.py).
    f_mu : log predicted thrust (per thruster in mode ``thruster``); f_index : (M,) int, each
        thruster's thrust parameter.
    inertia_mean, inertia_tril : (6,) kg m² and (6, 6): the inertia (its prior when sampled;
        ``inertia_tril`` zero when fixed).
    nu_sd : (R,) prior sds of the robust nuisance (R = 0 when idealised).
    centre, tril : the sampler's whitening ``θ = centre + tril w`` (``None`` until the Laplace
        step has run).
    f_basis, com_sd, d_matrix : mode ``thruster`` only (else ``None``): the orthogonal
        (M + 3, M + 3) rotation of the prior-whitened ``(log F, δ)`` into the impulse design's
        singular directions (:class:`~cassini_bayes.inference.thrust.design.ThrustDesign`),
        the centre of mass's prior sd (m) and the thrusters' unit directions (3, M).
    bit_width : (n_f,) s, each thrust parameter's one pulse width where the events fire every
        parameter at one width (the sampler then sees the impulse bits,
        :func:`~cassini_bayes.inference.thrust.coords.bit_widths`), else ``None``.
    tag_sd, tag_walk : the stated time-tag sd (1,) s, which the sampler scales, and (R,) 1 on its
        walk's columns (:func:`~cassini_bayes.inference.thrust.time_tags.tag_scale_fields`).
    """

    events: EventData
    log_noise_hat: object
    q_matrix: object
    tau_delay_scale: object
    tau_mu: object
    tau_sd: object
    a_mu: object
    c_mu: object
    f_mu: object
    f_index: object
    inertia_mean: object
    inertia_tril: object
    nu_sd: object
    centre: object = None
    tril: object = None
    f_basis: object = None
    com_sd: object = None
    d_matrix: object = None
    bit_width: object = None
    tag_sd: object = None
    tag_walk: object = None


class ThrustProblem(NamedTuple):
    """Everything the thrust model needs, prepared once (SI units).

    Attributes
    ----------
    data : :class:`ThrustData`, the arrays of :func:`thrust_model`.
    mode : ``"mean"``, ``"branch"`` or ``"thruster"``.
    names : thrust sites of the mode (``F`` along ``thrusters`` in mode ``thruster``).
    thrust_pred : predicted thrust (prior centre), N; (M,) per thruster in mode ``thruster``.
    tau : :class:`TauPrior`.
    inertia : :class:`InertiaGaussian` when the inertia is sampled, else ``None``.
    inertia_fixed : (3, 3) kg m² used when not sampled.
    sources : ``(telemetry, pulses)`` file names per event.
    n_samples, n_pulses : per event.
    fired : (M,) bool, thrusters with at least one pulse in any event.
    noise_hat : (E, 2) data noise levels (σ_ω rad/s, σ_ρ rad/s).
    layout : the nuisance layout (:class:`~cassini_bayes.inference.nuisance.NuisanceLayout`)
        of the robust model, ``None`` for the idealised one.
    thrusters : the spacecraft's thruster names (M).
    design : :class:`~cassini_bayes.inference.thrust.design.ThrustDesign` in mode
        ``thruster``, else ``None``.
    flex_mode : the search for a flexible mode (:class:`~cassini_bayes.inference.thrust.flex.
        ModeSearch`; robust model), else ``None``.
    clock : each event's labels on their grid (:class:`~cassini_bayes.inference.thrust.clock.
        ClockGrid`) where the model file states a regular clock (robust model), else ``None``.
    """

    data: ThrustData
    mode: str
    names: tuple[str, ...]
    thrust_pred: float | np.ndarray
    tau: TauPrior
    inertia: InertiaGaussian | None
    inertia_fixed: np.ndarray
    sources: tuple[tuple[str, str], ...]
    n_samples: np.ndarray
    n_pulses: np.ndarray
    fired: np.ndarray
    noise_hat: np.ndarray
    layout: object = None
    thrusters: tuple[str, ...] = ()
    design: ThrustDesign | None = None
    flex_mode: ModeSearch | None = None
    clock: tuple[ClockGrid, ...] | None = None

    @property
    def n_f(self) -> int:
        """Number of thrust parameters the sampler sees."""
        return thrust_sizes(self.mode, self.data)[0]

    @property
    def scale_free(self) -> bool:
        """Whether the likelihood holds the wheels at the model file's common spin-inertia scale
        (:func:`~cassini_bayes.inference.nuisance.without_common_scale`): the robust model with
        the inertia sampled, whose balance (Feldman & Lee Eq 17) is unchanged when the inertia,
        the thrusts, the torques and every wheel scale by one factor, so the data cannot tell the
        common scale ``u`` and the fit draws it from its prior and scales what it reports by
        ``1 + u``. Held in the likelihood instead, its noise covariance and rate-step terms would
        stay at the file's wheels while the sampled scale moved, and tilt the ridge."""
        return _scale_free(self.layout is not None, self.inertia)

    @property
    def n_c(self) -> int:
        """Number of centre-of-mass coordinates the sampler sees (3 in mode ``thruster``)."""
        return thrust_sizes(self.mode, self.data)[1]


def _pulse_slots(t: np.ndarray, log: PulseLog) -> np.ndarray:
    """Sample index of each pulse's first sample at or after its command (n when none)."""
    return np.searchsorted(t, log.t_on, side="left")


def _checked_events(events) -> tuple[list[Telemetry], list[PulseLog]]:
    """The events' telemetry and pulse logs (pulses outside the span dropped), one-line
    InputErrors for events that cannot calibrate anything."""
    if not events:
        raise InputError("no biasing event given; pass "
                         + spelled("--telemetry F.csv --pulses P.csv", "telemetry and pulses"))
    logs, tels = [], []
    for tel, log in events:
        if log is None:
            raise InputError("thrust calibration needs the pulse log of every event ("
                             + spelled("--pulses P.csv", "pulses")
                             + ", columns t_on, thruster, width)", path=tel.source)
        if tel.n < 10:
            raise InputError(f"only {tel.n} samples; a biasing event needs many", path=tel.source)
        tel = without_stale_samples(tel)                 # a warning naming them
        log = pulses_in_span(log, tel, tail_s=_TAIL_S)   # a warning per pulse left out
        if log.t_on.size == 0:
            raise InputError(f"no pulse of {log.source} falls inside the telemetry span "
                             f"{tel.t[0]:.10g}..{tel.t[-1]:.10g} s; thrust calibration needs an "
                             "event in which thrusters fire", path=tel.source)
        if not tel.active_wheels():
            raise InputError("no wheel rates (rwa1..rwa4, rpm); a biasing event needs them",
                             path=tel.source)
        logs.append(log)
        tels.append(tel)

    return tels, logs


def _check_torque_span(tel: Telemetry, log: PulseLog, spacecraft: Spacecraft,
                       inertia: np.ndarray) -> None:
    """Refuse an event whose momentum change (Feldman & Lee Eq 17's left side ``V``) leaves the
    span of its fired thrusters' torques ``Q`` (Eq 16) by more than :data:`SPAN_MISS_SHARE` of
    the change and :data:`SPAN_MISS_NOISE` × its sample noise: a thruster's position, direction
    or name in the model file is wrong, and no thrust could fit."""
    fired = np.unique(log.thruster)
    q = spacecraft.moment_matrix[:, fired]                       # (3, k) N m per N
    u, sv, _ = np.linalg.svd(q, full_matrices=True)
    rank = int(np.sum(sv > 1e-6 * max(float(np.max(sv, initial=0.0)), 1e-300)))
    if rank == 3:
        return
    h, _, _ = wheel_momentum(tel, spacecraft)
    v = np.asarray(impulse_lhs(tel.t, tel.omega, inertia, h))    # (n, 3) N m s
    miss = (v - v[0]) @ u[:, rank:]                              # outside the torques' span
    swing = float(np.max(np.linalg.norm(v - v[0], axis=1)))
    worst = int(np.argmax(np.linalg.norm(miss, axis=1)))
    miss_swing = float(np.linalg.norm(miss[worst]))
    noise = float(np.median(np.linalg.norm(np.diff(miss, axis=0), axis=1))) / 0.6745
    if miss_swing > SPAN_MISS_SHARE * swing and miss_swing > SPAN_MISS_NOISE * noise:
        names = " ".join(spacecraft.thruster_names[i] for i in fired)
        axis = np.array2string(u[:, rank:] @ miss[worst] / miss_swing, precision=2,
                               suppress_small=True)
        raise InputError(f"the momentum changes by {miss_swing:.3g} N m s about body axis {axis}"
                         f" ({miss_swing / swing:.0%} of the event's {swing:.3g} N m s), which "
                         f"the fired thrusters {names} cannot torque: check their position, "
                         "direction and names in the spacecraft model",
                         path=tel.source)


def _padded_events(tels: list[Telemetry], logs: list[PulseLog], spacecraft: Spacecraft,
                   noise_hat=None) -> tuple[dict, np.ndarray, np.ndarray]:
    """The events' arrays padded to common lengths (the first half of ``ThrustData``), the
    thrusters that fired (M,) and the data noise levels (E, 2)."""
    n_max = max(t.n for t in tels)
    # pulse arrays padded to a multiple of _PULSE_BUCKET: events whose pulse counts differ a
    # little (seeds of one scenario, SBC replicates) share shapes, so one compiled sampler
    m_max = -(-max(len(lg.t_on) for lg in logs) // _PULSE_BUCKET) * _PULSE_BUCKET
    dt_min = min(float(np.min(np.diff(t.t))) for t in tels)
    w_max = max(float(np.max(lg.width)) for lg in logs)
    # samples a pulse's thrust can still change after its first sample (≥ 1, static)
    k_slots = int(np.ceil((w_max + 0.02 + _TAIL_S) / dt_min)) + 1
    n_ev = len(tels)
    t_a = np.zeros((n_ev, n_max))
    w_a = np.zeros((n_ev, n_max, 3))
    h_a = np.zeros((n_ev, n_max, 3))
    mask = np.zeros((n_ev, n_max))
    ton = np.zeros((n_ev, m_max))
    thr = np.zeros((n_ev, m_max), int)
    wid = np.zeros((n_ev, m_max))
    slot = np.full((n_ev, m_max), n_max)
    wcov = np.zeros((n_ev, 3, 3))
    noise = np.zeros((n_ev, 2))
    fired = np.zeros(len(spacecraft.thrusters), bool)
    for e, (tel, log) in enumerate(zip(tels, logs)):
        n, m = tel.n, len(log.t_on)
        t = np.asarray(tel.t, float)
        h, wc, _ = wheel_momentum(tel, spacecraft)
        # pad by repeating the last sample: Δt = 0 adds nothing to ΔG; masked out anyway
        t_a[e] = np.r_[t, np.full(n_max - n, t[-1])]
        w_a[e] = np.r_[tel.omega, np.repeat(tel.omega[-1:], n_max - n, 0)]
        h_a[e] = np.r_[h, np.repeat(h[-1:], n_max - n, 0)]
        mask[e, :n] = 1.0
        ton[e, :m] = log.t_on
        thr[e, :m] = log.thruster
        wid[e, :m] = log.width      # padded pulses: width 0 → no impulse, slot n_max → dropped
        slot[e, :m] = _pulse_slots(t, log)
        wcov[e] = wc
        noise[e] = (rate_noise_levels(tel, pulse_bent(t, log.t_on, log.width))
                    if noise_hat is None else np.asarray(noise_hat, float)[e])
        fired[np.unique(log.thruster)] = True

    kw = dict(t=t_a, omega=w_a, h_wheels=h_a, mask=mask, t_on=ton, thruster=thr, width=wid,
              slot=slot, k_slots=k_slots, wheel_cov=wcov,
              log_noise_hat=np.log(noise))
    return kw, fired, noise


_lhs_basis = jax.jit(jax.vmap(impulse_lhs_basis))


def _interval_changes(x: np.ndarray) -> np.ndarray:
    """(E, 3, n): ``x[i] − x[i − 1]`` of ``x`` (E, n, 3) at ``i`` (0 at ``i = 0``)."""
    return np.ascontiguousarray(np.swapaxes(np.diff(x, axis=-2, prepend=x[..., :1, :]), -1, -2))


def _rate_steps(kw: dict, k_slots: int, n_thr: int, tau) -> dict:
    """The :class:`EventData` fields of the trapezoidal ``ΔG``'s correction across the pulses'
    rate steps (:func:`~cassini_bayes.physics.impulse.rate_step_correction`, first order: the
    intervals' mean rates and wheel momenta;
    :mod:`~cassini_bayes.physics.rate_step_moments`, second order: their changes and the
    thrusters' moments at the time constants ``tau``)."""
    moments = [interval_moments(*(kw[f][e] for f in ("t", "t_on", "thruster", "width", "slot")),
                                k_slots, n_thr, tau) for e in range(kw["t"].shape[0])]
    # padded as the pulses are (a few thruster pairs per pulse): similar events, one program
    bucket = 4 * _PULSE_BUCKET
    size = max(1, -(-max(int(np.count_nonzero(p)) for _, p in moments) // bucket) * bucket)
    pairs = [step_pairs(p, size) for _, p in moments]
    return dict(omega_mid=np.ascontiguousarray(interval_means(kw["omega"])),
                h_mid=np.ascontiguousarray(interval_means(kw["h_wheels"])),
                d_omega=_interval_changes(kw["omega"]), d_h=_interval_changes(kw["h_wheels"]),
                dt=np.diff(kw["t"], axis=-1, prepend=kw["t"][..., :1]),
                step_moments=np.stack([m for m, _ in moments]),
                step_pairs=StepPairs(*(np.stack(x) for x in zip(*pairs))))


def _lhs_basis_events(kw: dict) -> np.ndarray:
    """(E, 7, 3, n) N m s: every event's left side of Eq 17 at ``I = 0`` and its derivatives in
    the six inertia entries (:func:`~cassini_bayes.physics.impulse.impulse_lhs_basis`)."""
    basis = np.asarray(_lhs_basis(*jax.device_put([kw["t"], kw["omega"], kw["h_wheels"]])))
    return np.ascontiguousarray(basis.transpose(0, 1, 3, 2))


def _pulse_layouts(kw: dict, k_slots: int, n_thr: int) -> PulseLayout:
    """Every event's :func:`pulse_layout`, stacked (leading axis E)."""
    layouts = [pulse_layout(*(kw[k][e] for k in ("t", "t_on", "thruster", "width", "slot")),
                            k_slots, n_thr) for e in range(len(kw["t"]))]
    return PulseLayout(*(np.stack(x) for x in zip(*layouts)))


def _with_laplace(data: ThrustData, mode: str, sample_inertia: bool) -> ThrustData:
    """``data`` with the Laplace centre and Cholesky factor that whiten the sampler's vector;
    the search starts at the prior's centre, each event's noise at best (:data:`_NOISE_SCAN`)."""
    n_f, n_c = thrust_sizes(mode, data)
    n_ev = data.events.t.shape[0]
    dim = n_f + n_c + 3 + n_ev + (6 if sample_inertia else 0) + n_tag(data)
    noise = np.arange(n_f + n_c + 3, n_f + n_c + 3 + n_ev)     # coords.unpack's order
    centre, tril = laplace(laplace_density(n_f, n_c, sample_inertia), np.zeros(dim), data,
                           scan=(noise, _NOISE_SCAN))
    return data._replace(centre=jax.device_put(centre), tril=jax.device_put(tril))


def _time_tag_terms(kw: dict, layout, layout_e: PulseLayout, steps: dict, rates, q_f, tau,
                    i_lin, noise, time_tag_sd, grids=None):
    """The robust model's time-tag terms (:mod:`~cassini_bayes.inference.thrust.time_tags`):
    a regular clock's columns (``grids`` given, :mod:`~cassini_bayes.inference.thrust.clock`)
    and the walk's appended to ``kw["nu_cols"]`` and to the nuisance ``layout``, and the
    rank-one rows with their rates and gyroscopic terms; the rank-one rows alone where
    ``time_tag_sd`` is ``None`` and no clock is given (the idealised model)."""
    if grids is not None:
        cols, clock_sd = events_clock_columns(kw, layout_e, i_lin, q_f, tau, steps, grids)
        kw["nu_cols"] = np.concatenate([kw["nu_cols"], cols], 1)
        layout = with_clock_errors(layout, clock_sd)
    gyro = np.zeros((len(kw["t"]), 3, kw["t"].shape[1]))
    if time_tag_sd is not None:
        sens = events_tag_sensitivity(kw, layout_e, i_lin, q_f, tau, steps)
        cols = events_tag_steps(sens, kw, i_lin, noise, time_tag_sd)
        kw["nu_cols"] = np.concatenate([kw["nu_cols"], cols], 1)
        layout = with_time_tag_steps(layout, cols.shape[1], time_tag_sd)
        gyro = gyro_tag_terms(sens, kw, i_lin, noise, time_tag_sd)
    return layout, rank_one_rows(rates, gyro, kw, q_f, noise, i_lin, _PULSE_BUCKET)


def _prior_fields(kw: dict, q_mat, tp: TauPrior, mode: str, thrust_pred, inertia,
                  i_fixed) -> dict:
    """:class:`ThrustData`'s fields of the thrusters' geometry and the priors."""
    n_thr = q_mat.shape[1]
    i_mean, i_tril = inertia_mean_tril(inertia, i_fixed)
    return dict(
        q_matrix=q_mat, tau_delay_scale=tp.delay_scale, tau_mu=tp.log_mean, tau_sd=tp.log_sd,
        a_mu=float(rise_deficit(*tp.median()[:2])), c_mu=float(long_pulse_excess(*tp.median())),
        f_mu=np.log(thrust_pred), f_index=thrust_index(mode, n_thr), inertia_mean=i_mean,
        bit_width=bit_widths(kw["width"], kw["thruster"], thrust_index(mode, n_thr)),
        inertia_tril=i_tril)


def _column_statistics(nu_cols, mask) -> ColumnStatistics:
    """Every event's :func:`column_statistics` of its nuisance columns, stacked."""
    stats = [column_statistics(c, m) for c, m in zip(nu_cols, mask)]
    return ColumnStatistics(np.stack([x.gram for x in stats]), np.stack([x.total for x in stats]))


def _scale_free(robust: bool, inertia) -> bool:
    """:attr:`ThrustProblem.scale_free` of a fit that is ``robust`` with ``inertia`` sampled
    (``None``: fixed)."""
    return robust and inertia is not None


def prepare_thrust(events: Sequence[tuple[Telemetry, PulseLog]], spacecraft: Spacecraft, *,
                   mode: str = "mean", inertia: InertiaGaussian | None = None,
                   robust: bool = False, wheel_errors: str = "per_wheel",
                   noise_hat=None, flex="check", clock_sd_s: float | None = None
                   ) -> ThrustProblem:
    """Prepare the thrust problem from ``(telemetry, pulse log)`` pairs, one per biasing event.

    ``robust`` adds the nuisance parameters of the module docstring (sensor and wheel errors,
    external torque); ``wheel_errors`` (``"per_wheel"`` or ``"common"``) picks the wheel
    spin-inertia model. ``noise_hat`` (E, 2) rad/s replaces the white-noise levels estimated
    from the data (a plan's noise-free telemetry has none; :mod:`cassini_bayes.plan.thrust`).
    ``flex`` (robust model): ``"check"`` searches the events for a flexible mode (the result on
    ``problem.flex_mode``, judged by the adequacy checks), ``"model"`` also integrates its
    momentum out where they show one (:mod:`~cassini_bayes.inference.thrust.flex`), ``"off"``
    does neither, ``(freq_hz, damping)`` puts a mode there without a search. ``clock_sd_s``:
    a regular clock's label sd (s) in place of their scatter (:mod:`.clock`).

    Raises
    ------
    InputError
        No event, a pulse log with no pulse inside its telemetry span (nothing to calibrate), an
        unknown mode, too few samples.
    """
    names = thrust_names(mode)
    spacecraft.require_thrusters("thrust calibration", eq16=(mode == "branch"))
    tels, logs = _checked_events(events)
    tels, grids = events_on_grid(tels, robust and spacecraft.knowledge.regular_clock, clock_sd_s)
    n_ev, n_thr = len(tels), len(spacecraft.thrusters)
    i_fixed = np.asarray(spacecraft.inertia, float)
    i_lin = i_fixed if inertia is None else np.asarray(inertia_matrix(jnp.asarray(inertia.mean)))
    for tel, log in zip(tels, logs):
        _check_torque_span(tel, log, spacecraft, i_lin)
    wheels = sorted({w for tel in tels for w in tel.active_wheels()})
    layout = nuisance_layout(spacecraft, n_ev, wheels if robust else (),
                             wheel_errors=wheel_errors, torque_rate=robust)
    kw, fired, noise = _padded_events(tels, logs, spacecraft, noise_hat)
    q_mat = spacecraft.moment_matrix
    thrust_pred = spacecraft.thrust_per_thruster if mode == "thruster" else float(spacecraft.thrust)
    tp = tau_prior(spacecraft)
    q_f, tau0 = q_mat * thrust_pred, tp.median()
    sd_t = spacecraft.knowledge.time_tag_sd_s if robust and grids is None else 0.0
    k_slots = kw.pop("k_slots")
    b_covs = noise_covariances(i_lin, noise, kw["wheel_cov"])
    layout_e = with_tag_expectation(_pulse_layouts(kw, k_slots, n_thr), q_f, tau0, b_covs, sd_t)
    basis, steps = _lhs_basis_events(kw), _rate_steps(kw, k_slots, n_thr, tau0)
    kw["nu_cols"] = events_nuisance_columns(tels, spacecraft, layout if robust else None, i_lin,
                                            rotation_errors(layout_e, q_f, tau0, i_lin),
                                            _scale_free(robust, inertia))
    rates = with_pre_command_rates(events_time_tag_rates(layout_e, tau0, sd_t, n_thr),
                                   layout_e, q_f, tau0, b_covs, sd_t)
    mode_search = None
    if robust and flex != "off":
        mode_search, kw["nu_cols"], layout = flex_mode_columns(
            flex, kw, steps, basis, layout_e, tels, logs, spacecraft, thrust_pred, tp, i_lin,
            inertia, noise, layout, np.einsum("am,emn->ean", q_f, rates))
    layout, (rank_one, tag_rates, tag_gyro) = _time_tag_terms(
        kw, layout, layout_e, steps, rates, q_f, tau0, i_lin, noise, sd_t or None, grids)
    design, extra = (_per_thruster_design(layout_e, tau0, noise, i_lin, kw, spacecraft,
                                          thrust_pred, fired) if mode == "thruster" else (None, {}))
    nu_cols = kw.pop("nu_cols")
    tags = tag_scale_fields(layout, sd_t) if robust and sd_t > 0.0 else {}
    derived = dict(time_tag_rates=tag_rates, time_tag_gyro=tag_gyro, rank_one=rank_one,
                   pulses=layout_e, lhs_wheels=basis[:, 0], lhs_inertia=basis[:, 1:],
                   nu_cols=nu_cols, nu_stats=_column_statistics(nu_cols, kw["mask"]), **steps)
    # one device_put of everything, not jnp.asarray (a compiled one-operation program per
    # shape, every process; Python numbers stay weakly typed either way)
    kw, derived, rest = jax.device_put((kw, derived, dict(
        **_prior_fields(kw, q_mat, tp, mode, thrust_pred, inertia, i_fixed),
        nu_sd=layout.sd if robust else np.zeros(0), **extra, **tags)))
    events = EventData(**{f: kw.pop(f) for f in EventData._fields if f not in derived},
                       **derived)
    data = _with_laplace(ThrustData(events=events, **kw, **rest), mode, inertia is not None)
    return ThrustProblem(
        data=data, mode=mode, names=names, thrust_pred=thrust_pred, tau=tp,
        inertia=inertia, inertia_fixed=i_fixed,
        sources=tuple((t.source, lg.source) for t, lg in zip(tels, logs)),
        n_samples=np.array([t.n for t in tels]), n_pulses=np.array([len(lg.t_on) for lg in logs]),
        fired=fired, noise_hat=noise, layout=layout if robust else None,
        thrusters=spacecraft.thruster_names, design=design, flex_mode=mode_search,
        clock=None if grids is None else tuple(grids))


def _per_thruster_design(layout_e, tau_med, noise, i_lin, kw, spacecraft: Spacecraft,
                         thrust_pred, fired):
    """Mode ``thruster``: the combinations of the thrusts and the centre of mass the events
    identify (:func:`thrust_design`, from each pulse's impulse per newton at the prior-median
    time constants and the momentum noise), and the data fields its model reads."""
    n_thr = len(spacecraft.thrusters)
    q_mat = spacecraft.moment_matrix
    j = events_impulse(layout_e, np.eye(n_thr), tau_med)
    b_cov = noise_covariances(i_lin, noise, kw["wheel_cov"])
    dirs = np.stack([s.direction for s in spacecraft.thrusters], 1)
    design = thrust_design(j, kw["mask"], q_mat, dirs, thrust_pred, b_cov,
                           THRUST_PRIOR_LOG_SD, spacecraft.com_sd_m,
                           spacecraft.thruster_names, fired)
    return design, dict(f_basis=design.basis, com_sd=float(spacecraft.com_sd_m), d_matrix=dirs)
