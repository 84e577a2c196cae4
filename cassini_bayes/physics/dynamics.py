"""Rigid spacecraft with reaction wheels: equations of motion, fixed-step integrator (pure JAX).

Equations (body axes, docs/design.md §6; Feldman & Lee (2006) §III and Lee Eq 10):

    I ω̇ + ω × (I ω + H_w) + Ḣ_w = T_thr + T_ext,      H_w = Σ_k J_k ρ_k g_k,
    J_k (ρ̇_k + g_k · ω̇) = u_k                           (wheel k, motor torque u_k, N m),
    Ȧ = −[ω×] A                                          (attitude, A = dcm(q), inertial → body).

``I`` is the whole spacecraft's inertia about its centre of mass *including* the wheels, ``ρ_k``
the spin rate (rad/s) of wheel ``k`` about its unit axis ``g_k`` relative to the body and ``J_k``
its spin inertia, so that ``I ω + H_w`` is the total body-axis momentum of Feldman & Lee Eq 3.

State and integrator
--------------------
The state is ``(q, H_N, h)``: the attitude quaternion, the total angular momentum in *inertial*
axes ``H_N = Aᵀ (I ω + H_w)`` (N m s) and each wheel's absolute axial momentum
``h_k = J_k (ρ_k + g_k·ω)`` (N m s). In these variables the equations read

    Ḣ_N = Aᵀ (T_thr + T_ext,B) + T_ext,N,     ḣ_k = u_k,
    ω = I_s⁻¹ (A H_N − Σ_k h_k g_k),           I_s = I − Σ_k J_k g_k g_kᵀ,

so the rates are algebraic functions of the state. One step of length ``dt`` with motor torques and
thruster/external torques held (zero-order hold, as the flight software commands them):

* ``h`` and the constant external inertial torque are integrated exactly;
* the attitude increment ``φ`` (rotation vector, ``q(t+dt) = rotvec_to_quat(φ) ⊗ q(t)``) is found
  by a Runge-Kutta-Munthe-Kaas step of order 4 on ``φ̇ = dexp⁻¹_φ(ω)``;
* the body-axis impulse of the step (thrusters: the exact integral of the pulse profile over the
  step) is rotated to inertial axes with the attitude at mid-step;
* inside the step the RK stages see the momentum the body impulse has delivered by their time:
  the exact impulse to mid-step when the caller gives it (a pulse's profile is not linear over a
  step: its delay and fall put a tail into the next step), else half of the step's.

Consequences used by the tests: without torques ``H_N`` is constant to round-off (the conservation
the inertia method relies on); with torques ``ΔH_N`` equals the accumulated inertial impulse
exactly;
the attitude converges with order 4 in ``dt``.
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
from jax import Array

from cassini_bayes.frames import dcm, quat_multiply, quat_normalize, rotvec_to_quat

__all__ = [
    "Plant",
    "DynState",
    "make_plant",
    "body_rate",
    "wheel_rates",
    "state_from_rates",
    "step",
]


class Plant(NamedTuple):
    """Mass properties of the simulated (true) spacecraft; every field may be traced.

    Attributes
    ----------
    inertia : (3, 3) total inertia about the centre of mass incl. wheels, body axes, kg m².
    wheel_axes : (k, 3) unit spin axes, body axes.
    wheel_inertias : (k,) spin inertias, kg m².
    inertia_s_inv : (3, 3) ``(I − Σ J g gᵀ)⁻¹``, 1/(kg m²).
    """

    inertia: Array
    wheel_axes: Array
    wheel_inertias: Array
    inertia_s_inv: Array


class DynState(NamedTuple):
    """Integrator state.

    Attributes
    ----------
    q : (4,) attitude quaternion, scalar last, inertial → body.
    h_inertial : (3,) total angular momentum in inertial axes, N m s.
    h_wheels : (k,) absolute axial momentum of each wheel ``J_k (ρ_k + g_k·ω)``, N m s.
    """

    q: Array
    h_inertial: Array
    h_wheels: Array


def make_plant(inertia: Array, wheel_axes: Array, wheel_inertias: Array) -> Plant:
    """Build a :class:`Plant`; ``inertia`` (3, 3) kg m², axes (k, 3), spin inertias (k,) kg m²."""
    inertia = jnp.asarray(inertia)
    g = jnp.asarray(wheel_axes)
    j = jnp.asarray(wheel_inertias)
    i_s = inertia - jnp.einsum("k,ki,kj->ij", j, g, g)
    return Plant(inertia, g, j, jnp.linalg.inv(i_s))


def _omega(plant: Plant, h_body: Array, h_wheels: Array) -> Array:
    """Body rate (rad/s) from the body-axis total momentum and the wheels' absolute momenta."""
    return plant.inertia_s_inv @ (h_body - h_wheels @ plant.wheel_axes)


def body_rate(state: DynState, plant: Plant) -> Array:
    """Body rate ω (rad/s, body axes) of a state."""
    return _omega(plant, dcm(state.q) @ state.h_inertial, state.h_wheels)


def wheel_rates(state: DynState, plant: Plant, omega: Array | None = None) -> Array:
    """Wheel spin rates ρ_k (rad/s) relative to the body (0 for a wheel with ``J_k = 0``)."""
    omega = body_rate(state, plant) if omega is None else omega
    j = plant.wheel_inertias
    # A wheel with zero spin inertia is not a separate degree of freedom (switched off, locked).
    absolute = jnp.where(j > 0, state.h_wheels / jnp.where(j > 0, j, 1.0), 0.0)
    return jnp.where(j > 0, absolute - plant.wheel_axes @ omega, 0.0)


def state_from_rates(q: Array, omega: Array, rho: Array, plant: Plant) -> DynState:
    """State from attitude, body rate ω (rad/s) and wheel rates ρ (rad/s relative to the body)."""
    q = quat_normalize(jnp.asarray(q))
    omega = jnp.asarray(omega)
    rho = jnp.asarray(rho)
    # Feldman & Lee Eq 3: H_N = Aᵀ (I ω + Σ J ρ g)
    h_body = plant.inertia @ omega + (plant.wheel_inertias * rho) @ plant.wheel_axes
    h_wheels = plant.wheel_inertias * (rho + plant.wheel_axes @ omega)
    return DynState(q, dcm(q).T @ h_body, h_wheels)


def _dexpinv(phi: Array, omega: Array) -> Array:
    """``φ̇`` of the rotation vector of ``q(t) = rotvec_to_quat(φ) ⊗ q0`` for body rate ω.

    Series of dexp⁻¹ on so(3) to third order in φ (|φ| ≲ 1e-2 rad per step here, so the
    truncation is below 1e-8 of the increment).
    """
    c = jnp.cross(phi, omega)
    return omega + 0.5 * c + jnp.cross(phi, c) / 12.0


def _rotate(phi: Array, v: Array) -> Array:
    """``dcm(rotvec_to_quat(φ)) @ v`` by Rodrigues' formula (the frame turns by φ):
    ``v − (sin θ/θ) φ × v + ((1 − cos θ)/θ²) φ × (φ × v)``, with series near θ = 0."""
    th2 = jnp.sum(phi * phi)
    small = th2 < 1e-8
    th = jnp.sqrt(jnp.where(small, 1.0, th2))
    a = jnp.where(small, 1.0 - th2 / 6.0 + th2 * th2 / 120.0, jnp.sin(th) / th)
    b = jnp.where(small, 0.5 - th2 / 24.0 + th2 * th2 / 720.0, (1.0 - jnp.cos(th)) / (th * th))
    c = jnp.cross(phi, v)
    return v - a * c + b * jnp.cross(phi, c)


def step(state: DynState, plant: Plant, dt: float, motor_torque: Array,
         body_impulse: Array, inertial_torque: Array,
         body_impulse_half: Array | None = None) -> tuple[DynState, Array]:
    """Advance the state by ``dt`` seconds (see the module docstring).

    Parameters
    ----------
    state : the state at the start of the step.
    plant : true mass properties.
    dt : step, s.
    motor_torque : (k,) wheel motor torques ``u_k`` held over the step, N m (``ḣ_k = u_k``).
    body_impulse : (3,) angular impulse delivered in body axes over the step (thrusters plus any
        body-fixed external torque times ``dt``), N m s.
    inertial_torque : (3,) constant external torque in inertial axes, N m.
    body_impulse_half : (3,) the part of ``body_impulse`` delivered by mid-step, N m s (default
        half of it: an impulse spread evenly over the step).

    Returns
    -------
    (new_state, inertial_impulse) : the impulse (3,) actually added to ``H_N`` by
        ``body_impulse`` (rotated with the mid-step attitude), N m s.
    """
    a0 = dcm(state.q)
    if body_impulse_half is None:
        body_impulse_half = 0.5 * body_impulse
    # The momentum delivered inside the step by mid-step and by its end (body impulse rotated
    # at the start: a first guess, second order in the step's rotation).
    dh_half = a0.T @ body_impulse_half + inertial_torque * (0.5 * dt)
    dh_end = a0.T @ body_impulse + inertial_torque * dt

    def rate(phi, s, dh):
        h_body = _rotate(phi, a0 @ (state.h_inertial + dh))
        # I ω̇ + ω × (I ω + H_w) + Ḣ_w = T  in the form ω = I_s⁻¹ (A H_N − Σ h_k g_k)
        return _omega(plant, h_body, state.h_wheels + (s * dt) * motor_torque)

    # Runge-Kutta-Munthe-Kaas, classical RK4 tableau on φ̇ = dexp⁻¹_φ(ω(φ, t)).
    k1 = _dexpinv(jnp.zeros(3), rate(jnp.zeros(3), 0.0, 0.0))
    k2 = _dexpinv(0.5 * dt * k1, rate(0.5 * dt * k1, 0.5, dh_half))
    k3 = _dexpinv(0.5 * dt * k2, rate(0.5 * dt * k2, 0.5, dh_half))
    k4 = _dexpinv(dt * k3, rate(dt * k3, 1.0, dh_end))
    phi = (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    q1 = quat_normalize(quat_multiply(rotvec_to_quat(phi), state.q))
    # A(q_mid)ᵀ b with A(q_mid) = R(φ/2) A0, and R(φ/2)ᵀ b = R(−φ/2) b
    impulse_n = a0.T @ _rotate(-0.5 * phi, body_impulse)
    new = DynState(q1, state.h_inertial + impulse_n + inertial_torque * dt,
                   state.h_wheels + motor_torque * dt)
    return new, impulse_n
