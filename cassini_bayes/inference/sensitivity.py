"""How much each neglected effect could move the answer (Lee §4.1, made quantitative).

Lee recommends checking what a representative external torque does to the inertia estimate. Here
that check is done for every effect the robust model knows (external torque, gyro bias and scale
factor, wheel spin-inertia scales, wheel spin-axis tilts), linearised at the posterior mode:

For an effect ``G`` with parameters ``ν_G`` (prior sd ``d_G``) and the model *without* it
(parameters ``R`` = the fitted set minus ``G``), the Gaussian posterior mode of ``θ_R`` moves, when
the truth has ``ν_G ≠ 0`` but the model holds it at zero, by

    Δθ_R = −(F_RR + P_R)⁻¹ F_RG ν_G

(``F`` the data information of the full parameter vector at the mode, ``P`` the prior
precisions). With ``ν_G`` at its prior scale, ``Δπ`` has covariance ``K diag(d_G²) Kᵀ``,
``K = −[(F_RR + P_R)⁻¹ F_RG]_π``; the reported **shift** is its sd per inertia entry, kg m² —
how far an effect of typical size would push an estimate that ignores it. ``modelled`` says
whether the fit carried the effect (then it is already inside the posterior's width; the shift
says how much the idealised model would have been off). ``shift_in_sd`` divides by the run's own
posterior sd: a value above ~1 means an idealised fit's interval would be overconfident.

Models without a closed-form information matrix (the thrust model) use the same idea on the
robust posterior's draws (:func:`posterior_sensitivity`): the linear regression ``β`` of a target
(e.g. ``F``) on an effect's parameters over the draws is the posterior's own answer to "how does
the estimate move if this effect is pinned", and ``√(Σ_j β_j² d_j²)`` its shift for an effect of
prior size.
"""

from __future__ import annotations

from typing import Mapping, NamedTuple

import numpy as np

from cassini_bayes.physics.momentum import INERTIA_NAMES

__all__ = ["Sensitivity", "linear_sensitivity", "sensitivity_block", "posterior_sensitivity"]


class Sensitivity(NamedTuple):
    """Linearised sensitivity of ``π`` to each effect at its prior scale.

    ``effects`` names; ``shift`` (E, 6) kg m², sd of the shift of ``(Ixx … Iyz)`` per effect;
    ``modelled`` (E,) whether the fit estimated the effect; ``prior_sd`` (E,) tuple of the
    effects' prior sd vectors (their own units).
    """

    effects: tuple[str, ...]
    shift: np.ndarray
    modelled: np.ndarray
    prior_sd: tuple


def linear_sensitivity(info: np.ndarray, prior_prec: np.ndarray, prior_sd: np.ndarray,
                       active, groups: Mapping[str, np.ndarray]) -> Sensitivity:
    """Sensitivity of the first six parameters (``π``) to each group (module docstring).

    Parameters
    ----------
    info : (P, P) data information (Fisher) of the full parameter vector at the mode.
    prior_prec, prior_sd : (P,) prior precisions and standard deviations of the full vector.
    active : indices of the fitted parameters (must contain 0..5).
    groups : effect name → indices of its parameters in the full vector.
    """
    active = np.asarray(active)
    names, shifts, modelled, sds = [], [], [], []
    for name, idx in groups.items():
        idx = np.asarray(idx, int)
        keep = np.setdiff1d(active, idx)  # sorted; π (0..5) stays first
        if idx.size == 0:
            continue
        a = info[np.ix_(keep, keep)] + np.diag(prior_prec[keep])
        k = -np.linalg.solve(a, info[np.ix_(keep, idx)])[:6]
        cov = (k * prior_sd[idx]**2) @ k.T
        names.append(name)
        shifts.append(np.sqrt(np.maximum(np.diag(cov), 0.0)))
        modelled.append(bool(np.isin(idx, active).all()))
        sds.append(prior_sd[idx])
    return Sensitivity(tuple(names), np.array(shifts).reshape(-1, 6), np.array(modelled),
                       tuple(sds))


def sensitivity_block(sens: Sensitivity, posterior_sd: Mapping[str, float]) -> dict:
    """The ``sensitivity`` block of ``summary.json``.

    ``{effect: {"modelled": bool, "parameters": {Ixx: {"shift": kg m², "shift_in_sd": x}}}}``,
    with ``shift_in_sd`` = shift / the run's posterior sd of that parameter.
    """
    out = {}
    for e, name in enumerate(sens.effects):
        params = {}
        for i, p in enumerate(INERTIA_NAMES):
            sd = posterior_sd.get(p)
            shift = float(sens.shift[e, i])
            params[p] = {"shift": shift,
                         "shift_in_sd": (shift / sd) if sd and np.isfinite(sd) and sd > 0 else None}
        out[name] = {"modelled": bool(sens.modelled[e]), "parameters": params}
    return out


def posterior_sensitivity(targets: Mapping[str, np.ndarray],
                          groups: Mapping[str, tuple[np.ndarray, np.ndarray]],
                          units: Mapping[str, str] | None = None) -> dict:
    """The ``sensitivity`` block of ``summary.json`` from a robust fit's posterior draws.

    Parameters
    ----------
    targets : parameter name → (n,) posterior draws (e.g. ``F`` in N).
    groups : effect name → ``(draws (n, k), prior_sd (k,))`` of its nuisance parameters.
    units : parameter name → unit, recorded beside each shift.

    Returns
    -------
    dict
        As :func:`sensitivity_block` (every effect ``modelled``), each parameter entry also
        holding ``units``.
    """
    units = dict(units or {})
    out = {}
    for effect, (x, sd) in groups.items():
        x = np.asarray(x, float).reshape(np.shape(x)[0], -1)
        sd = np.asarray(sd, float).ravel()
        xc = x - x.mean(0)
        params = {}
        for name, y in targets.items():
            y = np.asarray(y, float).ravel()
            beta, *_ = np.linalg.lstsq(xc, y - y.mean(), rcond=None)
            shift = float(np.sqrt(np.sum((beta * sd) ** 2)))
            y_sd = float(y.std(ddof=1))
            params[name] = {"shift": shift,
                            "shift_in_sd": shift / y_sd if y_sd > 0 else None,
                            "units": units.get(name, "")}
        out[effect] = {"modelled": True, "parameters": params}
    return out
