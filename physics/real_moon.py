"""The Moon against JPL's ephemeris: frames, Euler angles and the model of the Moon compared.

JPL's DE ephemerides integrate the Moon's rotation beside the orbits and publish it as three
Euler angles (φ, θ, ψ), a 3-1-3 sequence from the ICRF to the Moon's principal axes (PA): the
body's axes in the ICRF are the columns of Rz(φ) Rx(θ) Rz(ψ). Their time derivatives give the
body's angular velocity (Euler's kinematic relations of §809–812 for this sequence):

    ω_body = (φ̇ sin θ sin ψ + θ̇ cos ψ,  φ̇ sin θ cos ψ − θ̇ sin ψ,  φ̇ cos θ + ψ̇).

theoria's frame is the J2000 ecliptic (X to the equinox, Z to the ecliptic pole): an ICRF
vector is turned by −ε₀ about X (the frame bias of ~0.02″ between the ICRF and the J2000 mean
equator is left out: it turns the positions and the attitudes alike and cancels in every
comparison made here).

The model compared (what `moon` integrates with DE421's Earth and Sun):
- the quadrupole (β, γ) and the degree-3 field of the Moon (physics.gravity_field) under the
  Earth, and the quadrupole under the Sun;
- a fluid core that does not follow the mantle (DE421: C_core/C = 0.0007, core–mantle friction
  K/C = 1.5e-8 per day, i.e. a coupling time of ~180,000 years against a precession period of
  18.6 years and a free libration of 2.9 years): the mantle turns alone, with moments
  (A − C_core, B − C_core, C − C_core). A spherical core removes an isotropic part, so the
  torques (which depend on differences of moments) are unchanged; only the inertia that turns is
  smaller, by 0.07% (which moves the Cassini obliquity by ~5″).
What it leaves out: the Moon's elastic tides (Love number k2 = 0.0216 with a 0.108-day lag; the
tide raised by the Earth points at the Earth and so takes no torque from it, its lag and the
spin's own flattening act at the level of the arcsecond), core–mantle friction, the Earth's own
figure acting on the Moon's (a 3e-7 share of the torque), the degree-4 field (~1e-3 of the
degree-3 torque) and the planets' direct torques.
"""
from __future__ import annotations

import math

import numpy as np

from . import constants as C
from . import quaternion as quat
from .constants import ARCSEC_RAD

# an ICRF vector into the J2000 ecliptic: turned by −ε₀ about X
Q_ECLIPTIC_FROM_ICRF = quat.from_axis_angle([1.0, 0.0, 0.0], -C.OBLIQUITY_J2000_RAD)


def ecliptic_from_icrf(v):
    """(..., 3) ICRF vectors in the J2000 ecliptic frame."""
    return quat.rotate(Q_ECLIPTIC_FROM_ICRF, np.asarray(v, float))


def euler313_quaternion(phi, theta, psi):
    """Attitude (body → frame of the angles) of the 3-1-3 Euler angles: Rz(φ) Rx(θ) Rz(ψ), (N, 4)."""
    phi, theta, psi = (np.atleast_1d(np.asarray(a, float)) for a in (phi, theta, psi))
    z = np.zeros_like(phi)

    def qz(a):
        return np.stack([np.cos(a / 2), z, z, np.sin(a / 2)], -1)

    qx = np.stack([np.cos(theta / 2), np.sin(theta / 2), z, z], -1)
    return quat.multiply(quat.multiply(qz(phi), qx), qz(psi))


def euler313_omega_body(angles, rates):
    """Body-frame angular velocity (N, 3) of the 3-1-3 angles (φ, θ, ψ) with rates (φ̇, θ̇, ψ̇)."""
    phi, th, psi = (np.atleast_1d(np.asarray(a, float)) for a in angles)
    dphi, dth, dpsi = (np.atleast_1d(np.asarray(a, float)) for a in rates)
    return np.stack([dphi * np.sin(th) * np.sin(psi) + dth * np.cos(psi),
                     dphi * np.sin(th) * np.cos(psi) - dth * np.sin(psi),
                     dphi * np.cos(th) + dpsi], -1)


def _frame_rotation(axis: int, angle: float) -> np.ndarray:
    """The frame rotation R_axis(angle) (vector components in a frame turned by +angle)."""
    c, s = math.cos(angle), math.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    m = np.eye(3)
    m[i, i] = m[j, j] = c
    m[i, j], m[j, i] = s, -s
    return m


def pa_to_me_matrix(angles_mas=C.MOON_PA_TO_ME_DE421_MAS) -> np.ndarray:
    """v_ME = M v_PA: DE421's principal-axis frame to its mean-Earth frame (constants: the
    rotations about z, y, x of JPL's lunar frame memo, moon_080317.tf, in milliarcseconds)."""
    a, b, c = (x * 1e-3 * ARCSEC_RAD for x in angles_mas)
    return _frame_rotation(0, -c) @ _frame_rotation(1, -b) @ _frame_rotation(2, -a)


def attitude_difference(q, q_ref):
    """The small rotation taking the reference attitude to q, as a rotation vector on the
    reference's body axes (N, 3) in radians: x, y tilt the pole (a tilt of the body's C axis by
    hypot(x, y)), z turns the body about its pole (longitude)."""
    d = quat.multiply(quat.conjugate(q_ref), q)
    d = d * np.where(d[..., :1] < 0, -1.0, 1.0)
    v = d[..., 1:]
    s = np.linalg.norm(v, axis=-1, keepdims=True)
    ang = 2 * np.arctan2(s, d[..., :1])
    return np.divide(v * ang, s, out=np.zeros_like(v), where=s > 0)


def mantle_moments(beta, gamma, core_fraction=0.0):
    """Moments of the part of the Moon that turns, scaled to its own polar moment 1, and the
    factor that converts the whole Moon's M R² / C into the same scale: ((A, B, C)/C_m, C/C_m).
    β = (C − A)/B, γ = (B − A)/C of the whole Moon; a spherical fluid core of polar moment
    core_fraction·C that does not turn with the mantle takes core_fraction·C off each moment."""
    A = (1.0 - beta * gamma) / (1.0 + beta)
    I = np.array([A, A + gamma, 1.0])  # C = 1
    f = float(core_fraction)
    return (I - f) / (1.0 - f), 1.0 / (1.0 - f)
