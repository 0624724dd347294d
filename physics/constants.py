"""Physical constants, each defined once, with its unit in its name and its source beside it.

Everything else in theoria imports these; a quantity in other units is either converted where it
is used or named here as a derived constant (computed from the defining ones, never retyped).

Units: km, s, day (86400 s), Julian year and century, AU (IAU 2012), degrees, arcseconds, radians.

Sources
-------
- IAU 2012 Resolution B2: the astronomical unit (a defined length).
- IAU 1976 system: Gauss's constant k (defining GM☉ in AU³/day²). With the 2012 AU it gives
  GM☉ = 1.3271244004e11 km³/s², the TDB-compatible value of the IAU 2009 system
  (1.32712440041e11; Luzum et al. 2011, Celest. Mech. Dyn. Astron. 110, 293).
- IAU 2009 system (Luzum et al. 2011): the Moon/Earth mass ratio.
- IERS Conventions 2010 (IERS TN 36, Table 1.1): GM⊕, the Earth's equatorial radius, J2, the
  nominal mean angular velocity of the Earth.
- IAU 2000 nutation (Mathews, Herring & Buffett 2002, J. Geophys. Res. 107, 2068): the Earth's
  dynamical ellipticity H_d.
- IAU 2006 precession (Capitaine, Wallace & Chapront 2003, A&A 412, 567, "P03"): the obliquity
  at J2000, ψ_A, p_A and the geodesic precession. IAU 1976 (Lieske et al. 1977, A&A 58, 1): the
  general precession Meeus uses.
- Simon et al. 1994 (A&A 282, 663) as quoted in Meeus, *Astronomical Algorithms*, 2nd ed. 1998:
  the Moon's fundamental arguments (eq. 47.1–47.7, linear terms), its mean eccentricity and
  inclination and mean perigee (ch. 47), the Sun's mean longitude (eq. 25.2), its eccentricity and
  the Earth's perihelion and semi-major axis (Table 31.A).
- Lunar laser ranging (Williams et al. 2014, J. Geophys. Res. Planets 119, 1546; the DE430
  lunar model, Williams, Boggs & Folkner 2013, JPL IOM 335-JW,DB,WF-20130722-016): the Moon's
  moment differences; the mean lunar equator's inclination I (IAU; Meeus ch. 53).
- The Astronomical Almanac: the sidereal year.
- JPL DE421 (Folkner, Williams & Boggs 2009, IPN Progress Report 42-178; its lunar model:
  Williams, Boggs & Folkner 2008, "DE421 Lunar Orbit, Physical Librations, and Surface
  Coordinates", JPL IOM 335-JW,DB,WF-20080314-001): the Moon's gravity field of degree 2 and 3
  (unnormalised, reference radius 1738 km), the fluid core's share of the moment C and the tidal
  Love number k2 of its lunar model. The numbers are those of the ephemeris file's header (the
  `de421` package that theoria depends on); tests/test_real_sky.py reads them back from that file.
  The rotation from DE421's principal-axis frame to its mean-Earth frame: the same memo, as NAIF's
  lunar frame kernel moon_080317.tf gives it (frame MOON_ME_DE421).
- Vondrák, Capitaine & Wallace 2011 (A&A 534, A22), long-term precession: the ecliptic and
  equator poles over ±200,000 years (SOFA/ERFA `ltpecl`, `ltpequ`, which the scenario calls).
- Peale 1969 (AJ 74, 483), Cassini states: the Moon's mean obliquity to the ecliptic is the
  IAU value I above (1.54242°, the mean lunar equator's inclination).

Frames and periods
------------------
The Moon's mean longitude and the longitudes of its node and perigee are published referred to the
mean equinox of date. The equinox moves along the ecliptic by the general precession in longitude
p_A per Julian century. Our models have a fixed ecliptic and fixed axes, so every rate is
converted to the fixed (sidereal) frame by subtracting p_A:

- sidereal month: 360°/(481267.88123421° − p_A) per century = 27.3216615 d
  (the Astronomical Almanac's 27.321 661 6 d);
- node: −1934.1362891° − p_A per century → 6793.477 d = 18.5995 yr against the stars
  (6798.38 d, the period usually quoted, is measured from the moving equinox);
- perigee: 4069.0137287° − p_A per century → 3232.605 d = 8.8504 yr against the stars (this is
  the usually quoted 3232.6 d).
"""
from __future__ import annotations

import math

# --- units and time ------------------------------------------------------------------------------

SECONDS_PER_DAY = 86400.0
JULIAN_YEAR_DAYS = 365.25
JULIAN_CENTURY_DAYS = 36525.0
ARCSEC_RAD = math.pi / 648000.0  # one second of arc in radians
AU_KM = 149597870.7  # IAU 2012 Resolution B2 (exact)
SIDEREAL_YEAR_DAYS = 365.256363  # Astronomical Almanac

# --- the Sun --------------------------------------------------------------------------------------

K_GAUSS = 0.01720209895  # AU^{3/2}/day, Gauss's constant (IAU 1976)
GM_SUN_AU3_DAY2 = K_GAUSS**2
GM_SUN_KM3_S2 = GM_SUN_AU3_DAY2 * AU_KM**3 / SECONDS_PER_DAY**2  # 1.3271244004e11 (IAU 2009, TDB)

# the Sun's geocentric mean orbit at J2000 (the Earth's heliocentric one turned by 180°)
SUN_MEAN_LONGITUDE_J2000_DEG = 280.46646  # Meeus eq. 25.2
SUN_PERIGEE_J2000_DEG = 282.937348  # 180° + the Earth's perihelion 102.937348° (Meeus Table 31.A)
SUN_ECCENTRICITY = 0.0167086  # Meeus Table 31.A (0.01670862 at J2000)
SUN_SEMI_MAJOR_AXIS_AU = 1.000001018  # Meeus Table 31.A

# --- the Earth ------------------------------------------------------------------------------------

GM_EARTH_KM3_S2 = 398600.4418  # IERS Conventions 2010
EARTH_RADIUS_KM = 6378.1366  # equatorial radius, IERS Conventions 2010
EARTH_J2 = 1.0826359e-3  # IERS Conventions 2010 (not in Euler's model)
EARTH_ROTATION_RAD_S = 7.292115e-5  # nominal mean angular velocity, IERS Conventions 2010
EARTH_DYNAMICAL_ELLIPTICITY = 0.0032737949  # H = (C − A)/C, IAU 2000 nutation (MHB2000, H_d)
OBLIQUITY_J2000_ARCSEC = 84381.406  # ε₀, IAU 2006 (P03)
OBLIQUITY_J2000_RAD = OBLIQUITY_J2000_ARCSEC * ARCSEC_RAD

# precession of the equator, arcsec per Julian century
LUNISOLAR_PRECESSION_IAU2006_ARCSEC_PER_CY = 5038.481507  # ψ_A: the equator on the fixed ecliptic of J2000 (P03)
GENERAL_PRECESSION_IAU2006_ARCSEC_PER_CY = 5028.796195  # p_A: adds the ecliptic's motion (P03)
GEODESIC_PRECESSION_ARCSEC_PER_CY = 1.919883  # relativistic part of ψ_A, not a torque (P03)
GENERAL_PRECESSION_IAU1976_ARCSEC_PER_CY = 5029.0966  # Lieske et al. 1977, as in Meeus eq. 21.5 and ch. 47
GENERAL_PRECESSION_DEG_PER_CY = GENERAL_PRECESSION_IAU2006_ARCSEC_PER_CY / 3600.0

# --- the Moon -------------------------------------------------------------------------------------

MOON_EARTH_MASS_RATIO = 0.0123000371  # M☾/M⊕, IAU 2009 system
GM_MOON_KM3_S2 = GM_EARTH_KM3_S2 * MOON_EARTH_MASS_RATIO
EARTH_MOON_DISTANCE_KM = 384400.0  # the mean distance usually quoted (the lunar unit of length)

# Fundamental arguments of the Moon's motion at J2000 and their rates, referred to the mean
# equinox of date (Meeus eq. 47.1–47.7, linear terms): (degrees, degrees per Julian century).
MOON_MEAN_LONGITUDE = (218.3164477, 481267.88123421)  # L′
MOON_MEAN_ELONGATION = (297.8501921, 445267.1114034)  # D
SUN_MEAN_ANOMALY = (357.5291092, 35999.0502909)  # M
MOON_MEAN_ANOMALY = (134.9633964, 477198.8675055)  # M′
MOON_ARGUMENT_OF_LATITUDE = (93.2720950, 483202.0175233)  # F
MOON_NODE = (125.0445479, -1934.1362891)  # Ω
MOON_PERIGEE_RATE_DEG_PER_CY = MOON_MEAN_LONGITUDE[1] - MOON_MEAN_ANOMALY[1]  # L′ − M′, 4069.0137287
MOON_PERIGEE_J2000_DEG = 83.3532465  # mean perigee ϖ (Meeus ch. 47)
MOON_MEAN_ECCENTRICITY = 0.0549  # Meeus ch. 47
MOON_MEAN_INCLINATION_DEG = 5.145396  # to the ecliptic, Meeus ch. 47
MOON_INCLINATION_RANGE_DEG = (4.99, 5.30)  # its oscillation about the mean (period 173 d)

# the Moon's figure and rotation
MOON_BETA_LLR = 631.0e-6  # (C − A)/B, lunar laser ranging (Williams et al. 2014; DE430)
MOON_GAMMA_LLR = 227.7e-6  # (B − A)/C, idem
MOON_EQUATOR_INCLINATION_DEG = 1.54242  # mean lunar equator to the ecliptic (IAU; Meeus ch. 53)

# DE421's lunar model (Williams, Boggs & Folkner 2008; the header of the ephemeris file). The field
# is unnormalised, referred to the principal axes, reference radius MOON_REFERENCE_RADIUS_KM.
MOON_BETA_DE421 = 0.0006310022025364629  # (C − A)/B, LBET
MOON_GAMMA_DE421 = 0.0002277305314199142  # (B − A)/C, LGAM
MOON_C22_DE421 = 2.238976709652413e-05  # C22M (J2M = 2.032732576370724e-4 follows from β, γ and C22)
# the degree-3 field (C30 = −J3, C31, S31, C32, S32, C33, S33): J3M, C31M, S31M, C32M, S32M, C33M, S33M
MOON_DEGREE3_DE421 = (-8.404701525941e-06, 2.8452435e-05, 5.9008e-06, 4.84638724000903e-06,
                      1.6841984741476e-06, 1.674047530039142e-06, -2.485526e-07)
MOON_REFERENCE_RADIUS_KM = 1738.0  # AM
MOON_CORE_MOMENT_FRACTION_DE421 = 0.0007  # IFAC: the fluid core's polar moment / the Moon's C
MOON_LOVE_K2_DE421 = 0.02163368386360741  # K2M, the Moon's tidal Love number (not modelled; sizes the tides)
MOON_TIDE_DELAY_DE421_DAYS = 0.1078586819856588  # TAUM, the time lag of the lunar tide (not modelled)
MOON_CORE_FRICTION_DE421_PER_DAY = 1.493760249305661e-08  # KVC: core–mantle friction / C (not modelled)
# C/(M R²) from γ = (B − A)/C and C22 = (B − A)/(4 M R²) (a relation, not a fit)
MOON_POLAR_MOMENT_FACTOR_DE421 = 4.0 * MOON_C22_DE421 / MOON_GAMMA_DE421  # 0.39327
# DE421's principal-axis (PA) frame to its mean-Earth (ME) frame: v_ME = R1(−c) R2(−b) R3(−a) v_PA with
# frame rotations R_i, angles about z, y, x: 67.92″, 78.56″, 0.30″ (moon_080317.tf's TKFRAME_31007, axes
# 3, 2, 1), written in milliarcseconds
MOON_PA_TO_ME_DE421_MAS = (67920, 78560, 300)
# DE421's optical libration (the Earth's centre seen on the Moon's mean-Earth axes): the largest |longitude|
# and |latitude| in each of 16 windows of 18.6 years from 1900 on (to 2197.6), the range of those maxima
# (computed from the file every 0.02 day; tests/test_real_sky.py recomputes them)
MOON_OPTICAL_LIBRATION_LON_MAX_DE421_DEG = (8.070, 8.141)
MOON_OPTICAL_LIBRATION_LAT_MAX_DE421_DEG = (6.862, 6.867)
MOON_OPTICAL_LIBRATION_DE421_WINDOWS = (1900, 16)  # first year, number of 18.6-year windows


def period_days(rate_deg_per_cy: float) -> float:
    """Period (days) of an angle that turns at `rate_deg_per_cy` degrees per Julian century."""
    return 360.0 * JULIAN_CENTURY_DAYS / abs(rate_deg_per_cy)


# derived periods (days): against the stars (sidereal, the frame of our models) and of date
SIDEREAL_MONTH_DAYS = period_days(MOON_MEAN_LONGITUDE[1] - GENERAL_PRECESSION_DEG_PER_CY)  # 27.3216615
TROPICAL_MONTH_DAYS = period_days(MOON_MEAN_LONGITUDE[1])  # 27.321582
ANOMALISTIC_MONTH_DAYS = period_days(MOON_MEAN_ANOMALY[1])  # 27.554550
ANOMALISTIC_YEAR_DAYS = period_days(SUN_MEAN_ANOMALY[1])  # 365.2596
NODE_PERIOD_OF_DATE_DAYS = period_days(MOON_NODE[1])  # 6798.38
NODE_PERIOD_SIDEREAL_DAYS = period_days(MOON_NODE[1] - GENERAL_PRECESSION_DEG_PER_CY)  # 6793.48
APSE_PERIOD_OF_DATE_DAYS = period_days(MOON_PERIGEE_RATE_DEG_PER_CY)  # 3231.50
APSE_PERIOD_SIDEREAL_DAYS = period_days(MOON_PERIGEE_RATE_DEG_PER_CY - GENERAL_PRECESSION_DEG_PER_CY)  # 3232.61
