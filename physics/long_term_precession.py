"""The Earth's pole over tens of millennia: the secular (averaged) torque of the Sun and the Moon
on a moving ecliptic, against the long-term precession of Vondrák, Capitaine & Wallace (2011).

Why averaged. The full integration (physics.earth_precession.run_earth) follows the spin (a day),
the Moon (a month) and the Sun (a year) to get the 26,000-year cycle: millions of kicks. Over a
span that long only the torque averaged over the day, the month, the year and the Moon's 18.6-year
node matters; averaged, it is a smooth function of the spin axis ŝ alone (§846 in vector form).

The averaged torque. For a body on a Kepler orbit of semi-major axis a and eccentricity e in the
plane normal to k̂, the orbit average of the quadrupole tidal tensor GM r rᵀ/r⁵ is
GM ⟨r⁻³⟩ (1 − k̂k̂ᵀ)/2 (isotropic in the plane: r⁻³dt ∝ r⁻¹df), ⟨r⁻³⟩ = 1/(a³(1 − e²)^{3/2}). The
torque on an axisymmetric Earth, τ = 3(C − A)(Q ŝ) × ŝ, becomes τ = 3(C − A) q (k̂·ŝ)(ŝ × k̂) with
q = GM⟨r⁻³⟩/2. The Moon's orbit is tilted by i to the ecliptic and its normal circles the
ecliptic pole in 18.6 years; averaged over that circle the quadratic form k̂k̂ᵀ becomes
cos²i k̂k̂ᵀ + (sin²i/2)(1 − k̂k̂ᵀ), which multiplies q by (1 − 3/2 sin²i) about the ecliptic pole.
With L = Cω ŝ (the spin's own angular momentum; the nutation's share is second order):

    dŝ/dt = κ (k̂·ŝ)(ŝ × k̂) + Ω_g (k̂ × ŝ),   κ = (3/2)(H/ω) Σ GM⟨r⁻³⟩(1 − 3/2 sin²i),  H = (C − A)/C,

whose westward rate on a fixed ecliptic is κ cos ε (physics.precession.precession_rate_orbit).
Ω_g is the geodesic precession (1.92″ per century, eastward about the orbit normal), which is
not a torque but is in the observed precession the long-term model was fitted to.

The moving ecliptic. The planets turn the Earth's orbit plane by ~47″ per century; k̂(t) is
Vondrák et al.'s ecliptic pole (ERFA `ltpecl`, their Table 1: polynomials and 8 periodic terms
fitted to a numerical solution and to IAU 2006 near J2000), referred to the fixed J2000 ecliptic.
The Sun moves in that plane and the Moon's orbit keeps its 5.1° about it (its node regresses
against the moving ecliptic: the Sun's pull, which sets the Moon's Laplace plane, lies in it).

The error of the averaging. What the average drops are the periodic terms (the nutation: 17″
over 18.6 years, 1.3″ over half a year, 0.2″ over half a month) and their products with the
torque's own variations, a secular term of relative order (nutation amplitude)·(relative torque
variation) ~ 1e-5 of the rate. tests/test_long_term_precession.py measures the secular pole
against the full integration over a millennium (same orbits, same ecliptic).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from . import constants as C
from .constants import ARCSEC_RAD, JULIAN_CENTURY_DAYS, JULIAN_YEAR_DAYS, OBLIQUITY_J2000_RAD

J2000_YEAR = 2000.0
GRID_YEARS = 10.0  # the ecliptic pole is tabulated this densely and interpolated (its shortest period: centuries)
# the geodesic precession as a rate (rad/day) about the orbit normal, eastward
GEODESIC_RAD_PER_DAY = C.GEODESIC_PRECESSION_ARCSEC_PER_CY * ARCSEC_RAD / JULIAN_CENTURY_DAYS


def _to_ecliptic_j2000(v):
    """(…, 3) vectors of the J2000 mean equator and equinox in the J2000 ecliptic frame (turned by
    −ε₀ about X; ε₀ = 84381.406″, the value Vondrák et al. use)."""
    v = np.asarray(v, float)
    ce, se = math.cos(OBLIQUITY_J2000_RAD), math.sin(OBLIQUITY_J2000_RAD)
    return np.stack([v[..., 0], ce * v[..., 1] + se * v[..., 2], -se * v[..., 1] + ce * v[..., 2]], -1)


def epoch_year(t_days):
    return J2000_YEAR + np.asarray(t_days, float) / JULIAN_YEAR_DAYS


def vondrak_ecliptic_pole(t_days):
    """The ecliptic pole of date (…, 3) in the J2000 ecliptic frame: Vondrák, Capitaine & Wallace
    (2011) through ERFA's ltpecl; t in days from J2000.0."""
    import erfa

    return _to_ecliptic_j2000(erfa.ltpecl(epoch_year(t_days)))


def vondrak_equator_pole(t_days):
    """The mean equator's pole of date (…, 3) in the J2000 ecliptic frame (ERFA's ltpequ)."""
    import erfa

    return _to_ecliptic_j2000(erfa.ltpequ(epoch_year(t_days)))


def fixed_ecliptic_pole(t_days):
    t = np.asarray(t_days, float)
    return np.broadcast_to(np.array([0.0, 0.0, 1.0]), t.shape + (3,)).copy()


def rotation_to_ecliptic_of_date(k):
    """Matrices (…, 3, 3) of the smallest rotation taking the J2000 ecliptic pole ẑ to k (…, 3):
    the J2000 ecliptic frame's orbits carried onto the ecliptic of date (Rodrigues' formula about
    ẑ × k)."""
    k = np.asarray(k, float)
    z = np.array([0.0, 0.0, 1.0])
    v = np.cross(z, k)
    c = k[..., 2]
    vx = np.zeros(k.shape[:-1] + (3, 3))
    vx[..., 0, 1], vx[..., 0, 2] = -v[..., 2], v[..., 1]
    vx[..., 1, 0], vx[..., 1, 2] = v[..., 2], -v[..., 0]
    vx[..., 2, 0], vx[..., 2, 1] = -v[..., 1], v[..., 0]
    f = (1.0 / (1.0 + c))[..., None, None]
    return np.eye(3) + vx + f * (vx @ vx)


def on_ecliptic_of_date(position: Callable, ecliptic_pole: Callable, span_days=None) -> Callable:
    """A position function of the fixed J2000 ecliptic (an orbit about ẑ) carried onto the moving
    ecliptic: p(t) → R(t) p(t), R the rotation taking ẑ to k̂(t). With `span_days` = (t0, t1) the
    pole is tabulated every GRID_YEARS over it and interpolated (for the millions of kick times of a
    full integration)."""
    pole = ecliptic_pole
    if span_days is not None:
        from scipy.interpolate import CubicSpline

        step = GRID_YEARS * JULIAN_YEAR_DAYS
        tg = np.arange(np.floor(span_days[0] / step) - 2, np.ceil(span_days[1] / step) + 3) * step
        spline = CubicSpline(tg, ecliptic_pole(tg))

        def pole(t):
            k = spline(t)
            return k / np.linalg.norm(k, axis=-1, keepdims=True)

    def moved(t):
        t = np.asarray(t, float)
        R = rotation_to_ecliptic_of_date(pole(t))
        return np.einsum("...ij,...j->...i", R, position(t))

    return moved


@dataclass(frozen=True)
class SecularTorques:
    """The averaged model's constants (rad/day): κ of the Sun and of the Moon (see the module
    docstring) and the geodesic precession Ω_g."""

    kappa_sun: float
    kappa_moon: float
    geodesic: float = GEODESIC_RAD_PER_DAY

    @property
    def kappa(self) -> float:
        return self.kappa_sun + self.kappa_moon


def kappa(gm, mean_inverse_cube, inclination, H, spin) -> float:
    """(3/2)(H/ω) GM⟨r⁻³⟩(1 − 3/2 sin²i), rad per time unit of GM and ω."""
    return 1.5 * H / spin * gm * mean_inverse_cube * (1.0 - 1.5 * math.sin(inclination) ** 2)


def kepler_inverse_cube(a, e) -> float:
    """⟨r⁻³⟩ over a Kepler orbit (time average): 1/(a³(1 − e²)^{3/2})."""
    return 1.0 / (a ** 3 * (1.0 - e * e) ** 1.5)


def secular_rate(s, k, torques: SecularTorques):
    """dŝ/dt (…, 3) for spin axes s and ecliptic poles k (both (…, 3), unit)."""
    c = np.sum(k * s, axis=-1, keepdims=True)
    return torques.kappa * c * np.cross(s, k) + torques.geodesic * np.cross(k, s)


def integrate_secular(torques: SecularTorques, ecliptic_pole: Callable, s0, t_days, rtol=1e-12, atol=1e-14):
    """The spin axis (N, 3) at the times t_days (days from J2000, any order and sign), started at
    J2000.0 with ŝ = s0 and integrated forward and backward by scipy DOP853 (the right-hand side is
    smooth: steps of centuries). The ecliptic pole is evaluated every GRID_YEARS and interpolated by
    a cubic spline (Vondrák et al.'s shortest ecliptic period is ~500 years: the spline's error is
    below 1e-9 rad). Returns unit vectors."""
    from scipy.integrate import solve_ivp
    from scipy.interpolate import CubicSpline

    t = np.asarray(t_days, float)
    s0 = np.asarray(s0, float) / np.linalg.norm(s0)
    out = np.empty(t.shape + (3,))
    step = GRID_YEARS * JULIAN_YEAR_DAYS
    lo, hi = min(float(t.min()), 0.0), max(float(t.max()), 0.0)
    tg = np.arange(np.floor(lo / step) - 2, np.ceil(hi / step) + 3) * step
    pole = CubicSpline(tg, ecliptic_pole(tg))

    kap, geo = torques.kappa, torques.geodesic

    def rhs(tt, y):  # secular_rate for one state, written out (the solver calls it hundreds of times)
        k0, k1, k2 = pole(tt)
        n = math.sqrt(k0 * k0 + k1 * k1 + k2 * k2)
        k0, k1, k2 = k0 / n, k1 / n, k2 / n
        s0_, s1, s2 = y
        a = kap * (k0 * s0_ + k1 * s1 + k2 * s2)
        c0, c1, c2 = s1 * k2 - s2 * k1, s2 * k0 - s0_ * k2, s0_ * k1 - s1 * k0  # s × k
        return np.array([(a - geo) * c0, (a - geo) * c1, (a - geo) * c2])

    for sel in (t >= 0, t < 0):
        tt = t[sel]
        if tt.size == 0:
            continue
        end = float(tt.max()) if tt[0] >= 0 else float(tt.min())
        if end == 0.0:
            out[sel] = s0
            continue
        sol = solve_ivp(rhs, (0.0, end), s0, method="DOP853", rtol=rtol, atol=atol, dense_output=True)
        out[sel] = sol.sol(tt).T
    return out / np.linalg.norm(out, axis=-1, keepdims=True)


def angle_between(a, b):
    """Angles (rad) between unit vectors a and b (…, 3), accurate for small angles."""
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))


def obliquity(s, k):
    """The obliquity of date: the angle (rad) between the spin axis and the ecliptic pole of date."""
    return angle_between(s, k)
