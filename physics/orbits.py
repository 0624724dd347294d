"""Where the centre of force F is, seen from the body's centre (Euler §825, §833).

Each orbit object has `position(t)` → (N,3) inertial vector from the body to F, usable
directly as `PointMass.position` in `physics.integrator`. Times may be any array.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .params import ParameterError


@dataclass(frozen=True)
class CircularOrbit:
    """§825: F moves uniformly on a circle of radius `radius` in the XY plane (normal to the
    body's C axis), at angular rate `rate` (Euler's δ), at angle `phase` when t = 0."""

    radius: float = 1.0
    rate: float = 1.0
    phase: float = 0.0

    def longitude(self, t):
        return self.phase + self.rate * np.asarray(t, float)

    def distance(self, t):
        return np.full(np.shape(t), float(self.radius))

    def position(self, t):
        lam = self.longitude(t)
        return self.radius * np.stack([np.cos(lam), np.sin(lam), np.zeros_like(lam)], axis=-1)


def solve_kepler(M, e, tol=1e-15, max_iter=50):
    """Eccentric anomaly E with E − e sin E = M, vectorised (Newton from a cubic-safe start).
    Valid for 0 ≤ e < 1; converges to round-off in a handful of iterations."""
    M = np.asarray(M, float)
    if not (0.0 <= e < 1.0):
        raise ParameterError("eccentricity", e, "allowed range [0, 1)")
    Mr = np.remainder(M + np.pi, 2.0 * np.pi) - np.pi  # reduce to [-π, π)
    E = Mr + e * np.sin(Mr) / (1.0 - np.sin(Mr + e) + np.sin(Mr)) if e > 0.8 else Mr + e * np.sin(Mr)
    for _ in range(max_iter):
        f = E - e * np.sin(E) - Mr
        dE = f / (1.0 - e * np.cos(E))
        E = E - dE
        if np.all(np.abs(dE) < tol):
            break
    return E + (M - Mr)


@dataclass(frozen=True)
class KeplerOrbit:
    """§833: F on a Keplerian ellipse about the body (semi-major axis a, eccentricity e, mean
    motion n, periapse at t = t_peri), in a plane tilted by `inclination` about the line of
    nodes at longitude `node`, periapse at `argp` from the node.

    Euler's parametrisation XF = δt + α sin At, 1/s³ = (1 + β cos At)/f³ is this orbit to
    first order in e with δ = A = n, α = 2e, β = 3e (true anomaly f = M + 2e sin M +
    (5/4)e² sin 2M + O(e³); (a/r)³ = 1 + 3e cos M + O(e²))."""

    a: float = 1.0
    e: float = 0.0
    n: float = 1.0
    t_peri: float = 0.0
    inclination: float = 0.0
    node: float = 0.0
    argp: float = 0.0

    def __post_init__(self):
        if not (0.0 <= self.e < 1.0):
            raise ParameterError("eccentricity", self.e, "allowed range [0, 1)")

    def mean_anomaly(self, t):
        return self.n * (np.asarray(t, float) - self.t_peri)

    def anomalies(self, t):
        """(true anomaly f, distance r) at t."""
        E = solve_kepler(self.mean_anomaly(t), self.e)
        e = self.e
        f = 2.0 * np.arctan2(np.sqrt(1 + e) * np.sin(E / 2), np.sqrt(1 - e) * np.cos(E / 2))
        # keep f continuous (same number of turns as M)
        M = self.mean_anomaly(t)
        f = f + 2.0 * np.pi * np.round((M - f) / (2.0 * np.pi))
        return f, self.a * (1.0 - e * np.cos(E))

    def true_anomaly(self, t):
        return self.anomalies(t)[0]

    def distance(self, t):
        return self.anomalies(t)[1]

    def longitude(self, t):
        """Angle of F in its orbital plane from the line of nodes: argp + f (continuous)."""
        return self.argp + self.true_anomaly(t)

    def position(self, t):
        f, r = self.anomalies(t)
        u = self.argp + f
        ci, si = np.cos(self.inclination), np.sin(self.inclination)
        cn, sn = np.cos(self.node), np.sin(self.node)
        xo, yo = r * np.cos(u), r * np.sin(u)
        return np.stack([cn * xo - sn * ci * yo, sn * xo + cn * ci * yo, si * yo], axis=-1)

    def true_anomaly_dd(self, t):
        """d²f/dt² (the forcing of the libration, §833): ḟ = n(1+e cos f)²/(1−e²)^{3/2},
        f̈ = −2n²e sin f (1+e cos f)³/(1−e²)³."""
        f, _ = self.anomalies(t)
        e = self.e
        return -2.0 * self.n**2 * e * np.sin(f) * (1 + e * np.cos(f)) ** 3 / (1 - e * e) ** 3

    def true_anomaly_rate(self, t):
        f, _ = self.anomalies(t)
        e = self.e
        return self.n * (1 + e * np.cos(f)) ** 2 / (1 - e * e) ** 1.5
