"""Kepler's equation and the two-body ellipse: the one solver every orbit in theoria uses.

    M = E − e sin E        (M mean anomaly, E eccentric anomaly, 0 ≤ e < 1)

Method: Newton's iteration, started on the far side of the root and written without cancellation,
so that it converges for every e < 1 and ends at round-off.

- Reduction: M is brought to m ∈ [0, π] (E is odd in M and E − M is 2π-periodic); the turns and
  the sign are put back at the end, so E keeps the number of turns of M.
- On [0, π] the function f(E) = E − e sin E − m is increasing (f′ = 1 − e cos E ≥ 1 − e > 0)
  and convex (f″ = e sin E ≥ 0). Newton's iteration started at any point above the root then
  falls monotonically to it: no overshoot, no cycling, whatever e is (the classical failure of
  Newton from E₀ = M near e → 1, M → 0 cannot happen). The start is the least of four upper
  bounds of the root: m + e (e sin E ≤ e), π, m/(1 − e) ((1 − e)E ≤ f + m), and
  (6m/(e c))^{1/3} with c = 1 − π²/20 (E − sin E ≥ c E³/6 on [0, π]); the last two keep the
  start within a factor ≈ 1.3 of the root when e → 1 and m → 0, where the first is poor. The
  iteration converges quadratically from there; it stops when a step is below 4 ulp of E, and
  counted over m from 1e-12 to π it takes at most 4 steps (that last one included) for e ≤ 0.3,
  6 for e ≤ 0.9 and 7 for e up to 0.999999 (3 to 5 on average).
- Round-off: f is evaluated as (1 − e)E + e(E − sin E) − m, with E − sin E from its Taylor series
  for E < 1, and f′ as (1 − e) + 2e sin²(E/2). Near e → 1, E → 0 the textbook form
  E − e sin E − M loses digits to cancellation (an error ≈ ε·E/(1 − e) relative to E: 79 ulp
  measured at e = 0.99); this form keeps E to a few ulp of its own size (measured against mpmath in the
  tests: within 2 ulp for e up to 0.999999 and m from 1e-12 to π; 1.3 ulp measured).

Halley's or Markley's (1995) methods reach round-off in fewer steps, but each step costs more and
neither is simpler to prove convergent.

Two ways in, one code: `eccentric_anomaly_scalar` (and `true_anomaly_scalar`, `radius_scalar`)
are compiled scalar functions, for numba code and for a Python caller with one angle (~0.6 µs a
call; a ufunc called with a scalar costs ~13 µs); `eccentric_anomaly`, `true_anomaly`,
`anomalies` and `position` take numpy arrays (broadcast; numba ufuncs over the same scalar code,
0.7-0.9 µs per angle measured on the shared machine under load). The scalar functions return NaN
for e outside [0, 1) or a non-finite M; the array entries refuse such an e with a ParameterError.
"""
from __future__ import annotations

import math

import numpy as np
from numba import config, njit, vectorize

from .errors import ParameterError

_C_CUBIC = 1.0 - math.pi**2 / 20.0  # E − sin E ≥ _C_CUBIC·E³/6 on [0, π]
_EPS = 2.220446049250313e-16  # double precision


@njit(cache=True)
def eccentric_anomaly_scalar(M, e):
    """E with E − e sin E = M, for any real M and 0 ≤ e < 1 (NaN otherwise). See the module."""
    if not (0.0 <= e < 1.0) or not math.isfinite(M):
        return math.nan
    turns = math.floor((M + math.pi) / (2.0 * math.pi))
    m = M - turns * (2.0 * math.pi)  # in [−π, π)
    sign = 1.0
    if m < 0.0:
        sign, m = -1.0, -m
    E = m
    if e > 0.0 and m > 0.0:
        E = min(m + e, math.pi, m / (1.0 - e), (6.0 * m / (e * _C_CUBIC)) ** (1.0 / 3.0))
        for _ in range(64):
            if E < 1.0:  # E − sin E by its series: no cancellation
                x2 = E * E
                esin = E * x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0 * (
                    1.0 - x2 / 110.0 * (1.0 - x2 / 156.0 * (1.0 - x2 / 210.0 * (1.0 - x2 / 272.0 * (
                        1.0 - x2 / 342.0))))))))
            else:
                esin = E - math.sin(E)
            s = math.sin(0.5 * E)
            dE = ((1.0 - e) * E + e * esin - m) / ((1.0 - e) + 2.0 * e * s * s)
            E -= dE
            if abs(dE) <= 4.0 * _EPS * E:
                break
    return sign * E + turns * (2.0 * math.pi)


@njit(cache=True)
def true_anomaly_scalar(E, e):
    """True anomaly f from the eccentric anomaly: f = E + 2 atan(β sin E/(1 − β cos E)),
    β = e/(1 + √(1 − e²)). Continuous in E (f − E stays within ±π/2), so f has E's turns."""
    beta = e / (1.0 + math.sqrt((1.0 - e) * (1.0 + e)))
    return E + 2.0 * math.atan2(beta * math.sin(E), 1.0 - beta * math.cos(E))


@njit(cache=True)
def radius_scalar(E, e):
    """r/a = 1 − e cos E, written (1 − e) + 2e sin²(E/2) (no cancellation near periapse)."""
    s = math.sin(0.5 * E)
    return (1.0 - e) + 2.0 * e * s * s


if config.DISABLE_JIT:
    # numba compiles a ufunc given its signatures even with the JIT off, and the scalar functions it
    # calls are then plain Python, which it cannot type: the simulation process that runs without
    # the JIT (it serves the first scenes while the compiled code warms) failed to import this
    # module on a fresh install. There numpy's element loop calls the same scalar functions.
    def _elementwise(scalar):
        loop = np.vectorize(scalar, otypes=[np.float64])
        return lambda a, b: loop(a, b)[()]  # a number for numbers, as a ufunc gives

    _eccentric_anomaly_v = _elementwise(eccentric_anomaly_scalar)
    _true_anomaly_v = _elementwise(true_anomaly_scalar)
    _radius_v = _elementwise(radius_scalar)
else:
    @vectorize(["float64(float64, float64)"], cache=True)
    def _eccentric_anomaly_v(M, e):
        return eccentric_anomaly_scalar(M, e)

    @vectorize(["float64(float64, float64)"], cache=True)
    def _true_anomaly_v(E, e):
        return true_anomaly_scalar(E, e)

    @vectorize(["float64(float64, float64)"], cache=True)
    def _radius_v(E, e):
        return radius_scalar(E, e)


def check_eccentricity(e, name: str = "eccentricity"):
    """e as an array, or a ParameterError naming `name` when some e is outside [0, 1)."""
    arr = np.asarray(e, float)
    bad = ~((arr >= 0.0) & (arr < 1.0))
    if np.any(bad):
        raise ParameterError(name, float(arr[bad].flat[0]) if arr.ndim else float(arr), "allowed range [0, 1)")
    return arr


def eccentric_anomaly(M, e):
    """Eccentric anomaly E (rad) with E − e sin E = M; M any real array (E has its turns), e a
    scalar or an array broadcast against M, 0 ≤ e < 1."""
    return _eccentric_anomaly_v(np.asarray(M, float), check_eccentricity(e))


def true_anomaly(M, e):
    """True anomaly f (rad) at mean anomaly M, continuous in M (f has M's turns)."""
    e = check_eccentricity(e)
    return _true_anomaly_v(_eccentric_anomaly_v(np.asarray(M, float), e), e)


def anomalies(M, e):
    """(E, f, r/a) at mean anomaly M: eccentric and true anomaly and the distance in units of a."""
    e = check_eccentricity(e)
    E = _eccentric_anomaly_v(np.asarray(M, float), e)
    return E, _true_anomaly_v(E, e), _radius_v(E, e)


def to_frame(x, y, inclination=0.0, node=0.0, argp=0.0):
    """(..., 3) coordinates of the in-plane point (x along periapse, y 90° ahead) of an orbit
    whose plane is tilted by `inclination` about the line of nodes at longitude `node`, periapse
    `argp` from the node: R_z(node) R_x(inclination) R_z(argp) (x, y, 0). Angles may be arrays."""
    cw, sw = np.cos(argp), np.sin(argp)
    cn, sn = np.cos(node), np.sin(node)
    ci, si = np.cos(inclination), np.sin(inclination)
    xp, yp = cw * x - sw * y, sw * x + cw * y  # in the plane, from the node
    return np.stack([cn * xp - sn * ci * yp, sn * xp + cn * ci * yp, si * yp], axis=-1)


def position(M, a, e, inclination=0.0, node=0.0, argp=0.0):
    """(..., 3) position on the Kepler ellipse (semi-major axis a, eccentricity e) at mean
    anomaly M, oriented as in `to_frame`. Every argument may be an array (node and periapse
    turning with time, for instance)."""
    e = check_eccentricity(e)
    E = _eccentric_anomaly_v(np.asarray(M, float), e)
    s = np.sin(0.5 * E)
    x = a * ((1.0 - e) - 2.0 * s * s)  # a(cos E − e) without cancellation at periapse
    y = a * np.sqrt((1.0 - e) * (1.0 + e)) * np.sin(E)
    return to_frame(x, y, inclination, node, argp)
