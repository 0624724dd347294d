"""The Earth's precession and nutation: the rigid Earth with its real figure under the Sun and
the Moon, the orbits of which come from a REBOUND integration of the Sun–Earth–Moon problem.

Units: days, astronomical units, solar masses (G = k², Gauss's constant). Frame: the fixed
ecliptic of the start (J2000.0), X toward the J2000 equinox; planets are left out, so the
ecliptic does not move and the precession found is the luni-solar precession (IAU 2006 ψ_A),
not the general precession p_A (which adds the motion of the ecliptic).

The regression of the Moon's node is not imposed: it comes out of the three-body integration
(and the long run's mean-element Moon takes its rates from that integration).

Constants: `physics.constants` (each with its source): Gauss's k, the IAU 2009 mass ratios,
the IERS 2010 spin rate, H_d of the IAU 2000 nutation, the IAU 2006 obliquity, and the mean elements
of the Moon and the Sun at J2000 on the ecliptic (Simon et al. 1994, as in Meeus). Here they are put
in this module's units (AU, days, solar masses).
"""
from __future__ import annotations

import functools
import math
import threading
from dataclasses import dataclass

import numpy as np

from . import constants as C
from . import kepler
from . import quaternion as quat
from .constants import ARCSEC_RAD, GM_SUN_AU3_DAY2, JULIAN_YEAR_DAYS, OBLIQUITY_J2000_RAD
from .integrator import PointMass, integrate
from .kept import new_store, note_reuse
from .rebound_run import integrate_to

# masses in solar masses (G = k²): from the ratios of the GM's
M_EARTH = C.GM_EARTH_KM3_S2 / C.GM_SUN_KM3_S2
M_MOON = M_EARTH * C.MOON_EARTH_MASS_RATIO
M_EMB = M_EARTH + M_MOON
GM_MOON_AU3_DAY2 = GM_SUN_AU3_DAY2 * M_MOON
SPIN_RAD_DAY = C.EARTH_ROTATION_RAD_S * C.SECONDS_PER_DAY
# mean elements at J2000 on the ecliptic (angles in degrees, a in AU)
MOON_J2000 = dict(L=C.MOON_MEAN_LONGITUDE[0], varpi=C.MOON_PERIGEE_J2000_DEG, node=C.MOON_NODE[0],
                  inc=C.MOON_MEAN_INCLINATION_DEG, e=C.MOON_MEAN_ECCENTRICITY)
SUN_J2000 = dict(L=C.SUN_MEAN_LONGITUDE_J2000_DEG, varpi=C.SUN_PERIGEE_J2000_DEG, e=C.SUN_ECCENTRICITY,
                 a=C.SUN_SEMI_MAJOR_AXIS_AU)

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

    def first(self, n: int) -> "Ephemeris":
        """The first n samples (views)."""
        return Ephemeris(self.t[:n], self.sun_x[:n], self.sun_v[:n], self.moon_x[:n], self.moon_v[:n])

    def joined(self, more: "Ephemeris") -> "Ephemeris":
        """These samples followed by `more`'s."""
        return Ephemeris(*(np.concatenate([getattr(self, f), getattr(more, f)])
                           for f in ("t", "sun_x", "sun_v", "moon_x", "moon_v")))

    def moon(self, t):
        return _hermite(self.t, self.moon_x, self.moon_v, t)

    def covers(self, t0, t1):
        return self.t[0] <= t0 + 1e-9 and t1 <= self.t[-1] + 1e-9


def moon_semi_major_axis(month=C.SIDEREAL_MONTH_DAYS):
    """Keplerian a of the Earth–Moon orbit with the observed sidereal month (AU). The Sun
    lengthens the mean month slightly (by ≈ m²/2·…, m = 0.075), which `calibrated_moon_elements`
    corrects so that the integrated Moon keeps the observed month."""
    n = 2 * np.pi / month
    return (GM_SUN_AU3_DAY2 * M_EMB / n ** 2) ** (1 / 3)


@functools.lru_cache(maxsize=8)
def calibrated_moon_elements(month=C.SIDEREAL_MONTH_DAYS, span_days=4 * JULIAN_YEAR_DAYS, iterations=3):
    """Osculating (a, e, i, Ω, L) at J2000 whose integrated Moon has the observed mean sidereal
    month, mean eccentricity, mean inclination, and mean node and mean longitude at J2000
    (osculating and mean elements differ by the Sun's periodic perturbations, and the Sun
    lengthens the mean month): fixed-point iteration a ← a·(n_sim/n_obs)^(2/3), e ← e + (e_obs −
    ē_sim), and the same for i, Ω and L, the mean ones fitted over `span_days` (a straight line
    in time for Ω and L, whose intercept is the mean value at J2000). The osculating node set to
    the mean one started the mean node ~1.4° off Meeus's, and with it the phase of the 18.6-year
    nutation (0.4″ of a cos Ω term in Δψ where IAU 2000A has 0.003″). The node regression, the
    perigee and its motion, and the mean distance come out of the integration. Cached (a few
    REBOUND runs of `span_days`): the result is a tuple of floats that depends on the arguments
    only."""
    d = math.radians
    a = moon_semi_major_axis(month)
    e, inc, node, lon = MOON_J2000["e"], d(MOON_J2000["inc"]), d(MOON_J2000["node"]), d(MOON_J2000["L"])
    target = 2 * np.pi / month
    for _ in range(iterations):
        me = moon_mean_elements(integrate_orbits(span_days, 0.5, moon_elements=(a, e, inc, node, lon)))
        a *= (me.n / target) ** (2.0 / 3.0)
        e += MOON_J2000["e"] - me.e
        inc += d(MOON_J2000["inc"]) - me.inc
        node += _turn(d(MOON_J2000["node"]) - me.node0)
        lon += _turn(d(MOON_J2000["L"]) - me.L0)
    return a, e, inc, node, lon


def _turn(angle: float) -> float:
    """An angle difference brought into (−π, π]."""
    return float(math.remainder(angle, 2 * math.pi))


def make_simulation(moon_elements=None):
    """REBOUND simulation (IAS15) at J2000 with the elements above; moon_elements = osculating
    (a, e, i) or (a, e, i, Ω, L) in AU and radians (default: Keplerian a of the month, the mean
    elements taken as osculating)."""
    import rebound

    sim = rebound.Simulation()
    sim.G = GM_SUN_AU3_DAY2
    sim.integrator = "ias15"
    d = math.radians
    m = MOON_J2000
    sim.add(m=M_EARTH)
    el = tuple(moon_elements) if moon_elements is not None else (moon_semi_major_axis(), m["e"], d(m["inc"]))
    a, e, inc = el[:3]
    node, lon = el[3:] if len(el) == 5 else (d(m["node"]), d(m["L"]))
    sim.add(m=M_MOON, a=a, e=e, inc=inc, Omega=node, omega=d(m["varpi"]) - node, l=lon, primary=sim.particles[0])
    s = SUN_J2000
    # the Sun seen from the Earth–Moon barycentre: longitude L☉, perigee ϖ☉, in the ecliptic
    sim.add(m=1.0, a=s["a"], e=s["e"], inc=0.0, Omega=0.0, omega=d(s["varpi"]), l=d(s["L"]), primary=sim.com())
    sim.move_to_com()
    return sim


# The longest ephemeris made for each start, sampling and Moon, with its simulation where it ended
# (a few kept, ~7 MB per century): the earth scene's sliders other than the span (H, obliquity,
# the step) do not move the orbits, a shorter span is the start of a longer one, and a longer one
# goes on from where the kept one ended. A run integrates to the same sample times in the same
# order, so its samples are bit for bit those of one run made afresh over the whole span.
_EPHEMERIDES_KEPT = 2
_ephemerides = new_store()
_ephemerides_lock = threading.Lock()


def integrate_orbits(duration_days, sample_days=0.5, moon_elements=None, t_start=0.0, progress=None) -> Ephemeris:
    """Integrate the Sun–Earth–Moon problem with REBOUND IAS15 from J2000 over
    [t_start, t_start + duration] and return the geocentric Sun and Moon sampled every
    `sample_days` (samples from t_start − sample to the end + sample, for interpolation).
    Read-only arrays: the same run is handed to every caller that asks for it or a shorter span.
    `progress(frac)` is called as the samples are made (it may raise to stop the integration; the
    simulation stopped half way is then not kept)."""
    n = int(np.ceil(duration_days / sample_days)) + 3
    key = (float(sample_days), None if moon_elements is None else tuple(map(float, moon_elements)), float(t_start))
    with _ephemerides_lock:
        made = _ephemerides.pop(key, None)  # taken out: only this caller goes on with its simulation
    if made is not None:
        note_reuse()
    if made is not None and len(made[0].t) >= n:
        eph, sim = made
        out = eph.first(n)
    else:
        eph, sim = made if made is not None else (None, make_simulation(moon_elements))
        tg = t_start - sample_days + sample_days * np.arange(n)
        more = _sample(sim, tg[0 if eph is None else len(eph.t):], progress)
        eph = out = more if eph is None else eph.joined(more)
        for a in (eph.t, eph.sun_x, eph.sun_v, eph.moon_x, eph.moon_v):
            a.flags.writeable = False
    with _ephemerides_lock:
        _ephemerides[key] = (eph, sim)
        while len(_ephemerides) > _EPHEMERIDES_KEPT:
            _ephemerides.popitem(last=False)
    return out


PROGRESS_EVERY_SAMPLES = 256  # ~0.1 s of REBOUND between two looks at whether to stop


def _sample(sim, tg, progress=None) -> Ephemeris:
    """The geocentric Sun and Moon of `sim` integrated to each time of tg in turn."""
    n = len(tg)
    out = np.empty((n, 3, 6))
    xyz = np.empty((3, 3))
    vel = np.empty((3, 3))
    for j, tj in enumerate(tg):  # the first call goes backward (REBOUND flips dt), then forward
        if progress is not None and j % PROGRESS_EVERY_SAMPLES == 0:
            progress(j / n)
        integrate_to(sim, tj)
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
        return 2 * np.pi / abs(self.node_rate) / JULIAN_YEAR_DAYS

    @property
    def apse_period_yr(self):
        return 2 * np.pi / abs(self.varpi_rate) / JULIAN_YEAR_DAYS


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
    vp, ecc = perigee_longitude(x, v, GM_SUN_AU3_DAY2 * M_EMB)
    wr, w0 = np.polyfit(t, vp, 1)
    r = np.linalg.norm(x, axis=1)
    return MeanElements(float(L0), float(n), float(n0), float(nr), float(w0), float(wr),
                        float(1.0 / np.mean(1.0 / r)), float(np.mean(ecc)), float(np.mean(inc)))


def kepler_position(t, a, e, inc, node, varpi, L):
    """Position on a Keplerian ellipse with (possibly time-dependent) node Ω, longitude of
    perigee ϖ and mean longitude L (rad); a in AU: mean anomaly L − ϖ, argument of perigee ϖ − Ω."""
    return kepler.position(L - varpi, a, e, inc, node, varpi - node)


def sun_mean_orbit(t):
    """The Sun seen from the Earth on its fixed mean Kepler ellipse of J2000 (AU, ecliptic J2000;
    t in days from J2000)."""
    t = np.asarray(t, float)
    s = SUN_J2000
    n = C.K_GAUSS * math.sqrt(1 + M_EMB) / s["a"] ** 1.5
    return kepler_position(t, s["a"], s["e"], 0.0, 0.0, math.radians(s["varpi"]), math.radians(s["L"]) + n * t)


@dataclass(frozen=True)
class MeanOrbits:
    """For runs of millennia: the Sun on its fixed Kepler ellipse, the Moon on a Kepler ellipse
    whose node and perigee turn at the rates measured from the REBOUND run (`moon_mean_elements`)."""

    moon: MeanElements

    def sun(self, t):
        return sun_mean_orbit(t)

    @staticmethod
    def sun_mean_longitude(t):
        """The Sun's mean longitude (rad) on its mean orbit, t in days from J2000."""
        s = SUN_J2000
        return math.radians(s["L"]) + C.K_GAUSS * math.sqrt(1 + M_EMB) / s["a"] ** 1.5 * np.asarray(t, float)

    def moon_pos(self, t):
        t = np.asarray(t, float)
        m = self.moon
        return kepler_position(t, m.a, m.e, m.inc, m.node0 + m.node_rate * t, m.varpi0 + m.varpi_rate * t,
                               m.L0 + m.n * t)


# ---------------------------------------------------------------------------------------------
# The Earth
# ---------------------------------------------------------------------------------------------

def earth_inertia(H=C.EARTH_DYNAMICAL_ELLIPTICITY):
    """(A, A, C) with C = 1: only ratios of moments enter the motion."""
    return np.array([1 - H, 1 - H, 1.0])


def earth_initial_attitude(obliquity=OBLIQUITY_J2000_RAD):
    """The celestial pole at ecliptic longitude 90°, colatitude ε (equinox on +X)."""
    return quat.from_axis_angle([1.0, 0, 0], -obliquity)


def run_earth(sun_fn, moon_fn, duration_days, step_days, H=C.EARTH_DYNAMICAL_ELLIPTICITY, obliquity=OBLIQUITY_J2000_RAD,
              spin=SPIN_RAD_DAY, bodies=("sun", "moon"), scheme="strang", sample_days=1.0, t0=0.0, progress=None):
    """Integrate the Earth's rotation under the Sun and/or the Moon (gravity gradient kicks,
    exact free flow). Returns (t, L_body, q, I)."""
    I = earth_inertia(H)
    masses = []
    if "sun" in bodies:
        masses.append(PointMass(GM_SUN_AU3_DAY2, sun_fn))
    if "moon" in bodies:
        masses.append(PointMass(GM_MOON_AU3_DAY2, moon_fn))
    stride = max(1, int(round(sample_days / step_days)))
    t, L, q = integrate(I, [0.0, 0.0, spin], duration_days, step_days, q0=earth_initial_attitude(obliquity),
                        masses=masses, scheme=scheme, stride=stride, t0=t0, progress=progress)
    return t, L, q, I


def precession_parts_modern(moon: MeanElements | None, H=C.EARTH_DYNAMICAL_ELLIPTICITY, obliquity=OBLIQUITY_J2000_RAD,
                            spin=SPIN_RAD_DAY):
    """Orbit-averaged precession rates (rad/day) of the solar and lunar parts (see
    `precession.precession_rate_orbit`), and Euler's §846 values (circle in the ecliptic at the
    mean distance, A in the denominator)."""
    from .precession import euler_N, precession_rate_orbit

    s = SUN_J2000
    n_sun = C.K_GAUSS * math.sqrt(1 + M_EMB) / s["a"] ** 1.5
    a_m = moon.a if moon is not None else moon_semi_major_axis()
    e_m = moon.e if moon is not None else MOON_J2000["e"]
    i_m = moon.inc if moon is not None else math.radians(MOON_J2000["inc"])
    sun = precession_rate_orbit(GM_SUN_AU3_DAY2, s["a"], s["e"], 0.0, H, spin, obliquity)
    lun = precession_rate_orbit(GM_MOON_AU3_DAY2, a_m, e_m, i_m, H, spin, obliquity)
    A, C_ = 1 - H, 1.0  # C = 1: only ratios of moments enter
    e_sun = -euler_N(GM_SUN_AU3_DAY2 / s["a"] ** 3, C_, A, spin) * math.cos(obliquity)
    e_lun = -euler_N(GM_MOON_AU3_DAY2 / a_m ** 3, C_, A, spin) * math.cos(obliquity)
    return dict(sun=sun, moon=lun, euler_sun=e_sun, euler_moon=e_lun, n_sun=n_sun)


def per_day_to_arcsec_per_yr(x):
    return x / ARCSEC_RAD * JULIAN_YEAR_DAYS


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
        out[k] = dict(dpsi=-fit.longitude[k][0] / ARCSEC_RAD, dpsi_cos=-fit.longitude[k][1] / ARCSEC_RAD,
                      deps=fit.obliquity[k][1] / ARCSEC_RAD, deps_sin=fit.obliquity[k][0] / ARCSEC_RAD)
    return out


def equatorial_to_ecliptic(ra_deg, dec_deg, obliquity=OBLIQUITY_J2000_RAD):
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


def figure_pole_free_of_diurnal(L_inertial, sun_pos, moon_pos, H=C.EARTH_DYNAMICAL_ELLIPTICITY):
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
    for gm, s in ((GM_SUN_AU3_DAY2, sun_pos), (GM_MOON_AU3_DAY2, moon_pos)):
        s = np.asarray(s, float)
        r = np.linalg.norm(s, axis=1, keepdims=True)
        sa = np.sum(s * a, axis=1, keepdims=True)
        tau += 3 * gm * (1.0 - A) / r ** 5 * sa * np.cross(s, a)
    fig = a - A * np.cross(a, tau) / Ln ** 2
    return fig / np.linalg.norm(fig, axis=1, keepdims=True)
