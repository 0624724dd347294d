"""Benchmark: a whole precession cycle of the Earth (25,800 years) with theoria's splitting
(exact spin, kicks at 2-day steps), against scipy DOP853 on the same model (the same mean-element
Sun and Moon, the same torque), measured over 10 years and extrapolated linearly to the span.
DOP853's tolerance is the loosest of 1e-6…1e-10 whose pole error after one year is no larger
than theoria's (both against theoria's yoshida4 at 0.25-day steps, itself 4e-6″ from DOP853 at
rtol 1e-10 after 10 years)."""
from __future__ import annotations

import time

import numpy as np
from scipy.integrate import solve_ivp

from theoria.physics import earth_precession as EP
from theoria.physics import quaternion as quat
from theoria.physics.euler_equations import rhs_state
from theoria.physics.constants import (ARCSEC_RAD, GM_SUN_AU3_DAY2, JULIAN_YEAR_DAYS,
                                       LUNISOLAR_PRECESSION_IAU2006_ARCSEC_PER_CY)
from theoria.scenarios.earth_long_view import run_long_view

from . import register_bench

YEARS = 25800.0
BASE_YEARS = 10.0


def _pole(q, L):
    a = quat.rotate(q, L)
    return a / np.linalg.norm(a, axis=-1, keepdims=True)


@register_bench("earth-precession-cycle-25800yr")
def earth_cycle():
    t0 = time.perf_counter()
    t, L, q, I, orb = run_long_view(YEARS, step_days=2.0, sample_years=5.0)
    t_ours = time.perf_counter() - t0
    ax = _pole(q, L)
    lam = np.unwrap(np.arctan2(ax[:, 1], ax[:, 0]))
    rate = -np.polyfit(t / JULIAN_YEAR_DAYS, lam, 1)[0] / ARCSEC_RAD
    ref_rate = LUNISOLAR_PRECESSION_IAU2006_ARCSEC_PER_CY / 100

    # the baseline over 10 years, same model
    dur = BASE_YEARS * JULIAN_YEAR_DAYS
    gms = np.array([GM_SUN_AU3_DAY2, EP.GM_MOON_AU3_DAY2])

    def torque(tt, qq, w):
        qq = qq / np.linalg.norm(qq)
        tau = np.zeros(3)
        for gm, pos in zip(gms, (orb.sun(np.array([tt]))[0], orb.moon_pos(np.array([tt]))[0])):
            s = quat.rotate_inverse(qq, pos)
            r2 = s @ s
            tau += 3 * gm / r2 ** 2.5 * np.cross(s, I * s)
        return tau

    q0 = EP.earth_initial_attitude()
    y0 = np.concatenate([[0.0, 0.0, EP.SPIN_RAD_DAY], q0])
    ang = lambda a, b: float(np.arctan2(np.linalg.norm(np.cross(a, b)), a @ b) / ARCSEC_RAD)  # noqa: E731

    def reference(d):  # theoria, yoshida4 at 0.25 d: 4e-6″ from DOP853 rtol 1e-10 after 10 yr
        tr, Lr, qr, _ = EP.run_earth(orb.sun, orb.moon_pos, d, 0.25, scheme="yoshida4", sample_days=d)
        return _pole(qr[-1], Lr[-1])

    def dop853(d, rtol):
        t1 = time.perf_counter()
        sol = solve_ivp(rhs_state, (0, d), y0, method="DOP853", rtol=rtol, atol=rtol * 1e-2, args=(I, torque))
        wq = sol.y[:, -1]
        return time.perf_counter() - t1, _pole(wq[3:] / np.linalg.norm(wq[3:]), I * wq[:3]), sol.t.size

    def ours(d):
        t2 = time.perf_counter()
        tt, LL, qq, _ = EP.run_earth(orb.sun, orb.moon_pos, d, 2.0, sample_days=d)
        return time.perf_counter() - t2, _pole(qq[-1], LL[-1])

    # the loosest DOP853 tolerance that matches theoria's pole error over one year
    one = JULIAN_YEAR_DAYS
    ref1 = reference(one)
    e_ours1 = ang(ours(one)[1], ref1)
    rtol = 1e-10
    for rt in (1e-6, 1e-7, 1e-8, 1e-9):
        if ang(dop853(one, rt)[1], ref1) <= e_ours1:
            rtol = rt
            break
    # the measured 10-year runs
    t_base10, base_pole, nsteps = dop853(dur, rtol)
    t_ours10, ours_pole = ours(dur)
    ref = reference(dur)
    return dict(theoria_s=t_ours, baseline_s=t_base10 * YEARS / BASE_YEARS,
                theoria_error=ang(ours_pole, ref), baseline_error=ang(base_pole, ref),
                error_unit="arcsec of pole after 10 yr vs yoshida4 at 0.25 d",
                baseline_rtol=rtol, baseline_measured_10yr_s=t_base10, theoria_10yr_s=t_ours10,
                dop853_steps_10yr=int(nsteps),
                precession_rate_arcsec_per_yr=rate, precession_rate_iau2006_psi_a=ref_rate,
                precession_period_yr=360 * 3600 / rate)


MILLENNIUM = 1000.0


@register_bench("earth-secular-cycle-25800yr")
def earth_secular_cycle():
    """The long view's averaged (secular) model over a whole cycle on Vondrák's moving ecliptic,
    cold (its REBOUND calibration of the Moon included, the caches emptied), against the full
    integration of the same torques (kicks every 2 days, Sun and Moon on their mean orbits carried
    onto the same moving ecliptic), whose time for the cycle is measured over a millennium and
    scaled. Error: the secular pole against the full integration's mean pole after 1,000 years (the
    nutation fitted out of their difference), and against Vondrák et al. 2011 over ±13,000 years."""
    from theoria.physics import long_term_precession as LT
    from theoria.scenarios import earth_long_view as LV

    LV.secular_calibration.cache_clear()
    EP.calibrated_moon_elements.cache_clear()
    t0 = time.perf_counter()
    t = np.linspace(0.0, YEARS * JULIAN_YEAR_DAYS, 5161)
    LV.secular_pole(t, "moving")
    t_ours = time.perf_counter() - t0
    err_full, t_full = secular_error_against_full(MILLENNIUM)
    ts = np.linspace(-13000.0, 13000.0, 261) * JULIAN_YEAR_DAYS
    vond = float(np.max(LT.angle_between(LV.secular_pole(ts, "moving"), LT.vondrak_equator_pole(ts))) / ARCSEC_RAD)
    return dict(theoria_s=t_ours, baseline_s=t_full * YEARS / MILLENNIUM, theoria_error=err_full, baseline_error=0.0,
                error_unit="arcsec: secular mean pole − full integration's mean pole after 1,000 years",
                baseline_measured_1000yr_s=t_full, pole_vs_vondrak_max_arcsec_13kyr=vond)


def secular_error_against_full(years=MILLENNIUM, step_days=2.0, sample_years=0.1):
    """(drift in arcsec after `years`, wall time of the full run): the full integration of the long
    view (moving ecliptic, the mean Kepler orbits of the 4-year calibration) against the secular model
    of the same orbits (kepler_secular_torques) from the same start. Their difference is a constant (the full run
    starts on the mean pole, so its own mean pole sits off by the nutation at J2000), the nutation
    (the node's terms fitted with sin/cos of Ω and 2Ω; the shorter ones average out at samples of
    0.1 yr) and the drift of the averaging, c₁·t, whose size at the end is returned."""
    from theoria.physics import long_term_precession as LT
    from theoria.scenarios import earth_long_view as LV

    orb = LV.secular_calibration()[1]
    tq = LV.kepler_secular_torques(orb)  # the same orbits in both models: only the averaging differs
    span = (0.0, years * JULIAN_YEAR_DAYS)
    sun = LT.on_ecliptic_of_date(orb.sun, LT.vondrak_ecliptic_pole, span)
    moon = LT.on_ecliptic_of_date(orb.moon_pos, LT.vondrak_ecliptic_pole, span)
    t1 = time.perf_counter()
    tt, LL, qq, _ = EP.run_earth(sun, moon, years * JULIAN_YEAR_DAYS, step_days, sample_days=sample_years * JULIAN_YEAR_DAYS)
    t_full = time.perf_counter() - t1
    full = _pole(qq, LL)
    sec = LV.secular_pole(tt, "moving", tq)
    d = LV._tangent(sec, full)  # (across, obliquity) in arcsec
    node = orb.moon.node0 + orb.moon.node_rate * tt
    X = np.stack([np.ones_like(tt), tt / tt[-1], np.sin(node), np.cos(node), np.sin(2 * node), np.cos(2 * node)], 1)
    c, *_ = np.linalg.lstsq(X, d, rcond=None)
    return float(np.hypot(*c[1])), t_full
