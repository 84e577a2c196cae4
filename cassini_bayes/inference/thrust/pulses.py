"""Per-pulse angular impulses of a thrust fit, measured against predicted: the run's
``pulse_impulses`` group, which the report plots (:func:`pulse_impulses`).

A *pulse group* is the pulses between two telemetry samples ``a < b`` such that none of the
event's other pulses acts between them: ``a`` is the sample before the group's first pulse and
``b`` the first sample at which the last one has delivered its whole impulse (in the model's
sparse form, :class:`~cassini_bayes.inference.thrust.likelihood.PulseLayout`, ``K`` samples
after its first). Groups whose spans overlap are merged. Over a group, Feldman & Lee Eq 17 reads

    V(t_b) − V(t_a) = Σ_p Q_{s_p} F_{s_p} I(Δ_p; τ)        (I: the §V closed-form impulse)

the left side *measured* (the momentum's change, at the posterior-mean inertia, less the
posterior-mean robust nuisance), the right side *predicted* at each posterior draw of the thrust
and time constants. Both are projected on the group's mean predicted direction, so one number per
group compares them; the measurement's sd is the white telemetry noise of two samples,
``√(2 ûᵀ B û)`` with ``B`` at the posterior-mean noise levels (the likelihood's ``B``).
"""

from __future__ import annotations

import numpy as np

from cassini_bayes.inference.thrust.likelihood import moment_matrix_at
from cassini_bayes.inference.thrust.prior import COM_NAMES
from cassini_bayes.names import INERTIA_NAMES, TAU_NAMES
from cassini_bayes.physics.momentum import inertia_matrix
from cassini_bayes.physics.pulse import pulse_impulse

__all__ = ["pulse_groups", "pulse_impulses", "IMPULSE_DRAWS", "QUANTILES"]

IMPULSE_DRAWS = 1000
"""Posterior draws (evenly spaced) the predicted impulses are computed from."""
QUANTILES = (0.05, 0.5, 0.95)


def pulse_groups(slot: np.ndarray, width: np.ndarray, n: int, k: int) -> list[tuple[int, int,
                                                                                      list[int]]]:
    """``(a, b, pulse indices)`` of each pulse group of one event (module docstring): pulses of
    width > 0 whose first sample ``slot`` lies in the data; ``k`` samples after it the pulse has
    delivered its impulse. A group that starts at the first sample or ends past the last is
    left out (its momentum change is not measured)."""
    spans = sorted((int(s) - 1, int(s) + k, i) for i, (s, w) in enumerate(zip(slot, width))
                   if w > 0 and 0 <= s < n)
    groups: list[tuple[int, int, list[int]]] = []
    for a, b, i in spans:
        if groups and a < groups[-1][1]:
            ga, gb, idx = groups[-1]
            groups[-1] = (ga, max(gb, b), idx + [i])
        else:
            groups.append((a, b, [i]))
    return [(a, b, idx) for a, b, idx in groups if a >= 0 and b <= n - 1]


def _flat(post, name) -> np.ndarray:
    v = np.asarray(post[name].values, float)
    return v.reshape(v.shape[0] * v.shape[1], -1)


def pulse_impulses(problem, post, nu_draws=None):
    """The ``pulse_impulses`` group (an ``xarray.Dataset``) of a thrust posterior.

    Parameters
    ----------
    problem : :class:`~cassini_bayes.inference.thrust.data.ThrustProblem`.
    post : the posterior group (thrust parameters, ``tau_*``, ``sigma_omega``, ``sigma_rho``, the
        inertia entries when sampled).
    nu_draws : (chain × draw, R) draws of the robust nuisance, or ``None`` (idealised model).

    Returns
    -------
    xarray.Dataset
        Along ``group``: ``t`` (s, the first pulse's command on its event's clock), ``event``,
        ``thrusters`` (names joined by ``+``), ``n_pulses``, ``on_time`` (s, commanded),
        ``measured`` and ``measured_sd`` (N m s) and ``predicted`` (N m s, posterior quantiles
        along ``quantile``).
    """
    kw = problem.data
    ev = kw.events
    k = int(np.asarray(ev.pulses.dt).shape[-1])                          # K transient samples
    com = (np.concatenate([_flat(post, n) for n in COM_NAMES], 1).mean(0) if problem.n_c
           else None)
    q = moment_matrix_at(kw, com)                                        # (3, M) m
    f = np.concatenate([_flat(post, n) for n in problem.names], 1)
    n_s = f.shape[0]
    pick = np.unique(np.linspace(0, n_s - 1, min(IMPULSE_DRAWS, n_s)).astype(int))
    f_m = f[pick][:, np.asarray(kw.f_index)]                            # (S, M) N
    tau = np.concatenate([_flat(post, n) for n in TAU_NAMES], 1)[pick]  # (S, 3) s
    sampled = all(n in post for n in INERTIA_NAMES)
    pi = (np.concatenate([_flat(post, n) for n in INERTIA_NAMES], 1).mean(0) if sampled
          else np.asarray(kw.inertia_mean, float))
    i_m = np.asarray(inertia_matrix(pi), float)
    nu = (np.zeros(np.asarray(kw.nu_sd).shape[0]) if nu_draws is None
          else np.asarray(nu_draws, float).mean(0))
    s2 = np.stack([_flat(post, "sigma_omega").mean(0), _flat(post, "sigma_rho").mean(0)],
                  -1) ** 2                                               # (E, 2) rad²/s²
    rows = {"t": [], "event": [], "thrusters": [], "n_pulses": [], "on_time": [], "measured": [],
            "measured_sd": [], "predicted": []}
    for e in range(len(problem.sources)):
        n = int(np.asarray(ev.mask[e]).sum())
        slot, width = np.asarray(ev.slot[e]), np.asarray(ev.width[e], float)
        thr, t_on = np.asarray(ev.thruster[e]), np.asarray(ev.t_on[e], float)
        groups = pulse_groups(slot, width, n, k)
        if not groups:
            continue
        v = (np.asarray(ev.lhs_wheels[e], float)
             + np.tensordot(pi, np.asarray(ev.lhs_inertia[e], float), 1))   # Feldman & Lee Eq 17
        v = (v - np.tensordot(nu, np.asarray(ev.nu_cols[e], float), 1)).T   # (n, 3) N m s
        b_cov = s2[e, 0] * i_m @ i_m + s2[e, 1] * np.asarray(ev.wheel_cov[e], float)
        used = sorted({i for _, _, idx in groups for i in idx})
        # Feldman & Lee §V: each pulse's impulse per newton at every draw's time constants
        imp = np.asarray(pulse_impulse(width[used][None, :], tau[:, :1], tau[:, 1:2],
                                       tau[:, 2:]), float)              # (S, m) s
        col = {i: c for c, i in enumerate(used)}
        for a, b, idx in groups:
            cols = [col[i] for i in idx]
            # Σ_p Q_s F_s I_p per draw: (S, 3) N m s
            pred = (imp[:, cols] * f_m[:, thr[idx]]) @ q[:, thr[idx]].T
            u = pred.mean(0)
            norm = np.linalg.norm(u)
            if not norm > 0:
                continue
            u = u / norm
            rows["t"].append(float(t_on[idx].min()))
            rows["event"].append(e)
            rows["thrusters"].append("+".join(problem.thrusters[s]
                                              for s in sorted(set(thr[idx]))))
            rows["n_pulses"].append(len(idx))
            rows["on_time"].append(float(width[idx].sum()))
            rows["measured"].append(float((v[b] - v[a]) @ u))
            rows["measured_sd"].append(float(np.sqrt(2.0 * u @ b_cov @ u)))
            rows["predicted"].append(np.quantile(pred @ u, QUANTILES).tolist())
    return _as_dataset(rows)


def _as_dataset(rows: dict[str, list]):
    """The pulse groups' ``rows`` as the ``pulse_impulses`` group, with units."""
    import xarray as xr

    g = ("group",)
    return xr.Dataset(
        {"t": (g, np.asarray(rows["t"], float), {"units": "s"}),
         "event": (g, np.asarray(rows["event"], int)),
         "thrusters": (g, np.asarray(rows["thrusters"], dtype=str)),
         "n_pulses": (g, np.asarray(rows["n_pulses"], int)),
         "on_time": (g, np.asarray(rows["on_time"], float), {"units": "s"}),
         "measured": (g, np.asarray(rows["measured"], float), {"units": "N m s"}),
         "measured_sd": (g, np.asarray(rows["measured_sd"], float), {"units": "N m s"}),
         "predicted": (("group", "quantile"),
                       np.asarray(rows["predicted"], float).reshape(-1, len(QUANTILES)),
                       {"units": "N m s"})},
        coords={"quantile": list(QUANTILES)},
        attrs={"description": "angular impulse of each pulse group along its predicted "
                              "direction: measured (momentum change) and predicted (posterior "
                              "quantiles), Feldman & Lee Eq 17"})
