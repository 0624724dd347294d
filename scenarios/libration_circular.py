"""Libration in a circular orbit (Problem 93, §825–831): the pendulum in 2ζ; locked, librating,
separatrix and circulating starts; the small-oscillation frequency √(2N).

Check rows E7 (small-oscillation period), E7.finite-amplitude (the exact pendulum period) and
E7.separatrix.
"""
from __future__ import annotations

import dataclasses

import numpy as np
from ..physics import libration as lib
from ..physics import quaternion as quat
from ..physics.integrator import PointMass, integrate, step_count
from ..physics.orbits import CircularOrbit
from ..physics.params import Param, ParameterError
from ..physics.trajectory import Trajectory
from .drawing import Camera
from .base import Comparison, Run, Scenario, register
from .budget import Cost, trajectory_bytes
from .base import get
from .checks import register_check
from ._libration import planar_moments, run_samples, stride_for, zeta_of
from .drawing import Label, Option, Points, Segments, Sphere
from ._ch16_drawing import (ORBIT_OPTION, PANEL_AXES_COLOR, PANEL_COLOR, POINT_COLOR, SEPARATRIX_COLOR, ZETA_COLOR,
                            ZETA_OPTION, Panel, body_scene, camera_basis, centre_of_force, f_and_zeta,
                            frame_with_panel, wrap)
from . import _validity

# the run's first integral may wander by at most this fraction of the gap 1 − k² to the separatrix
# before its case, period and amplitude stop meaning anything
SEPARATRIX_DRIFT_FRACTION = 0.1


NO_TORQUE = "no torque"  # A = B: Euler's classification (§826) has no case for it

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
    start = values["start"]
    if start == "locked":
        zeta0, spin, phi0 = zeq, 1.0, 0.0
    elif start == "separatrix":
        if w0 == 0:
            raise ParameterError("asymmetry", g, "nonzero for a separatrix (B ≠ A)")
        # φ̇ = ±ω₀ cos φ₀, heading for the unstable point ±90° (§826 3rd)
        spin = 1.0 - np.sign(phi0 or 1.0) * w0 * np.cos(phi0) / d  # moving away from ζ_eq
    phidot0 = d * (1.0 - spin)  # ζ̇ = δ − γ'
    I, orbit, q0, om0 = circular_setup(g, d, zeta0, spin)
    case = lib.classify(phi0, phidot0, w0) if w0 > 0 else NO_TORQUE
    T_small = lib.small_oscillation_period(g, gm, 1.0) if w0 > 0 else np.inf
    T_exact = lib.pendulum_period(phi0, phidot0, w0) if w0 > 0 else (np.pi / abs(phidot0) if phidot0 else np.inf)
    if case == "separatrix":  # the period is infinite: a start on it by construction (1 − k² of 4e-16,
        T_exact = np.inf      # the rounding of the start, gave a finite 197 at ζ₀ = 20°) or at the
        # unstable point itself (ζ₀ = 90° at rest relative to F: cos 90° rounds to 6e-17, and 1 − k² of
        # 4e-33 gave a finite "exact" period of 400)
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
                        scheme="yoshida4", stride=stride_for(n), progress=progress)
    pos = orbit.position(t)
    traj = Trajectory(t, q, L, I, time_unit="unit", bodies={"attractor": pos}, moment_unit="C")  # δ is in rad per unit
    zeta = zeta_of(q, pos)
    zeta = zeta - 2 * np.pi * np.round((zeta[0] - zeta0) / (2 * np.pi))
    zdot = d - traj.omega_body[:, 2]
    phi = zeta - zeq
    phi -= np.pi * np.round((phi[0] - phi0) / np.pi)  # the same branch as φ₀
    circ = case in ("circulating", NO_TORQUE)  # without a torque the body turns relative to F at its start rate
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
        # no torque, no pendulum: its modulus is undefined (said in the notes)
        "modulus_k2": float(lib.pendulum_modulus_sq(phi0, phidot0, w0)) if w0 > 0 else np.nan,
        "separatrix_gap_1_minus_k2": float(lib.pendulum_modulus_gap(phi0, phidot0, w0)) if w0 > 0 else np.nan,
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
        Comparison("libration period (small oscillation §831: 2π/√(2N))", T_small, T_meas, T_exact, "unit",
                   "modern: finite-amplitude pendulum in 2ζ, 4K(sin ζₘₐₓ)/√(2N)"),
        Comparison("largest digression ζₘₐₓ", None, amp_meas, m["libration_amplitude_exact_rad"], "rad",
                   missing="the body turns round relative to F: there is no largest digression" if circ else ""),
    ]
    if "circulation_period_euler" in m:
        comps.append(Comparison("half turn relative to F, π/(m√n) (§826 4th)", m["circulation_period_euler"], T_meas,
                                T_exact, "unit", "Euler keeps the first term of t√n = ζ/m − sin 2ζ/(4m³)"))
    if "separatrix_time_to_80deg" in m:
        comps.append(Comparison("time to creep to 80° on the separatrix, ln tan(45° + ζ/2)/√(2n) (§826 3rd)",
                                m["separatrix_time_to_80deg_euler"], m["separatrix_time_to_80deg"], None, "unit"))
    notes = [f"Euler's case: {case} (§826)." if case != NO_TORQUE else
             "No torque (A = B): none of Euler's cases (§826), which need B ≠ A; the body turns relative to F at "
             "its starting rate, and the pendulum's modulus k² and the gap 1 − k² are undefined (NaN).",
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
    warnings: list[str] = []
    # near the separatrix: the run's own first integral must stay well inside the gap 1 − k²
    # (k² = (first integral + N/2)/N, so the integral's drift over N is the run's error in k²)
    gap = m["separatrix_gap_1_minus_k2"]
    if w0 > 0 and case in ("librating", "circulating") and Nn != 0:
        k2_drift = m["first_integral_abs_drift"] / abs(Nn)
        if k2_drift > SEPARATRIX_DRIFT_FRACTION * abs(gap):
            warnings.append(
                f"Near the separatrix: 1 − k² = {gap:.3g}, but the run's first integral (§825) wanders by {k2_drift:.2g} "
                f"in k², more than {SEPARATRIX_DRIFT_FRACTION:g} of that gap: the simulated period, amplitude and even the "
                "case (librating or circulating) are not to be trusted. The exact period (from 1 − k² formed without "
                "cancellation) is; raise steps_per_period to bring the run closer.")
    # the step against the fastest period: the swing through ζ_eq at up to ω₀k (torque ∝ sin 2φ), or
    # the small oscillation
    if w0 > 0:
        k = np.sqrt(max(float(m["modulus_k2"]), 0.0))
        T_fast = min(2 * np.pi / w0, np.pi / (w0 * max(k, 1e-300)))
    else:
        T_fast = np.pi / abs(phidot0) if phidot0 else np.inf
    _validity.add(warnings, _validity.coarse_step(step, T_fast, "the swing through F's direction", "time units",
                                                  "steps_per_period"))
    # a period that is not measured says why (a sweep's NaN was otherwise unexplained)
    if not np.isfinite(T_meas):
        if case == "locked":
            why = "locked: the body keeps its long axis toward F, so there is no libration period to measure"
            notes.append(why[0].upper() + why[1:] + ".")
        elif case == "separatrix":
            why = "on the separatrix the period is infinite: none is measured"
            notes.append(why[0].upper() + why[1:] + ".")
        elif w0 <= 0 and not phidot0:
            why = "no torque (A = B) and no starting spin relative to F: nothing turns, no period to measure"
            notes.append(why[0].upper() + why[1:] + ".")
        else:
            why = (f"the run holds fewer than two {'half turns relative to F' if circ else 'whole swings'} "
                   f"({values['periods']:g} period{'' if values['periods'] == 1 else 's'}): the period is "
                   "measured from at least two; set periods ≥ 2")
            warnings.append(why[0].upper() + why[1:] + ".")
        comps[0] = dataclasses.replace(comps[0], missing=why)
    return Run("libration-circular", values, traj, m, comps, notes, plot_series=series, extras=extras,
               warnings=warnings)


def _draw(run, spec, view):
    """The body, F on its circle, the arc ζ from the A axis to F, and beside them the phase
    portrait (ζ, dζ/dt) of the run with the separatrix (§825–831) and the state now as a dot."""
    d, _ = body_scene(run, spec, view, bodies={"F": centre_of_force(run)})
    f_and_zeta(d, run, spec, view)
    # the separatrix and the portrait are curves, not time series: drawn here, not in the time plot
    d.plot = {k: v for k, v in run.plot_series.items() if not k.startswith("separatrix_")}
    s = run.trajectory.series
    if view.option("portrait", spec) and "zeta_dot" in s:
        frame_with_panel(d, _phase_portrait(d, s))
    return d


def _phase_portrait(d, s):
    sz = np.asarray(s["separatrix_zeta_rad"], float)
    lo = float(np.nanmin(sz))  # the separatrix spans one period π of the pendulum in 2ζ
    zw = wrap(s["zeta_rad"], lo, np.pi)
    zd = np.asarray(s["zeta_dot"], float)
    ymax = 1.15 * max(np.nanmax(np.abs(zd)), np.nanmax(np.abs(s["separatrix_zeta_dot_plus"])), 1e-12)
    right, up, look = camera_basis(d.camera)
    p = Panel(look - 3.9 * right + 0.2 * up, right, up, (lo, lo + np.pi), (-ymax, ymax))
    mid = lo + np.pi / 2
    sep = np.concatenate([p.map(sz, s["separatrix_zeta_dot_plus"]), p.map(sz, s["separatrix_zeta_dot_minus"])])
    d.add(Segments(name="portrait/frame", points=p.frame(), colors=PANEL_COLOR, thickness=0.01),
          Segments(name="portrait/axes", points=np.concatenate([p.hline(0.0), p.vline(mid)]), colors=PANEL_AXES_COLOR,
                   thickness=0.006),
          Points(name="portrait/separatrix", points=sep[np.all(np.isfinite(sep), axis=1)], colors=SEPARATRIX_COLOR,
                 size=0.02),
          Points(name="portrait/trajectory", points=p.map(zw, zd), colors=POINT_COLOR, size=0.02),
          Sphere(name="portrait/state", radius=0.06, color=ZETA_COLOR, position=p.map(zw[d.frames], zd[d.frames])),
          # title above and axes below, from the panel's left edge (a label starts at its point)
          Label(name="portrait/title", text="phase portrait (ζ, dζ/dt); red: separatrix", position=p.map(lo, ymax * 1.12)),
          Label(name="portrait/axes_label", text=f"across: ζ, {np.degrees(lo):.0f}° … {np.degrees(lo + np.pi):.0f}°; "
                f"up: dζ/dt, ±{ymax:.3g}", position=p.map(lo, -ymax * 1.14)))
    return p


def _cost(values):
    """periods × steps_per_period steps (the libration period cancels), F's position and six
    series (ζ, Euler's ζ, ζ̇ and the three separatrix curves) per sample."""
    n = step_count(values["periods"], 1.0 / values["steps_per_period"])
    samples = run_samples(n)
    return Cost(n, samples, trajectory_bytes(samples, bodies=1, series=6))


register(Scenario(
    series_units={"attractor_[xyz]": "a", "zeta_dot": "rad/unit", "separatrix_zeta_dot_(plus|minus)": "rad/unit"},
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
        Param("asymmetry", 0.05, -0.45, 0.45, "", "(B − A)/C; negative: B < A, Euler's case II",
              label="Asymmetry (B − A)/C"),
        Param("orbital_rate", 1.0, 0.0, 100.0, "rad/unit", "angular rate δ of F (GM = δ²s³)", exclusive_min=True,
              label="Orbital rate δ of F"),
        Param("zeta0_deg", 20.0, -180.0, 180.0, "deg", "initial arc AF = ζ₀", label="Starting arc AF = ζ₀",
              applies={"start": ("sliders", "separatrix")}),
        Param("spin_ratio", 1.0, -3.0, 5.0, "", "initial spin about C divided by δ", label="Starting spin about C / δ",
              applies={"start": "sliders"}),
        Param("start", "sliders", kind="choice", choices=("sliders", "locked", "separatrix"),
              help="'separatrix' sets the spin that puts the start on the separatrix",
              label="Start", choice_labels=("from the sliders", "locked on F", "on the separatrix")),
        Param("periods", 4.0, 1.0, 50.0, "", "libration periods to simulate", label="Libration periods"),
        Param("steps_per_period", 400, 50, 20000, "", "integrator steps per period", kind="int",
              label="Integrator steps per period", advanced=True),
    ),
    camera=Camera((0.8, -2.0, 5.2), (0.0, 0.0, 0.0)),  # from above F's orbit plane (body xy)
    simulate_fn=_libration_circular,
    draw=_draw,
    options={**ZETA_OPTION, **ORBIT_OPTION,
             "portrait": Option("phase portrait (ζ, dζ/dt) with the separatrix")},
    cost_fn=_cost,
    euler_formula=("ζ̈ + N sin 2ζ = 0, N = 3GM (B − A) / (2C s³) (§825)\n"
                   "small swings: period T = 2π / √(2N) (§831)"),
    presets=(
        ("Libration: swinging about F", {}),
        ("Libration: locked", {"start": "locked"}),
        ("Libration: the separatrix", {"start": "separatrix"}),
        ("Libration: circulating", {"spin_ratio": 2.0}),
        ("Libration: case II (B < A)", {"asymmetry": -0.05}),
    ),
    # times in the unit of `orbital_rate` (rad per time unit); ½ζ̇² − ½N cos 2ζ in its square
    metric_units={"libration_period": "unit", "libration_period_euler": "unit", "libration_period_exact": "unit",
                  "period_rel_error_vs_exact": "", "modulus_k2": "", "separatrix_gap_1_minus_k2": "",
                  "first_integral_abs_drift": "1/unit^2"},
))


# The checks run at the default δ = 1, where the run's time unit is 1/δ: their tables say "1/δ", the
# unit of Euler's periods, and the numbers hold for any δ read in it.
@register_check("E7", "libration in a circular orbit: small-oscillation period 2π/√(2N)", "§825–831")
def e7():
    # small amplitude: Euler's period is exact up to the pendulum correction (1 + ζ₀²/4 + …)
    z0 = 2.0
    r = get("libration-circular").simulate({"zeta0_deg": z0, "periods": 4, "steps_per_period": 400})
    m = r.metrics
    T, Te, Tx = m["libration_period"], m["libration_period_euler"], m["libration_period_exact"]
    rel = abs(T / Te - 1)
    zr = np.radians(z0)
    tol = float(1.5 * zr**2 / 4)  # the first neglected term of K(k): T = T₀(1 + k²/4 + …), k = sin ζ₀
    return {"euler": Te, "simulated": T, "modern": Tx, "rel_error": rel, "tolerance": tol, "unit": "1/δ",
            "note": (f"ζ₀ = {z0}°; measured vs exact pendulum period 4K(sin ζ₀)/√(2N): "
                     f"{abs(T / Tx - 1):.1e}; Euler's small-oscillation period is low by ζ₀²/4 = {zr**2 / 4:.1e}")}


@register_check("E7.finite-amplitude", "libration period at ζ₀ = 60°: exact pendulum period (elliptic K)", "§826")
def e7_finite():
    sc = get("libration-circular")
    m = sc.simulate({"zeta0_deg": 60.0, "periods": 4, "steps_per_period": 400}).metrics
    # the integrator's error at 400 steps per period, estimated without the exact answer: step
    # doubling for a 4th-order scheme, err(h) ≈ (T(2h) − T(h))/(2⁴ − 1) (order 4 measured: the error
    # falls 16× per halving, 7.4e-8, 4.7e-9, 2.9e-10 at 200, 400, 800 steps)
    m2 = sc.simulate({"zeta0_deg": 60.0, "periods": 4, "steps_per_period": 200}).metrics
    est = abs(m2["libration_period"] - m["libration_period"]) / 15 / m["libration_period_exact"]
    rel = abs(m["libration_period"] / m["libration_period_exact"] - 1)
    return {"euler": m["libration_period_euler"], "simulated": m["libration_period"], "modern": m["libration_period_exact"],
            "rel_error": rel, "tolerance": 3 * est, "unit": "1/δ",
            "note": (f"Euler's small-oscillation period is {abs(m['libration_period_euler'] / m['libration_period_exact'] - 1):.1%} "
                     f"short at 60°; the measured period matches 4K(sin 60°)/√(2N) to {rel:.1e}. Tolerance 3× the "
                     f"integrator's error estimated by step doubling, (T₂₀₀ − T₄₀₀)/15 = {est:.1e} (4th order)")}


@register_check("E7.separatrix", "separatrix: time from 10° to 80° = ln tan(45° + ζ/2)/√(2n)", "§826 (3rd)")
def e7_separatrix():
    m = get("libration-circular").simulate({"start": "separatrix", "zeta0_deg": 10.0}).metrics
    sim, eul = m["separatrix_time_to_80deg"], m["separatrix_time_to_80deg_euler"]
    return {"euler": eul, "simulated": sim, "modern": None, "rel_error": abs(sim / eul - 1), "tolerance": 1e-4,
            "unit": "1/δ", "note": ("Euler's integral is exact on the separatrix; the run departs from it only by "
                                    "the integrator's error, amplified near the unstable point (measured ~4e-6)")}


@register_check("E7.near-separatrix", "1 − k² = 2e-8: the exact period from the gap formed without cancellation; "
                "the run, whose first integral wanders more than that, says so", "§826, modern")
def e7_near_separatrix():
    from decimal import Decimal, localcontext

    g = 0.05
    w0 = float(np.sqrt(3 * g))
    spin = 1 - w0 * (1 - 1e-8)
    r = get("libration-circular").simulate({"asymmetry": g, "zeta0_deg": 0.0, "spin_ratio": spin, "periods": 2.0})
    with localcontext() as ctx:  # 4K(k)/ω₀ in 40 digits from the same floats (AGM), sharing no code
        ctx.prec = 50
        W0 = (Decimal(3) * Decimal(g)).sqrt()
        kp2 = 1 - ((1 - Decimal(spin)) / W0) ** 2  # ζ₀ = 0: k² = (φ̇₀/ω₀)², φ̇₀ = δ(1 − spin), δ = 1
        a, b = Decimal(1), kp2.sqrt()
        for _ in range(200):
            if abs(a - b) < Decimal(10) ** -45:
                break
            a, b = (a + b) / 2, (a * b).sqrt()
        pi = Decimal("3.14159265358979323846264338327950288419716939937510582097494")
        ref = float(4 * (pi / (2 * a)) / W0)
    exact = r.metrics["libration_period_exact"]
    rel = abs(exact / ref - 1)
    warned = [w for w in r.warnings if w.startswith("Near the separatrix")]
    return dict(euler=r.metrics["libration_period_euler"], simulated=r.metrics["libration_period"], modern=exact,
                rel_error=rel, tolerance=1e-9, passed=rel <= 1e-9 and bool(warned), unit="1/δ",
                note=f"reference 4K/ω₀ in 40-digit decimal arithmetic: {ref:.12g}; rel_error: the exact (modern) period "
                     "(the rounding of the inputs moves 1 − k² by ~5e-9 relative, K by ~2.5e-10: tolerance 1e-9) "
                     f"against it (1 − k² = {r.metrics['separatrix_gap_1_minus_k2']:.3g}). " + (warned[0] if warned else "NO WARNING"))
