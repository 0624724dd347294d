"""Euler's equations of motion and the kinematics of the attitude (ch. 15, §798–811).

Euler's §808 (and §813) in his notation, with x, y, z = γ'cos α, γ'cos β, γ'cos γ the
components of the angular velocity on the principal axes and Maa, Mbb, Mcc the moments:

    dx + (cc − bb)/aa · yz dt = 2gP dt/(Maa)   and cyclic,

which is today's A ω̇₁ = (B − C) ω₂ω₃ + P (the factor 2g is Euler's unit of force).

Text errors found while deriving (English translation of §803–813):
- §803: all three equations carry "2gP dt" on the left; the second and third must have Q and R
  (the moments about IB and IC), as §808 and §810 have.
- §806: "cos α = P/aa · √(PP/a⁴ + QQ/b⁴ + RR/c⁴)" must be divided by the root, not multiplied.
- §810: "dl sin l = dt(y cos n − z sin m)" must read z cos m (as §809 has).
- §809: "dν sin² n = −γ'dt(cos α cos l + cos α cos m)": the second term is cos β cos m.
- §813: "AD = α, BD = β" are the arcs AO, BO to the pole of rotation O.
"""
from __future__ import annotations

import numpy as np

from . import quaternion as quat


def omega_dot(omega, inertia, torque=(0.0, 0.0, 0.0)):
    """Body angular acceleration from Euler's equations (§798, §808):
    A ω̇₁ = (B − C) ω₂ω₃ + P, B ω̇₂ = (C − A) ω₃ω₁ + Q, C ω̇₃ = (A − B) ω₁ω₂ + R."""
    w = np.asarray(omega, float)
    I = np.asarray(inertia, float)
    L = I * w
    return (np.cross(L, w) + np.asarray(torque, float)) / I


def quaternion_dot(q, omega_body):
    """dq/dt = ½ q ⊗ (0, ω) for q rotating body vectors into the inertial frame (§809–811)."""
    w = np.asarray(omega_body, float)
    zero = np.zeros(w.shape[:-1] + (1,))
    return 0.5 * quat.multiply(q, np.concatenate([zero, w], axis=-1))


def direction_cosines_dot(pqr, omega_body):
    """Euler's §811: the cosines (p, q, r) of a fixed point Z on the body axes change as
    dp + dt(yr − zq) = 0 and cyclic, i.e. d(p,q,r)/dt = (p,q,r) × ω."""
    return np.cross(np.asarray(pqr, float), np.asarray(omega_body, float))


def kinetic_energy(omega_body, inertia):
    """Half of Euler's vis viva, §803: M γ'²(aa cos²α + bb cos²β + cc cos²γ)/2 = ½ Σ Iᵢωᵢ²."""
    w = np.asarray(omega_body, float)
    return 0.5 * np.sum(np.asarray(inertia, float) * w * w, axis=-1)


def angular_momentum_body(omega_body, inertia):
    return np.asarray(inertia, float) * np.asarray(omega_body, float)


def rhs_state(t, y, inertia, torque_body=None):
    """Right-hand side for y = (ω₁, ω₂, ω₃, q_w, q_x, q_y, q_z), for scipy's solve_ivp.

    `torque_body(t, q, omega)` returns the body-frame torque, or None for free motion.
    This is the independent reference the tests and benchmarks compare against.
    """
    w = y[:3]
    q = y[3:]
    tau = np.zeros(3) if torque_body is None else torque_body(t, q, w)
    return np.concatenate([omega_dot(w, inertia, tau), quaternion_dot(q, w)])
