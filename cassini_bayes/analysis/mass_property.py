"""Monte Carlo mass-property analysis of the RWA4 spin-axis calibration (Brown 2012 §III.B).

The RCS method (Brown Eq 1) finds the RWA4 spin axis from the change of the spacecraft's momentum
when RWA4 spins up while the body drifts freely. Over a short drift (attitude nearly constant) Eq 1
reduces to momentum conservation in body axes,

    I Δω = −J Δρ u,

and the calibration solves it with the *assumed* inertia Î (the current best estimate), so

    û ∝ −Î Δω / (J Δρ) = Î I⁻¹ u        (then normalised).

The extra error the method suffers from mass-property uncertainty is the angle between û and u.
Brown ran two Monte Carlo analyses of it: (1) Î varied "randomly within the stated uncertainties" of
the pre-launch mass-properties report, and (2) Î varied over "the full range of spacecraft inertia
properties that were measured from flight telemetry"; both gave at most 1.5°, which with the 1.4°
worst testbed error gives < 3° in total.

Here:

* analysis 1 draws Î = I + δ with the moments perturbed by a fraction within ±``moi`` (±10 %) and
  the products within ±``poi`` kg m² (±75 kg m²) — the knowledge requirements of Feldman & Lee §IV,
  which are the stated uncertainties available to us;
* analysis 2 draws the perturbation over the range of the prediction − flight-estimate differences
  observed in Feldman & Lee Table 1 (moments as Eq 12 fractions, products as Eq 13 kg m²), each
  element independently between the smallest and the largest observed difference;
* the perturbation of each element is ``"uniform"`` over its interval (default; "varied randomly
  within the stated uncertainties") or ``"normal"`` with the interval as ±3σ about its centre;
* :func:`mass_property_mc_posterior` replaces the box by an inertia posterior: the assumed
  inertia is the posterior mean and the true one each posterior draw (docs/budgets.md);
* the true axis ``u`` is drawn on RWA4's articulation cone (54.7356° from +Z, articulation angle
  uniform over an interval; RWA1 is at 90°) or fixed at the RWA1 axis.

Everything is one vectorised JAX function of a key: 10⁵ draws take milliseconds
(``benchmarks/bench_mass_property.py``). Inertias in kg m², angles in radians inside.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import Any, Literal, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from cassini_bayes.analysis.paper_facts import (
    INERTIA_2000_ESTIMATED,
    INERTIA_2000_PREDICTED,
    TABLE1,
)

__all__ = [
    "ARTICULATION_CONE_RAD",
    "RWA1_PHI_RAD",
    "PerturbationBox",
    "requirement_box",
    "flight_estimate_box",
    "axis_on_cone",
    "inertia_matrix",
    "rcs_axis_error_rad",
    "sample_assumed_inertia",
    "MassPropertyDraws",
    "mass_property_mc",
    "mass_property_mc_posterior",
    "ErrorSummary",
    "summarise_errors",
    "plot_mass_property",
]

# Brown (2012) §I: RWA4 is canted cos⁻¹(1/√3) = 54.7356° from its articulation axis (+Z).
ARTICULATION_CONE_RAD = float(np.arccos(1.0 / np.sqrt(3.0)))
# Articulation angle (from +X about +Z) of the RWA1 axis [0, √(2/3), √(1/3)] on that cone.
RWA1_PHI_RAD = float(np.pi / 2)


class PerturbationBox(NamedTuple):
    """Intervals of the perturbation ``Î − I`` of each inertia element.

    Moments (Ixx, Iyy, Izz) are perturbed by a fraction of the true moment, products (Ixy, Ixz, Iyz)
    by an absolute amount.

    Attributes
    ----------
    moi_low, moi_high : (3,) fractional perturbation interval of the moments.
    poi_low, poi_high : (3,) perturbation interval of the products, kg m².
    """

    moi_low: np.ndarray
    moi_high: np.ndarray
    poi_low: np.ndarray
    poi_high: np.ndarray

    def scaled(self, factor: float) -> "PerturbationBox":
        """The box with every interval scaled by ``factor`` about zero."""
        return PerturbationBox(*(np.asarray(b, float) * factor for b in self))

    def only(self, element: int) -> "PerturbationBox":
        """The box with every element but ``element`` (0-5: Ixx Iyy Izz Ixy Ixz Iyz) held at 0."""
        keep = np.arange(6) == element
        lo = np.where(keep, np.concatenate([self.moi_low, self.poi_low]), 0.0)
        hi = np.where(keep, np.concatenate([self.moi_high, self.poi_high]), 0.0)
        return PerturbationBox(lo[:3], hi[:3], lo[3:], hi[3:])

    def to_dict(self) -> dict[str, list[float]]:
        return {k: np.asarray(v, float).tolist() for k, v in self._asdict().items()}


def requirement_box(moi_fraction: float = 0.10, poi_kgm2: float = 75.0) -> PerturbationBox:
    """Symmetric box of the pre-launch knowledge requirements (Feldman & Lee §IV: ±10 %, ±75)."""
    m, p = np.full(3, float(moi_fraction)), np.full(3, float(poi_kgm2))
    return PerturbationBox(-m, m, -p, p)


def _epoch_differences(epoch: str) -> tuple[np.ndarray, np.ndarray]:
    if epoch == "march_2000":  # Feldman & Lee Eq 1 (prediction) vs Eq 8 (flight estimate)
        pred, est = np.asarray(INERTIA_2000_PREDICTED), np.asarray(INERTIA_2000_ESTIMATED)
    else:
        pred = np.asarray(TABLE1[epoch]["pred"], float)
        est = np.asarray(TABLE1[epoch]["est"], float)
    # Feldman & Lee Eq 12 (moments, fraction of the prediction) and Eq 13 (products, kg m^2)
    return (pred[:3] - est[:3]) / pred[:3], pred[3:] - est[3:]


def flight_estimate_box(epochs=("pre_soi", "post_prm", "post_probe")) -> PerturbationBox:
    """Box spanned by the observed prediction − flight-estimate differences.

    ``epochs`` names columns of Feldman & Lee Table 1 (``pre_soi``, ``post_prm``, ``post_probe``)
    and/or ``march_2000`` (Eq 1 vs Eq 8). Each element's interval runs from the smallest to the
    largest observed difference (Eq 12 fractions for moments, Eq 13 kg m² for products).
    """
    if not epochs:
        raise ValueError("flight_estimate_box needs at least one epoch")
    known = (*TABLE1, "march_2000")
    for e in epochs:
        if e not in known:
            raise ValueError(f"unknown epoch {e!r}; known: {', '.join(known)}")
    moi, poi = zip(*(_epoch_differences(e) for e in epochs))
    moi, poi = np.stack(moi), np.stack(poi)
    return PerturbationBox(moi.min(0), moi.max(0), poi.min(0), poi.max(0))


@jax.jit
def axis_on_cone(phi_rad, cone_rad: float = ARTICULATION_CONE_RAD) -> Array:
    """Unit spin axis (body) at articulation angle ``phi_rad`` on the cone ``cone_rad`` from +Z.

    ``phi_rad`` (...,) → (..., 3). ``phi = π/2`` on the 54.7356° cone is the RWA1 axis.
    """
    phi = jnp.asarray(phi_rad)
    s, c = jnp.sin(cone_rad), jnp.cos(cone_rad)
    return jnp.stack([s * jnp.cos(phi), s * jnp.sin(phi), jnp.full_like(phi, c)], axis=-1)


def inertia_matrix(moments, products) -> Array:
    """Symmetric (..., 3, 3) tensor from (..., 3) moments (Ixx, Iyy, Izz) and products
    (Ixy, Ixz, Iyz)."""
    m, p = jnp.asarray(moments), jnp.asarray(products)
    xx, yy, zz = m[..., 0], m[..., 1], m[..., 2]
    xy, xz, yz = p[..., 0], p[..., 1], p[..., 2]
    rows = [jnp.stack([xx, xy, xz], -1), jnp.stack([xy, yy, yz], -1), jnp.stack([xz, yz, zz], -1)]
    return jnp.stack(rows, -2)


@jax.jit
def rcs_axis_error_rad(inertia_true, inertia_assumed, axis) -> Array:
    """Angle (rad) between the true RWA4 axis and the RCS-method estimate made with ``Î``.

    Brown (2012) Eq 1 over a short drift: ``I Δω = −J Δρ u``, solved with the assumed inertia, gives
    ``û ∝ Î I⁻¹ u``. Broadcasts: ``inertia_true`` (..., 3, 3), ``inertia_assumed`` (..., 3, 3),
    ``axis`` (..., 3) unit vectors. The angle is taken with ``atan2(|û × u|, û · u)``, exact near 0.
    """
    i_true = jnp.asarray(inertia_true)
    i_hat = jnp.asarray(inertia_assumed)
    u = jnp.asarray(axis)
    batch = jnp.broadcast_shapes(i_true.shape[:-2], i_hat.shape[:-2], u.shape[:-1])
    i_hat = jnp.broadcast_to(i_hat, (*batch, 3, 3))
    u = jnp.broadcast_to(u, (*batch, 3))
    # Brown (2012) Eq 1, small drift: body-rate change Δω = −(J Δρ) I⁻¹ u; estimate ∝ −Î Δω
    if i_true.ndim == 2:  # one true tensor (the Monte Carlo case): invert once (3×3, SPD)
        inv = jnp.linalg.inv(i_true).reshape((1,) * len(batch) + (3, 3))
        dw = jnp.sum(inv * u[..., None, :], axis=-1)
    else:
        i_true = jnp.broadcast_to(i_true, (*batch, 3, 3))
        dw = jnp.linalg.solve(i_true, u[..., None])[..., 0]
    u_hat = jnp.sum(i_hat * dw[..., None, :], axis=-1)  # elementwise: faster than a batched dot
    cross = jnp.linalg.norm(jnp.cross(u_hat, u), axis=-1)
    return jnp.arctan2(cross, jnp.sum(u_hat * u, axis=-1))


@partial(jax.jit, static_argnames=("n", "distribution"))
def sample_assumed_inertia(key, inertia_true, box: PerturbationBox, n: int,
                           distribution: Literal["uniform", "normal"] = "uniform") -> Array:
    """``n`` assumed tensors Î = I + δ, δ drawn element-wise over ``box`` (kg m²), (n, 3, 3).

    ``"uniform"``: each element uniform over its interval; ``"normal"``: normal with the interval as
    ±3σ about its centre.
    """
    i_true = jnp.asarray(inertia_true)
    lo = jnp.concatenate([jnp.asarray(box.moi_low), jnp.asarray(box.poi_low)])
    hi = jnp.concatenate([jnp.asarray(box.moi_high), jnp.asarray(box.poi_high)])
    lo, hi = lo[None, :], hi[None, :]
    if distribution == "uniform":
        x = lo + (hi - lo) * jax.random.uniform(key, (n, 6))
    elif distribution == "normal":
        x = 0.5 * (lo + hi) + (hi - lo) / 6.0 * jax.random.normal(key, (n, 6))
    else:
        raise ValueError(f"distribution must be 'uniform' or 'normal', got {distribution!r}")
    moments = jnp.diagonal(i_true)[None, :] * (1.0 + x[:, :3])
    products = jnp.stack([i_true[0, 1], i_true[0, 2], i_true[1, 2]])[None, :] + x[:, 3:]
    return inertia_matrix(moments, products)


class MassPropertyDraws(NamedTuple):
    """One Monte Carlo analysis: per-draw articulation angle and extra axis error.

    Attributes
    ----------
    phi_rad : (n,) articulation angle of the true RWA4 axis (from +X about +Z), rad.
    error_rad : (n,) angle between the RCS estimate with Î and the true axis, rad.
    """

    phi_rad: Array
    error_rad: Array


@partial(jax.jit, static_argnames=("n", "distribution"))
def _mc(key, inertia_true, moi_low, moi_high, poi_low, poi_high, phi_low, phi_high, n,
        distribution):
    key_i, key_phi = jax.random.split(key)
    box = PerturbationBox(moi_low, moi_high, poi_low, poi_high)
    i_hat = sample_assumed_inertia(key_i, inertia_true, box, n, distribution)
    phi = jax.random.uniform(key_phi, (n,), minval=phi_low, maxval=phi_high)
    return MassPropertyDraws(phi, rcs_axis_error_rad(inertia_true, i_hat, axis_on_cone(phi)))


def mass_property_mc(key, inertia_true, box: PerturbationBox, n: int = 100_000, *,
                     phi_range_rad=(RWA1_PHI_RAD, RWA1_PHI_RAD),
                     distribution: Literal["uniform", "normal"] = "uniform") -> MassPropertyDraws:
    """Brown (2012) §III.B Monte Carlo: extra RWA4 axis error of the RCS method from ``Î ≠ I``.

    Parameters
    ----------
    key : jax.random key.
    inertia_true : (3, 3) true inertia, kg m².
    box : perturbation intervals of the assumed inertia (:func:`requirement_box`,
        :func:`flight_estimate_box`).
    n : number of draws.
    phi_range_rad : (low, high) articulation angles the true axis is drawn from uniformly, rad;
        a zero-width range (default, RWA1) fixes it.
    distribution : ``"uniform"`` or ``"normal"`` (interval = ±3σ), per element.

    Returns
    -------
    MassPropertyDraws
    """
    lo, hi = (float(x) for x in phi_range_rad)
    f = jnp.asarray
    return _mc(key, f(inertia_true, dtype=float), f(box.moi_low, dtype=float),
               f(box.moi_high, dtype=float), f(box.poi_low, dtype=float),
               f(box.poi_high, dtype=float), lo, hi, int(n), distribution)


def mass_property_mc_posterior(key, inertia_draws, inertia_assumed, n: int = 100_000, *,
                               phi_range_rad=(RWA1_PHI_RAD, RWA1_PHI_RAD)) -> MassPropertyDraws:
    """Brown's Monte Carlo fed from an inertia posterior instead of a box.

    The calibration assumes ``inertia_assumed`` (3, 3) (the posterior mean, what it would
    upload); the true inertia is each of ``n`` draws taken, with replacement, from
    ``inertia_draws`` (m, 3, 3) kg m² (the posterior); the true axis is drawn on the cone as in
    :func:`mass_property_mc`. Returns the extra RCS-method error of every draw.
    """
    key_i, key_phi = jax.random.split(key)
    draws = jnp.asarray(inertia_draws, dtype=float)
    idx = jax.random.choice(key_i, draws.shape[0], (int(n),), replace=True)
    lo, hi = (float(x) for x in phi_range_rad)
    phi = jax.random.uniform(key_phi, (int(n),), minval=lo, maxval=hi)
    err = rcs_axis_error_rad(draws[idx], jnp.asarray(inertia_assumed, dtype=float),
                             axis_on_cone(phi))
    return MassPropertyDraws(phi, err)


@dataclass(frozen=True)
class ErrorSummary:
    """Percentiles of an extra-error distribution, degrees."""

    n: int
    mean_deg: float
    p50_deg: float
    p95_deg: float
    p99_deg: float
    max_deg: float

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


def summarise_errors(error_rad) -> ErrorSummary:
    """Mean, 50/95/99th percentiles and maximum of ``error_rad`` (rad), in degrees."""
    e = np.degrees(np.asarray(error_rad, float))
    p50, p95, p99 = np.percentile(e, [50, 95, 99])
    return ErrorSummary(int(e.size), float(e.mean()), float(p50), float(p95), float(p99),
                        float(e.max()))


def plot_mass_property(analyses: dict[str, MassPropertyDraws], budget_deg: float = 1.5):
    """Figure: histogram of each analysis's extra error, and its 99th percentile vs articulation.

    ``analyses`` maps a label to its draws. Returns a matplotlib ``Figure``.
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 4.2), layout="constrained")
    ax0, ax1 = fig.subplots(1, 2)
    for label, d in analyses.items():
        e = np.degrees(np.asarray(d.error_rad))
        (_, _, patches) = ax0.hist(e, bins=80, density=True, histtype="step", lw=1.4, label=label)
        color = patches[0].get_edgecolor()
        ax0.axvline(np.percentile(e, 99), color=color, ls=":", lw=1)
        phi = np.degrees(np.asarray(d.phi_rad))
        if np.ptp(phi) > 0:
            edges = np.linspace(phi.min(), phi.max(), 25)
            idx = np.clip(np.digitize(phi, edges) - 1, 0, len(edges) - 2)
            p99 = [np.percentile(e[idx == k], 99) if np.any(idx == k) else np.nan
                   for k in range(len(edges) - 1)]
            ax1.plot(0.5 * (edges[1:] + edges[:-1]), p99, color=color, label=label)
    ax0.axvline(budget_deg, color="k", ls="--", lw=1, label=f"paper: ≤ {budget_deg:g}°")
    ax0.set(xlabel="extra RWA4 axis error (deg)", ylabel="density",
            title="Extra error from mass-property uncertainty (dotted: 99th percentile)")
    ax0.legend(fontsize=8)
    ax1.axhline(budget_deg, color="k", ls="--", lw=1)
    ax1.axvline(np.degrees(RWA1_PHI_RAD), color="grey", lw=0.8, ls=":")
    ax1.set(xlabel="articulation angle of the true axis (deg; RWA1 at 90°)",
            ylabel="99th percentile (deg)", title="99th percentile along the articulation cone")
    if ax1.lines:
        ax1.legend(fontsize=8)
    return fig
