"""The Earth's precession and nutation: the rigid Earth with its real figure under the Sun and
the Moon, the orbits of which come from a REBOUND integration of the Sun–Earth–Moon problem.

Units: days, astronomical units, solar masses (G = k², Gauss's constant). Frame: the fixed
ecliptic of the start (J2000.0), X toward the J2000 equinox; planets are left out, so the
ecliptic does not move and the precession found is the luni-solar precession (IAU 2006 ψ_A),
not the general precession p_A (which adds the motion of the ecliptic).

The regression of the Moon's node is not imposed: it comes out of the three-body integration
(and the long run's mean-element Moon takes its rates from that integration).

Constants and their sources
---------------------------
  k = 0.01720209895 AU^{3/2}/day          Gauss's constant (IAU 1976/2012)
  M☉/(M⊕ + M☾) = 328900.56               IAU 2009 system of constants (Luzum et al. 2011)
  M⊕/M☾ = 81.30056907                     IAU 2009 (DE421 value)
  H = (C − A)/C = 0.0032737949            dynamical ellipticity, IAU 2000 nutation (Mathews,
                                           Herring & Buffett 2002, H_d)
  ω⊕ = 7.292115e-5 rad/s                  IERS Conventions 2010 (nominal mean angular velocity)
  ε₀ = 84381.406″ = 23.43927944°          obliquity at J2000, IAU 2006 (Capitaine et al. 2003)
  Moon, mean elements at J2000 on the ecliptic (Simon et al. 1994, as in Meeus, Astronomical
  Algorithms ch. 47): L = 218.3165°, ϖ = 83.3532°, Ω = 125.0446°, i = 5.145°, e = 0.0549,
  sidereal month 27.321661 d.
  Sun (geocentric), J2000: L = 280.4665°, ϖ = 282.9373°, e = 0.016709, a = 1.000001 AU.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from . import quaternion as quat
from .integrator import PointMass, integrate
from .precession import ARCSEC

K_GAUSS = 0.01720209895
GM_SUN = K_GAUSS ** 2  # AU³/day²
SUN_OVER_EMB = 328900.5614
EARTH_OVER_MOON = 81.30056907
M_EMB = 1.0 / SUN_OVER_EMB
M_EARTH = M_EMB * EARTH_OVER_MOON / (1 + EARTH_OVER_MOON)
M_MOON = M_EMB / (1 + EARTH_OVER_MOON)
GM_MOON = GM_SUN * M_MOON
H_DYN = 0.0032737949
SPIN = 7.292115e-5 * 86400.0  # rad/day
OBLIQUITY = math.radians(84381.406 / 3600.0)
AU_KM = 1.495978707e8
DAYS_PER_YEAR = 365.25
SIDEREAL_MONTH = 27.321661
MOON_J2000 = dict(L=218.3165, varpi=83.3532, node=125.0446, inc=5.145, e=0.0549)
SUN_J2000 = dict(L=280.4665, varpi=282.9373, e=0.016709, a=1.000001)

# IAU 2000A nutation (MHB2000), luni-solar terms, coefficients of sin (Δψ) and cos (Δε) in
# arcsec at J2000 (the table of SOFA/ERFA nut00a; Mathews, Herring & Buffett 2002, Table 6).
# The tests recompute them by a least-squares fit of erfa.nut00a.
IAU2000_NUTATION = {
    "18.6yr": dict(argument="Ω", dpsi=-17.2064161, deps=9.2052331),
    "semiannual": dict(argument="2F−2D+2Ω = 2L☉", dpsi=-1.3170906, deps=0.5730336),
    "13.66d": dict(argument="2F+2Ω = 2L☾", dpsi=-0.2276413, deps=0.0978459),
    "9.3yr": dict(argument="2Ω", dpsi=0.2074554, deps=-0.0897492),
    "annual": dict(argument="l'", dpsi=0.1475877, deps=0.0073871),
}
# IAU 2006 precession (Capitaine, Wallace & Chapront 2003, P03), arcsec per Julian century:
PSI_A_RATE = 5038.481507  # luni-solar precession ψ_A: the equator on the fixed ecliptic of J2000
P_A_RATE = 5028.796195  # general precession in longitude p_A (adds the ecliptic's motion)
GEODESIC_PRECESSION = 1.919883  # relativistic part of ψ_A (not a torque), arcsec/cy


# ---------------------------------------------------------------------------------------------
# Orbits: REBOUND integration sampled on a grid, cubic Hermite interpolation between samples
# ---------------------------------------------------------------------------------------------

def _hermite(tg, x, v, t):
    """Cubic Hermite interpolation of positions x (M,3) with velocities v on the uniform grid
    tg (M,) at times t (N,). Error ≈ (Δ·ω)⁴/384 of the orbit radius."""
    t = np.asarray(t, float)
    dt = tg[1] - tg[0]
    u = (t - tg[0]) / dt
    i = np.clip(np.floor(u).astype(np.int64), 0, len(tg) - 2)
    s = (u - i)[:, None]
    h00 = (1 + 2 * s) * (1 - s) ** 2
    h10 = s * (1 - s) ** 2
    h01 = s * s * (3 - 2 * s)
    h11 = s * s * (s - 1)
    return h00 * x[i] + h10 * dt * v[i] + h01 * x[i + 1] + h11 * dt * v[i + 1]


@dataclass
class Ephemeris:
    """Geocentric Sun and Moon on a uniform time grid (days from J2000), positions in AU,
    velocities in AU/day, from a Sun–Earth–Moon REBOUND integration."""

    t: np.ndarray
    sun_x: np.ndarray
    sun_v: np.ndarray
    moon_x: np.ndarray
    moon_v: np.ndarray

    def sun(self, t):
        return _hermite(self.t, self.sun_x, self.sun_v, t)

    def moon(self, t):
        return _hermite(self.t, self.moon_x, self.moon_v, t)

    def covers(self, t0, t1):
        return self.t[0] <= t0 + 1e-9 and t1 <= self.t[-1] + 1e-9


def moon_semi_major_axis(month=SIDEREAL_MONTH):
    """Keplerian a of the Earth–Moon orbit with the observed sidereal month (AU). The Sun
    lengthens the mean month slightly (by ≈ m²/2·…, m = 0.075), which `calibrated_moon_elements`
    corrects so that the integrated Moon keeps the observed month."""
    n = 2 * np.pi / month
    return (GM_SUN * M_EMB / n ** 2) ** (1 / 3)


@functools.lru_cache(maxsize=8)
def calibrated_moon_elements(month=SIDEREAL_MONTH, span_days=4 * 365.25, iterations=3):
    """Osculating (a, e, i) at J2000 whose integrated Moon has the observed mean sidereal month,
    mean eccentricity and mean inclination (osculating and mean elements differ by the Sun's
    periodic perturbations, and the Sun lengthens the mean month): fixed-point iteration
    a ← a·(n_sim/n_obs)^(2/3), e ← e + (e_obs − ē_sim), i ← i + (i_obs − ī_sim). Only these
    three are fitted; the node regression, the perigee motion and the mean distance come out of
    the integration. Cached (a few REBOUND runs of `span_days`): the result is a tuple of floats
    that depends on the arguments only."""
    a = moon_semi_major_axis(month)
    e, inc = MOON_J2000["e"], math.radians(MOON_J2000["inc"])
    target = 2 * np.pi / month
    for _ in range(iterations):
        me = moon_mean_elements(integrate_orbits(span_days, 0.5, moon_elements=(a, e, inc)))
        a *= (me.n / target) ** (2.0 / 3.0)
        e += MOON_J2000["e"] - me.e
        inc += math.radians(MOON_J2000["inc"]) - me.inc
    return a, e, inc


def make_simulation(moon_elements=None):
    """REBOUND simulation (IAS15) at J2000 with the elements above; moon_elements = osculating
    (a, e, i) (default: Keplerian a of the month, the mean e and i taken as osculating)."""
    import rebound

    sim = rebound.Simulation()
    sim.G = GM_SUN
    sim.integrator = "ias15"
    d = math.radians
    m = MOON_J2000
    sim.add(m=M_EARTH)
    a, e, inc = moon_elements if moon_elements is not None else (moon_semi_major_axis(), m["e"], d(m["inc"]))
    sim.add(m=M_MOON, a=a, e=e, inc=inc,
            Omega=d(m["node"]), omega=d(m["varpi"] - m["node"]), l=d(m["L"]), primary=sim.particles[0])
    s = SUN_J2000
    # the Sun seen from the Earth–Moon barycentre: longitude L☉, perigee ϖ☉, in the ecliptic
    sim.add(m=1.0, a=s["a"], e=s["e"], inc=0.0, Omega=0.0, omega=d(s["varpi"]), l=d(s["L"]), primary=sim.com())
    sim.move_to_com()
    return sim


def integrate_orbits(duration_days, sample_days=0.5, moon_elements=None, t_start=0.0) -> Ephemeris:
    """Integrate the Sun–Earth–Moon problem with REBOUND IAS15 from J2000 over
    [t_start, t_start + duration] and return the geocentric Sun and Moon sampled every
    `sample_days` (samples from t_start − sample to the end + sample, for interpolation)."""
    sim = make_simulation(moon_elements)
    n = int(np.ceil(duration_days / sample_days)) + 3
    tg = t_start - sample_days + sample_days * np.arange(n)
    out = np.empty((n, 3, 6))
    xyz = np.empty((3, 3))
    vel = np.empty((3, 3))
    for j, tj in enumerate(tg):  # the first call goes backward (REBOUND flips dt), then forward
        sim.integrate(tj, exact_finish_time=1)
        sim.serialize_particle_data(xyz=xyz, vxvyvz=vel)
        out[j, :, :3] = xyz
        out[j, :, 3:] = vel
    e = out[:, 0]
    return Ephemeris(tg, out[:, 2, :3] - e[:, :3], out[:, 2, 3:] - e[:, 3:], out[:, 1, :3] - e[:, :3],
                     out[:, 1, 3:] - e[:, 3:])


def orbit_normal_node(x, v):
    """Longitude of the ascending node Ω and inclination of the osculating orbit (x, v)."""
    hvec = np.cross(x, v)
    node = np.unwrap(np.arctan2(hvec[:, 0], -hvec[:, 1]))
    inc = np.arctan2(np.hypot(hvec[:, 0], hvec[:, 1]), hvec[:, 2])
    return node, inc


def perigee_longitude(x, v, gm):
    """Longitude of perigee ϖ (unwrapped) from the eccentricity vector (projected on the
    ecliptic; for the Moon's 5° inclination this differs from Ω + ω by < 0.2°)."""
    r = np.linalg.norm(x, axis=1, keepdims=True)
    ev = np.cross(v, np.cross(x, v)) / gm - x / r
    return np.unwrap(np.arctan2(ev[:, 1], ev[:, 0])), np.linalg.norm(ev, axis=1)


@dataclass(frozen=True)
class MeanElements:
    """Mean elements of the Moon's orbit measured from a REBOUND run (linear fits): mean
    longitude L₀ + n t, node Ω₀ + Ω̇t, perigee ϖ₀ + ϖ̇t, mean a, e, inclination (days, AU, rad)."""

    L0: float
    n: float
    node0: float
    node_rate: float
    varpi0: float
    varpi_rate: float
    a: float
    e: float
    inc: float

    @property
    def node_period_yr(self):
        return 2 * np.pi / abs(self.node_rate) / DAYS_PER_YEAR

    @property
    def apse_period_yr(self):
        return 2 * np.pi / abs(self.varpi_rate) / DAYS_PER_YEAR


def moon_mean_elements(eph: Ephemeris) -> MeanElements:
    """Fit the Moon's mean elements to the integrated orbit (the node regression comes from
    here). a from the mean motion through the Keplerian relation would hide the Sun's effect;
    the mean of 1/r is used instead (a = ⟨1/r⟩⁻¹ for a Kepler ellipse)."""
    t = eph.t
    x, v = eph.moon_x, eph.moon_v
    lon = np.unwrap(np.arctan2(x[:, 1], x[:, 0]))
    n, L0 = np.polyfit(t, lon, 1)
    node, inc = orbit_normal_node(x, v)
    nr, n0 = np.polyfit(t, node, 1)
    vp, ecc = perigee_longitude(x, v, GM_SUN * M_EMB)
    wr, w0 = np.polyfit(t, vp, 1)
    r = np.linalg.norm(x, axis=1)
    return MeanElements(float(L0), float(n), float(n0), float(nr), float(w0), float(wr),
                        float(1.0 / np.mean(1.0 / r)), float(np.mean(ecc)), float(np.mean(inc)))


def _kepler_E(M, e):
    E = M + e * np.sin(M)
    for _ in range(6):
        E = E - (E - e * np.sin(E) - M) / (1 - e * np.cos(E))
    return E


def kepler_position(t, a, e, inc, node, varpi, L):
    """Position on a Keplerian ellipse with (possibly time-dependent) node, perigee and mean
    longitude arrays (rad); a in AU. Private helper (orbits.py is another engineer's)."""
    M = L - varpi
    E = _kepler_E(np.remainder(M, 2 * np.pi), e)
    xo = a * (np.cos(E) - e)
    yo = a * np.sqrt(1 - e * e) * np.sin(E)
    w = varpi - node
    cw, sw, cn, sn, ci, si = np.cos(w), np.sin(w), np.cos(node), np.sin(node), np.cos(inc), np.sin(inc)
    X = (cn * cw - sn * sw * ci) * xo + (-cn * sw - sn * cw * ci) * yo
    Y = (sn * cw + cn * sw * ci) * xo + (-sn * sw + cn * cw * ci) * yo
    Z = (sw * si) * xo + (cw * si) * yo
    return np.stack([X, Y, Z], -1)


@dataclass(frozen=True)
class MeanOrbits:
    """For runs of millennia: the Sun on its fixed Kepler ellipse, the Moon on a Kepler ellipse
    whose node and perigee turn at the rates measured from the REBOUND run (`moon_mean_elements`)."""

    moon: MeanElements

    def sun(self, t):
        t = np.asarray(t, float)
        s = SUN_J2000
        n = K_GAUSS * math.sqrt(1 + M_EMB) / s["a"] ** 1.5
        return kepler_position(t, s["a"], s["e"], 0.0, 0.0, math.radians(s["varpi"]),
                               math.radians(s["L"]) + n * t)

    def moon_pos(self, t):
        t = np.asarray(t, float)
        m = self.moon
        return kepler_position(t, m.a, m.e, m.inc, m.node0 + m.node_rate * t, m.varpi0 + m.varpi_rate * t,
                               m.L0 + m.n * t)


# ---------------------------------------------------------------------------------------------
# The Earth
# ---------------------------------------------------------------------------------------------

def earth_inertia(H=H_DYN):
    """(A, A, C) with C = 1: only ratios of moments enter the motion."""
    return np.array([1 - H, 1 - H, 1.0])


def earth_initial_attitude(obliquity=OBLIQUITY):
    """The celestial pole at ecliptic longitude 90°, colatitude ε (equinox on +X)."""
    return quat.from_axis_angle([1.0, 0, 0], -obliquity)


def run_earth(sun_fn, moon_fn, duration_days, step_days, H=H_DYN, obliquity=OBLIQUITY, spin=SPIN,
              bodies=("sun", "moon"), scheme="strang", sample_days=1.0, t0=0.0, progress=None):
    """Integrate the Earth's rotation under the Sun and/or the Moon (gravity gradient kicks,
    exact free flow). Returns (t, L_body, q, I)."""
    I = earth_inertia(H)
    masses = []
    if "sun" in bodies:
        masses.append(PointMass(GM_SUN, sun_fn))
    if "moon" in bodies:
        masses.append(PointMass(GM_MOON, moon_fn))
    stride = max(1, int(round(sample_days / step_days)))
    t, L, q = integrate(I, [0.0, 0.0, spin], duration_days, step_days, q0=earth_initial_attitude(obliquity),
                        masses=masses, scheme=scheme, stride=stride, t0=t0, progress=progress)
    return t, L, q, I


def precession_parts_modern(moon: MeanElements | None, H=H_DYN, obliquity=OBLIQUITY, spin=SPIN):
    """Orbit-averaged precession rates (rad/day) of the solar and lunar parts (see
    `precession.precession_rate_orbit`), and Euler's §846 values (circle in the ecliptic at the
    mean distance, A in the denominator)."""
    from .precession import euler_N, precession_rate_orbit

    s = SUN_J2000
    n_sun = K_GAUSS * math.sqrt(1 + M_EMB) / s["a"] ** 1.5
    a_m = moon.a if moon is not None else moon_semi_major_axis()
    e_m = moon.e if moon is not None else MOON_J2000["e"]
    i_m = moon.inc if moon is not None else math.radians(MOON_J2000["inc"])
    sun = precession_rate_orbit(GM_SUN, s["a"], s["e"], 0.0, H, spin, obliquity)
    lun = precession_rate_orbit(GM_MOON, a_m, e_m, i_m, H, spin, obliquity)
    A, C = 1 - H, 1.0
    e_sun = -euler_N(GM_SUN / s["a"] ** 3, C, A, spin) * math.cos(obliquity)
    e_lun = -euler_N(GM_MOON / a_m ** 3, C, A, spin) * math.cos(obliquity)
    return dict(sun=sun, moon=lun, euler_sun=e_sun, euler_moon=e_lun, n_sun=n_sun)


def per_day_to_arcsec_per_yr(x):
    return x / ARCSEC * DAYS_PER_YEAR


# ---------------------------------------------------------------------------------------------
# Nutation fit and stars (pure: the catalogue is passed in by the caller)
# ---------------------------------------------------------------------------------------------

def nutation_arguments(t, sun_dir, moon_dir, moon: MeanElements):
    """Fundamental arguments measured from the simulated orbits (days, rad): the Moon's mean
    node Ω (from the REBOUND orbit normal), the mean longitudes L☉, L☾ (straight lines fitted to
    the simulated directions), the Sun's mean anomaly l' = L☉ − ϖ☉ and the Moon's l = L☾ − ϖ."""
    from .precession import mean_longitude

    _, _, Ls = mean_longitude(t, sun_dir)
    _, _, Lm = mean_longitude(t, moon_dir)
    Om = moon.node0 + moon.node_rate * np.asarray(t, float)
    return {"18.6yr": Om, "9.3yr": 2 * Om, "semiannual": 2 * Ls,
            "annual": Ls - math.radians(SUN_J2000["varpi"]), "13.66d": 2 * Lm,  # annual: l' = L☉ − ϖ☉
            "9.13d": 2 * Lm - Om, "27.55d": Lm - (moon.varpi0 + moon.varpi_rate * np.asarray(t, float))}


def nutation_arcsec(fit):
    """Δψ (coefficient of sin θ) and Δε (coefficient of cos θ) in arcsec from a PoleFit of the
    pole longitude λ and obliquity p: Δψ = −Δλ (the equinox moves opposite to the pole's
    longitude... i.e. precession and Δψ are positive westward), Δε = Δp."""
    out = {}
    for k in fit.longitude:
        out[k] = dict(dpsi=-fit.longitude[k][0] / ARCSEC, dpsi_cos=-fit.longitude[k][1] / ARCSEC,
                      deps=fit.obliquity[k][1] / ARCSEC, deps_sin=fit.obliquity[k][0] / ARCSEC)
    return out


def equatorial_to_ecliptic(ra_deg, dec_deg, obliquity=OBLIQUITY):
    """Unit vectors (N,3) in the J2000 ecliptic frame of stars given by J2000 RA/Dec (deg)."""
    ra, dec = np.radians(np.asarray(ra_deg, float)), np.radians(np.asarray(dec_deg, float))
    x = np.cos(dec) * np.cos(ra)
    y = np.cos(dec) * np.sin(ra)
    z = np.sin(dec)
    ce, se = math.cos(obliquity), math.sin(obliquity)
    return np.stack([x, ce * y + se * z, -se * y + ce * z], -1)


def pole_star_passages(t_yr, pole, names, ra_deg, dec_deg, within_deg=5.0):
    """For each star that the pole path passes within `within_deg`: (name, year of closest
    approach, separation in degrees), sorted by year. pole: (N,3) unit vectors, ecliptic J2000."""
    stars = equatorial_to_ecliptic(ra_deg, dec_deg)
    sep = np.degrees(np.arccos(np.clip(pole @ stars.T, -1, 1)))  # (N, S)
    out = []
    for j, name in enumerate(names):
        i = int(np.argmin(sep[:, j]))
        if sep[i, j] <= within_deg:
            out.append((str(name), float(t_yr[i]), float(sep[i, j])))
    return sorted(out, key=lambda r: r[1])


def figure_pole_free_of_diurnal(L_inertial, sun_pos, moon_pos, H=H_DYN):
    """The figure axis with its diurnal (free) circle removed — the pole the IAU nutation series
    refer to (the CIP of a rigid Earth) — from the angular-momentum axis and the torque:

        â = L̂ − A (L̂ × τ)/|L|²

    (the forced part of the figure axis's offset from L: â turns about L̂ at |L|/A, so to follow
    L̂ as L̂ moves at τ⊥/|L| it must lead by that amount; the "Oppolzer terms"). τ is the
    gravity-gradient torque of the Sun and the Moon with the figure axis taken along L̂
    (the error is of the order of the offset itself, ~1e-8 rad).
    Units: L in C·rad/day with C = 1 (as `run_earth`), positions in AU."""
    L = np.asarray(L_inertial, float)
    Ln = np.linalg.norm(L, axis=1, keepdims=True)
    a = L / Ln
    A = 1 - H
    tau = np.zeros_like(L)
    for gm, s in ((GM_SUN, sun_pos), (GM_MOON, moon_pos)):
        s = np.asarray(s, float)
        r = np.linalg.norm(s, axis=1, keepdims=True)
        sa = np.sum(s * a, axis=1, keepdims=True)
        tau += 3 * gm * (1.0 - A) / r ** 5 * sa * np.cross(s, a)
    fig = a - A * np.cross(a, tau) / Ln ** 2
    return fig / np.linalg.norm(fig, axis=1, keepdims=True)
