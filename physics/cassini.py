"""The Moon's Cassini state (Cassini 1693; Colombo 1966; Peale 1969, AJ 74, 483).

Cassini's laws: the Moon turns once per month about an axis that keeps a fixed angle I ≈ 1.54°
to the ecliptic pole; the orbit normal (5.15° from the ecliptic pole) circles that pole in 18.6
years, and the spin axis follows it so that the three normals stay in one plane, with the
ecliptic pole between the other two (Cassini state 2).

Peale's equation, derived here for a synchronous Moon. Let ŝ be the spin (C) axis, n̂ the orbit
normal, k̂ the ecliptic pole, θ the angle ŝ–n̂ and I the angle ŝ–k̂ (θ = i + I in state 2).

1. The Earth's potential energy on the Moon, V = (3GM⊕/2r³) r̂ᵀ I r̂ + const (MacCullagh, Euler
   §815), averaged over a month with the long axis A locked on the mean Earth (body angle φ = u,
   the argument of latitude from the node on the Moon's equator): with r̂ = cos u ê₁ + sin u ê₂,
   ê₂ = cos θ ê₂′ + sin θ ẑ, one finds ⟨(r̂·x)²⟩ = (1 + c)²/4 + (1 − c)²/8, ⟨(r̂·y)²⟩ = (1 − c)²/8,
   ⟨(r̂·z)²⟩ = (1 − c²)/2 (c = cos θ), so
        ⟨V⟩ = K⊕ [(C − A)(1 − c²)/2 + (B − A)(1 − c)²/8] + const,   K⊕ = (3/2) GM⊕⟨r⁻³⟩.
2. A potential V(ŝ·n̂) turns the body with τ = −ŝ × ∇V = −V′(c) ŝ × n̂; with L = Cω ŝ,
        dŝ/dt = (K⊕/(Cω)) [(C − A) c + (B − A)(1 − c)/4] (ŝ × n̂).
   The Sun (not synchronous: its average takes A′ = (A + B)/2 about the spin) adds
        dŝ/dt = (K☉/(Cω)) (C − A′) cos I (ŝ × k̂).
3. In the frame turning with the node (rate g < 0 about k̂) the state is fixed when
   dŝ/dt = g k̂ × ŝ. All three vectors lie in one plane (Cassini's third law); the component
   normal to it gives, with k̂ × ŝ = −sin I ê⊥ and ŝ × n̂ = sin θ ê⊥,

        (|g| − K☉ (C − A′)/(Cω) cos I) sin I = K⊕/(Cω) [(C − A) cos θ + (B − A)(1 − cos θ)/4] sin θ.

   For the Moon the (B − A) term is (1 − cos θ)/4 ≈ 0.002 of the (C − A) one: the obliquity is
   set by β, the node's period and the Earth's torque.

The simulation (scenarios/cassini.py) integrates the rigid Moon under the Earth and the Sun with
every monthly term, which none of the averaging above assumes, and measures the mean obliquity.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq


def peale_residual(I, inclination, node_rate, k_earth, k_sun, moments):
    """The Cassini-state equation above, left minus right side (rad/day): zero at the equilibrium
    obliquity I (rad, state 2; a number or an array). node_rate g (rad/day, < 0 for a regressing
    node), k_earth = (3/2)GM⊕⟨r⁻³⟩/ω and k_sun = (3/2)GM☉⟨r⁻³⟩/ω (rad/day), moments (A, B, C)."""
    A, B, C = moments
    th = inclination + I
    lhs = (abs(node_rate) - k_sun * (C - 0.5 * (A + B)) / C * np.cos(I)) * np.sin(I)
    rhs = k_earth * ((C - A) / C * np.cos(th) + (B - A) / C * (1 - np.cos(th)) / 4) * np.sin(th)
    return lhs - rhs


def peale_obliquity(inclination, node_rate, k_earth, k_sun, moments) -> float | None:
    """The equilibrium obliquity I (rad) of Cassini state 2: the first root of `peale_residual`
    between 0 and 180° − i (the Moon's lies near 1.5°); None when there is none (a figure too weak
    for its node's regression: the spin cannot keep up with the orbit plane)."""
    f = lambda I: peale_residual(I, inclination, node_rate, k_earth, k_sun, moments)  # noqa: E731
    grid = np.linspace(1e-12, math.pi - inclination - 1e-9, 2001)
    values = f(grid)  # the residual takes arrays: the whole grid at once
    change = np.flatnonzero(np.sign(values[:-1]) * np.sign(values[1:]) <= 0)
    if len(change) == 0:
        return None
    j = int(change[0])
    if values[j] == 0.0:
        return float(grid[j])
    return brentq(f, grid[j], grid[j + 1], xtol=1e-15)


def torque_coefficient(gm, mean_inverse_cube, spin) -> float:
    """(3/2) GM⟨r⁻³⟩/ω (rad per time unit of GM and ω)."""
    return 1.5 * gm * mean_inverse_cube / spin


def cassini_frame(node, latitude_argument, obliquity):
    """Quaternions (N, 4), body → ecliptic, of a Moon in Cassini state 2 turning uniformly: its
    equator's descending node on the orbit's ascending node `node`, tilted by `obliquity`, the long
    axis on the mean Earth (body x toward the Earth when the Moon is at argument of latitude F,
    i.e. turned by F + π): Rz(Ω) Rx(−I) Rz(F + π) (Meeus ch. 53's frame)."""
    from . import quaternion as quat

    node = np.atleast_1d(np.asarray(node, float))
    F = np.atleast_1d(np.asarray(latitude_argument, float))
    n = len(node)
    z = np.broadcast_to([0.0, 0.0, 1.0], (n, 3))
    x = np.broadcast_to([1.0, 0.0, 0.0], (n, 3))
    q1 = quat.from_axis_angle(z, node)
    q2 = quat.from_axis_angle(x, np.full(n, -float(obliquity)))
    q3 = quat.from_axis_angle(z, F + np.pi)
    return quat.multiply(quat.multiply(q1, q2), q3)


def out_of_plane(s, n, k):
    """Signed angle (rad) of ŝ out of the plane of n̂ and k̂ (Cassini's third law: zero), (N,)."""
    p = np.cross(k, n)
    p = p / np.linalg.norm(p, axis=-1, keepdims=True)
    return np.arcsin(np.clip(np.sum(s * p, axis=-1), -1, 1))


def side_of_pole(s, n, k):
    """+1 where ŝ and n̂ lie on opposite sides of k̂ in their plane (state 2), −1 on the same side."""
    a = np.cross(k, n)
    b = np.cross(k, s)
    return -np.sign(np.sum(a * b, axis=-1))
