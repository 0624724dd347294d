"""Check rows E9–E10 (Problems 95–96) and the Earth's precession and nutation against IAU."""
from __future__ import annotations

import functools

import numpy as np

from .. import earth_precession as EP
from ..precession import linear_theory, resonance_849
from ..scenarios.base import get
from ..scenarios.precession import simulate_circular, spheroid_moments
from .base import register_check


@register_check("E9", "momentary motion of the pole near a principal axis (aa, bb, cc unequal)", "§840")
def e9():
    r = get("pole-near-axis").simulate({"moments": (1.3, 1.0, 0.8), "duration_turns": 1.0})
    m = r.metrics
    errs = [abs(m[k] - m[k + "_euler"]) / abs(m[k + "_euler"]) for k in ("dspin_dt", "dbeta_dt", "dgamma_dt")]
    return dict(euler=m["dbeta_dt_euler"], simulated=m["dbeta_dt"], modern=None, rel_error=max(errs),
                tolerance=1e-6, unit="rad/s",
                note=f"dγ'/dt, dβ/dt, dγ/dt at O = A (where Euler's dropped terms vanish); worst of the three. "
                     f"dγ'/dt {m['dspin_dt']:.6g} vs {m['dspin_dt_euler']:.6g}. §840 prints γ'dβ without its minus sign. "
                     "Tolerance: the quartic fit of a 1/200-turn run")


@register_check("E9.equal-moments", "bb = cc: spin unchanged, pole moves ⟂ FA at 2N cos ζ sin ζ, sense C→B", "§841–843")
def e9_equal():
    r = get("pole-near-axis").simulate({"moments": (1.2, 1.0, 1.0), "duration_turns": 1.0})
    m = r.metrics
    rel = abs(m["pole_speed"] - m["pole_speed_euler_842"]) / m["pole_speed_euler_842"]
    dang = abs((m["pole_direction_deg"] - m["pole_direction_deg_euler"] + 180) % 360 - 180)
    passed = rel <= 1e-6 and dang <= 1e-4 and abs(m["dspin_dt"]) <= 1e-9 * m["pole_speed"] * 10
    return dict(euler=m["pole_speed_euler_842"], simulated=m["pole_speed"], modern=None, rel_error=rel,
                tolerance=1e-6, unit="rad/s", passed=passed,
                note=f"direction of Oo {m['pole_direction_deg']:.5f}° vs Euler {m['pole_direction_deg_euler']:.5f}°; "
                     f"dγ'/dt = {m['dspin_dt']:.2g} (Euler: 0)")


def _circular(r, f, n_deg=23.44, orbits=60, steps=200, on_axis=False):
    t, L, q, I, N, corr = simulate_circular(r, f, np.radians(n_deg), 0.0, orbits, steps, on_axis=on_axis)
    from ..scenarios.precession import fit_circular
    from ..trajectory import Trajectory

    traj = Trajectory(t, q, L, I)
    fit, _ = fit_circular(t, traj.figure_axis, 1.0, corr.eps_gyro)
    return fit, N, corr, I, traj


# E10 rows: 800 steps per orbit (hε' = 0.39 rad per step). At 200 steps (1.6 rad per step) the
# splitting error in the nutation amplitudes was 4.5N (ε/δ = 50, f = 0.01), at 400 1.6N, at 800
# 1.4N, the same in units of N at f = 0.005: converged to the O(N/δ) terms the theories drop.
E10_STEPS = 800


@functools.lru_cache(maxsize=2)
def _circular_e10(r, f):
    return _circular(r, f, steps=E10_STEPS)


def _rows_vs_corrected(pairs, N, k=3):
    """pairs: (simulated, corrected theory, Euler). Passed when every simulated value is within 3N
    of the corrected linear theory (Euler's with the gyroscopic term he dropped; what remains is
    of order N/δ, tests/test_precession.py) AND Euler's value is off the simulated one by his
    predicted offset (Euler/corrected − 1, which comes from his A for C) within the same 3N:
    a check that can tell his rate from the right one."""
    rel = max(abs(s / c - 1) for s, c, _ in pairs)
    euler_gap = max(abs((e / s - 1) - (e / c - 1)) for s, c, e in pairs)
    return rel, euler_gap, rel <= k * N and euler_gap <= k * N


@register_check("E10", "precession at the mean rate N cos n, ε ≫ δ (ε/δ = 50, f = 0.01)", "§844–846")
def e10():
    r, f = 50.0, 0.01
    fit, N, corr, I, _ = _circular_e10(r, f)
    eul = linear_theory(N, r, 1.0, np.radians(23.44))
    ca = (I[2] - I[0]) / I[0]
    rel, gap, ok = _rows_vs_corrected([(fit.rate_longitude, corr.precession_rate, eul.precession_rate)], N)
    return dict(euler=eul.precession_rate, simulated=fit.rate_longitude, modern=corr.precession_rate,
                rel_error=rel, tolerance=3 * N, unit="rad per 1/δ", passed=ok,
                note=f"modern = the corrected linear theory (C for A in N); tolerance 3N/δ = {3 * N:.2g}, the order of "
                     f"the terms it drops. Euler is {100 * (eul.precession_rate / fit.rate_longitude - 1):+.3f}% off the "
                     f"simulation, predicted {100 * (eul.precession_rate / corr.precession_rate - 1):+.3f}% "
                     f"(his N has A for C: (C−A)/A = {ca:.4f}); |measured − predicted| = {gap:.2g} ≤ 3N also required")


@register_check("E10.nutation", "nutation in 2φ: obliquity and longitude terms (ε/δ = 50, f = 0.01)", "§844, §847, §849")
def e10_nutation():
    r, f = 50.0, 0.01
    fit, N, corr, I, _ = _circular_e10(r, f)
    eul = linear_theory(N, r, 1.0, np.radians(23.44))
    ap = -fit.obliquity["2phi"][1]
    al = fit.longitude["2phi"][0]
    ca = (I[2] - I[0]) / I[0]
    rel, gap, ok = _rows_vs_corrected([(ap, corr.obliquity_amplitude, eul.obliquity_amplitude),
                                       (al, corr.longitude_amplitude, eul.longitude_amplitude)], N)
    return dict(euler=eul.obliquity_amplitude, simulated=ap, modern=corr.obliquity_amplitude, rel_error=rel,
                tolerance=3 * N, unit="rad", passed=ok,
                note=f"longitude term {al:.5g} (corrected theory {corr.longitude_amplitude:.5g}, Euler "
                     f"{eul.longitude_amplitude:.5g}); worst relative error of the two against the corrected linear "
                     f"theory, tolerance 3N/δ: the terms of order N/δ both theories drop (e.g. the 2φ term seen from the "
                     f"precessing pole has frequency 2(δ + N cos n), not 2δ: −0.92N in the amplitudes); measured "
                     f"{rel / N:.2f}N, the same in units of N at half the flattening ({E10_STEPS} steps per orbit; "
                     f"200 steps added a splitting error of 3N). Euler's offsets: obliquity {100 * (eul.obliquity_amplitude / ap - 1):+.3f}% "
                     f"(predicted {100 * (eul.obliquity_amplitude / corr.obliquity_amplitude - 1):+.3f}%), longitude "
                     f"{100 * (eul.longitude_amplitude / al - 1):+.3f}% (predicted "
                     f"{100 * (eul.longitude_amplitude / corr.longitude_amplitude - 1):+.3f}%), from his A for C "
                     f"((C−A)/A = {ca:.4f}); |measured − predicted| = {gap:.2g} ≤ 3N also required")


@register_check("E10.resonance", "ε' = 2δ: the pole of rotation leaves the figure axis at N sin n(1 + cos n)/2", "§849")
def e10_resonance():
    f = 0.01
    I = spheroid_moments(f)
    r = 2 * I[0] / I[2]  # the resonance with the gyroscopic term kept (Euler: ε = 2δ)
    n = np.radians(23.44)
    fit, N, corr, _, traj = _circular(r, f, orbits=4, steps=400, on_axis=True)
    alpha = np.arccos(np.clip(np.sum(traj.rotation_axis * traj.figure_axis, axis=1), -1, 1))
    sel = traj.t > np.pi
    slope = np.polyfit(traj.t[sel], alpha[sel], 1)[0]
    # Euler's §849 rate with ε → ε' (the corrected N·A/C·… identical: N is fixed by the torque)
    pred = resonance_849(N, 1.0, n)["alpha_growth_rate"]
    rel = abs(slope - pred) / pred
    return dict(euler=pred, simulated=slope, modern=None, rel_error=rel, tolerance=0.05, unit="rad per 1/δ",
                note=f"ε/δ = 2A/C = {r:.4f}; α reached {alpha.max():.3g} rad in 4 revolutions (Euler's formulas diverge). "
                     "Tolerance: terms of order α and N/δ beside the secular growth over the fitted span")


@functools.lru_cache(maxsize=1)
def _earth_run():
    return get("earth").simulate({"years": 40.0})


@register_check("E10.earth-precession", "Earth: luni-solar precession vs IAU 2006 ψ_A + geodesic precession (40-yr run)",
                "§846, modern")
def e10_earth_precession():
    m = _earth_run().metrics
    sim, psi_a = m["precession_rate_arcsec_per_yr"], m["precession_rate_iau2006_psi_a_arcsec_per_yr"]
    ref = psi_a + EP.GEODESIC_PRECESSION / 100
    return dict(euler=m["precession_rate_euler_arcsec_per_yr"], simulated=sim, modern=ref,
                rel_error=abs(sim - ref) / ref, tolerance=1e-4, unit="arcsec/yr",
                note=f"modern = IAU 2006 ψ_A {psi_a:.6f} + the geodesic precession {EP.GEODESIC_PRECESSION / 100:.6f}″/yr "
                     "(ψ_A holds it with the opposite sense, a relativistic effect no Newtonian rigid Earth has; "
                     f"Capitaine et al. 2003). Without it the gap would be {sim - psi_a:+.6f}″/yr. "
                     f"A consistency check, not a prediction: H_d (MHB2000) was fitted to the observed precession. "
                     "Tolerance 1e-4 (5 mas/yr): the second-order and non-rigid contributions to ψ_A that a rigid "
                     "first-order torque model leaves out are of the mas/yr order (Lambert & Capitaine 2004: "
                     "−4.9 mas/cy from zonal deformation), and the 40-yr fit of the 18.6-yr term beside the secular "
                     f"one. Solar {m['precession_solar_arcsec_per_yr']:.3f}, lunar "
                     f"{m['precession_lunar_arcsec_per_yr']:.3f}″/yr; period {m['precession_period_yr']:.0f} yr")


@register_check("E10.earth-nutation", "Earth: 18.6-yr nutation Δψ, Δε vs IAU 2000A (40-yr run)", "modern")
def e10_earth_nutation():
    m = _earth_run().metrics
    a = m["nutation_longitude_18_6yr_arcsec"], m["nutation_obliquity_18_6yr_arcsec"]
    b = m["nutation_longitude_18_6yr_iau2000_arcsec"], m["nutation_obliquity_18_6yr_iau2000_arcsec"]
    rel = max(abs(a[0] / b[0] - 1), abs(a[1] / b[1] - 1))
    return dict(euler=None, simulated=a[0], modern=b[0], rel_error=rel, tolerance=0.003, unit="arcsec",
                note=f"Δε {a[1]:.4f}″ vs {b[1]:.4f}″; worst of the two; Euler has no 18.6-yr term (his centre moves in "
                     f"the ecliptic). Moon's node period {m['moon_node_period_yr']:.3f} yr from REBOUND. Tolerance 0.3% = "
                     "3× the measured gap (0.07% in Δψ, 0.10% in Δε): IAU 2000A is the non-rigid Earth (MHB2000), "
                     "whose response at 18.6 yr is close to the rigid one; the gap is that non-rigid response (not "
                     "modelled), and the issue's 3% bound is far outside it")


@register_check("E10.earth-semiannual", "Earth: semi-annual nutation vs IAU 2000A and Euler's 2φ term", "§844, modern")
def e10_earth_semiannual():
    m = _earth_run().metrics
    sim, ref = m["nutation_longitude_semiannual_arcsec"], m["nutation_longitude_semiannual_iau2000_arcsec"]
    se, re_ = m["nutation_obliquity_semiannual_arcsec"], m["nutation_obliquity_semiannual_iau2000_arcsec"]
    rel = max(abs(sim / ref - 1), abs(se / re_ - 1))
    return dict(euler=m["nutation_longitude_semiannual_euler_arcsec"], simulated=sim, modern=ref, rel_error=rel,
                tolerance=0.05, unit="arcsec",
                note=f"Δε {se:.4f}″ vs {re_:.4f}″ (Euler {m['nutation_obliquity_semiannual_euler_arcsec']:.4f}″). "
                     "A rigid Earth: IAU 2000A (the non-rigid MHB2000 Earth) is larger, measured 2.9% in Δψ and 3.4% in "
                     "Δε, by the non-rigid response (elastic mantle, fluid core, the free-core-nutation resonance) "
                     "that the rigid model leaves out; tolerance 5% ≈ 1.5× that gap (the issue's 10% is only an outer "
                     "bound). The rigid-Earth value itself is Euler's linear theory within 0.2%")
