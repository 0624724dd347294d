"""A whole precession cycle (§846 with modern values): the Earth's pole among the stars over
25,800 years, from a secularly calibrated Sun–Moon model.
"""
from __future__ import annotations

import functools
import math
import numpy as np
from ..physics import earth_precession as EP
from ..physics import quaternion as quat
from ..physics.params import Param, ParameterError
from ..physics.constants import (ARCSEC_RAD, LUNISOLAR_PRECESSION_IAU2006_ARCSEC_PER_CY, OBLIQUITY_J2000_RAD,
                                 SIDEREAL_MONTH_DAYS)
from ..physics.precession import pole_angles
from ..physics.trajectory import Trajectory
from .drawing import Camera
from .base import Comparison, Run, Scenario, register
from ._ch16_drawing import EARTH_OPTIONS, earth_scene
from ._earth import MIN_STEPS, YR
from . import _validity


@functools.lru_cache(maxsize=4)
def mean_orbits(calibration_years=40.0) -> EP.MeanOrbits:
    """The mean-element orbits of the long view, from a REBOUND run of `calibration_years`
    (cached: a 40-year IAS15 run takes seconds and depends on nothing else)."""
    el = EP.calibrated_moon_elements()
    eph = EP.integrate_orbits(calibration_years * YR, 0.5, moon_elements=el)
    return EP.MeanOrbits(EP.moon_mean_elements(eph))


LONG_MIN_SAMPLES = 5


def _check_long(values):
    """A straight line through the pole longitude needs a few stored samples and steps."""
    lo = max(LONG_MIN_SAMPLES * values["sample_years"], MIN_STEPS * values["step_days"] / YR, 100.0)
    if values["years"] < lo:
        raise ParameterError("years", values["years"],
                             f"{lo:.4g} ≤ years ≤ 30000 (at least 100 yr, {LONG_MIN_SAMPLES} samples of sample_years = "
                             f"{values['sample_years']:g} and {MIN_STEPS} steps)")


def run_long_view(years=25800.0, step_days=2.0, sample_years=5.0, scheme="strang", progress=None,
                  calibration_years=40.0):
    """One run over a whole precession cycle. The Sun on its Kepler ellipse; the Moon on a Kepler
    ellipse whose node and perigee turn at the rates measured from a REBOUND run of
    `calibration_years` (the node regression comes from the integration, not imposed).
    Returns (t_days, L, q, I, MeanOrbits)."""
    orb = mean_orbits(float(calibration_years))
    t, L, q, I = EP.run_earth(orb.sun, orb.moon_pos, years * YR, step_days, scheme=scheme,
                              sample_days=sample_years * YR, progress=progress)
    return t, L, q, I, orb


def _earth_long(values, progress=None):
    t, L, q, I, orb = run_long_view(values["years"], values["step_days"], values["sample_years"], progress=progress)
    axis = quat.rotate(q, L)
    p, lam = pole_angles(axis)
    ty = t / YR
    c = np.polyfit(ty, lam, 1)
    rate = -c[0] / ARCSEC_RAD
    mod = EP.precession_parts_modern(orb.moon)
    eul = -(mod["euler_sun"] + mod["euler_moon"]) / ARCSEC_RAD * YR
    m = dict(precession_rate_arcsec_per_yr=rate, precession_rate_euler_arcsec_per_yr=eul,
             precession_period_yr=360 * 3600 / rate, precession_period_euler_yr=360 * 3600 / eul,
             turned_deg=float(np.degrees(lam[0] - lam[-1])),
             obliquity_min_deg=float(np.degrees(p.min())), obliquity_max_deg=float(np.degrees(p.max())),
             moon_node_period_yr=orb.moon.node_period_yr)
    # the celestial pole in J2000 equatorial RA/Dec, for the star chart
    ce, se = math.cos(OBLIQUITY_J2000_RAD), math.sin(OBLIQUITY_J2000_RAD)
    ye = ce * axis[:, 1] - se * axis[:, 2]
    ze = se * axis[:, 1] + ce * axis[:, 2]
    ra = np.degrees(np.unwrap(np.arctan2(ye, axis[:, 0])))
    dec = np.degrees(np.arcsin(np.clip(ze, -1, 1)))
    sun = orb.sun(t)
    moon = orb.moon_pos(t)
    traj = Trajectory(ty, q, L * YR, I, time_unit="yr",
                      bodies={"sun": sun / np.linalg.norm(sun, axis=1, keepdims=True),
                              "moon": moon / np.linalg.norm(moon, axis=1, keepdims=True)})
    lam_e = lam[0] - eul * ARCSEC_RAD * ty
    warnings = _validity.add([], _validity.coarse_step(values["step_days"], SIDEREAL_MONTH_DAYS / 2,
                                                       "the Moon's pull, which repeats twice a month", "d", "step_days"))
    return Run("earth-long-view", values, traj, m,
                  [Comparison("precession period", 360 * 3600 / eul, m["precession_period_yr"],
                              360 * 3600 / (LUNISOLAR_PRECESSION_IAU2006_ARCSEC_PER_CY / 100), "yr",
                              "modern: IAU 2006 ψ_A rate (fixed ecliptic); with the ecliptic's motion (p_A) 25,772 yr")],
                  ["Nutation is sampled too sparsely here to be seen (samples every "
                   f"{values['sample_years']:g} yr); the pole path is the angular-momentum axis in the J2000 ecliptic.",
                   "Pass the bright-star catalogue (assets/bright_stars.csv, read by the app) to "
                   "physics.earth_precession.pole_star_passages to list the pole stars along the path."],
                  plot_series={"pole longitude (deg)": np.degrees(lam), "pole longitude, Euler (deg)": np.degrees(lam_e),
                               "obliquity (deg)": np.degrees(p), "obliquity, Euler (deg)": np.full_like(p, np.degrees(p[0])),
                               "pole RA J2000 (deg)": ra, "pole Dec J2000 (deg)": dec}, warnings=warnings)


def _draw(run, spec, view):
    return earth_scene(run, spec, view, long_view=True)


register(Scenario(
    name="earth-long-view",
    title="A whole precession cycle: the pole among the stars",
    section="§846 (modern values)",
    group="ch. 16",
    summary=("One run over ~25,800 years: the Earth's axis, tilted 23.4°, circles the pole of the "
            "ecliptic once. On the celestial sphere the pole passes Polaris now, was near Thuban 5,000 "
            "years ago and will be near Vega in about 12,000 years. A long run: the progress bar shows "
            "how far it has got."),
    params=(
        Param("years", 25800.0, 0.0, 30000.0, "yr", "length of the run from J2000", exclusive_min=True, step=100.0),
        Param("step_days", 2.0, 0.0, 5.0, "day", "integrator step", exclusive_min=True, step=0.5),
        Param("sample_years", 5.0, 0.0, 1000.0, "yr", "spacing of the stored states", exclusive_min=True),
    ),
    camera=Camera((3.6, -3.2, 4.4), (0.0, 0.0, 0.6)),  # the pole's circle near the top of the sphere
    preview={'step_days': 5.0, 'sample_years': 50.0},
    simulate_fn=_earth_long,
    draw=_draw,
    options={k: v for k, v in EARTH_OPTIONS.items() if k != "wiggle"},  # sampled every few years: no nutation
    check=_check_long,
    euler_formula=("mean precession N cos n per attracting body, N = 3GM (C − A) / (2Aε s³) (§846)"),
    presets=(
        ("Earth: 25,800 years", {}),
        ("Earth: to Vega, 13,000 years", {"years": 13000.0}),
    ),
))
