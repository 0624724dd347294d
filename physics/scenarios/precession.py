"""Chapter 16, Problems 95–96: the pole near a principal axis (§840–843) and the precession and
nutation of an oblate spinning body pulled by a centre on a circle (§844–849)."""
from __future__ import annotations

import numpy as np

from .. import quaternion as quat
from ..inertia import validate_moments
from ..integrator import PointMass, integrate
from ..params import Param, ParameterError
from ..precession import (TYPOS_840_843, TYPOS_844_849, equal_moments_841, euler_N, fit_pole, linear_theory,
                          pole_angles, pole_rates_840, resonance_849)
from ..trajectory import Trajectory
from .base import Comparison, Result, Scenario, register

MAX_SAMPLES = 20000


def _stride(n_steps):
    return max(1, int(np.ceil(n_steps / MAX_SAMPLES)))


def _fixed_direction(u):
    u = np.asarray(u, float)

    def pos(t):
        return np.broadcast_to(u, (np.size(t), 3)).copy()

    return pos


# --- pole-near-axis (§840–843) ------------------------------------------------------------

def measure_pole_rates(t, omega_body):
    """dγ'/dt, dβ/dt, dγ/dt at t = 0 from a short simulated run: β, γ = arccos(ω_B/|ω|),
    arccos(ω_C/|ω|); a quartic fitted by least squares, its slope at t = 0."""
    w = np.linalg.norm(omega_body, axis=1)
    beta = np.arccos(np.clip(omega_body[:, 1] / w, -1, 1))
    gamma = np.arccos(np.clip(omega_body[:, 2] / w, -1, 1))
    out = []
    for y in (w, beta, gamma):
        c = np.polynomial.polynomial.polyfit(t - t[0], y, 4)
        out.append(float(c[1]))
    return out


def _pole_near_axis(values, progress=None):
    I = validate_moments(values["moments"], "moments")
    spin = values["spin"]
    zeta = np.radians(values["zeta_deg"])
    az = np.radians(values["azimuth_deg"])
    a0 = np.radians(values["offset_deg"])
    # direction of F on the body axes A, B, C (body x, y, z): cos ζ, cos η, cos θ
    cz, ce, ct = np.cos(zeta), np.sin(zeta) * np.cos(az), np.sin(zeta) * np.sin(az)
    u = np.array([cz, ce, ct])
    tidal = values["tidal"]
    w0 = spin * np.array([np.cos(a0), np.sin(a0), 0.0])  # O at α from A, toward B
    T = 2 * np.pi / spin
    dur = values["duration_turns"] * T
    step = T / values["steps_per_turn"]
    n = int(np.ceil(dur / step))
    t, L, q = integrate(I, w0, dur, step, masses=[PointMass(tidal, _fixed_direction(u))],
                        scheme="yoshida4", stride=_stride(n), progress=progress)
    # F is fixed in space, the body turns: F's inertial position (initial body frame = space)
    traj = Trajectory(t, q, L, I, time_unit="s", bodies={"centre": np.tile(u, (len(t), 1))},
                      figure_axis_index=0)
    # the momentary rates: a separate short run over 1/200 turn, finely sampled
    ts, Ls, qs = integrate(I, w0, T / 200, T / 20000, masses=[PointMass(tidal, _fixed_direction(u))],
                           scheme="yoshida4")
    dspin, dbeta, dgamma = measure_pole_rates(ts, Ls / I)
    e = pole_rates_840(I, spin, (cz, ce, ct), tidal)
    m = dict(dspin_dt=dspin, dspin_dt_euler=e.dspin_dt, dbeta_dt=dbeta, dbeta_dt_euler=e.dbeta_dt,
             dgamma_dt=dgamma, dgamma_dt_euler=e.dgamma_dt, pole_speed=float(np.hypot(dbeta, dgamma)),
             pole_speed_euler=e.pole_speed)
    comps = [Comparison("dγ'/dt (change of spin)", e.dspin_dt, dspin, None, "rad/s²", "§840"),
             Comparison("dβ/dt (pole toward/away from B)", e.dbeta_dt, dbeta, None, "rad/s",
                        "§840 (the printed formula lacks the minus sign)"),
             Comparison("dγ/dt (pole toward/away from C)", e.dgamma_dt, dgamma, None, "rad/s", "§840")]
    notes = ["Text: " + t for t in TYPOS_840_843]
    if a0 > 0:
        notes.append(f"the pole starts {values['offset_deg']:g}° from A: Euler's rates drop the free "
                     f"wobble γ'(aa−cc)/bb·α, of size {spin * abs(I[0] - I[2]) / I[1] * a0:.3g} rad/s in dβ/dt")
    if np.isclose(I[1], I[2], rtol=1e-12):
        q841 = equal_moments_841(I, spin, (cz, ce, ct), tidal)
        ang = np.arctan2(-dgamma, -dbeta)  # displacement of O on (B, C) is (−dβ, −dγ)
        ang_e = np.arctan2(q841["direction_BC"][1], q841["direction_BC"][0])
        m.update(N_843=q841["N"], pole_speed_euler_842=q841["pole_speed"],
                 pole_direction_deg=float(np.degrees(ang)), pole_direction_deg_euler=float(np.degrees(ang_e)),
                 perpendicularity_841=float(dbeta * ce + dgamma * ct))
        comps.append(Comparison("|Oo|/dt = 2N cos ζ sin ζ (bb = cc)", q841["pole_speed"],
                                m["pole_speed"], None, "rad/s", "§842"))
        comps.append(Comparison("direction of Oo on (B, C)", float(np.degrees(ang_e)),
                                float(np.degrees(ang)), None, "deg",
                                "§843: at right angles to FA, around A in the sense C→B when aa > cc"))
        comps.append(Comparison("dβ cos η + dγ cos θ", 0.0, m["perpendicularity_841"], None, "rad/s", "§841"))
    ob = traj.omega_body / np.linalg.norm(traj.omega_body, axis=1, keepdims=True)
    return Result("pole-near-axis", values, traj, m, comps, notes,
                  plot_series={"β − 90° (deg)": np.degrees(np.arccos(np.clip(ob[:, 1], -1, 1))) - 90,
                               "γ − 90° (deg)": np.degrees(np.arccos(np.clip(ob[:, 2], -1, 1))) - 90,
                               "spin γ' (rad/s)": np.linalg.norm(traj.omega_body, axis=1)})


register(Scenario(
    name="pole-near-axis",
    title="The pole of rotation near a principal axis",
    section="§840–843",
    group="ch. 16",
    summary=("A body spins fast about (nearly) its principal axis A while a distant mass F pulls on it. "
            "Euler computes the first instants: the spin rate changes only if the moments B and C "
            "differ, and the pole of rotation O leaves A at right angles to the arc AF, fastest when F "
            "is 45° from the axis (§842: rate 2N cos ζ sin ζ). The table compares his rates with the "
            "simulated ones."),
    params=(
        Param("moments", (1.2, 1.0, 1.0), kind="vec3", minimum=1e-6, maximum=1e6, unit="kg m^2",
              help="Euler's aa, bb, cc: moments about A (the spin axis, body x), B, C"),
        # at least 1e-6 rad/s (found by tests/test_fuzz.py: spin 1.6e-171 with moments 1e-6 underflowed
        # |ω|² to 0 and the rate fit got NaN)
        Param("spin", 10.0, 1e-6, 1e4, "rad/s", "spin γ' about A"),
        Param("tidal", 1.0, 0.0, 1e6, "1/s^2", "GM/s³ of the centre of force", exclusive_min=True),
        Param("zeta_deg", 40.0, 0.0, 180.0, "deg", "arc AF from the spin axis to the centre"),
        Param("azimuth_deg", 30.0, -180.0, 180.0, "deg", "azimuth of F around A, from B toward C"),
        Param("offset_deg", 0.0, 0.0, 10.0, "deg", "initial arc AO of the pole from A (toward B)"),
        Param("duration_turns", 5.0, 0.0, 1e4, "turns", "length of the drawn run", exclusive_min=True),
        Param("steps_per_turn", 200, 4, 1e5, "1", "integrator steps per turn", kind="int"),
    ),
    simulate_fn=_pole_near_axis,
    euler_formula=("dγ' = 6gee (cc − bb) dt cos η cos ϑ / (aa s³) (§840)\n"
                   "γ' dβ = −6gee (aa − cc) dt cos ζ cos ϑ / (bb s³)\n"
                   "γ' dγ = −6gee (bb − aa) dt cos ζ cos η / (cc s³)   (6gee = 3GM)\n"
                   "bb = cc: Oo = 2N cos ζ sin ζ dt, N = 3gee (aa − cc) / (γ' cc s³) (§842–843)"),
    presets=(
        ("Pole: F at 40°, B = C", {}),
        ("Pole: F at 45°, the fastest drift", {"zeta_deg": 45.0}),
        ("Pole: B ≠ C, the spin changes", {"moments": (1.2, 1.0, 0.8)}),
    ),
))


# --- precession-circular (§844–849) ---------------------------------------------------------

def spheroid_moments(flattening):
    """Homogeneous oblate spheroid, semi-axes a = b = 1, c = 1 − f (unit mass):
    A = B = (1 + (1−f)²)/5, C = 2/5."""
    c = 1.0 - flattening
    return np.array([(1 + c * c) / 5, (1 + c * c) / 5, 0.4])


def figure_frame(n, lam):
    """Unit vectors â (figure axis at colatitude n, longitude λ), e_p (increasing p), e_λ."""
    a = np.array([np.sin(n) * np.cos(lam), np.sin(n) * np.sin(lam), np.cos(n)])
    ep = np.array([np.cos(n) * np.cos(lam), np.cos(n) * np.sin(lam), -np.sin(n)])
    el = np.array([-np.sin(lam), np.cos(lam), 0.0])
    return a, ep, el


def attitude_from_pole(n, lam, spin_phase=0.0):
    """q taking body z to the figure axis (n, λ): Rz(λ)·Ry(n)·Rz(spin_phase)."""
    qz = quat.from_axis_angle([0, 0, 1.0], lam)
    qy = quat.from_axis_angle([0, 1.0, 0], n)
    qs = quat.from_axis_angle([0, 0, 1.0], spin_phase)
    return quat.multiply(quat.multiply(qz, qy), qs)


def initial_state_844(theory, n, lam0, delta, h):
    """ω₀ (body frame) and q₀ so that the pole of rotation O sits at Euler's x, y (§844, §848):
    the forced offset at φ₀ = λ₀ plus the free part (u, v) = (0, h). On the sphere O − A =
    −ε⁻¹... i.e. ω = ε(â − x e_p − y e_λ) (x = α cos ZAO, y = α sin ZAO: x > 0 points toward Z
    moving A east, y > 0 moves A toward Z, as equations 1–2 of §844 require)."""
    x, y = theory.offset(lam0)
    y = y + h
    a, ep, el = figure_frame(n, lam0)
    w_in = theory.eps * (a - x * ep - y * el)
    q0 = attitude_from_pole(n, lam0)
    return quat.rotate_inverse(q0, w_in), q0


def simulate_circular(eps_over_delta, flattening, obliquity, h, orbits, steps_per_orbit,
                      scheme="yoshida4", lam0=np.pi / 2, progress=None, max_samples=MAX_SAMPLES, on_axis=False):
    """Run §844's problem: δ = 1, GM/s³ = 1, s = 1. Returns (t, L, q, I, N, corrected theory).

    The pole of rotation starts at its forced place (plus h) of the corrected linear theory, or
    on the figure axis if `on_axis` or if that place is infinite (at the resonance)."""
    I = spheroid_moments(flattening)
    delta, eps = 1.0, eps_over_delta
    N = euler_N(1.0, I[2], I[0], eps)
    corr = linear_theory(N, eps, delta, obliquity, I[2] / I[0], corrected=True)
    if on_axis or not (np.isfinite(corr.F) and np.isfinite(corr.G)):
        q0 = attitude_from_pole(obliquity, lam0)
        w0 = np.array([0.0, 0.0, eps])
    else:
        w0, q0 = initial_state_844(corr, obliquity, lam0, delta, h)
    dur = 2 * np.pi * orbits
    n = int(np.ceil(orbits * steps_per_orbit))
    centre = lambda t: np.stack([np.cos(t), np.sin(t), np.zeros_like(t)], -1)  # noqa: E731
    t, L, q = integrate(I, w0, dur, dur / n, q0=q0, masses=[PointMass(1.0, centre)], scheme=scheme,
                        stride=max(1, int(np.ceil(n / max_samples))), progress=progress)
    return t, L, q, I, N, corr


def fit_circular(t, axis, delta, eps_gyro):
    """Two-pass fit of the figure-axis pole: secular + 2φ terms + the free wobble at ε'."""
    p, lam = pole_angles(axis)
    c1, c0 = np.polyfit(t, lam, 1)
    phi = c0 + c1 * t - delta * t
    # the free wobble's frequency is ε' shifted by terms of order N (the torque): over a long run
    # that shift smears a fit at exactly ε', so the frequency is refined by maximising its amplitude
    span = t[-1] - t[0]
    f0 = fit_pole(t, axis, {"2phi": 2 * phi})
    tc = t - 0.5 * (t[0] + t[-1])
    res = p - f0.mean_obliquity - f0.rate_obliquity * tc - f0.obliquity["2phi"][0] * np.sin(2 * phi) \
        - f0.obliquity["2phi"][1] * np.cos(2 * phi)
    ws = eps_gyro + np.linspace(-8.0, 8.0, 33) * np.pi / max(span, 1e-300)
    ph = np.outer(ws, t)
    power = (np.sin(ph) @ res) ** 2 + (np.cos(ph) @ res) ** 2
    w = ws[int(np.argmax(power))]
    return fit_pole(t, axis, {"2phi": 2 * phi, "free": w * t}), phi


def resonance_sweep(flattening, obliquity, ratios=(20.0, 8.0, 4.0, 3.0, 2.5, 2.2), orbits=30, steps=100):
    """The 2φ nutation in obliquity measured at several ε/δ beside Euler's (§844) and the corrected
    value: shows the growth toward ε = 2δ (Euler) / ε = 2δA/C (corrected). Rows (ε/δ, simulated,
    Euler, corrected)."""
    out = []
    for r in ratios:
        t, L, q, I, N, corr = simulate_circular(r, flattening, obliquity, 0.0, orbits, steps, max_samples=4000)
        traj = Trajectory(t, q, L, I)
        fit, _ = fit_circular(t, traj.figure_axis, 1.0, corr.eps_gyro)
        out.append((r, -fit.obliquity["2phi"][1], linear_theory(N, r, 1.0, obliquity).obliquity_amplitude,
                    corr.obliquity_amplitude))
    return out


def _check_circular(values):
    if values["orbits"] < 0.5:  # found by tests/test_fuzz.py: orbits=1e-258 made the fits' SVD fail
        raise ParameterError("orbits", values["orbits"], "at least 0.5 revolutions (the fits of the secular "
                             "rate and the 2φ term need half a turn), allowed range [0.5, 1e+05] revolutions")
    if values["orbits"] * values["steps_per_orbit"] > 5e6:
        raise ParameterError("steps_per_orbit", values["steps_per_orbit"],
                             f"orbits × steps_per_orbit ≤ 5e6 (here {values['orbits']:g} orbits)")


def _precession_circular(values, progress=None):
    r = values["eps_over_delta"]
    n = np.radians(values["obliquity_deg"])
    h = values["h"]
    t, L, q, I, N, corr = simulate_circular(r, values["flattening"], n, h, values["orbits"],
                                            values["steps_per_orbit"], progress=progress)
    delta, eps = 1.0, r
    eul = linear_theory(N, eps, delta, n)
    cen = np.stack([np.cos(t), np.sin(t), np.zeros_like(t)], -1)
    traj = Trajectory(t, q, L, I, time_unit="1/δ", bodies={"centre": cen})
    fit, phi = fit_circular(t, traj.figure_axis, delta, corr.eps_gyro)
    ap = -fit.obliquity["2phi"][1]  # p = n − a_p cos 2φ
    al = fit.longitude["2phi"][0]  # λ = … + a_λ sin 2φ
    alpha = np.arccos(np.clip(np.sum(traj.rotation_axis * traj.figure_axis, axis=1), -1, 1))
    res = resonance_849(N, delta, n)
    m = dict(
        precession_rate=fit.rate_longitude, precession_rate_euler=eul.precession_rate,
        precession_rate_corrected=corr.precession_rate,
        precession_period_orbits=abs(1.0 / fit.rate_longitude) if fit.rate_longitude else float("inf"),
        nutation_obliquity=ap, nutation_obliquity_euler=eul.obliquity_amplitude,
        nutation_obliquity_corrected=corr.obliquity_amplitude,
        nutation_longitude=al, nutation_longitude_euler=eul.longitude_amplitude,
        nutation_longitude_corrected=corr.longitude_amplitude,
        free_wobble_obliquity=fit.amplitude("free", "obliquity"), free_wobble_euler=h,
        N=N, N_over_delta=N / delta, C_over_A=I[2] / I[0],
        resonance_denominator_euler=eps ** 2 - 4 * delta ** 2,
        resonance_denominator_corrected=corr.eps_gyro ** 2 - 4 * delta ** 2,
        eps_over_delta_resonance_corrected=2 * I[0] / I[2],
        alpha_max_rad=float(np.max(alpha)), alpha_growth_rate_849=res["alpha_growth_rate"],
        fit_rms_longitude=fit.rms_longitude, fit_rms_obliquity=fit.rms_obliquity,
    )
    comps = [
        Comparison("mean precession of the axis", eul.precession_rate, fit.rate_longitude, corr.precession_rate,
                   "rad per 1/δ", "Euler §846: −N cos n; 'modern': the gyroscopic term kept, −N cos n·A/C"),
        Comparison("nutation in obliquity (coefficient of −cos 2φ)", eul.obliquity_amplitude, ap,
                   corr.obliquity_amplitude, "rad", "§844, §849: εN sin n(ε + 2δ cos n)/(2δ(εε − 4δδ))"),
        Comparison("nutation in longitude (coefficient of sin 2φ)", eul.longitude_amplitude, al,
                   corr.longitude_amplitude, "rad", "§844: εN(ε cos n + 2δ)/(2δ(εε − 4δδ)); §849 prints a different, wrong, form"),
        Comparison("free (diurnal) wobble of the axis in obliquity", h, m["free_wobble_obliquity"],
                   h * eps / corr.eps_gyro, "rad", "§844: h; with the gyroscopic term h·A/C"),
    ]
    notes = [f"N/δ = {N:.3g}: Euler holds p and λ fixed inside his equations 4–5, an error of relative order N/δ.",
             f"Euler drops the gyroscopic term of §840: his N has the equatorial moment where the true "
             f"precession has the polar one, so his rate is {I[2] / I[0]:.4f}× the corrected one."]
    if abs(r - 2) < 1.0 or abs(r - 2 * I[0] / I[2]) < 1.0:
        notes.append(f"ε/δ = {r:g} is near the resonance: Euler's formulas diverge at ε = 2δ (§849: "
                     f"\"the attempts found go to infinity\"), the corrected linear theory at ε/δ = 2A/C = "
                     f"{2 * I[0] / I[2]:.4f}. At the resonance the pole of rotation leaves the figure axis at the "
                     f"rate N sin n(1 + cos n)/2 = {res['alpha_growth_rate']:.3g} rad per 1/δ (§849); here it "
                     f"reached α = {np.degrees(m['alpha_max_rad']):.3g}°.")
    if m["alpha_max_rad"] > 0.1:
        notes.append(f"the pole of rotation went {np.degrees(m['alpha_max_rad']):.3g}° from the figure axis: "
                     "Euler's small-α hypothesis (§845) no longer holds.")
    notes += ["Text: " + t_ for t_ in TYPOS_844_849]
    rows = resonance_sweep(values["flattening"], n)
    notes.append("Nutation in obliquity toward the resonance (30 revolutions each, same flattening): "
                 + "; ".join(f"ε/δ = {r_:g}: simulated {a:.3g}, Euler {e:.3g}, corrected {c:.3g} rad"
                             for r_, a, e, c in rows))
    pe, le = eul.pole(t, np.pi / 2, h)
    p, lam = pole_angles(traj.figure_axis)
    sec = eul.precession_rate * t
    return Result("precession-circular", values, traj, m, comps, notes, plot_series={
        "obliquity p (rad)": p, "obliquity p, Euler §847 (rad)": pe,
        "longitude λ (rad)": lam, "longitude λ, Euler §847 (rad)": le,
        "λ − Euler's mean precession (rad)": lam - np.pi / 2 - sec,
        "Euler's nutation in λ (rad)": le - np.pi / 2 - sec,
    })


register(Scenario(
    name="precession-circular",
    title="Precession and nutation under a centre on a circle",
    section="§844–849",
    group="ch. 16",
    summary=("An oblate body (flattened like the Earth) spins fast at rate ε while a mass F goes round "
            "it on a circle at rate δ. The figure axis turns slowly backward around the pole of F's "
            "orbit (precession, at the mean rate N cos n) and nods twice per revolution of F "
            "(nutation, in 2φ): watch the axis trace its path on the celestial sphere. Slide ε/δ down "
            "toward 2: Euler's nutation formulas blow up there (§849) while the simulated body does "
            "something finite but no longer small."),
    params=(
        Param("eps_over_delta", 20.0, 0.05, 1000.0, "1", "spin ε over the orbital rate δ of the centre", step=0.1),
        Param("flattening", 0.1, 0.0, 0.5, "1", "flattening f of a homogeneous spheroid, c = a(1 − f)",
              exclusive_min=True, step=0.01),
        Param("obliquity_deg", 23.44, 0.0, 89.0, "deg", "arc ZA between figure axis and pole of the orbit",
              exclusive_min=True),
        Param("h", 0.0, 0.0, 0.1, "rad", "Euler's h: free offset of the pole of rotation from its forced place"),
        Param("orbits", 100.0, 0.0, 1e5, "revolutions", "length of the run in revolutions of the centre",
              exclusive_min=True),
        Param("steps_per_orbit", 100, 8, 1e5, "1", "integrator steps per revolution (yoshida4)", kind="int"),
    ),
    simulate_fn=_precession_circular,
    check=_check_circular,
    euler_formula=("ZA = n − εN sin n (ε + 2δ cos n) / (2δ(εε − 4δδ)) · cos 2φ + h sin(ε/δ · (φ + ζ)) (§844)\n"
                   "XZA = m − Nt cos n + εN (ε cos n + 2δ) / (2δ(εε − 4δδ)) · sin 2φ + h/sin n · cos(ε/δ · (φ + ζ))\n"
                   "N = 3gee (aa − cc) / (ε cc s³) (§847)"),
    presets=(
        ("Precession: fast spin, small nods", {}),
        ("Precession: ε/δ = 3, big nods", {"eps_over_delta": 3.0}),
        ("Precession: ε/δ = 2.2, Euler's nutation fails", {"eps_over_delta": 2.2}),
        ("Precession: with a free wobble h", {"h": 0.02}),
    ),
))
