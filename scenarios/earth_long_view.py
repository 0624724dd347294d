"""A whole precession cycle (§846 with modern values): the Earth's pole among the stars over
26,000 years, on the moving ecliptic of Vondrák, Capitaine & Wallace (2011), against their pole.

Two models of the same torques:
- "secular" (default): the torque of the Sun and the Moon averaged over the day, the month, the
  year and the Moon's 18.6-year node (physics.long_term_precession), the ecliptic pole of date
  from Vondrák et al. (ERFA ltpecl), the geodesic precession; a whole cycle in well under a second
  once the Moon's mean orbit is known (a 4-year REBOUND run). Its error against the full
  integration is measured over a millennium (tests, `theoria bench`). With `zoom_years` > 0 the
  day-, month- and year-scale terms are added back over a window: the full integration from the
  secular pole at `zoom_year`, whose difference from the secular pole is the nutation.
- "full": every kick of the Sun and the Moon on their mean Kepler orbits (the Moon's node and
  perigee turning at the rates of a 40-year REBOUND run), carried onto the moving ecliptic, from
  J2000 on.

Check row E10.earth-long-term: the pole within 0.1° of Vondrák et al.'s over ±13,000 years.
"""
from __future__ import annotations

import functools
import math

import numpy as np

from ..physics import earth_precession as EP
from ..physics import long_term_precession as LT
from ..physics import quaternion as quat
from ..physics.constants import (ARCSEC_RAD, EARTH_DYNAMICAL_ELLIPTICITY, GENERAL_PRECESSION_IAU2006_ARCSEC_PER_CY,
                                 GM_SUN_AU3_DAY2, LUNISOLAR_PRECESSION_IAU2006_ARCSEC_PER_CY, OBLIQUITY_J2000_RAD,
                                 SIDEREAL_MONTH_DAYS)
from ..physics.params import POSITIVE, Param, ParameterError
from ..physics.precession import pole_angles
from ..physics.trajectory import Trajectory
from .base import Comparison, Run, Scenario, register
from .checks import register_check
from .drawing import Camera, Label, Option, Path, Sphere, unit, z_to_many
from ._ch16_drawing import EARTH_OPTIONS, bright_stars, earth_scene
from ._earth import MIN_STEPS, YR
from .budget import Cost, trajectory_bytes
from ._earth import CALIBRATION_STEPS, REBOUND_STEPS_PER_DAY, rotation_run
from . import _validity

J2000_YEAR = 2000.0
SECULAR_CALIBRATION_YEARS = 4.0  # the REBOUND run that gives the secular model its Moon


@functools.lru_cache(maxsize=4)
def mean_orbits(calibration_years=40.0) -> EP.MeanOrbits:
    """The mean-element orbits of the full model, from a REBOUND run of `calibration_years`
    (cached: a 40-year IAS15 run takes seconds and depends on nothing else)."""
    el = EP.calibrated_moon_elements()
    eph = EP.integrate_orbits(calibration_years * YR, 0.5, moon_elements=el)
    return EP.MeanOrbits(EP.moon_mean_elements(eph))


@functools.lru_cache(maxsize=4)
def secular_calibration(calibration_years=SECULAR_CALIBRATION_YEARS, H=EARTH_DYNAMICAL_ELLIPTICITY):
    """The averaged model's constants and the Moon's mean elements, from one REBOUND run of
    `calibration_years` (the same calibrated Sun–Earth–Moon integration as the Earth scenario).
    The Sun: its mean Kepler orbit (a, e). The Moon: the node-averaged tidal tensor of the
    integrated Moon: with z normal to the ecliptic, q⊥ − q∥ = ⟨(x² + y²)/2r⁵ − z²/r⁵⟩ =
    ⟨r⁻³ (1 − 3/2 sin²i)⟩/2 for any node, so a few years suffice (the solar perturbations of r are in
    it: +9e-5 against the Kepler ellipse of the mean elements). Returns (SecularTorques, MeanOrbits)."""
    el = EP.calibrated_moon_elements()
    eph = EP.integrate_orbits(calibration_years * YR, 0.5, moon_elements=el)
    x = eph.moon_x
    r5 = np.linalg.norm(x, axis=1) ** 5
    q = float(np.mean(0.5 * (x[:, 0] ** 2 + x[:, 1] ** 2) / r5 - x[:, 2] ** 2 / r5))
    spin = EP.SPIN_RAD_DAY
    k_sun = LT.kappa(GM_SUN_AU3_DAY2, LT.kepler_inverse_cube(EP.SUN_J2000["a"], EP.SUN_J2000["e"]), 0.0, H, spin)
    k_moon = 3.0 * H / spin * EP.GM_MOON_AU3_DAY2 * q
    return LT.SecularTorques(k_sun, k_moon), EP.MeanOrbits(EP.moon_mean_elements(eph))


def secular_torques() -> LT.SecularTorques:
    return secular_calibration()[0]


def kepler_secular_torques(orb: EP.MeanOrbits, H=EARTH_DYNAMICAL_ELLIPTICITY) -> LT.SecularTorques:
    """The averaged torques of exactly the full model's orbits (the Sun's and the Moon's mean Kepler
    ellipses, ⟨r⁻³⟩ = 1/(a³(1 − e²)^{3/2})) and, like the full model, no geodesic precession: what
    the averaging error is measured with."""
    spin = EP.SPIN_RAD_DAY
    me = orb.moon
    return LT.SecularTorques(
        LT.kappa(GM_SUN_AU3_DAY2, LT.kepler_inverse_cube(EP.SUN_J2000["a"], EP.SUN_J2000["e"]), 0.0, H, spin),
        LT.kappa(EP.GM_MOON_AU3_DAY2, LT.kepler_inverse_cube(me.a, me.e), me.inc, H, spin), 0.0)


def ecliptic_pole_function(ecliptic: str):
    return LT.vondrak_ecliptic_pole if ecliptic == "moving" else LT.fixed_ecliptic_pole


def initial_pole():
    """The mean pole at J2000.0 in the J2000 ecliptic frame: longitude 90°, obliquity ε₀."""
    return quat.rotate(EP.earth_initial_attitude(), np.array([0.0, 0.0, 1.0]))


def secular_pole(t_days, ecliptic="moving", torques: LT.SecularTorques | None = None):
    """The averaged model's spin axis (N, 3) at t_days (days from J2000, either side)."""
    return LT.integrate_secular(torques or secular_torques(), ecliptic_pole_function(ecliptic), initial_pole(), t_days)


LONG_MIN_SAMPLES = 5


def _check_long(values):
    """A straight line through the pole longitude needs a few stored samples and steps; the full
    integration starts at J2000 (where the pole's state is known) and runs forward."""
    lo = max(LONG_MIN_SAMPLES * values["sample_years"], MIN_STEPS * values["step_days"] / YR, 100.0)
    if values["years"] < lo:
        raise ParameterError("years", values["years"],
                             f"{lo:.4g} ≤ years ≤ 30000 (at least 100 yr, {LONG_MIN_SAMPLES} samples of sample_years = "
                             f"{values['sample_years']:g} and {MIN_STEPS} steps)")
    if values["model"] == "full" and values["start_year"] != J2000_YEAR:
        raise ParameterError("start_year", values["start_year"], "2000 with model = full (the full integration "
                             "runs forward from J2000; the secular model runs either way)")
    end = values["start_year"] + values["years"]
    if end > MAX_END_YEAR:
        raise ParameterError("years", values["years"], f"start_year + years ≤ {MAX_END_YEAR:g}: years ≤ "
                             f"{MAX_END_YEAR - values['start_year']:g}")
    if values["zoom_years"] > 0:
        z0, z1 = values["zoom_year"], values["zoom_year"] + values["zoom_years"]
        if not (values["start_year"] <= z0 and z1 <= end):
            raise ParameterError("zoom_year", values["zoom_year"], f"{values['start_year']:g} ≤ zoom_year and "
                                 f"zoom_year + zoom_years ≤ {end:g} (the zoom lies inside the run)")


MAX_END_YEAR = 32000.0


def run_long_view(years=25800.0, step_days=2.0, sample_years=5.0, scheme="strang", progress=None,
                  calibration_years=40.0, ecliptic="fixed"):
    """The full model over a span from J2000. The Sun on its Kepler ellipse; the Moon on a Kepler
    ellipse whose node and perigee turn at the rates measured from a REBOUND run of
    `calibration_years` (the node regression comes from the integration, not imposed); both carried
    onto the ecliptic of date when `ecliptic` is "moving". Returns (t_days, L, q, I, MeanOrbits)."""
    orb = mean_orbits(float(calibration_years))
    sun, moon = orb.sun, orb.moon_pos
    if ecliptic == "moving":
        sun = LT.on_ecliptic_of_date(orb.sun, LT.vondrak_ecliptic_pole)
        moon = LT.on_ecliptic_of_date(orb.moon_pos, LT.vondrak_ecliptic_pole)
    t, L, q, I = EP.run_earth(sun, moon, years * YR, step_days, scheme=scheme,
                              sample_days=sample_years * YR, progress=progress)
    return t, L, q, I, orb


def zoom_in(values, s_secular_at):
    """The day-, month- and year-scale terms added back over [zoom_year, zoom_year + zoom_years]: the
    full integration (kicks at step_days) started on the secular pole there, on the ecliptic of
    that date. Returns (t_days, full pole (N, 3), secular pole (N, 3))."""
    z0 = (values["zoom_year"] - J2000_YEAR) * YR
    span = values["zoom_years"] * YR
    orb = mean_orbits(40.0)
    ecl = ecliptic_pole_function(values["ecliptic"])
    sun = LT.on_ecliptic_of_date(orb.sun, ecl)
    moon = LT.on_ecliptic_of_date(orb.moon_pos, ecl)
    q0 = z_to_many(s_secular_at(np.array([z0])))[0][0]
    I = EP.earth_inertia()
    from ..physics.integrator import PointMass, integrate

    t, L, q = integrate(I, [0.0, 0.0, EP.SPIN_RAD_DAY], span, values["step_days"], q0=q0,
                        masses=[PointMass(GM_SUN_AU3_DAY2, sun), PointMass(EP.GM_MOON_AU3_DAY2, moon)],
                        stride=max(1, int(round(1.0 / values["step_days"]))), t0=z0)
    full = unit(quat.rotate(q, L))
    return t, full, s_secular_at(t)


def _on_circle(t, mean_longitude, inc, node):
    """Unit vectors on a circular orbit of inclination `inc` and node `node` at mean longitude L."""
    u = np.asarray(mean_longitude, float) - node
    x, y = np.cos(u), np.sin(u)
    cn, sn, ci, si = np.cos(node), np.sin(node), math.cos(inc), math.sin(inc)
    return np.stack([cn * x - sn * ci * y, sn * x + cn * ci * y, si * y + 0 * t], -1)


def _tangent(a, b):
    """b − a on the sphere at a, as (Δλ·sin p, Δp) in arcsec (east along the parallel, down in polar
    angle), for unit vectors a, b (N, 3) about the ecliptic pole +z."""
    pa, la = pole_angles(a)
    pb, lb = pole_angles(b)
    dl = np.remainder(lb - la + np.pi, 2 * np.pi) - np.pi
    return np.stack([dl * np.sin(pa), pb - pa], -1) / ARCSEC_RAD


def _earth_long(values, progress=None):
    t_start = (values["start_year"] - J2000_YEAR) * YR
    ecl = ecliptic_pole_function(values["ecliptic"])
    notes = []
    if values["model"] == "full":
        t, L, q, I, orb = run_long_view(values["years"], values["step_days"], values["sample_years"], progress=progress,
                                        ecliptic=values["ecliptic"])
        axis = unit(quat.rotate(q, L))
        notes.append("Full model: every kick of the Sun and the Moon (steps of "
                     f"{values['step_days']:g} days); the pole path is the angular-momentum axis, sampled every "
                     f"{values['sample_years']:g} yr (the nutation is there but too fast to be seen at that spacing).")
    else:
        n = int(round(values["years"] / values["sample_years"])) + 1
        t = t_start + np.linspace(0.0, values["years"] * YR, n)
        tq, orb = secular_calibration()  # (the Moon drawn from this 4-year run's mean elements)
        axis = secular_pole(t, values["ecliptic"], tq)
        if progress is not None:
            progress(1.0)
        I = EP.earth_inertia()
        q = z_to_many(axis)[0]  # the figure axis on the pole (the spin's phase is not followed)
        L = np.tile([0.0, 0.0, EP.SPIN_RAD_DAY], (len(t), 1))  # C = 1: L = ω on the figure axis
        notes.append("Secular model: the torque of the Sun and the Moon averaged over the day, the month, the year "
                     "and the Moon's 18.6-year node; the pole is the mean pole "
                     f"(no nutation). κ☉ = {tq.kappa_sun / ARCSEC_RAD * YR:.4f}″/yr, κ☾ = "
                     f"{tq.kappa_moon / ARCSEC_RAD * YR:.4f}″/yr, geodesic precession "
                     f"{tq.geodesic / ARCSEC_RAD * YR * 100:.4f}″/cy.")
    ty = t / YR  # years from J2000
    k = ecl(t)
    obl = LT.obliquity(axis, k)
    ref = LT.vondrak_equator_pole(t)
    sep = LT.angle_between(axis, ref)
    obl_ref = LT.obliquity(ref, LT.vondrak_ecliptic_pole(t))
    # the pole's longitude about the ecliptic pole of date (in the frame carried with the ecliptic by
    # the smallest rotation): its rate is the general precession (on a fixed ecliptic: the luni-solar)
    Rk = LT.rotation_to_ecliptic_of_date(k)
    p, lam = pole_angles(np.einsum("nji,nj->ni", Rk, axis))
    rate = -np.polyfit(ty, lam, 1)[0] / ARCSEC_RAD
    rate_ref = -np.polyfit(ty, pole_angles(np.einsum("nji,nj->ni", Rk, ref))[1], 1)[0] / ARCSEC_RAD
    mod = EP.precession_parts_modern(orb.moon)
    eul = -(mod["euler_sun"] + mod["euler_moon"]) / ARCSEC_RAD * YR
    m = dict(precession_rate_arcsec_per_yr=rate, precession_rate_euler_arcsec_per_yr=eul,
             precession_rate_vondrak_arcsec_per_yr=rate_ref,
             precession_period_yr=360 * 3600 / rate, precession_period_euler_yr=360 * 3600 / eul,
             turned_deg=float(np.degrees(lam[0] - lam[-1])),
             obliquity_min_deg=float(np.degrees(obl.min())), obliquity_max_deg=float(np.degrees(obl.max())),
             obliquity_vondrak_min_deg=float(np.degrees(obl_ref.min())),
             obliquity_vondrak_max_deg=float(np.degrees(obl_ref.max())),
             pole_vs_vondrak_max_deg=float(np.degrees(sep.max())),
             pole_vs_vondrak_final_deg=float(np.degrees(sep[-1])),
             moon_node_period_yr=orb.moon.node_period_yr)
    # the celestial pole in J2000 equatorial RA/Dec, for the star chart
    ce, se = math.cos(OBLIQUITY_J2000_RAD), math.sin(OBLIQUITY_J2000_RAD)
    ye = ce * axis[:, 1] - se * axis[:, 2]
    ze = se * axis[:, 1] + ce * axis[:, 2]
    ra = np.degrees(np.unwrap(np.arctan2(ye, axis[:, 0])))
    dec = np.degrees(np.arcsin(np.clip(ze, -1, 1)))
    if values["model"] == "full":
        sun = LT.on_ecliptic_of_date(orb.sun, ecl)(t)
        moon = LT.on_ecliptic_of_date(orb.moon_pos, ecl)(t)
    else:  # samples years apart: where the Sun and the Moon are, on circles of their mean motions
        sun = LT.on_ecliptic_of_date(lambda tt: _on_circle(tt, orb.sun_mean_longitude(tt), 0.0, 0.0), ecl)(t)
        me = orb.moon
        moon = LT.on_ecliptic_of_date(lambda tt: _on_circle(tt, me.L0 + me.n * tt, me.inc, me.node0 + me.node_rate * tt),
                                      ecl)(t)
    traj = Trajectory(ty, q, L * YR, I, time_unit="yr",
                      bodies={"sun": unit(sun), "moon": unit(moon)}, moment_unit="C")
    lam_e = lam[0] - eul * ARCSEC_RAD * (ty - ty[0])
    extras = {"vondrak_pole": ref, "ecliptic_pole": k}
    plot = {"obliquity of date (deg)": np.degrees(obl), "obliquity, Vondrák 2011 (deg)": np.degrees(obl_ref),
            "pole − Vondrák 2011 (arcmin)": np.degrees(sep) * 60,
            "pole longitude (deg)": np.degrees(lam), "pole longitude, Euler (deg)": np.degrees(lam_e),
            "pole RA J2000 (deg)": ra, "pole Dec J2000 (deg)": dec}
    if values["zoom_years"] > 0:
        tz, full, sec = zoom_in(values, lambda tt: secular_pole(tt, values["ecliptic"]))
        d = _tangent(sec, full)
        d = d - d.mean(axis=0)
        m["zoom_nutation_longitude_range_arcsec"] = float(np.ptp(d[:, 0]))
        m["zoom_nutation_obliquity_range_arcsec"] = float(np.ptp(d[:, 1]))
        extras["zoom"] = {"t_yr": tz / YR, "full_pole": full, "secular_pole": sec, "offset_arcsec": d}
        notes.append(f"Zoom {values['zoom_year']:g}–{values['zoom_year'] + values['zoom_years']:g}: the full "
                     "integration from the secular pole adds the nutation back (peak to peak "
                     f"{m['zoom_nutation_longitude_range_arcsec']:.1f}″ across and "
                     f"{m['zoom_nutation_obliquity_range_arcsec']:.1f}″ in obliquity).")
    eclip = ("the ecliptic of date moves as Vondrák et al. (2011) have it (computed with the IAU's SOFA/ERFA library): the planets turn the "
             "Earth's orbit plane, the obliquity swings" if values["ecliptic"] == "moving" else
             "the ecliptic is held fixed at J2000 (no planets): the pole drifts from the real one by degrees "
             "over millennia")
    notes.append(f"Frame: the J2000 ecliptic; {eclip}. The pole is compared with Vondrák, Capitaine & Wallace "
                 "(2011, A&A 534, A22) long-term precession (the IAU's SOFA/ERFA library), valid ±200,000 years.")
    today = GENERAL_PRECESSION_IAU2006_ARCSEC_PER_CY / 100  # ″/yr
    comps = [Comparison("precession period", 360 * 3600 / eul, m["precession_period_yr"], 360 * 3600 / rate_ref, "yr",
                        f"from the mean rate about the ecliptic pole of date over the run ({rate_ref:.2f}″/yr for "
                        f"Vondrák's pole); today's rate, {today:.2f}″/yr (IAU 2006), gives the textbook "
                        f"{360 * 3600 / today:,.0f} years: the rate changes over the millennia (it goes with cos ε as "
                        "the obliquity swings, and the ecliptic itself moves)"),
             Comparison("pole − Vondrák 2011, largest (°)", None, m["pole_vs_vondrak_max_deg"], 0.0, "deg",
                        f"the angle between this run's pole and the long-term precession's over "
                        f"{values['start_year']:g}…{values['start_year'] + values['years']:g}"),
             Comparison("obliquity of date, smallest (°)", None, m["obliquity_min_deg"], m["obliquity_vondrak_min_deg"],
                        "deg", "the obliquity's slow swing (the ecliptic tilts; period ~41,000 yr); Euler's "
                        "obliquity is fixed. Modern: Vondrák et al.'s equator and ecliptic poles, same dates"),
             Comparison("obliquity of date, largest (°)", None, m["obliquity_max_deg"], m["obliquity_vondrak_max_deg"],
                        "deg", "")]
    warnings = []
    if values["model"] == "full" or values["zoom_years"] > 0:  # the secular model takes no step
        warnings = _validity.add([], _validity.coarse_step(values["step_days"], SIDEREAL_MONTH_DAYS / 2,
                                                           "the Moon's pull, which repeats twice a month", "d", "step_days"))
    return Run("earth-long-view", values, traj, m, comps, notes, plot_series=plot, extras=extras, warnings=warnings)


# the stars marked on the pole's path at the date it passes nearest them
POLE_STARS = ("Polaris", "Thuban", "Vega")
PASS_WITHIN_DEG = 12.0


def year_label(y: float) -> str:
    """Astronomical year → 'AD 1234' or '2800 BC' (year 0 is 1 BC)."""
    y = int(round(y))
    return f"AD {y}" if y > 0 else f"{1 - y} BC"


def pole_star_marks(run):
    """[(name, year, separation in degrees, index of the nearest sample, star direction)] for the
    pole stars the run's path passes within PASS_WITHIN_DEG of (the catalogue's J2000 positions:
    proper motion is left out, 0.35″/yr for Vega, i.e. ~1° over 12,000 years)."""
    cat = bright_stars()
    names = list(cat.names)
    keep = [names.index(n) for n in POLE_STARS if n in names]
    if not keep:
        return []
    axis = unit(run.trajectory.L_inertial)
    stars = EP.equatorial_to_ecliptic(cat.ra_deg[keep], cat.dec_deg[keep])
    sep = np.degrees(LT.angle_between(axis[:, None, :], stars[None, :, :]))
    out = []
    for j, jj in enumerate(keep):
        i = int(np.argmin(sep[:, j]))
        if sep[i, j] <= PASS_WITHIN_DEG and 0 < i < len(axis) - 1:  # a real closest approach, not the run's end
            out.append((names[jj], J2000_YEAR + float(run.trajectory.t[i]), float(sep[i, j]), i, stars[j]))
    return out


VONDRAK_COLOR = (120, 120, 120)
STAR_MARK_COLOR = (230, 150, 20)


def _draw(run, spec, view):
    from ._ch16_drawing import CELESTIAL_RADIUS

    d = earth_scene(run, spec, view, long_view=True)
    R = CELESTIAL_RADIUS
    if view.option("vondrak", spec) and "vondrak_pole" in run.extras:
        ref = np.asarray(run.extras["vondrak_pole"], float)
        d.add(Path(name="vondrak_pole", points=1.003 * R * ref, color=VONDRAK_COLOR, thickness=0.008))
    if view.option("pole_stars", spec):
        for name, year, sep, i, star in pole_star_marks(run):
            pos = R * unit(run.trajectory.L_inertial[i])
            d.add(Sphere(name=f"pole_stars/{name}/mark", radius=0.035, color=STAR_MARK_COLOR, position=1.006 * pos),
                  Label(name=f"pole_stars/{name}/label", text=f"{name}: {year_label(year)} ({sep:.1f}°)",
                        position=R * 1.03 * star + np.array([0.0, 0.0, 0.08])))
    # the plot shows what the Read tab points to, the obliquity's swing of a degree: beside the pole's
    # longitude and RA (hundreds of degrees) and its distance from Vondrák's (arcminutes) on one axis
    # it was a flat line; the pole's path is the scene itself, and every series stays in the run
    d.plot = {k: v for k, v in d.plot.items() if k.startswith("obliquity")}
    return d


@register_check("E10.earth-long-term", "Earth: the pole over ±13,000 years vs Vondrák et al. 2011 (≤ 0.1°)",
                "§846, modern")
def e10_earth_long_term():
    t = np.linspace(-13000.0, 13000.0, 521) * YR
    s = secular_pole(t, "moving")
    sep = np.degrees(LT.angle_between(s, LT.vondrak_equator_pole(t)))
    fixed = np.degrees(LT.angle_between(secular_pole(t, "fixed"), LT.vondrak_equator_pole(t)))
    k = LT.vondrak_ecliptic_pole(t)
    obl = np.degrees(LT.obliquity(s, k))
    tq = secular_torques()
    rate = tq.kappa * math.cos(OBLIQUITY_J2000_RAD) / ARCSEC_RAD * YR
    j = int(np.argmax(sep))
    return dict(euler=float(fixed.max()), simulated=float(sep.max()), modern=0.0, rel_error=float(sep.max()),
                tolerance=0.1, unit="deg",
                note=(f"error and tolerance in degrees: the largest angle between the secular model's pole and "
                      f"Vondrák, Capitaine & Wallace's (2011, computed with the IAU's SOFA/ERFA library) from 11,000 BC to AD 15,000, "
                      f"{sep.max():.3f}° in {J2000_YEAR + t[j] / YR:.0f}; the ecliptic of date from the same paper "
                      f"drives the Sun's and the Moon's planes, theoria's averaged torque moves the "
                      f"equator. Euler's column: the same torque on the fixed J2000 ecliptic ({fixed.max():.2f}°). "
                      f"The obliquity swings between {obl.min():.3f}° and {obl.max():.3f}°. What is left: the model's "
                      f"rate at J2000 on a fixed ecliptic, {rate:.4f}″/yr, against ψ_A + the geodesic term "
                      f"{LUNISOLAR_PRECESSION_IAU2006_ARCSEC_PER_CY / 100:.4f} + 0.0192″/yr (the rigid Earth's H_d, "
                      f"the Moon's ⟨r⁻³⟩ from a 4-year run, second-order terms; 0.005″/yr is 0.018° over 13,000 "
                      f"years), the Earth's eccentricity held at its J2000 value (the real one drifts 0.0167 → "
                      f"0.019 → 0.014), and the accuracy of Vondrák's fit itself"))


SECULAR_STEPS_PER_YEAR = 1 / 400.0  # DOP853 on the averaged equations (measured: a step per ~450 years)


def _cost(values):
    """Full model: one rotation run (Sun and Moon) over `years` at step_days, a state every
    sample_years, after the mean orbits' 40-year REBOUND run (cached). Secular model: a pole per
    sample from the averaged torque, after a 4-year REBOUND calibration (cached). Kept: each state
    with the Sun's and the Moon's directions, Vondrák's pole beside it, and ten series (the pole's
    angles, the obliquity and the distance from Vondrák's pole). A zoom window: the full torque over
    `zoom_years` at step_days, a state a day (`zoom_in`: its time, the full and the secular pole and
    their offset, 9 numbers a state), after the mean orbits' run."""
    calibrated = EP.calibrated_moon_elements.cache_info().currsize > 0
    steps = 0.0 if calibrated else CALIBRATION_STEPS
    if values["model"] == "full":
        n, samples = rotation_run(values["years"] * YR, values["step_days"], values["sample_years"] * YR)
        cached = mean_orbits.cache_info().currsize > 0  # the mean orbits: once per process
        steps += n + (0 if cached else REBOUND_STEPS_PER_DAY * 40 * YR)
    else:
        samples = float(np.floor(values["years"] / values["sample_years"] + 0.5) + 1)  # as _earth_long samples it (inf for a tiny sample_years)
        cached = secular_calibration.cache_info().currsize > 0
        steps += SECULAR_STEPS_PER_YEAR * values["years"] + 10 + (
            0 if cached else SECULAR_CALIBRATION_YEARS * YR * REBOUND_STEPS_PER_DAY)  # REBOUND's steps, not its samples
    zoom_bytes = 0.0
    if values["zoom_years"] > 0:
        n, kept = rotation_run(values["zoom_years"] * YR, values["step_days"], 1.0)
        orbits_needed = values["model"] != "full" and mean_orbits.cache_info().currsize == 0
        steps += n + (REBOUND_STEPS_PER_DAY * 40 * YR if orbits_needed else 0)
        zoom_bytes = 9 * 8 * kept
    return Cost(steps, samples, trajectory_bytes(samples, bodies=3, series=10, extra=zoom_bytes))


register(Scenario(
    series_units={"(sun|moon)_[xyz]": "1"},  # directions
    name="earth-long-view",
    title="A whole precession cycle: the pole among the stars",
    section="§846 (modern values)",
    group="ch. 16",
    summary=("One run over ~26,000 years: the Earth's axis, tilted 23.4°, circles the pole of the "
            "ecliptic once. On the celestial sphere the pole passes Polaris now, was near Thuban 4,800 "
            "years ago and will be near Vega in about 12,000 years. The ecliptic itself moves (the planets "
            "tilt the Earth's orbit): the grey path is the long-term precession of Vondrák et al. (2011), "
            "and the obliquity swings by a degree (time plot). The averaged torque runs the whole cycle in a "
            "second; the full day-by-day integration is one choice away."),
    params=(
        Param("years", 25800.0, 100.0, 30000.0, "yr", "length of the run", step=100.0,
              label="Length of the run"),
        Param("start_year", J2000_YEAR, -28000.0, J2000_YEAR, "yr", "first year (astronomical: 0 = 1 BC, −2999 = 3000 BC)",
              step=100.0, label="First year"),
        Param("model", "secular", kind="choice", choices=("secular", "full"),
              help="'secular': the torque averaged over day, month, year and the Moon's node (fast, either "
                   "direction in time); 'full': every kick of the Sun and the Moon (from J2000 on, ~1 s per 2,000 yr)",
                   label="Torque", choice_labels=('averaged (secular, fast)', 'every kick (full)')),
        Param("ecliptic", "moving", kind="choice", choices=("moving", "fixed"),
              help="'moving': the ecliptic of date of Vondrák et al. 2011; 'fixed': the J2000 ecliptic (no planets)",
              label="Ecliptic", choice_labels=('moving (planets, Vondrák 2011)', 'fixed at J2000')),
        Param("step_days", 2.0, 0.0, 5.0, "day", "integrator step of the full model (and of the zoom)",
              exclusive_min=True, step=0.5, label="Integrator step", advanced=True,
              applies=[{"model": "full"}, {"model": "secular", "zoom_years": POSITIVE}]),
        Param("sample_years", 5.0, 0.0, 1000.0, "yr", "spacing of the stored states", exclusive_min=True,
              label="Spacing of the stored states", advanced=True),
        Param("zoom_year", J2000_YEAR, -28000.0, MAX_END_YEAR, "yr", "start of the zoom window (secular model)", step=100.0,
              label="Zoom window starts", advanced=True, applies={"model": "secular", "zoom_years": POSITIVE}),
        Param("zoom_years", 0.0, 0.0, 40.0, "yr", "length of the zoom window with the full torque (0: none)",
              label="Zoom window length (full torque)", advanced=True, applies={"model": "secular"}),
    ),
    camera=Camera((3.6, -3.2, 4.4), (0.0, 0.0, 0.6)),  # the pole's circle near the top of the sphere
    # the first picture: the secular sky alone, sparsely stored; a zoom window with the full torque
    # (a REBOUND run of up to 40 years, seconds) comes with the refined run
    preview={'step_days': 5.0, 'sample_years': 50.0, 'zoom_years': 0.0},
    simulate_fn=_earth_long,
    draw=_draw,
    options={**{k: v for k, v in EARTH_OPTIONS.items() if k != "wiggle"},  # sampled every few years: no nutation
             "vondrak": Option("pole of Vondrák et al. 2011 (grey)"),
             "pole_stars": Option("Polaris, Thuban, Vega at their dates")},
    cost_fn=_cost,
    check=_check_long,
    euler_formula=("mean precession N cos n per attracting body, N = 3GM (C − A) / (2Aε s³) (§846)"),
    presets=(
        ("Earth: 25,800 years", {}),
        ("Earth: Thuban to Vega, 3000 BC – AD 15,000", {"start_year": -2999.0, "years": 18000.0}),
        ("Earth: to Vega, 13,000 years", {"years": 13000.0}),
        ("Earth: fixed ecliptic (no planets), 26,000 years", {"ecliptic": "fixed", "years": 26000.0}),
        ("Earth: the full integration, 2,000 years", {"model": "full", "years": 2000.0}),
    ),
))
