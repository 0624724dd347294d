"""The Moon seen from the Earth: optical and physical libration (beyond Euler §833–839).

Sources (values used below):
- Moments from lunar laser ranging: β = (C−A)/B = 631.0e-6, γ = (B−A)/C = 227.7e-6
  (Williams et al., "Lunar interior properties from the GRAIL mission", JGR Planets 119, 2014,
  and the DE430 lunar model, Williams, Boggs & Folkner 2013, JPL IOM 335-JW,DB,WF-20130722-016).
- Inclination of the mean lunar equator to the ecliptic I = 1.54242° (IAU; Meeus,
  *Astronomical Algorithms* 2nd ed., ch. 53). Cassini's laws: the equator's descending node is the
  orbit's ascending node Ω; the ecliptic pole lies between the spin pole and the orbit pole.
- The Moon's geocentric position: the main terms of the ELP-2000/82 truncation in Meeus ch. 47
  (Tables 47.A/B, fundamental arguments of eq. 47.1–47.7), good to ~10″; referred to the fixed
  ecliptic of J2000 by removing the general precession in longitude, 5029.0966″/century: the
  IAU 1976 value (Lieske et al. 1977, A&A 58, 1) that Meeus uses (eq. 21.5 and ch. 47). IAU 2006
  (Capitaine et al. 2003, P03) has p_A = 5028.796195″/century; the 0.3″/century difference moves
  the Moon by < 0.1″ within a century of J2000, far below this truncation's ~10″.
- Optical libration in longitude and latitude: Meeus ch. 53 (l', b' for a uniformly rotating
  Moon in the Cassini state). The maxima quoted for it, about ±7.9° and ±6.8°, are short of the real
  Moon's: DE421 reaches 8.07–8.14° and 6.86–6.87° in each 18.6-yr cycle of 1900–2200
  (physics.constants, MOON_OPTICAL_LIBRATION_*_DE421_DEG).
- Physical libration in longitude τ: Meeus ch. 53 after Eckhardt (1981, Moon & Planets 25, 3):
  τ = −0.00467° sin M′ (−16.8″, anomalistic month) + 0.02520° E sin M (+90.7″, anomalistic year)
  + 0.00115° sin(M′ − 2D) + … (degrees).

Euler's §836 in this setting: each term α_k sin(A_k t + 𝔄_k) of the Moon's longitude forces
ζ_k = A_k²α_k/(A_k² − 2N) sin(…), so the body's own rotation departs from uniform by
τ_k = α_k − ζ_k = −α_k·2N/(A_k² − 2N) (the physical libration), 2N = 3γ·GM_E⟨1/r³⟩.
"""
from __future__ import annotations

import numpy as np

from . import constants as C
from . import quaternion as quat

GM_EARTH_KM3_DAY2 = C.GM_EARTH_KM3_S2 * C.SECONDS_PER_DAY**2
# the general precession in longitude Meeus uses (IAU 1976), to refer his longitudes of date to J2000
PRECESSION_DEG_PER_CY = C.GENERAL_PRECESSION_IAU1976_ARCSEC_PER_CY / 3600.0
MEEUS_TAU_MPRIME_DEG = -0.00467  # physical libration in longitude, sin M′ (Meeus ch. 53, Eckhardt 1981)
MEEUS_TAU_ANNUAL_DEG = 0.02520  # ... E sin M


def moments(beta=C.MOON_BETA_LLR, gamma=C.MOON_GAMMA_LLR):
    """(A, B, C) with C = 1 from β = (C−A)/B and γ = (B−A)/C: A = (1 − βγ)/(1 + β), B = A + γ."""
    A = (1.0 - beta * gamma) / (1.0 + beta)
    return np.array([A, A + gamma, 1.0])


def fundamental_arguments(t_days):
    """Meeus eq. 47.1–47.7 (degrees → radians), t in days from J2000.0 (TT): L′, D, M, M′, F, Ω, E."""
    T = np.asarray(t_days, float) / C.JULIAN_CENTURY_DAYS
    Lp, D, M, Mp, F, Om = (np.radians(a0 + rate * T) for a0, rate in _ARGUMENTS)
    E = 1.0 - 0.002516 * T - 0.0000074 * T * T  # the Earth's eccentricity against J2000 (Meeus eq. 47.6)
    return Lp, D, M, Mp, F, Om, E


# (value at J2000, rate) of L′, D, M, M′, F, Ω in degrees and degrees per century (Meeus eq. 47.1–47.7)
_ARGUMENTS = (C.MOON_MEAN_LONGITUDE, C.MOON_MEAN_ELONGATION, C.SUN_MEAN_ANOMALY, C.MOON_MEAN_ANOMALY,
              C.MOON_ARGUMENT_OF_LATITUDE, C.MOON_NODE)


# Meeus Table 47.A (D, M, M′, F, Σl in 1e-6°, Σr in 1e-3 km): the largest terms
_LR = np.array([
    (0, 0, 1, 0, 6288774, -20905355), (2, 0, -1, 0, 1274027, -3699111), (2, 0, 0, 0, 658314, -2955968),
    (0, 0, 2, 0, 213618, -569925), (0, 1, 0, 0, -185116, 48888), (0, 0, 0, 2, -114332, -3149),
    (2, 0, -2, 0, 58793, 246158), (2, -1, -1, 0, 57066, -152138), (2, 0, 1, 0, 53322, -170733),
    (2, -1, 0, 0, 45758, -204586), (0, 1, -1, 0, -40923, -129620), (1, 0, 0, 0, -34720, 108743),
    (0, 1, 1, 0, -30383, 104755), (2, 0, 0, -2, 15327, 10321), (0, 0, 1, 2, -12528, 0),
    (0, 0, 1, -2, 10980, 79661), (4, 0, -1, 0, 10675, -34782), (0, 0, 3, 0, 10034, -23210),
    (4, 0, -2, 0, 8548, -21636), (2, 1, -1, 0, -7888, 24208), (2, 1, 0, 0, -6766, 30824),
    (1, 0, -1, 0, -5163, -8379), (1, 1, 0, 0, 4987, -16675), (2, -1, 1, 0, 4036, -12831),
    (2, 0, 2, 0, 3994, -10445), (4, 0, 0, 0, 3861, -11650), (2, 0, -3, 0, 3665, 14403),
    (0, 1, -2, 0, -2689, -7003), (2, -1, -2, 0, 2390, 10056), (1, 0, 1, 0, -2348, 6322),
    (2, -2, 0, 0, 2236, -9884),
], float)
# Meeus Table 47.B (D, M, M′, F, Σb in 1e-6°)
_B = np.array([
    (0, 0, 0, 1, 5128122), (0, 0, 1, 1, 280602), (0, 0, 1, -1, 277693), (2, 0, 0, -1, 173237),
    (2, 0, -1, 1, 55413), (2, 0, -1, -1, 46271), (2, 0, 0, 1, 32573), (0, 0, 2, 1, 17198),
    (2, 0, 1, -1, 9266), (0, 0, 2, -1, 8822), (2, -1, 0, -1, 8216), (2, 0, -2, -1, 4324),
    (2, 0, 1, 1, 4200), (2, 1, 0, -1, -3359), (2, -1, -1, 1, 2463),
], float)

# rates of D, M, M′, F in rad/day (for Euler's forced terms)
_RATES = np.radians(np.array([a[1] for a in _ARGUMENTS[1:5]]) / C.JULIAN_CENTURY_DAYS)
MEAN_MOTION = np.radians(C.MOON_MEAN_LONGITUDE[1] / C.JULIAN_CENTURY_DAYS)  # dL′/dt, rad/day (of date)


def _e_factor(E, m):
    return np.where(np.abs(m) == 1, E, np.where(np.abs(m) == 2, E * E, 1.0))


def moon_geocentric(t_days):
    """Geocentric ecliptic longitude λ, latitude β (rad, fixed ecliptic J2000) and distance
    (km) of the Moon: the main terms of Meeus ch. 47."""
    Lp, D, M, Mp, F, Om, E = fundamental_arguments(t_days)
    args = np.stack([D, M, Mp, F])  # (4, N)
    argL = _LR[:, :4] @ args  # (K, N)
    eL = np.stack([_e_factor(E, m) for m in _LR[:, 1]])
    lon = Lp + np.radians(1e-6) * np.sum(_LR[:, 4:5] * eL * np.sin(argL), axis=0)
    dist = 385000.56 + 1e-3 * np.sum(_LR[:, 5:6] * eL * np.cos(argL), axis=0)
    argB = _B[:, :4] @ args
    eB = np.stack([_e_factor(E, m) for m in _B[:, 1]])
    lat = np.radians(1e-6) * np.sum(_B[:, 4:5] * eB * np.sin(argB), axis=0)
    T = np.asarray(t_days, float) / C.JULIAN_CENTURY_DAYS
    lon = lon - np.radians(PRECESSION_DEG_PER_CY) * T
    return lon, lat, dist


def earth_from_moon(t_days):
    """(N,3) km: the Earth's position relative to the Moon, fixed ecliptic J2000."""
    lon, lat, dist = moon_geocentric(np.atleast_1d(t_days))
    u = np.stack([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)], axis=-1)
    return -dist[:, None] * u


def mean_frame(t_days, incl_deg=C.MOON_EQUATOR_INCLINATION_DEG):
    """Quaternion (N,4) of the uniformly rotating Moon in the Cassini state (Meeus ch. 53):
    body → ecliptic R = Rz(Ω) Rx(−I) Rz(F + π); body x toward the mean Earth direction."""
    Lp, D, M, Mp, F, Om, E = fundamental_arguments(np.atleast_1d(t_days))
    T = np.asarray(np.atleast_1d(t_days), float) / C.JULIAN_CENTURY_DAYS
    Om = Om - np.radians(PRECESSION_DEG_PER_CY) * T  # node on the fixed ecliptic
    z = np.array([0.0, 0.0, 1.0])
    x = np.array([1.0, 0.0, 0.0])
    q1 = quat.from_axis_angle(np.broadcast_to(z, (len(T), 3)), Om)
    q2 = quat.from_axis_angle(np.broadcast_to(x, (len(T), 3)), np.full(len(T), -np.radians(incl_deg)))
    q3 = quat.from_axis_angle(np.broadcast_to(z, (len(T), 3)), F + np.pi)
    return quat.multiply(quat.multiply(q1, q2), q3)


def sub_earth_point(q, earth_pos):
    """Selenographic longitude and latitude (rad) of the Earth's direction in the body frame:
    the total (optical + physical) libration as seen from the Earth's centre."""
    s = quat.rotate_inverse(q, earth_pos)
    r = np.linalg.norm(s, axis=-1)
    return np.arctan2(s[:, 1], s[:, 0]), np.arcsin(s[:, 2] / r)


def optical_libration_meeus(t_days, incl_deg=C.MOON_EQUATOR_INCLINATION_DEG):
    """Meeus eq. 53.1: l′ = A − F, b′ = asin(−sin W cos β sin I − sin β cos I), W = λ − Ω
    (no nutation; both λ and Ω on the same ecliptic). An independent closed form."""
    lon, lat, _ = moon_geocentric(t_days)
    Lp, D, M, Mp, F, Om, E = fundamental_arguments(t_days)
    T = np.asarray(t_days, float) / C.JULIAN_CENTURY_DAYS
    W = lon - (Om - np.radians(PRECESSION_DEG_PER_CY) * T)
    I = np.radians(incl_deg)
    A = np.arctan2(np.sin(W) * np.cos(lat) * np.cos(I) - np.sin(lat) * np.sin(I), np.cos(W) * np.cos(lat))
    lp = np.remainder(A - F + np.pi, 2 * np.pi) - np.pi
    bp = np.arcsin(-np.sin(W) * np.cos(lat) * np.sin(I) - np.sin(lat) * np.cos(I))
    return lp, bp


def physical_libration(q, t_days, incl_deg=C.MOON_EQUATOR_INCLINATION_DEG):
    """Rotation of the body relative to the uniformly rotating Cassini frame, as a rotation
    vector (N,3) in the mean body frame (rad): component z is the physical libration in
    longitude τ (the body ahead of uniform rotation: τ > 0)."""
    qm = mean_frame(t_days, incl_deg)
    r = quat.multiply(quat.conjugate(qm), q)
    r = r * np.sign(r[:, :1])
    v = r[:, 1:]
    s = np.linalg.norm(v, axis=1, keepdims=True)
    ang = 2 * np.arctan2(s, r[:, :1])
    return np.divide(v * ang, s, out=np.zeros_like(v), where=s > 0)


def longitude_terms():
    """The Moon's longitude terms (α_k in rad, rate A_k in rad/day, phase function) used for
    Euler's forced libration: [(label, α, A, arg(t))]."""
    out = []
    names = "D M M' F".split()
    for row in _LR[:14]:
        mult = row[:4]
        label = ""
        for m, n in zip(mult, names):
            if m:
                sign = "−" if m < 0 else ("+" if label else "")
                label += sign + (f"{abs(int(m))}" if abs(m) != 1 else "") + n
        A = float(mult @ _RATES)

        def arg(t, mult=mult):
            Lp, D, M, Mp, F, Om, E = fundamental_arguments(t)
            return mult @ np.stack([D, M, Mp, F])

        out.append((label, float(np.radians(row[4] * 1e-6)), A, arg, int(mult[1])))
    return out


def euler_physical_libration(t_days, gamma, two_N):
    """§836 summed over the Moon's longitude terms: τ(t) = Σ −α_k·2N/(A_k² − 2N)·sin(arg_k)
    (rad), and the per-term coefficients {label: coefficient}."""
    t = np.asarray(t_days, float)
    _, _, _, _, _, _, E = fundamental_arguments(t)
    tau = np.zeros_like(t)
    coef = {}
    for label, alpha, A, arg, mM in longitude_terms():
        c = -alpha * two_N / (A * A - two_N)
        coef[label] = c
        tau += c * (E ** abs(mM)) * np.sin(arg(t))
    return tau, coef
