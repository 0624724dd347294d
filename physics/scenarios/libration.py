"""Chapter 16: a body pulled by a distant mass F (Problems 92–94, §820–838).

All three scenarios integrate the full rigid body (physics.integrator, exact free flow +
gravity-gradient kicks of §815) with F moving on a prescribed orbit; ζ (Euler's arc AF, the
angle from the body's A axis to F about C) is read from the attitude afterwards.
"""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from .. import libration as lib
from .. import quaternion as quat
from ..gravity_gradient import starting_axis, torque_first_order
from ..inertia import validate_moments
from ..integrator import PointMass, integrate
from ..orbits import CircularOrbit, KeplerOrbit
from ..params import Param, ParameterError
from ..trajectory import Trajectory
from .base import Comparison, Result, Scenario, register

MAX_SAMPLES = 6000


def planar_moments(gamma):
    """(A, B, C) with C = 1 and (B − A)/C = γ: A = 0.75 − γ/2, B = 0.75 + γ/2 (a real body for
    |γ| ≤ 0.5)."""
    return np.array([0.75 - 0.5 * gamma, 0.75 + 0.5 * gamma, 1.0])


def zeta_of(traj_q, positions):
    """Euler's ζ = angle of F from the body's A axis, measured about C (unwrapped)."""
    s = quat.rotate_inverse(traj_q, positions)
    return np.unwrap(np.arctan2(s[:, 1], s[:, 0]))


def _stride(n_steps):
    return max(1, int(np.ceil(n_steps / MAX_SAMPLES)))


# --- gravity-start (§820–822) ------------------------------------------------------------

def _gravity_start(values, progress=None):
    I = validate_moments(values["inertia"], "inertia")
    d = np.array(values["direction"], float)
    u = d / np.linalg.norm(d)
    s, gm = values["distance"], values["gm"]
    tau0 = torque_first_order(I, u * s, gm)
    axis_e, rate_e = starting_axis(I, tau0)
    if rate_e == 0:
        raise ParameterError("direction", values["direction"],
                             "not along a principal axis (no torque there, §815: the body stays at rest)")
    # a time in which the body turns by `turn_deg` if the acceleration stayed constant
    T = np.sqrt(2.0 * np.radians(values["turn_deg"]) / rate_e)
    pos = lambda t: np.broadcast_to(u * s, (len(np.atleast_1d(t)), 3)).copy()  # noqa: E731
    n = 2000
    t, L, q = integrate(I, np.zeros(3), T, T / n, masses=[PointMass(gm, pos)], scheme="yoshida4",
                        stride=2, progress=progress)
    traj = Trajectory(t, q, L, I, time_unit="s", bodies={"attractor": pos(t)})
    w = traj.omega_body
    # first instant: ω(t)/t at the first stored step (error O(t): the body has hardly moved)
    w1 = w[1] / t[1]
    axis_s = w1 / np.linalg.norm(w1)
    ang = float(np.arccos(np.clip(axis_s @ axis_e, -1, 1)))
    cos_of_e = float(axis_e @ u)
    rate_s = float(np.linalg.norm(w1))
    axis_end = w[-1] / np.linalg.norm(w[-1])
    m = {
        "start_axis_angle_error_rad": ang,
        "angular_acceleration_rad_per_s2": rate_s,
        "angular_acceleration_euler_rad_per_s2": rate_e,
        "cos_OF_euler": cos_of_e,
        "cos_OF_simulated": float(axis_s @ u),
        "axis_drift_at_end_rad": float(np.arccos(np.clip(axis_end @ axis_e, -1, 1))),
    }
    comps = [
        Comparison("starting axis cos α (§820)", float(axis_e[0]), float(axis_s[0])),
        Comparison("starting axis cos β (§820)", float(axis_e[1]), float(axis_s[1])),
        Comparison("starting axis cos γ (§820)", float(axis_e[2]), float(axis_s[2])),
        Comparison("angular acceleration √(P²/A²+Q²/B²+R²/C²)", rate_e, rate_s, None, "rad/s²"),
        Comparison("cos OF (§820)", cos_of_e, float(axis_s @ u)),
    ]
    notes = []
    if abs(u[2]) < 1e-12:
        notes.append("F lies in the AB plane: §821 says the body starts about C exactly (P = Q = 0).")
    notes.append("The translation prints cos α = P/aa · √(…); it must be P/aa : √(…) (a division).")
    series = {"omega_x": w[:, 0], "omega_y": w[:, 1], "omega_z": w[:, 2],
              "axis_angle_from_euler_rad": np.arccos(np.clip(
                  (w / np.maximum(np.linalg.norm(w, axis=1, keepdims=True), 1e-300)) @ axis_e, -1, 1))}
    series["axis_angle_from_euler_rad"][0] = 0.0
    traj.series.update(series)
    return Result("gravity-start", values, traj, m, comps, notes, plot_series=dict(series))


def _check_gravity_start(v):
    validate_moments(v["inertia"], "inertia")
    if not np.linalg.norm(v["direction"]) > 0:
        raise ParameterError("direction", v["direction"], "not the zero vector")


register(Scenario(
    name="gravity-start",
    title="A body at rest pulled by a distant mass",
    section="§820–822",
    group="ch. 16",
    summary=("A body at rest and a distant mass F in a given direction. F pulls harder on the near "
            "parts of the body than on the far ones, which gives a small torque (the gravity-gradient "
            "torque, §815). The body starts turning about the axis with cosines ∝ P/A : Q/B : R/C "
            "(§820); with F in the plane of the A and B axes it starts about C (§821). Watch the "
            "rotation axis drift from Euler's starting axis as the body turns."),
    params=(
        Param("inertia", (2.0, 3.0, 4.0), 1e-6, 1e6, "kg m^2", "principal moments A, B, C", kind="vec3"),
        Param("direction", (1.0, 0.6, 0.4), -1.0, 1.0, "", "direction of F in the body frame (x, y, z)", kind="vec3"),
        Param("distance", 10.0, 1e-3, 1e9, "m", "distance s of F from the centre", exclusive_min=True),
        Param("gm", 1000.0, 0.0, 1e20, "m^3/s^2", "G·M of F", exclusive_min=True),
        Param("turn_deg", 10.0, 1e-3, 90.0, "deg", "simulate until the body would have turned this far"),
    ),
    simulate_fn=_gravity_start,
    euler_formula=("P = 3GM (C − B) cos η cos ϑ / s³, and the same for Q and R in turn (§815)\n"
                   "cos α : cos β : cos γ = P/A : Q/B : R/C (§820)"),
    check=lambda v: _check_gravity_start(v),
    presets=(
        ("Pull: F oblique", {}),
        ("Pull: F in the AB plane, starts about C (§821)", {"direction": (1.0, 0.6, 0.0)}),
    ),
))


# --- libration-circular (§825–831) -------------------------------------------------------

def circular_setup(gamma, rate, zeta0, spin_ratio):
    """Inertia, orbit, initial attitude and spin for Problem 93 (GM = δ²s³ with s = 1)."""
    I = planar_moments(gamma)
    orbit = CircularOrbit(radius=1.0, rate=rate)
    q0 = quat.from_axis_angle([0, 0, 1], -zeta0)  # A axis at λ = −ζ₀, F at X
    return I, orbit, q0, np.array([0.0, 0.0, spin_ratio * rate])


def _libration_circular(values, progress=None):
    g, d = values["asymmetry"], values["orbital_rate"]
    if d < 1e-100:  # found by tests/test_fuzz.py: 1e-308 made gm = d² underflow, then NaN → int crashed
        raise ParameterError("orbital_rate", d, "at least 1e-100 (its square must not underflow), allowed range (0, 100] rad/unit")
    zeta0 = np.radians(values["zeta0_deg"])
    spin = values["spin_ratio"]
    gm = d * d
    zeq = lib.equilibrium_zeta(g)
    w0 = lib.small_oscillation_omega(g, gm, 1.0)
    phi0 = np.remainder(zeta0 - zeq + 0.5 * np.pi, np.pi) - 0.5 * np.pi
    preset = values["preset"]
    if preset == "locked":
        zeta0, spin, phi0 = zeq, 1.0, 0.0
    elif preset == "separatrix":
        if w0 == 0:
            raise ParameterError("asymmetry", g, "nonzero for a separatrix (B ≠ A)")
        # φ̇ = ±ω₀ cos φ₀, heading for the unstable point ±90° (§826 3rd)
        spin = 1.0 - np.sign(phi0 or 1.0) * w0 * np.cos(phi0) / d  # moving away from ζ_eq
    phidot0 = d * (1.0 - spin)  # ζ̇ = δ − γ'
    I, orbit, q0, om0 = circular_setup(g, d, zeta0, spin)
    case = lib.classify(phi0, phidot0, w0) if w0 > 0 else "circulating"
    T_small = lib.small_oscillation_period(g, gm, 1.0) if w0 > 0 else np.inf
    T_exact = lib.pendulum_period(phi0, phidot0, w0) if w0 > 0 else (np.pi / abs(phidot0) if phidot0 else np.inf)
    T_ref = T_exact if (np.isfinite(T_exact) and case != "separatrix") else T_small
    if not np.isfinite(T_ref):
        T_ref = 2 * np.pi / d
    if d > 0 and T_ref > 1e6 * 2 * np.pi / d:  # found by tests/test_fuzz.py: asymmetry 1e-172 gave a
        # libration period of 1e86, a step of 2e84 and ω ~ 1e69 after one step
        raise ParameterError("asymmetry", g, "0, or large enough for a libration within 10⁶ revolutions "
                             "(|asymmetry| ≳ 1e-12), allowed range [-0.45, 0.45]")
    duration = values["periods"] * T_ref
    step = T_ref / values["steps_per_period"]
    n = int(np.ceil(duration / step))
    t, L, q = integrate(I, om0, duration, step, q0=q0, masses=[PointMass(gm, orbit.position)],
                        scheme="yoshida4", stride=_stride(n), progress=progress)
    pos = orbit.position(t)
    traj = Trajectory(t, q, L, I, time_unit="1/δ·rad", bodies={"attractor": pos})
    zeta = zeta_of(q, pos)
    zeta = zeta - 2 * np.pi * np.round((zeta[0] - zeta0) / (2 * np.pi))
    zdot = d - traj.omega_body[:, 2]
    phi = zeta - zeq
    phi -= np.pi * np.round((phi[0] - phi0) / np.pi)  # the same branch as φ₀
    circ = case == "circulating"
    T_meas = lib.measured_period(t, phi, circulating=circ) if case not in ("locked", "separatrix") else np.nan
    # the first integral of §825, dζ² − N cos 2ζ dt² = C dt², conserved on a circular orbit
    Nn = lib.euler_N(g, gm, 1.0)
    jac = 0.5 * zdot**2 - 0.5 * Nn * np.cos(2 * zeta)
    amp_meas = float(np.max(np.abs(phi))) if not circ else np.nan
    # Euler's curve: the small-oscillation solution (§831) from the same start
    if w0 > 0:
        z_euler = zeq + phi0 * np.cos(w0 * t) + phidot0 / w0 * np.sin(w0 * t)
    else:
        z_euler = zeta0 + phidot0 * t
    m = {
        "libration_period": T_meas,
        "libration_period_euler": T_small,
        "libration_period_exact": T_exact,
        "libration_amplitude_rad": amp_meas,
        "libration_amplitude_exact_rad": lib.libration_amplitude(phi0, phidot0, w0) if (w0 > 0 and not circ) else np.nan,
        "period_rel_error_vs_exact": abs(T_meas / T_exact - 1) if np.isfinite(T_exact) and np.isfinite(T_meas) else np.nan,
        "modulus_k2": float(lib.pendulum_modulus_sq(phi0, phidot0, w0)) if w0 > 0 else np.inf,
        "first_integral_abs_drift": float(np.max(np.abs(jac - jac[0]))),
    }
    if case == "circulating" and w0 > 0:
        # §826 4th: C = m²n, t√n = ζ/m − sin 2ζ/(4m³): half a turn relative to F takes π/(m√N)
        m2 = (phidot0**2 - Nn * np.cos(2 * phi0)) / Nn
        # m² ≤ 0: the chosen start does not circulate (found by tests/test_fuzz.py), no such period
        m["circulation_period_euler"] = float(np.pi / (np.sqrt(m2) * np.sqrt(Nn))) if m2 > 0 and Nn > 0 else np.nan
    if case == "separatrix" and w0 > 0 and abs(phi0) < np.radians(80.0):
        target = np.sign(phi0 or 1.0) * np.radians(80.0)
        k = np.nonzero(np.abs(phi) >= np.radians(80.0))[0]
        if len(k) and k[0] > 0:  # interpolate the crossing between samples
            i = k[0]
            x0, x1 = abs(phi[i - 1]), abs(phi[i])
            m["separatrix_time_to_80deg"] = float(t[i - 1] + (np.radians(80.0) - x0) / (x1 - x0) * (t[i] - t[i - 1]))
        else:
            m["separatrix_time_to_80deg"] = float(t[k[0]]) if len(k) else np.nan
        m["separatrix_time_to_80deg_euler"] = float(
            abs(lib.separatrix_time_euler(target, w0) - lib.separatrix_time_euler(phi0, w0)))
    comps = [
        Comparison("libration period (small oscillation §831: 2π/√(2N))", T_small, T_meas, T_exact, "1/δ",
                   "modern: finite-amplitude pendulum in 2ζ, 4K(sin ζ_max)/√(2N)"),
        Comparison("largest digression ζ_max", None, amp_meas, m["libration_amplitude_exact_rad"], "rad"),
    ]
    if "circulation_period_euler" in m:
        comps.append(Comparison("half turn relative to F, π/(m√n) (§826 4th)", m["circulation_period_euler"], T_meas,
                                T_exact, "1/δ", "Euler keeps the first term of t√n = ζ/m − sin 2ζ/(4m³)"))
    if "separatrix_time_to_80deg" in m:
        comps.append(Comparison("time to creep to 80° on the separatrix, ln tan(45° + ζ/2)/√(2n) (§826 3rd)",
                                m["separatrix_time_to_80deg_euler"], m["separatrix_time_to_80deg"], None, "1/δ"))
    notes = [f"Euler's case: {case} (§826).",
             "Euler's √(2n) is in his units: his n is N = 3GM(B−A)/(2Cs³); the small-oscillation "
             "angular frequency is √(2N) = δ√(3(B−A)/C) on a Kepler circle, and his π/√(2n) is half "
             "a full period."]
    if g < 0:
        notes.append("B < A (case II, §827): the B axis faces F; ζ librates about 90°.")
    # phase portrait: the trajectory and the separatrix φ̇ = ±ω₀ cos φ (sampled on len(t) points)
    sep_phi = np.linspace(-0.5 * np.pi, 0.5 * np.pi, len(t))
    series = {
        "zeta_rad": zeta, "zeta_euler_rad": z_euler, "zeta_dot": zdot,
        "separatrix_zeta_rad": zeq + sep_phi,
        "separatrix_zeta_dot_plus": lib.separatrix_rate(sep_phi, w0),
        "separatrix_zeta_dot_minus": -lib.separatrix_rate(sep_phi, w0),
    }
    traj.series.update(series)
    notes.append("plot_series: ζ(t) with Euler's small-oscillation curve; the phase portrait is "
                 "(zeta_rad, zeta_dot); the separatrix is the parametric curve "
                 "(separatrix_zeta_rad, separatrix_zeta_dot_±) — not a time series; the same curve is in "
                 "extras['separatrix'] (zeta_rad, zeta_dot_plus, zeta_dot_minus).")
    extras = {"separatrix": {"zeta_rad": series["separatrix_zeta_rad"],
                             "zeta_dot_plus": series["separatrix_zeta_dot_plus"],
                             "zeta_dot_minus": series["separatrix_zeta_dot_minus"]}}
    return Result("libration-circular", values, traj, m, comps, notes, plot_series=series, extras=extras)


register(Scenario(
    name="libration-circular",
    title="Libration in a circular orbit (Problem 93)",
    section="§825–831",
    group="ch. 16",
    summary=("A mass F goes round the body at a steady rate, in the plane of the body's A and B axes. "
            "The angle ζ between the A axis and F obeys a pendulum equation in 2ζ (§825). Depending on "
            "the start, the body stays locked facing F, swings to and fro about F (libration), creeps "
            "toward 90° along the dividing curve (the separatrix), or turns round and round relative "
            "to F (circulation): Euler's four cases. Drag the initial spin across the separatrix and "
            "watch the phase portrait change."),
    params=(
        Param("asymmetry", 0.05, -0.45, 0.45, "", "(B − A)/C; negative: B < A, Euler's case II"),
        Param("orbital_rate", 1.0, 0.0, 100.0, "rad/unit", "angular rate δ of F (GM = δ²s³)", exclusive_min=True),
        Param("zeta0_deg", 20.0, -180.0, 180.0, "deg", "initial arc AF = ζ₀"),
        Param("spin_ratio", 1.0, -3.0, 5.0, "", "initial spin about C divided by δ"),
        Param("preset", "sliders", kind="choice", choices=("sliders", "locked", "separatrix"),
              help="'separatrix' sets the spin that puts the start on the separatrix"),
        Param("periods", 4.0, 1.0, 50.0, "", "libration periods to simulate"),
        Param("steps_per_period", 400, 50, 20000, "", "integrator steps per period", kind="int"),
    ),
    simulate_fn=_libration_circular,
    euler_formula=("ζ̈ + N sin 2ζ = 0, N = 3GM (B − A) / (2C s³) (§825)\n"
                   "small swings: period T = 2π / √(2N) (§831)"),
    presets=(
        ("Libration: swinging about F", {}),
        ("Libration: locked", {"preset": "locked"}),
        ("Libration: the separatrix", {"preset": "separatrix"}),
        ("Libration: circulating", {"spin_ratio": 2.0}),
        ("Libration: case II (B < A)", {"asymmetry": -0.05}),
    ),
))


# --- libration-eccentric (§833–838) ------------------------------------------------------

class ForcedSolution:
    """The forced (periodic) libration on the Kepler orbit (periapse at t = 0), §838: found
    once by shooting (physics.libration.periodic_libration), evaluated at any t."""

    def __init__(self, gamma, e, n, progress=None):
        self.orbit = KeplerOrbit(a=1.0, e=e, n=n)
        N = lib.euler_N(gamma, n * n, 1.0)
        m = lib.forced_amplitude_euler(2 * e, n, N)
        zeq = lib.equilibrium_zeta(gamma)
        if gamma == 0:  # no torque (§837, n = 0): uniform rotation, ζ is the equation of the centre
            lam0, lamdot0, P = -zeq, float(n), 2 * np.pi / n
        else:
            guess = (-zeq, float(self.orbit.true_anomaly_rate(np.array([0.0]))[0] - m * n))
            lam0, lamdot0, P = lib.periodic_libration(self.orbit, gamma, n * n, guess=guess, progress=progress)
        lam0 = float(np.remainder(lam0 + 0.5 * np.pi, np.pi) - 0.5 * np.pi)  # ζ ≡ ζ + π
        self.lam0, self.lamdot0, self.P = lam0, lamdot0, P
        self.sol = solve_ivp(lib.planar_rhs(self.orbit, gamma, n * n), (0.0, P), [lam0, lamdot0],
                             method="DOP853", rtol=1e-12, atol=1e-13, dense_output=True).sol

    def zeta(self, t):
        tt = np.remainder(np.asarray(t, float), self.P)
        return self.orbit.true_anomaly(tt) - self.sol(tt)[0]


def _forced_amplitude_of_run(t, zeta, n, period, free_period):
    """First harmonic (frequency n) of ζ(t) from the rigid-body run, fitted over its whole orbits
    with the 2nd and 3rd harmonics and, when the run has a free swing, sin/cos at its period."""
    keep = t - t[0] <= period * np.floor((t[-1] - t[0]) / period + 1e-9)
    if np.count_nonzero(keep) < 16:  # less than one whole orbit: fit what there is
        keep = np.ones_like(t, bool)
    tt, z = t[keep] - t[0], zeta[keep]
    cols = [np.ones_like(tt)] + [f(k * n * tt) for k in (1, 2, 3) for f in (np.sin, np.cos)]
    if np.isfinite(free_period) and free_period > 0:
        w = 2 * np.pi / free_period
        cols += [np.sin(w * tt), np.cos(w * tt)]
    coef, *_ = np.linalg.lstsq(np.stack(cols, 1), z, rcond=None)
    return float(np.hypot(coef[1], coef[2]))


def _libration_eccentric(values, progress=None):
    g, e, n = values["asymmetry"], values["eccentricity"], values["orbital_rate"]
    if n < 1e-100:  # as in libration-circular: n² must not underflow
        raise ParameterError("orbital_rate", n, "at least 1e-100 (its square must not underflow), allowed range (0, 100] rad/unit")
    I = planar_moments(g)
    gm = n * n
    orbit = KeplerOrbit(a=1.0, e=e, n=n)
    N = lib.euler_N(g, gm, 1.0)
    if abs(1.0 - 3.0 * g) < 0.03:
        raise ParameterError("asymmetry", g, "not within 0.01 of 1/3 (resonance A² = 2N: no forced libration)")
    P = 2 * np.pi / n
    duration = values["orbits"] * P
    step = P / values["steps_per_orbit"]
    fs = ForcedSolution(g, e, n, progress=progress)
    lam0, lamdot0 = fs.lam0, fs.lamdot0
    dz = np.radians(values["free_zeta0_deg"])
    q0 = quat.from_axis_angle([0, 0, 1], lam0 - dz)  # ζ₀ = f(0) − λ₀ + dz, f(0) = 0
    om0 = np.array([0.0, 0.0, lamdot0])
    nst = int(np.ceil(duration / step))
    t, L, q = integrate(I, om0, duration, step, q0=q0, masses=[PointMass(gm, orbit.position)],
                        scheme="yoshida4", stride=_stride(nst),
                        progress=(lambda f: progress(0.1 + 0.9 * f)) if progress is not None else None)
    pos = orbit.position(t)
    traj = Trajectory(t, q, L, I, time_unit="1/n·rad", bodies={"attractor": pos})
    zeta = zeta_of(q, pos)
    z_forced = fs.zeta(t)
    zeta -= np.pi * np.round((zeta[0] - z_forced[0] - dz) / np.pi)
    z_forced = fs.zeta(t)
    z_free = zeta - z_forced
    # forced part: harmonics of the periodic solution over one period
    tp = np.linspace(0, P, 2049)[:-1]
    zf1 = fs.zeta(tp)
    a, b = lib.harmonics(tp, zf1, n, 3)
    alpha, beta, A = 2 * e, 3 * e, n
    # B < A: the stable state has the B axis toward F (§827, ζ = 90° + φ), where Euler's formulas
    # hold with |n|. His §837 reading of n < 0 as "smaller digressions" is about the A axis facing
    # F, which his own §837 separatrix shows is unstable — the simulation never stays there.
    Ns = abs(N)
    m1 = lib.forced_amplitude_euler(alpha, A, Ns)
    m2e = lib.second_order_euler(alpha, beta, A, Ns)
    w0 = lib.small_oscillation_omega(g, gm, 1.0)
    z_euler = m1 * np.sin(A * t) + (dz * np.cos(w0 * t) if w0 > 0 else dz)
    free_period = lib.measured_period(t, z_free) if dz != 0 else np.nan
    amp_run = _forced_amplitude_of_run(t, zeta, n, P, free_period)
    mt = {
        "forced_amplitude_rad": amp_run,
        "forced_amplitude_periodic_rad": float(np.hypot(a[0], b[0])),
        "forced_amplitude_euler_rad": float(m1),
        "forced_amplitude_rel_error": float(abs(amp_run / m1 - 1)) if m1 else np.nan,
        "forced_second_harmonic_rad": float(a[1]),
        "second_order_euler_rad": float(m2e),
        "forced_max_rad": float(np.max(np.abs(zf1))),
        "free_amplitude_rad": float(np.max(np.abs(z_free))),
        "free_period": free_period,
        "free_period_euler": 2 * np.pi / w0 if w0 > 0 else np.inf,
    }
    # modern: the linearised free period about the forced solution (Floquet, exact in e), lengthened by
    # the free swing's own amplitude φ²/4 (pendulum); only worth computing when there is a free part
    if dz != 0 and g > 0 and w0 < 0.5 * n:
        nu = lib.free_libration_floquet(fs.orbit, g, gm, fs.lam0, fs.lamdot0)
        mt["free_period_floquet"] = 2 * np.pi / nu if nu > 0 else np.nan
        mt["free_period_modern"] = mt["free_period_floquet"] * (1 + dz**2 / 4)
    comps = [
        Comparison("forced libration amplitude A²α/(A²−2N) (§833)", m1, mt["forced_amplitude_rad"],
                   mt["forced_amplitude_periodic_rad"], "rad",
                   "simulated: first harmonic of ζ in the rigid-body run (whole orbits; a free swing fitted "
                   "alongside at its measured period); modern: that of the periodic solution of the planar "
                   "equation (DOP853, the ellipse to all orders)"),
        Comparison("sin 2At coefficient (§835)", m2e, mt["forced_second_harmonic_rad"], None, "rad",
                   "Euler keeps only the 1/s³ modulation β; the ellipse adds (5/4)e² sin 2M to the true anomaly, "
                   "which gives 5e²A²/(4A²−2N) — larger than Euler's term"),
        Comparison("free libration period 2π/√(2N) (§838)", mt["free_period_euler"], mt["free_period"],
                   mt.get("free_period_modern"), "1/n",
                   "modern: Floquet period of small swings about the forced libration (the ellipse to all orders) "
                   "× (1 + φ²/4) for the free amplitude φ"),
    ]
    notes = ["Euler's α = 2e, A = n (anomalistic = orbital rate for a fixed ellipse), β = 3e: the ellipse to first order in e.",
             "For B < A the forced libration is about ζ = 90° (the B axis toward F) and Euler's formula is used with |n|; "
             "his §837 remark that n < 0 makes the digressions smaller concerns the unstable state with A toward F.",
             "The translation prints ζ = AA/(AA−2n) sin At (α dropped) at the end of §833; §834 has it right."]
    series = {"zeta_rad": zeta, "zeta_euler_rad": z_euler, "zeta_forced_rad": z_forced, "zeta_free_rad": z_free}
    traj.series.update(series)
    return Result("libration-eccentric", values, traj, mt, comps, notes, plot_series=series)


register(Scenario(
    name="libration-eccentric",
    title="Forced libration in an eccentric orbit (Problem 94)",
    section="§833–838",
    group="ch. 16",
    summary=("Now F moves on a Kepler ellipse, fast near periapse and slow far away. Its uneven motion "
            "forces the body to swing, ζ ≈ A²α/(A² − 2N) · sin At (§833), on top of any free swing "
            "left from the start (§838). Raise the eccentricity to see where Euler's first-order "
            "formula stops matching; bring (B − A)/C toward 1/3 to approach the resonance A² = 2N, "
            "where his amplitude blows up."),
    params=(
        Param("asymmetry", 0.05, -0.45, 0.45, "", "(B − A)/C"),
        Param("eccentricity", 0.05, 0.0, 0.5, "", "eccentricity e of F's orbit"),
        Param("orbital_rate", 1.0, 0.0, 100.0, "rad/unit", "mean motion n", exclusive_min=True),
        Param("free_zeta0_deg", 2.0, -60.0, 60.0, "deg", "initial offset from the forced libration (free part)"),
        Param("orbits", 20.0, 1.0, 500.0, "", "orbits to simulate"),
        Param("steps_per_orbit", 400, 50, 20000, "", "integrator steps per orbit", kind="int"),
    ),
    simulate_fn=_libration_eccentric,
    euler_formula=("ζ = A²α/(A² − 2N) · sin At + Nαβ/(4(A² − 2N)) · sin 2At (§833–835)"),
    presets=(
        ("Forced swing: a nearly circular orbit", {}),
        ("Forced swing: e = 0.3, beyond Euler's first order", {"eccentricity": 0.3}),
        ("Forced swing: near the resonance A² = 2N", {"asymmetry": 0.3}),
    ),
))


# --- gravity-gradient-accuracy (§815–818) ------------------------------------------------

def _gg_accuracy(values, progress=None):
    from ..gravity_gradient import fitted_order, force_error_vs_size, torque_error_vs_size
    from ..inertia import ellipsoid_moments

    a = np.array(values["semi_axes"], float)
    d = np.array(values["direction"], float)
    if not np.linalg.norm(d) > 0:
        raise ParameterError("direction", values["direction"], "not the zero vector")
    u = d / np.linalg.norm(d)
    ratios = np.geomspace(values["min_ratio"], values["max_ratio"], values["n_points"])
    et = torque_error_vs_size(a, u, ratios)
    ef = force_error_vs_size(a, u, ratios)
    I = ellipsoid_moments(a)
    # the "time" axis of this trajectory is size/distance, so every plot is error vs size/s
    n = len(ratios)
    traj = Trajectory(ratios, np.tile(quat.IDENTITY, (n, 1)), np.zeros((n, 3)), I, time_unit="size/distance",
                      bodies={"attractor": u[None, :] * a.max() / ratios[:, None]})
    small = ratios <= 0.1 * ratios.max() if n > 2 else np.ones(n, bool)
    sel = small if small.sum() >= 2 else np.ones(n, bool)
    m = {"torque_error_order": fitted_order(ratios[sel], et[sel]), "force_error_order": fitted_order(ratios[sel], ef[sel]),
         "torque_rel_error_at_max_ratio": float(et[-1]), "force_rel_error_at_max_ratio": float(ef[-1]),
         "torque_rel_error_at_min_ratio": float(et[0])}
    comps = [Comparison("order of the torque error in size/s (§816)", 2.0, m["torque_error_order"]),
             Comparison("order of the §818 force error in size/s", 2.0, m["force_error_order"])]
    notes = ["The x axis (trajectory.t) is size/distance (largest semi-axis / s); exact values by Gauss quadrature "
             "over the homogeneous ellipsoid (16×16×32 points; converged to ~1e-6 relative at s = 1.25 sizes)."]
    series = {"torque_rel_error": et, "force_rel_error": ef, "ratio_squared": ratios**2}
    traj.series.update(series)
    return Result("gravity-gradient-accuracy", values, traj, m, comps, notes, plot_series=series)


def _check_ratios(v):
    if not v["min_ratio"] < v["max_ratio"]:
        raise ParameterError("min_ratio", v["min_ratio"], f"below max_ratio = {v['max_ratio']:g}")


register(Scenario(
    name="gravity-gradient-accuracy",
    title="How good is Euler's first-order torque?",
    section="§815–818",
    group="ch. 16",
    summary=("Euler keeps only the first term of the pull in powers of size/distance (§816). Here the "
            "pull of F is integrated exactly over a homogeneous ellipsoid and compared with his "
            "formula at many distances: the relative error of his torque, and of the small extra force "
            "on the centre (§818), falls as (size/distance)². It reaches about 6% when F is only two "
            "body sizes away."),
    params=(
        Param("semi_axes", (1.0, 0.8, 0.6), 1e-3, 1e3, "m", "semi-axes a, b, c of the ellipsoid", kind="vec3"),
        Param("direction", (0.6, 0.5, 0.3), -1.0, 1.0, "", "direction of F in the body frame", kind="vec3"),
        Param("min_ratio", 0.01, 1e-3, 0.5, "", "smallest size/distance"),
        Param("max_ratio", 0.5, 0.01, 0.8, "", "largest size/distance (F outside the body)"),
        Param("n_points", 12, 3, 60, "", "number of distances", kind="int"),
    ),
    simulate_fn=_gg_accuracy,
    euler_formula=("τ = (3GM/s³) ŝ × I ŝ + O(size²/s²) (§815–816)"),
    check=lambda v: _check_ratios(v),
    presets=(
        ("Accuracy: F from 100 to 2 body sizes away", {}),
        ("Accuracy: a long needle", {"semi_axes": (1.0, 0.2, 0.2)}),
        ("Accuracy: nearly a sphere", {"semi_axes": (1.0, 0.98, 0.96)}),
    ),
))
