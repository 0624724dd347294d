"""Euler 1768, *Methodus facilis motus corporum coelestium utcunque perturbatos …* (seed 003,
§I–§XXXIV): the Moon's motion written as equations for its orbital elements, integrated.

Elements (Euler's letters): p half the parameter (semi-latus rectum), q eccentricity, Υ true
anomaly, ψ longitude of the node, ω inclination to the fixed plane (the ecliptic, in which the
Sun moves), σ argument of latitude; ∅ the angle described in the orbit (d∅/dt = h/v²);
v = p/(1 + q cos Υ) (§XXIV; §XXXII writes the lunar form with 1 − q cos Υ, q < 0 — the same
ellipse with Υ counted from apogee). n = B/(A + C) = GM_sun/GM_earth+moon (§XXII, §XXXI).
With K = 1/w³ − 1/u³ (w Moon–Sun, u Earth–Sun distance), μ the Moon–Sun angle at the Earth and
ν the angle of §XVII (cos μ, sin ν of §XV, §XVII, §XXXI):

    dp = −2n v³u K sin ν d∅                                                   (§XXVII.1)
    dq = n v²u K [cos μ sin Υ − sin ν (q + 2cos Υ + q cos²Υ)/(1 + q cos Υ)] d∅
         − n v³ sin Υ/w³ d∅                                                   (§XXVII.3)
    dΥ = d∅ − n v³ cos Υ/(q w³) d∅
         + (n v²u K/q) [cos μ cos Υ + (2 + q cos Υ) sin ν sin Υ/(1 + q cos Υ)] d∅ (§XXVII.4*)
    dψ = −n v³u K sin σ sin(θ − ψ)/p d∅                                       (§XXVIII.1)
    dω = −n v³u K cos σ sin(θ − ψ) sin ω/p d∅,   dω/sin ω = dψ/tan σ            (§XXVIII.2*)
    dσ = d∅ − dψ cos ω                                                        (§XXVIII.3)

Corrections to the translation (re-derived from the force components and checked against a
direct Cartesian integration of the same forces, which agrees to round-off level):
- (*) §XXVII item 4 prints "− (n v²u d∅/q)(…)[…]": the sign must be +. It follows from Euler's
  own relation q(d∅ − dΥ) sin Υ = dp/v − dq cos Υ (§XXVI), which the text gets right one step
  earlier, and agrees with Gauss's equation for the true anomaly.
- (*) §XXVIII item 2 prints dω/sin σ; it is dω/sin ω.
- §XX: the "2" in v⁴d∅² = −2∝B dt² ∫… is right only with the first integral (the translator's
  footnote 41 flags it); we integrate dp instead, where it does not arise.
The Sun moves on a fixed Kepler ellipse about the Earth in the fixed plane (§XXX); the Moon's
pull on the Earth is in μ = GM_earth + GM_moon (§XIV).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .. import constants as C
from .. import kepler
from ..constants import JULIAN_YEAR_DAYS
from ..rebound_run import integrate_to

KM_PER_UNIT = C.EARTH_MOON_DISTANCE_KM  # the length unit: the Moon's mean distance

# Mean elements at J2000 (Simon et al. 1994; Meeus, Astronomical Algorithms, ch. 47 and 25),
# referred to the ecliptic: Moon and the geocentric Sun (values and sources in physics.constants).
MOON_J2000 = dict(eccentricity=C.MOON_MEAN_ECCENTRICITY, inclination_deg=C.MOON_MEAN_INCLINATION_DEG,
                  node_deg=C.MOON_NODE[0], perigee_deg=C.MOON_PERIGEE_J2000_DEG,
                  mean_longitude_deg=C.MOON_MEAN_LONGITUDE[0], sidereal_month_days=C.SIDEREAL_MONTH_DAYS)
SUN_J2000 = dict(eccentricity=C.SUN_ECCENTRICITY, perigee_deg=C.SUN_PERIGEE_J2000_DEG,
                 mean_longitude_deg=C.SUN_MEAN_LONGITUDE_J2000_DEG)

# Published mean periods from the rates of Simon et al. 1994 (Meeus ch. 47; see physics.constants).
# The usually quoted node period 6798.38 d = 18.613 yr is measured from the moving equinox;
# against the stars (the frame of our model: fixed ecliptic and axes) it is 6793.48 d =
# 18.5995 yr. The usually quoted perigee period 3232.6 d = 8.8504 yr is already the one against
# the stars (from the equinox of date: 3231.50 d). Compare the model with the *_SIDEREAL values.
# Inclination 4.99°–5.30° (period 173 d).
NODE_PERIOD_YR = C.NODE_PERIOD_OF_DATE_DAYS / JULIAN_YEAR_DAYS  # 18.613 yr, from the equinox of date
NODE_PERIOD_SIDEREAL_YR = C.NODE_PERIOD_SIDEREAL_DAYS / JULIAN_YEAR_DAYS  # 18.5995 yr
APSE_PERIOD_YR = C.APSE_PERIOD_SIDEREAL_DAYS / JULIAN_YEAR_DAYS  # 8.8504 yr (= 3232.6 d, against the stars)
APSE_PERIOD_SIDEREAL_YR = APSE_PERIOD_YR


def units():
    """(μ_earth+moon, μ_sun) in lunar units (384400 km) and days."""
    s = KM_PER_UNIT**3 / C.SECONDS_PER_DAY**2
    return (C.GM_EARTH_KM3_S2 + C.GM_MOON_KM3_S2) / s, C.GM_SUN_KM3_S2 / s


@njit(cache=True)
def sun_state(t, sun):
    """Sun's position (x, y) and distance about the Earth at time t (days) on its fixed Kepler
    ellipse in the ecliptic. sun = (a, e, mean motion, mean anomaly at 0, longitude of perigee)."""
    a, e, nm, M0, varpi = sun[0], sun[1], sun[2], sun[3], sun[4]
    E = kepler.eccentric_anomaly_scalar(M0 + nm * t, e)
    u = a * kepler.radius_scalar(E, e)
    th = kepler.true_anomaly_scalar(E, e) + varpi
    return u * math.cos(th), u * math.sin(th), u, th


@njit(cache=True)
def _K(v, u, cosmu):
    """1/w³ − 1/u³ without cancellation: (u³ − w³)/(u³w³), u − w = (2vu cos μ − v²)/(u + w)."""
    w = math.sqrt(v * v + u * u - 2.0 * v * u * cosmu)
    dw = (2.0 * v * u * cosmu - v * v) / (u + w)
    return dw * (u * u + u * w + w * w) / (u**3 * w**3), w


@njit(cache=True)
def _cartesian_into(out, y, mu, mus, sx, sy, u):
    """rhs_cartesian with the Sun's state (sx, sy, u) given, written into `out`."""
    X, Y, Z = y[0], y[1], y[2]
    v = math.sqrt(X * X + Y * Y + Z * Z)
    cosmu = (X * sx + Y * sy) / (v * u)
    K, w = _K(v, u, cosmu)
    w3 = w**3
    out[0], out[1], out[2] = y[3], y[4], y[5]
    out[3] = -mu * X / v**3 + mus * (sx * K - X / w3)
    out[4] = -mu * Y / v**3 + mus * (sy * K - Y / w3)
    out[5] = -mu * Z / v**3 + mus * (-Z / w3)


@njit(cache=True)
def rhs_cartesian(t, y, mu, mus, sun):
    """Moon relative to the Earth: r̈ = −μ r/v³ + μ_S[R(1/w³ − 1/u³) − r/w³] (§XIV)."""
    sx, sy, u, th = sun_state(t, sun)
    out = np.empty(6)
    _cartesian_into(out, y, mu, mus, sx, sy, u)
    return out


@njit(cache=True)
def _elements_into(out, y, mu, mus, sx, sy, u, th, sign4, series):
    """rhs_elements with the Sun's state (sx, sy, u, th) given, written into `out`."""
    p, q, Y, psi, om, sig = y[0], y[1], y[2], y[3], y[4], y[5]
    n = mus / mu
    cY, sY = math.cos(Y), math.sin(Y)
    v = p / (1.0 + q * cY)
    dphi = math.sqrt(mu * p) / (v * v)
    cs, ss = math.cos(sig), math.sin(sig)
    co, so = math.cos(om), math.sin(om)
    d = th - psi
    cd, sd = math.cos(d), math.sin(d)
    cosmu = cs * cd + ss * co * sd
    sinnu = ss * cd - cs * co * sd
    K, w = _K(v, u, cosmu)
    w3 = w**3
    if series != 0.0:
        K = 3.0 * v * cosmu / u**4 + 3.0 * v * v * (5.0 * cosmu * cosmu - 1.0) / (2.0 * u**5)
        w3 = 1.0 / (1.0 / u**3 + K)
    den = 1.0 + q * cY
    out[0] = -2.0 * n * v**3 * u * K * sinnu
    out[1] = n * v * v * u * K * (cosmu * sY - sinnu * (q + 2.0 * cY + q * cY * cY) / den) - n * v**3 * sY / w3
    out[2] = 1.0 - n * v**3 * cY / (q * w3) + sign4 * (n * v * v * u * K / q) * (cosmu * cY + (2.0 + q * cY) * sinnu * sY / den)
    dpsi = -n * v**3 * u * K * ss * sd / p
    out[3] = dpsi
    out[4] = -n * v**3 * u * K * cs * sd * so / p
    out[5] = 1.0 - dpsi * co
    for k in range(6):
        out[k] *= dphi


@njit(cache=True)
def rhs_elements(t, y, mu, mus, sun, sign4=1.0, series=0.0):
    """Euler's element equations (§XXVII–XXVIII, corrected as in the module docstring), per
    unit time: each d/d∅ times d∅/dt = √(μp)/v². y = (p, q, Υ, ψ, ω, σ).
    sign4 = +1: the corrected sign of the last term of dΥ (§XXVII.4); −1: as printed.
    series = 1: Euler's expansion of §XXXIII, 1/w³ − 1/u³ ≈ 3v cos μ/u⁴ + 3v²(5cos²μ − 1)/(2u⁵)
    (and 1/w³ = 1/u³ + that), instead of the exact distances."""
    sx, sy, u, th = sun_state(t, sun)
    out = np.empty(6)
    _elements_into(out, y, mu, mus, sx, sy, u, th, sign4, series)
    return out


@njit(cache=True)
def _rhs_into(out, which, y, mu, mus, sun_at, sign4, series):
    if which == 0:
        _cartesian_into(out, y, mu, mus, sun_at[0], sun_at[1], sun_at[2])
    else:
        _elements_into(out, y, mu, mus, sun_at[0], sun_at[1], sun_at[2], sun_at[3], sign4, series)


@njit(cache=True)
def _rk4(which, y0, i0, h, nsteps, stride, mu, mus, sun, sign4, series):
    """nsteps RK4 steps from step i0 of k systems side by side: which[s] is system s's kind (0
    Cartesian, 1 elements), y0[s] its state (the time of step i is i·h, formed so in every piece: a
    piece that started at i0·h and added i·h rounded its times differently from the uncut run).
    Returns the states every `stride` steps, (rows, k, 6).

    Each system's arithmetic is `y + ½h·k1` … `y + h/6·(k1 + 2k2 + 2k3 + k4)` element by element,
    in buffers made once; the Sun's place is found once per stage for all the systems, once for
    the two middle stages (same time), and taken over from the step before when its end time is
    this step's start: a system's numbers are those of the textbook RK4 run alone, bit for bit."""
    k_sys, m = y0.shape
    nout = nsteps // stride + 1
    out = np.empty((nout, k_sys, m))
    y = y0.copy()
    out[0] = y
    k1, k2, k3, k4, tmp = np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    s0, s_mid, s1 = np.empty(4), np.empty(4), np.empty(4)
    t = i0 * h
    t_end_prev = np.nan
    row = 1
    for i in range(1, nsteps + 1):
        if t == t_end_prev:
            s0[:] = s1
        else:
            s0[0], s0[1], s0[2], s0[3] = sun_state(t, sun)
        s_mid[0], s_mid[1], s_mid[2], s_mid[3] = sun_state(t + 0.5 * h, sun)
        t_end_prev = t + h
        s1[0], s1[1], s1[2], s1[3] = sun_state(t_end_prev, sun)
        for s in range(k_sys):
            ys = y[s]
            _rhs_into(k1, which[s], ys, mu, mus, s0, sign4, series)
            for j in range(m):
                tmp[j] = ys[j] + 0.5 * h * k1[j]
            _rhs_into(k2, which[s], tmp, mu, mus, s_mid, sign4, series)
            for j in range(m):
                tmp[j] = ys[j] + 0.5 * h * k2[j]
            _rhs_into(k3, which[s], tmp, mu, mus, s_mid, sign4, series)
            for j in range(m):
                tmp[j] = ys[j] + h * k3[j]
            _rhs_into(k4, which[s], tmp, mu, mus, s1, sign4, series)
            c = h / 6.0
            for j in range(m):
                ys[j] = ys[j] + c * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
        t = (i0 + i) * h
        if i % stride == 0:
            out[row] = y
            row += 1
    return out


RK4_CHUNKS = 50  # with a progress callback: the run in this many compiled pieces, the callback between
KINDS = {"cartesian": 0, "elements": 1}


def integrate_rk4(kind: str, y0, duration_days: float, step_days: float, sample_days: float, mu, mus, sun,
                  printed_sign: bool = False, euler_series: bool = False, progress=None):
    """Classical RK4 at a fixed step (compiled). kind = "cartesian" | "elements".
    Returns (t, states) sampled every `sample_days` (rounded to whole steps). printed_sign /
    euler_series: see `rhs_elements`. `progress(frac)`, if given, is called between pieces of
    about 1/RK4_CHUNKS of the run (it may raise to stop the run); the pieces restart from the
    state and step reached and round exactly as the uncut run, so the result does not depend on
    `progress` (the app's numbers are the command line's)."""
    t, (states,) = integrate_rk4_together((kind,), (y0,), duration_days, step_days, sample_days, mu, mus, sun,
                                          printed_sign, euler_series, progress)
    return t, states


def integrate_rk4_together(kinds, y0s, duration_days: float, step_days: float, sample_days: float, mu, mus, sun,
                           printed_sign: bool = False, euler_series: bool = False, progress=None):
    """`integrate_rk4` of several systems over the same span and step (e.g. the element equations
    and the Cartesian reference), side by side: the Sun's place is computed once for all of them,
    and each system's states are those of its run alone, bit for bit. Returns (t, [states, ...])."""
    stride = max(1, int(round(sample_days / step_days)))
    nsteps = int(math.ceil(duration_days / step_days / stride)) * stride
    which = np.array([KINDS[k] for k in kinds], np.int64)
    sign4, ser = (-1.0 if printed_sign else 1.0), (1.0 if euler_series else 0.0)
    sun = np.asarray(sun, float)
    y = np.array([np.asarray(v, float) for v in y0s])
    if progress is None:
        out = _rk4(which, y, 0, step_days, nsteps, stride, mu, mus, sun, sign4, ser)
    else:
        per = max(1, nsteps // stride // RK4_CHUNKS) * stride  # steps per piece, whole samples
        pieces, done = [y[None]], 0
        while done < nsteps:
            n = min(per, nsteps - done)
            part = _rk4(which, y, done, step_days, n, stride, mu, mus, sun, sign4, ser)
            pieces.append(part[1:])
            y = part[-1].copy()
            done += n
            progress(done / nsteps)
        out = np.concatenate(pieces)
    # each system's states an array of its own: a run that keeps one does not hold the others
    return np.arange(out.shape[0]) * stride * step_days, [out[:, s].copy() for s in range(len(which))]


# --- conversions --------------------------------------------------------------------------------

def cartesian_to_elements(r, vel, mu):
    """Euler's elements (p, q, Υ, ψ, ω, σ) of the osculating orbit, arrays (N,3) → (N,6)."""
    r = np.atleast_2d(r)
    vel = np.atleast_2d(vel)
    hvec = np.cross(r, vel)
    h = np.linalg.norm(hvec, axis=1)
    rn = np.linalg.norm(r, axis=1)
    p = h * h / mu
    om = np.arccos(np.clip(hvec[:, 2] / h, -1, 1))
    psi = np.arctan2(hvec[:, 0], -hvec[:, 1])
    # argument of latitude: angle from the node direction in the orbit plane
    nx, ny = np.cos(psi), np.sin(psi)
    cos_s = (r[:, 0] * nx + r[:, 1] * ny) / rn
    sin_s = r[:, 2] / (rn * np.sin(om))
    sig = np.arctan2(sin_s, cos_s)
    evec = np.cross(vel, hvec) / mu - r / rn[:, None]
    q = np.linalg.norm(evec, axis=1)
    cosY = np.sum(evec * r, axis=1) / (q * rn)
    sinY = np.sum(r * vel, axis=1) * h / (mu * q * rn)  # ṙ = (μ/h) q sin Υ
    Y = np.arctan2(sinY, cosY)
    return np.stack([p, q, Y, psi, om, sig], axis=1)


def elements_to_position(el):
    """Euler §IV: X = v(cos σ cos ψ − sin σ cos ω sin ψ), Y = v(cos σ sin ψ + sin σ cos ω cos ψ),
    Z = v sin σ sin ω, v = p/(1 + q cos Υ)."""
    el = np.atleast_2d(el)
    p, q, Y, psi, om, sig = el.T
    v = p / (1 + q * np.cos(Y))
    cs, ss, cp, sp, co, so = np.cos(sig), np.sin(sig), np.cos(psi), np.sin(psi), np.cos(om), np.sin(om)
    return np.stack([v * (cs * cp - ss * co * sp), v * (cs * sp + ss * co * cp), v * ss * so], axis=1)


def elements_to_cartesian(el, mu):
    """Position and velocity from (p, q, Υ, ψ, ω, σ)."""
    el = np.atleast_2d(el)
    p, q, Y, psi, om, sig = el.T
    r = elements_to_position(el)
    rn = np.linalg.norm(r, axis=1)
    h = np.sqrt(mu * p)
    vr = mu / h * q * np.sin(Y)
    vt = h / rn
    cs, ss, cp, sp, co, so = np.cos(sig), np.sin(sig), np.cos(psi), np.sin(psi), np.cos(om), np.sin(om)
    rhat = r / rn[:, None]
    that = np.stack([-ss * cp - cs * co * sp, -ss * sp + cs * co * cp, cs * so], axis=1)
    return r, vr[:, None] * rhat + vt[:, None] * that


def initial_conditions(eccentricity=None, inclination_deg=None, semi_major_axis=None, sun_eccentricity=None):
    """Moon's initial elements (p, q, Υ, ψ, ω, σ) and the Sun's ellipse at J2000 (mean elements
    taken as osculating). The semi-major axis defaults to the value whose Kepler period is the
    sidereal month (then `calibrate_semi_major_axis` fixes the mean motion in the perturbed
    problem). Returns (elements, sun tuple, mu, mus)."""
    mu, mus = units()
    M_ = MOON_J2000
    e = M_["eccentricity"] if eccentricity is None else eccentricity
    inc = math.radians(M_["inclination_deg"] if inclination_deg is None else inclination_deg)
    n_moon = 2 * math.pi / M_["sidereal_month_days"]
    a = (mu / n_moon**2) ** (1 / 3) if semi_major_axis is None else semi_major_axis
    node = math.radians(M_["node_deg"])
    peri = math.radians(M_["perigee_deg"])
    Mm = math.radians(M_["mean_longitude_deg"] - M_["perigee_deg"])
    f = float(kepler.true_anomaly(Mm, e))
    g = peri - node  # argument of perigee (dog-leg longitude of perigee − node)
    el = np.array([a * (1 - e * e), e, f, node, inc, g + f])
    S = SUN_J2000
    es = S["eccentricity"] if sun_eccentricity is None else sun_eccentricity
    a_s = C.AU_KM / KM_PER_UNIT
    n_s = math.sqrt((mus + mu) / a_s**3)
    sun = (a_s, es, n_s, math.radians(S["mean_longitude_deg"] - S["perigee_deg"]), math.radians(S["perigee_deg"]))
    return el, sun, mu, mus


def mean_motion(t, el):
    """Mean sidereal motion (rad/day) from a linear fit of the unwrapped true longitude in the
    orbit (ψ + σ, the 'dog-leg' longitude)."""
    lon = np.unwrap(el[:, 3] + el[:, 5])
    return float(np.polyfit(t, lon, 1)[0])


def calibrate_mean_elements(el0, sun, mu, mus, target_month_days: float, mean_eccentricity: float,
                            mean_inclination: float, span_days: float = 730.0, step_days: float = 0.05,
                            iterations: int = 3):
    """Adjust the initial osculating a, q, ω so that the perturbed orbit has the observed mean
    sidereal motion, mean eccentricity and mean inclination (mean elements are averages; the
    osculating ones swing by ±0.15° in ω, ±0.01 in q and 0.7% in n): fixed-point iterations
    a ← a·(n_mean/n_target)^{2/3}, q ← q + (q̄_target − q̄), ω ← ω + (ω̄_target − ω̄) on a
    `span_days` run. Returns the adjusted initial elements."""
    el = np.array(el0, float)
    target = 2 * math.pi / target_month_days
    for _ in range(iterations):
        t, E = integrate_rk4("elements", el, span_days, step_days, 0.25, mu, mus, sun)
        nm = mean_motion(t, E)
        a = el[0] / (1 - el[1] ** 2) * (nm / target) ** (2 / 3)
        el[1] += mean_eccentricity - float(np.mean(E[:, 1]))
        el[4] += mean_inclination - float(np.mean(E[:, 4]))
        el[0] = a * (1 - el[1] ** 2)
    return el


def linear_rate(t, angle):
    """Slope of a least-squares line through the unwrapped angle (rad per unit of t)."""
    return float(np.polyfit(t, np.unwrap(angle), 1)[0])


def node_and_apse(t_days, el):
    """Node longitude ψ, perigee longitude ϖ = ψ + σ − Υ, their mean rates (rad/day) and periods (yr)."""
    psi = el[:, 3]
    varpi = el[:, 3] + el[:, 5] - el[:, 2]
    rn = linear_rate(t_days, psi)
    ra = linear_rate(t_days, varpi)
    return {"node_rate": rn, "apse_rate": ra,
            "node_period_yr": 2 * math.pi / abs(rn) / JULIAN_YEAR_DAYS,
            "apse_period_yr": 2 * math.pi / abs(ra) / JULIAN_YEAR_DAYS,
            "psi": psi, "varpi": varpi}


def first_order_rates(sun, month_days: float, inclination_rad: float):
    """Classical first-order secular rates from the averaged solar tidal term (Newton's and
    Clairaut's first approximation): node −(3/4)(n'²/n)cos i, perigee +(3/4)(n'²/n).
    The perigee value is the famous 'half the apse motion' of 1747."""
    n = 2 * math.pi / month_days
    ns = sun[2]
    base = 0.75 * ns * ns / n
    return {"node_rate": -base * math.cos(inclination_rad), "apse_rate": base}


def oblateness_rates(month_days: float, eccentricity: float, obliquity: float = C.OBLIQUITY_J2000_RAD,
                     j2: float = C.EARTH_J2, radius_km: float = C.EARTH_RADIUS_KM) -> dict:
    """Secular node and perigee rates (rad/day) that the Earth's J2 would add to the Moon's orbit
    near the ecliptic; NOT in Euler's model (nor ours) — this sizes what the comparison with the
    observed periods leaves out.

    For an orbit whose normal h makes the angle θ with the Earth's pole P, the orbit-averaged J2
    potential turns h about P: dh/dt = −k cos θ (P × h), and turns the perigee in the orbit plane
    at (k/2)(3cos²θ − 1), with k = (3/2) n J2 (R/a)²/(1 − e²)² (the classical first-order
    rates: dΩ/dt = −k cos θ, dω/dt = (k/2)(5cos²θ − 1)). The Sun keeps h circling the ecliptic
    pole at 5° (much faster than J2 alone would move it); averaging the J2 turn over that circle
    (small i, P at the obliquity ε from the ecliptic pole) gives the extra node rate on the
    ecliptic −k(cos²ε − ½sin²ε) = −k(1 − (3/2)sin²ε), and the extra perigee rate
    (k/2)(3cos²ε − 1). Size for the Moon: k = 1.03e-7 rad/d, i.e. 8.5e-5 of the node rate and
    4.0e-5 of the perigee rate (both make the real periods shorter than the model's)."""
    n = 2 * math.pi / month_days
    k = 1.5 * n * j2 * (radius_km / KM_PER_UNIT) ** 2 / (1 - eccentricity**2) ** 2
    se2 = math.sin(obliquity) ** 2
    return {"k": k, "node_rate": -k * (1 - 1.5 * se2), "apse_rate": 0.5 * k * (3 * (1 - se2) - 1)}


def euler_identity_residuals(t, el, r, vel):
    """Euler's identities along a solution (§VII–IX): dω sin σ = dψ sin ω cos σ (i.e.
    dω/sin ω = dψ/tan σ, written without the poles) and dσ = d∅ − dψ cos ω, d∅/dt = |r×v|/r².
    Derivatives of the osculating elements by 4th-order central differences on an even grid.
    Returns the max residual of each, relative to max|dψ/dt sin ω| and max|dψ/dt|."""
    dt = t[1] - t[0]

    def deriv(a):
        a = np.unwrap(a)
        return (a[:-4] - 8 * a[1:-3] + 8 * a[3:-1] - a[4:]) / (12 * dt)

    psi, om, sig = el[:, 3], el[:, 4], el[:, 5]
    dpsi, dom, dsig = deriv(psi), deriv(om), deriv(sig)
    c = slice(2, -2)
    h = np.linalg.norm(np.cross(r, vel), axis=1)
    dphi = h / np.sum(r * r, axis=1)
    res1 = dom * np.sin(sig[c]) - dpsi * np.sin(om[c]) * np.cos(sig[c])
    res2 = dsig - (dphi[c] - dpsi * np.cos(om[c]))
    return (float(np.max(np.abs(res1)) / np.max(np.abs(dpsi * np.sin(om[c])))),
            float(np.max(np.abs(res2)) / np.max(np.abs(dpsi))))


def rebound_three_body(el0, sun, mu, mus, duration_days: float, sample_days: float = 0.5,
                       integrator: str = "ias15"):
    """Independent check: Sun, Earth and Moon as three massive bodies in REBOUND (G = 1, lunar
    units and days), started from the same Moon elements, the Sun on the same ellipse about the
    Earth–Moon barycentre. Returns t and the Moon's geocentric (r, v)."""
    import rebound

    r, v = elements_to_cartesian(el0, mu)
    r, v = r[0], v[0]
    a_s, es, ns, M0, varpi = sun
    # the Sun's geocentric state at t = 0 (Kepler ellipse in the ecliptic)
    E = kepler.eccentric_anomaly_scalar(M0, es)
    f = kepler.true_anomaly_scalar(E, es)
    u = a_s * kepler.radius_scalar(E, es)
    th = f + varpi
    mu_s = mus + mu
    h = math.sqrt(mu_s * a_s * (1 - es * es))
    vr = mu_s / h * es * math.sin(f)
    vt = h / u
    R = np.array([u * math.cos(th), u * math.sin(th), 0.0])
    V = np.array([vr * math.cos(th) - vt * math.sin(th), vr * math.sin(th) + vt * math.cos(th), 0.0])
    m_e = mu / (1.0 + C.MOON_EARTH_MASS_RATIO)
    m_m = mu - m_e
    bary = m_m / mu * r
    vbary = m_m / mu * v
    sim = rebound.Simulation()
    sim.G = 1.0
    sim.add(m=mus, x=bary[0] + R[0], y=bary[1] + R[1], z=0.0, vx=vbary[0] + V[0], vy=vbary[1] + V[1], vz=vbary[2])
    sim.add(m=m_e)
    sim.add(m=m_m, x=r[0], y=r[1], z=r[2], vx=v[0], vy=v[1], vz=v[2])
    sim.move_to_com()
    sim.integrator = integrator
    n = int(round(duration_days / sample_days)) + 1
    t = np.arange(n) * sample_days
    rr = np.empty((n, 3))
    vv = np.empty((n, 3))
    buf = np.empty((3, 3))
    for k, tk in enumerate(t):
        integrate_to(sim, float(tk))
        sim.serialize_particle_data(xyz=buf)
        rr[k] = buf[2] - buf[1]
        sim.serialize_particle_data(vxvyvz=buf)
        vv[k] = buf[2] - buf[1]
    return t, rr, vv


def cos_mu_sin_nu(sigma, theta_minus_psi, omega, small_inclination: bool = False):
    """cos μ and sin ν of §XV/§XVII/§XXXI: cos μ = cos σ cos(θ−ψ) + sin σ cos ω sin(θ−ψ),
    sin ν = sin σ cos(θ−ψ) − cos σ cos ω sin(θ−ψ). With small_inclination, Euler's §XXXIV
    forms with cos ω = 1 − ω²/2: cos μ ≈ cos(σ−θ+ψ) − ½ω² sin σ sin(θ−ψ),
    sin ν ≈ sin(σ−θ+ψ) + ½ω² cos σ sin(θ−ψ) (the text's extra factor cos ω in the last term is
    harmless at this order but should not be there)."""
    s, d, w = np.asarray(sigma, float), np.asarray(theta_minus_psi, float), np.asarray(omega, float)
    if small_inclination:
        return (np.cos(s - d) - 0.5 * w * w * np.sin(s) * np.sin(d),
                np.sin(s - d) + 0.5 * w * w * np.cos(s) * np.sin(d))
    return (np.cos(s) * np.cos(d) + np.sin(s) * np.cos(w) * np.sin(d),
            np.sin(s) * np.cos(d) - np.cos(s) * np.cos(w) * np.sin(d))
