"""Hansen coefficients X^{−3,2}_k(e): the Fourier coefficients in the mean anomaly of the
tidal (gravity-gradient) forcing on an eccentric orbit, and Goldreich & Peale's H(p, e).

The planar spin–orbit equation (Euler's §833 with nothing neglected; Goldreich & Peale 1966,
AJ 71, 425) is θ̈ = −(ω₀²/2)(a/r)³ sin 2(θ − f). With the Fourier series in the mean anomaly M

    (a/r)³ e^{2if} = Σ_k X^{−3,2}_k(e) e^{ikM},   k integer,

the forcing is Σ_p H(p, e) sin(2θ − 2pM) with p = k/2 and

    H(p, e) = X^{−3,2}_{2p}(e) = (1/2π) ∫₀^{2π} (a/r)³ e^{i(2f − 2pM)} dM

(real: f is odd in M). Near θ̇ = pn only the term p is slow; averaging over the others leaves a
pendulum of half-width ω₀√|H(p, e)| in θ̇/n.

The integral is computed in the eccentric anomaly E (dM = (1 − e cos E) dE, a/r =
1/(1 − e cos E)):

    H(p, e) = (1/π) ∫₀^π cos(2f(E) − 2p(E − e sin E)) / (1 − e cos E)² dE,

a smooth periodic (even) integrand, so the trapezoid rule converges geometrically (the nearest
singularity is at cos E = 1/e, a distance acosh(1/e) from the real axis); the number of nodes is
doubled until two estimates agree to the rounding of the integrand. Exact for any e < 1 and any
half-integer p; no Kepler equation is solved.

Goldreich & Peale's truncated series (their Table I; Wisdom, Peale & Mignard 1984, Icarus 58,
137, eq. 4; Murray & Dermott 1999, *Solar System Dynamics*, Table 5.1) are kept as
`goldreich_peale_series` for comparison: at e = 0.5 the p = 5/2 series is 11 % low.
"""
from __future__ import annotations

import math

import numpy as np

from .errors import ParameterError

# Goldreich & Peale (1966), Table I: H(p, e) to the orders they give
_GP_SERIES = {
    0.5: lambda e: -e / 2 + e**3 / 16,
    1.0: lambda e: 1 - 5 * e**2 / 2 + 13 * e**4 / 16,
    1.5: lambda e: 7 * e / 2 - 123 * e**3 / 16,
    2.0: lambda e: 17 * e**2 / 2 - 115 * e**4 / 6,
    2.5: lambda e: 845 * e**3 / 48 - 32525 * e**5 / 768,
}
# the order in e of the first term each series leaves out (for the size of its error)
GP_SERIES_NEXT_ORDER = {0.5: 5, 1.0: 6, 1.5: 5, 2.0: 6, 2.5: 7}

MAX_NODES = 1 << 22


def _check(p, e) -> float:
    if not (np.isfinite(e) and 0.0 <= e < 1.0):
        raise ParameterError("eccentricity", e, "0 ≤ e < 1 (a closed orbit)")
    two_p = 2.0 * float(p)
    if not (np.isfinite(two_p) and two_p == round(two_p)):
        raise ParameterError("p", p, "a multiple of 1/2 (θ̇/n = p: the forcing has only the harmonics 2pM, 2p whole)")
    return float(p)


def _integrand(E, p, e):
    """cos(2f − 2pM)/(1 − e cos E)² on nodes E, with f from E by the half-angle formula."""
    f = 2.0 * np.arctan2(math.sqrt(1.0 + e) * np.sin(0.5 * E), math.sqrt(1.0 - e) * np.cos(0.5 * E))
    M = E - e * np.sin(E)
    w = 1.0 - e * np.cos(E)
    return np.cos(2.0 * f - 2.0 * p * M) / (w * w)


def hansen_H(p, e, rtol: float = 1e-15) -> float:
    """H(p, e) = X^{−3,2}_{2p}(e) by the trapezoid rule in E (module docstring), for any
    half-integer p and 0 ≤ e < 1. Raises ParameterError outside that range."""
    p = _check(p, e)
    if e == 0.0:
        return 1.0 if p == 1.0 else 0.0

    def trap(n):  # n intervals on [0, π]: ends weighted ½
        E = np.linspace(0.0, math.pi, n + 1)
        y = _integrand(E, p, e)
        return (y.sum() - 0.5 * (y[0] + y[-1])) / n, float(np.abs(y).max())

    # start above the harmonic 2p − 2 the integrand carries (e → 0: cos((2 − 2p)E)): with fewer
    # nodes the trapezoid rule aliases it, and two coarse estimates could agree on a wrong value
    n = 64
    while n < 4 * (abs(2.0 * p) + 2.0):
        n *= 2
    prev, scale = trap(n)
    while n < MAX_NODES:
        n *= 2
        cur, scale = trap(n)
        if abs(cur - prev) <= rtol * scale * 8:
            return float(cur)
        prev = cur
    raise ParameterError("eccentricity", e, "small enough for the quadrature to converge within 4 million nodes "
                         "(e below ~0.99999)")


def resonance_half_width(p, e, omega0) -> float:
    """Half-width in θ̇/n of the p resonance, ω₀√|H(p, e)| (the averaged pendulum
    γ̈ = −(ω₀²/2) H sin 2γ, γ = θ − pM, has separatrix |γ̇| = ω₀√|H|), ω₀² = 3(B − A)/C."""
    return float(omega0) * math.sqrt(abs(hansen_H(p, e)))


def goldreich_peale_series(p, e) -> float:
    """Goldreich & Peale's (1966, Table I) truncated series for H(p, e), p = 1/2 … 5/2 (kept for
    the comparison: valid while e is small, see `GP_SERIES_NEXT_ORDER`)."""
    p = _check(p, e)
    if p not in _GP_SERIES:
        raise ParameterError("p", p, "one of 1/2, 1, 3/2, 2, 5/2 (the resonances of Goldreich & Peale's table)")
    return float(_GP_SERIES[p](e))
