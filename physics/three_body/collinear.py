"""Euler 1767, *De motu rectilineo trium corporum se mutuo attrahentium* (seed 003, §1–§11).

Three masses A, B, C on a line at x < y < z (units with G = 1). With p = y − x, q = z − y and
q = α p, the motions in which the ratio α stays fixed (§7) obey Euler's quintic (Eq. 33)

    (A+B)α⁵ + (3A+2B)α⁴ + (3A+B)α³ − (B+3C)α² − (2B+3C)α − (B+C) = 0,

which has one sign change, hence (Descartes) exactly one positive root (§8). Then p obeys the
radial Kepler equation p̈ = −(D/2)/p² with D/2 = A + B + C/(α+1)² − C/α² (§7, Eq. 34–35),
so the spacing can collapse from rest (Case II, §11: distances ∝ cos²φ, t ∝ φ + sinφ cosφ),
expand from a collision (Case I, §10), or — with angular momentum, which Euler does not write
but which the same α allows — turn rigidly (the collinear central configuration).

Errors in the translation, checked here by re-deriving from Eqs. (1)–(3):
- Eq. (17), (19), (22), (24), (27) and §7 carry "B ∓ C" or "B − C": the correct coefficient is
  B + C (q̈ = ż̈ − ÿ = A/p² − A/(p+q)² − (B+C)/q²). The quintic (33) itself is right.
- The translator's table for the Earth–Moon points (α1 = 0.17737, α2 = 0.167417,
  α3 = 1.00711; L1 = 326490 km, L2 = 448755 km, L3 = 381686 km) is slightly off: with its
  own inputs the root of the quintic is α = 0.177628, 0.167711, 1.007124, i.e. L1 = 326419 km,
  L2 = 448868 km, L3 = 381681 km — the table is off by +71, −113 and +5 km
  (`translator_table_errors`). With the IAU mass ratio 0.0123000371: 326381, 448915, 381675 km.
"""
from __future__ import annotations

import math

import numpy as np

from ..constants import EARTH_MOON_DISTANCE_KM

# The translator's "Applications" table (seed 003, end of §11): d = 384400 km (the usual mean
# distance, as ours), M_earth = 5.98e24 kg, M_moon = 7.34e22 kg.
TRANSLATOR_TABLE = {
    "distance_km": EARTH_MOON_DISTANCE_KM,
    "mass_earth_kg": 5.98e24,
    "mass_moon_kg": 7.34e22,
    "alpha": (0.17737, 0.167417, 1.00711),
    "L_km": (326490.0, 448755.0, 381686.0),
}



def quintic_coefficients(A: float, B: float, C: float) -> np.ndarray:
    """Coefficients (highest power first) of Euler's quintic, 1767 §7 Eq. (33)."""
    return np.array([A + B, 3 * A + 2 * B, 3 * A + B, -(B + 3 * C), -(2 * B + 3 * C), -(B + C)], float)


def sign_changes(coeffs) -> int:
    """Number of sign changes of the nonzero coefficients (Descartes' rule, §8)."""
    s = [np.sign(c) for c in coeffs if c != 0]
    return int(sum(1 for a, b in zip(s, s[1:]) if a != b))


def quintic_root(A: float, B: float, C: float) -> float:
    """The single positive root α = q/p of Euler's quintic (1767 §7–8).

    A, B, C ≥ 0 in the order they stand on the line, at most one of them zero (a massless body
    is the restricted problem). There is one sign change, so one positive root (Descartes);
    found by bisection-safe Brent iteration on a bracket, polished by Newton.
    """
    if min(A, B, C) < 0 or sum(1 for m in (A, B, C) if m > 0) < 2:
        raise ValueError("masses must be ≥ 0 with at most one zero")
    c = quintic_coefficients(A, B, C)
    f = np.poly1d(c)
    lo, hi = 0.0, 1.0
    while f(hi) <= 0:  # f(0) = −(B+C) < 0 unless B = C = 0 (excluded), f(∞) > 0
        hi *= 2.0
        if hi > 1e12:
            raise ValueError("no positive root found")
    from scipy.optimize import brentq

    return float(brentq(f, lo, hi, xtol=1e-15, rtol=1e-15, maxiter=200))


def kepler_constant(A: float, B: float, C: float, alpha: float) -> float:
    """D/2 = A + B + C/(α+1)² − C/α² (1767 §7, Eq. 34): p̈ = −(D/2)/p² along the motion."""
    return A + B + C / (alpha + 1) ** 2 - C / alpha**2


def positions_on_line(A: float, B: float, C: float, alpha: float, p: float) -> np.ndarray:
    """x, y, z of the three bodies with the centre of mass at 0 (1767 §2, Eqs. 8–10 with
    E = F = 0): x = −((B+C)p + Cq)/M, y = (Ap − Cq)/M, z = (Ap + (A+B)q)/M, q = αp."""
    M = A + B + C
    q = alpha * p
    return np.array([-((B + C) * p + C * q) / M, (A * p - C * q) / M, (A * p + (A + B) * q) / M])


def rotation_rate(A: float, B: float, C: float, alpha: float, p: float) -> float:
    """Angular velocity of the rigid collinear rotation with spacing p: Ω² = (D/2)/p³."""
    return math.sqrt(kepler_constant(A, B, C, alpha) / p**3)


def collapse_time(K: float, p0: float) -> float:
    """Case II (§11): time from rest at p0 to the collision, T = (π/2)·√(p0³/(2K))."""
    return 0.5 * math.pi * math.sqrt(p0**3 / (2 * K))


def homothetic_collapse(K: float, p0: float, phi):
    """Case II (1767 §11, Eqs. 51–55): bodies released from rest at spacing p0.

    With r = a sinφ, p = p0 cos²φ and t = n³a²(φ + sinφ cosφ); the scale is fixed by the radial
    Kepler equation p̈ = −K/p² (K = D/2), which gives n³a² = √(p0³/(2K)).
    Returns (t, p) for the given φ (0 ≤ φ < π/2)."""
    phi = np.asarray(phi, float)
    tau = math.sqrt(p0**3 / (2 * K))
    return tau * (phi + np.sin(phi) * np.cos(phi)), p0 * np.cos(phi) ** 2


def homothetic_expansion(K: float, energy: float, r_over_a):
    """Case I (1767 §10, Eqs. 46–50): expansion from a collision, p = n²(r² − a²),
    t = n³[r√(r²−a²) − a² ln((r + √(r²−a²))/a)].

    From ṗ = r/√p and p = n²(r² − a²): ṗ² = 1/n² + a²/p, so a² = 2K (D = a², §9) and
    1/n² = 2·energy (energy = ṗ²/2 − K/p > 0 per unit reduced mass). r/a ≥ 1. Returns (t, p)."""
    x = np.asarray(r_over_a, float)
    a = math.sqrt(2 * K)
    n = 1.0 / math.sqrt(2 * energy)
    r = a * x
    s = np.sqrt(np.maximum(r * r - a * a, 0.0))
    t = n**3 * (r * s - a * a * np.log((r + s) / a))
    return t, n * n * (r * r - a * a)


# --- the restricted problem: collinear points of a primary and a secondary -------------------

def lagrange_alphas(mass_ratio: float) -> tuple[float, float, float]:
    """α of the quintic for the three collinear points of a primary (1) and a secondary
    (mass_ratio), the third body massless (translator's application, after §11):

    L1 (between): order primary, 0, secondary → (A, B, C) = (1, 0, μ'), α = (sec − L1)/(L1 − pri)
    L2 (beyond the secondary): (1, μ', 0), α = (L2 − sec)/d
    L3 (beyond the primary): (0, 1, μ'), α = d/(pri − L3)
    """
    m = mass_ratio
    return quintic_root(1.0, 0.0, m), quintic_root(1.0, m, 0.0), quintic_root(0.0, 1.0, m)


def lagrange_distances(mass_ratio: float, distance: float) -> tuple[float, float, float]:
    """Distances of L1, L2, L3 from the primary: d/(1+α1), d(1+α2), d/α3."""
    a1, a2, a3 = lagrange_alphas(mass_ratio)
    return distance / (1 + a1), distance * (1 + a2), distance / a3


def lagrange_distances_cr3bp(mass_ratio: float, distance: float) -> tuple[float, float, float]:
    """The same points found independently: zeros of the x-derivative of the effective
    potential of the circular restricted problem in the rotating frame (modern form),
    Ω_x = x − (1−μ)(x+μ)/|x+μ|³ − μ(x−1+μ)/|x−1+μ|³, μ = m2/(m1+m2), barycentre at 0.
    Returned as distances from the primary (at x = −μ)."""
    from scipy.optimize import brentq

    mu = mass_ratio / (1 + mass_ratio)

    def g(x):
        r1 = x + mu
        r2 = x - 1 + mu
        return x - (1 - mu) * r1 / abs(r1) ** 3 - mu * r2 / abs(r2) ** 3

    eps = 1e-9
    x1 = brentq(g, -mu + eps, 1 - mu - eps, xtol=1e-15)
    x2 = brentq(g, 1 - mu + eps, 2.0, xtol=1e-15)
    x3 = brentq(g, -2.0, -mu - eps, xtol=1e-15)
    return (x1 + mu) * distance, (x2 + mu) * distance, -(x3 + mu) * distance


def translator_table_errors() -> dict:
    """How far the translator's Earth–Moon table is from the root of the quintic with the
    translator's own inputs (d = 384400 km, 5.98e24 kg, 7.34e22 kg). Returns the recomputed
    α and L (km), and the differences table − quintic."""
    tt = TRANSLATOR_TABLE
    mr = tt["mass_moon_kg"] / tt["mass_earth_kg"]
    alphas = lagrange_alphas(mr)
    Ls = lagrange_distances(mr, tt["distance_km"])
    return {
        "mass_ratio": mr,
        "alpha": alphas,
        "L_km": Ls,
        "alpha_table": tt["alpha"],
        "L_km_table": tt["L_km"],
        "L_error_km": tuple(t - c for t, c in zip(tt["L_km"], Ls)),
        "alpha_error": tuple(t - c for t, c in zip(tt["alpha"], alphas)),
    }


def lagrange_points_rotating(mass_ratio: float) -> dict:
    """All five Lagrange points in the frame turning with the primaries (barycentre at 0,
    primary at (−μ, 0), secondary at (1 − μ, 0), unit distance). L1–L3 from Euler's quintic,
    L4/L5 the equilateral points (Lagrange 1772), for the markers of the restricted scene."""
    mu = mass_ratio / (1 + mass_ratio)
    L = lagrange_distances(mass_ratio, 1.0)
    h = math.sqrt(3) / 2
    return {"L1": (L[0] - mu, 0.0), "L2": (L[1] - mu, 0.0), "L3": (-L[2] - mu, 0.0),
            "L4": (0.5 - mu, h), "L5": (0.5 - mu, -h)}


def jacobi_function(x, y, mass_ratio: float):
    """2Ω(x, y) = x² + y² + 2(1−μ)/r1 + 2μ/r2 in the rotating frame (unit distance and rate);
    the zero-velocity curves are its level sets 2Ω = C_J (Jacobi constant)."""
    mu = mass_ratio / (1 + mass_ratio)
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    r1 = np.hypot(x + mu, y)
    r2 = np.hypot(x - 1 + mu, y)
    return x * x + y * y + 2 * (1 - mu) / r1 + 2 * mu / r2


def zero_velocity_grid(mass_ratio: float, n: int = 201, extent: float = 1.6):
    """(X, Y, 2Ω) on an n×n grid of the rotating plane, for drawing the zero-velocity curves;
    the levels through the L-points are 2Ω(L_k)."""
    g = np.linspace(-extent, extent, n)
    X, Y = np.meshgrid(g, g)
    return X, Y, jacobi_function(X, Y, mass_ratio)
