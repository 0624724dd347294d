"""The real sky, shared by the scenarios held against it: JPL's DE421 ephemeris (the `de421`
package, read by `jplephem`; the file ships inside the package, nothing is downloaded).

DE421 (Folkner, Williams & Boggs 2009) as the `de421` package ships it covers JD 2414992.5 –
2524624.5 (1899 December 4 – 2200 February 1) in TDB; it holds the positions of the Sun, the Earth–Moon barycentre and the Moon
(geocentric) in the ICRF, and the Moon's libration angles (3-1-3 Euler angles from the ICRF to
its principal axes) with their rates. Here everything is turned into theoria's J2000 ecliptic
frame and times are days from J2000.0 (TDB).
"""
from __future__ import annotations

import functools

import numpy as np

from ..physics import real_moon
from ..physics.constants import JULIAN_YEAR_DAYS

J2000_JD = 2451545.0
J2000_YEAR = 2000.0


class DE421:
    """Positions and the Moon's attitude from DE421, in the J2000 ecliptic frame (km, days)."""

    def __init__(self):
        import de421
        from jplephem.ephem import Ephemeris

        self.eph = Ephemeris(de421)
        self.first_day = float(self.eph.jalpha) - J2000_JD
        self.last_day = float(self.eph.jomega) - J2000_JD

    # the span, in days from J2000 and in years (TDB)
    @property
    def first_year(self) -> float:
        return J2000_YEAR + self.first_day / JULIAN_YEAR_DAYS

    @property
    def last_year(self) -> float:
        return J2000_YEAR + self.last_day / JULIAN_YEAR_DAYS

    def constant(self, name: str) -> float:
        """A constant of the ephemeris file's header (LBET, C31M, IFAC, EMRAT, ...)."""
        return float(getattr(self.eph, name))

    def _pos(self, name, t):
        t = np.atleast_1d(np.asarray(t, float))
        return np.asarray(self.eph.position(name, J2000_JD, t), float).T  # (N, 3) km, ICRF

    def moon_geocentric_icrf(self, t):
        return self._pos("moon", t)

    def earth_from_moon(self, t):
        """(N, 3) km: the Earth's centre seen from the Moon's, ecliptic J2000."""
        return real_moon.ecliptic_from_icrf(-self._pos("moon", t))

    def sun_from_moon(self, t):
        """(N, 3) km: the Sun's centre seen from the Moon's, ecliptic J2000."""
        emb, moon, sun = self._pos("earthmoon", t), self._pos("moon", t), self._pos("sun", t)
        return real_moon.ecliptic_from_icrf(sun - (emb + self.eph.moon_share * moon))

    def sun_from_earth(self, t):
        emb, moon, sun = self._pos("earthmoon", t), self._pos("moon", t), self._pos("sun", t)
        return real_moon.ecliptic_from_icrf(sun - (emb - self.eph.earth_share * moon))

    def libration_angles(self, t):
        """DE421's (φ, θ, ψ) and their rates (per day), each (3, N)."""
        t = np.atleast_1d(np.asarray(t, float))
        p, v = self.eph.position_and_velocity("librations", J2000_JD, t)
        return np.asarray(p, float), np.asarray(v, float)

    def moon_attitude(self, t):
        """The Moon's principal axes: attitude quaternions (N, 4), body → ecliptic J2000, and the
        body-frame angular velocity (N, 3) in rad/day."""
        ang, rate = self.libration_angles(t)
        q_icrf = real_moon.euler313_quaternion(*ang)
        from ..physics import quaternion as quat

        return quat.multiply(real_moon.Q_ECLIPTIC_FROM_ICRF, q_icrf), real_moon.euler313_omega_body(ang, rate)


@functools.lru_cache(maxsize=1)
def de421() -> DE421:
    """The DE421 ephemeris (loaded once per process; its arrays are read as they are needed)."""
    return DE421()
