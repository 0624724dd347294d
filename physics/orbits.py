"""Where the centre of force F is, seen from the body's centre (Euler §825, §833).

Each orbit object has `position(t)` → (N,3) inertial vector from the body to F, usable
directly as `PointMass.position` in `physics.integrator`. Times may be any array.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import kepler


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
        kepler.check_eccentricity(self.e)

    def mean_anomaly(self, t):
        return self.n * (np.asarray(t, float) - self.t_peri)

    def anomalies(self, t):
        """(true anomaly f, distance r) at t; f is continuous (it has the mean anomaly's turns)."""
        _, f, r = kepler.anomalies(self.mean_anomaly(t), self.e)
        return f, self.a * r

    def anomalies_at(self, t: float) -> tuple[float, float]:
        """`anomalies` at one time t, as two floats: the compiled scalar functions (~2 µs), for the
        right-hand side of an ODE solver (the array path costs ~30 µs for a single value)."""
        E = kepler.eccentric_anomaly_scalar(self.n * (float(t) - self.t_peri), self.e)
        return kepler.true_anomaly_scalar(E, self.e), self.a * kepler.radius_scalar(E, self.e)

    def true_anomaly(self, t):
        return self.anomalies(t)[0]

    def distance(self, t):
        return self.anomalies(t)[1]

    def longitude(self, t):
        """Angle of F in its orbital plane from the line of nodes: argp + f (continuous)."""
        return self.argp + self.true_anomaly(t)

    def position(self, t):
        return kepler.position(self.mean_anomaly(t), self.a, self.e, self.inclination, self.node, self.argp)

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
