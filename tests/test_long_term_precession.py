"""The pole over tens of millennia: the secular (averaged) torque on Vondrák, Capitaine & Wallace's
moving ecliptic against their equator pole (their published series, through ERFA), and the
averaging against the full integration of the same torques."""
from __future__ import annotations

import math

import numpy as np
import pytest

from theoria.physics import constants as C
from theoria.physics import long_term_precession as LT
from theoria.physics.constants import JULIAN_YEAR_DAYS
from theoria.physics.precession import precession_rate_orbit

YR = JULIAN_YEAR_DAYS


def test_vondrak_poles_at_j2000_are_the_j2000_frame():
    k = LT.vondrak_ecliptic_pole(0.0)
    assert np.allclose(k, [0.0, 0.0, 1.0], atol=5e-11)
    e = LT.vondrak_equator_pole(0.0)
    assert LT.obliquity(e, k) == pytest.approx(C.OBLIQUITY_J2000_RAD, abs=5e-11)


def test_rotation_onto_the_ecliptic_of_date():
    k = LT.vondrak_ecliptic_pole(np.array([-9000.0, 3000.0, 12000.0]) * YR)
    R = LT.rotation_to_ecliptic_of_date(k)
    assert np.allclose(R @ np.array([0.0, 0.0, 1.0]), k, atol=1e-14)
    assert np.allclose(np.swapaxes(R, -1, -2) @ R, np.eye(3), atol=1e-14)
    assert np.allclose(np.linalg.det(R), 1.0)


def test_secular_rate_is_the_orbit_averaged_precession_on_a_fixed_ecliptic():
    """dŝ/dt of the vector form against physics.precession's rate formula (λ̇ = −κ cos ε), coded apart."""
    H, w, eps = C.EARTH_DYNAMICAL_ELLIPTICITY, 6.3, math.radians(23.44)
    gm, a, e, inc = 2.9e-4, 1.0, 0.0167, 0.0
    tq = LT.SecularTorques(LT.kappa(gm, LT.kepler_inverse_cube(a, e), inc, H, w), 0.0, 0.0)
    s = np.array([0.0, math.sin(eps), math.cos(eps)])
    v = LT.secular_rate(s, np.array([0.0, 0.0, 1.0]), tq)
    lam_dot = -v[0] / math.sin(eps)  # at longitude 90°: the pole moves along −x as λ decreases... λ̇ = −vₓ/sin ε
    assert lam_dot == pytest.approx(precession_rate_orbit(gm, a, e, inc, H, w, eps), rel=1e-12)


def test_pole_within_a_tenth_of_a_degree_of_vondrak_over_13000_years():
    """The goal: theoria's averaged torque, driven by Vondrák et al.'s ecliptic, keeps the equator's
    pole within 0.1° of theirs from 11,000 BC to AD 15,000 (measured 0.041°); on the fixed J2000
    ecliptic it strays by degrees (2.4°), which is what the ecliptic's motion is worth."""
    from theoria.scenarios.earth_long_view import secular_pole

    t = np.linspace(-13000.0, 13000.0, 261) * YR
    ref = LT.vondrak_equator_pole(t)
    sep = np.degrees(LT.angle_between(secular_pole(t, "moving"), ref))
    assert sep.max() < 0.1
    assert np.degrees(LT.angle_between(secular_pole(t, "fixed"), ref)).max() > 1.0
    # the obliquity's slow swing: within a few hundredths of a degree of theirs at every date
    k = LT.vondrak_ecliptic_pole(t)
    obl, obl_ref = LT.obliquity(secular_pole(t, "moving"), k), LT.obliquity(ref, k)
    assert np.degrees(np.ptp(obl_ref)) > 1.0
    assert np.degrees(np.abs(obl - obl_ref)).max() < 0.05


@pytest.mark.slow
def test_averaging_error_against_the_full_integration_over_a_millennium():
    """The secular model against every kick of the same Sun and Moon (mean Kepler orbits on the same
    moving ecliptic, no geodesic term in either) over 1,000 years: after fitting out the constant
    offset and the node's nutation, the drift is 1.0″ (2e-5 of the 50,300″ the pole turns): the
    second-order terms the average drops. Bound 3″."""
    from theoria.benchmarks.precession import secular_error_against_full

    drift, _ = secular_error_against_full(1000.0)
    assert drift < 3.0
