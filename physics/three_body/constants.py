"""Lunar and solar constants shared by the three-body modules, each with its source.

The Moon's mean longitude and the longitudes of its node and perigee are published referred to
the mean equinox of date (Simon et al. 1994, A&A 282, 663; quoted in Meeus, *Astronomical
Algorithms*, 2nd ed. 1998, eqs. 47.1–47.7). The equinox moves along the ecliptic by the general
precession in longitude p_A = 5028.796195″ per Julian century (IAU 2006 precession, Capitaine,
Wallace & Chapront 2003, A&A 412, 567). Our models have a fixed ecliptic and fixed axes, so every
rate is converted to the fixed (sidereal) frame by subtracting p_A:

- sidereal month: 360°/(481267.88123421° − p_A) per century = 27.3216615 d
  (the Astronomical Almanac's 27.321 661 6 d);
- node: −1934.1362891° − p_A per century → 6793.477 d = 18.5995 yr against the stars
  (6798.38 d, the period usually quoted, is measured from the moving equinox);
- perigee: 4069.0137287° − p_A per century → 3232.605 d = 8.8504 yr against the stars (this is
  the usually quoted 3232.6 d).
"""
from __future__ import annotations

JULIAN_CENTURY_DAYS = 36525.0
JULIAN_YEAR_DAYS = 365.25
GENERAL_PRECESSION_DEG_PER_CY = 5028.796195 / 3600.0  # p_A, IAU 2006

MOON_MEAN_LONGITUDE_RATE_DEG_PER_CY = 481267.88123421  # of date (Meeus 47.1)
MOON_NODE_RATE_DEG_PER_CY = -1934.1362891  # of date (Meeus 47.7)
MOON_PERIGEE_RATE_DEG_PER_CY = 4069.0137287  # of date: L' − M' (Meeus 47.1, 47.4)


def _period_days(rate_deg_per_cy: float) -> float:
    return 360.0 * JULIAN_CENTURY_DAYS / abs(rate_deg_per_cy)


# the sidereal month used everywhere in `physics.three_body` (27.3216615 d)
SIDEREAL_MONTH_DAYS = _period_days(MOON_MEAN_LONGITUDE_RATE_DEG_PER_CY - GENERAL_PRECESSION_DEG_PER_CY)
# sidereal year 365.256363 d (Astronomical Almanac)
SIDEREAL_YEAR_DAYS = 365.256363

NODE_PERIOD_OF_DATE_DAYS = _period_days(MOON_NODE_RATE_DEG_PER_CY)  # 6798.38 d
NODE_PERIOD_SIDEREAL_DAYS = _period_days(MOON_NODE_RATE_DEG_PER_CY - GENERAL_PRECESSION_DEG_PER_CY)  # 6793.48 d
APSE_PERIOD_OF_DATE_DAYS = _period_days(MOON_PERIGEE_RATE_DEG_PER_CY)  # 3231.50 d
APSE_PERIOD_SIDEREAL_DAYS = _period_days(MOON_PERIGEE_RATE_DEG_PER_CY - GENERAL_PRECESSION_DEG_PER_CY)  # 3232.61 d

# The Earth's figure (not in Euler's model): J2 and equatorial radius (IERS Conventions 2010),
# obliquity of the ecliptic at J2000 (IAU 2006: 84381.406″).
EARTH_J2 = 1.0826359e-3
EARTH_RADIUS_KM = 6378.1366
OBLIQUITY_RAD = 84381.406 / 3600.0 * 3.141592653589793 / 180.0
