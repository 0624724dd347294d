"""Euler's three papers on three bodies (seed 003): `collinear` (1767), `syzygy` (1766),
`lunar-perturbation` (1768). Orbit scenarios: the Trajectory carries identity attitudes, zero
spin and `bodies` positions; `plot_series` carries the curves to draw beside Euler's."""
from __future__ import annotations

import math

import numpy as np

from ..params import Param, ParameterError
from ..trajectory import Trajectory
from ..three_body import collinear as col
from ..three_body.nbody import integrate_dop853
from .base import Diverged, Comparison, Result, Scenario, register

GROUP = "three bodies"


def orbit_trajectory(t, bodies: dict, time_unit: str, series: dict | None = None) -> Trajectory:
    """A Trajectory for an orbit scene: identity attitude, zero spin, the bodies' positions."""
    n = len(t)
    q = np.zeros((n, 4))
    q[:, 0] = 1.0
    return Trajectory(np.asarray(t, float), q, np.zeros((n, 3)), np.ones(3), time_unit=time_unit,
                      bodies={k: np.asarray(v, float) for k, v in bodies.items()}, series=dict(series or {}))


# --- collinear (1767) ----------------------------------------------------------------------

def _collinear(values, progress=None):
    A, B, C = values["masses"]
    if sum(1 for m in (A, B, C) if m > 0) < 3:
        raise ParameterError("masses", values["masses"], "each mass > 0 (the restricted case is the L-point part)")
    alpha = col.quintic_root(A, B, C)
    K = col.kepler_constant(A, B, C, alpha)
    x = col.positions_on_line(A, B, C, alpha, 1.0)  # spacing p = 1 (A–B distance)
    pos0 = np.zeros((3, 3))
    pos0[:, 0] = x
    motion = values["motion"]
    nsamp = 600
    if motion == "restricted":
        return _restricted(values, alpha)
    if motion == "rotating":
        Om = col.rotation_rate(A, B, C, alpha, 1.0)
        vel0 = np.zeros((3, 3))
        vel0[:, 1] = Om * x
        T = values["turns"] * 2 * math.pi / Om
        t = np.linspace(0.0, T, nsamp)
        p_euler = np.ones_like(t)
    elif motion == "collapse":  # Case II, §11: from rest, stop at φ = φ_max before the collision
        vel0 = np.zeros((3, 3))
        phi = np.linspace(0.0, math.radians(values["phi_max_deg"]), nsamp)
        t, p_euler = col.homothetic_collapse(K, 1.0, phi)
    else:  # Case I, §10: expansion from a collision; start at p = 1 on the branch with energy E
        E = values["energy"]
        r_a0 = math.sqrt(1.0 * 2 * E / (2 * K) + 1)  # p = (r² − a²)/(2E), a² = 2K
        ra = np.linspace(r_a0, r_a0 * 3.0, nsamp)
        ta, p_euler = col.homothetic_expansion(K, E, ra)
        t = ta - ta[0]
        vel0 = np.zeros((3, 3))
        vel0[:, 0] = x * math.sqrt(2 * (E + K / 1.0)) / 1.0  # v_i = x_i ṗ/p, p = 1
    t_asked = t
    t, P, V = integrate_dop853([A, B, C], pos0, vel0, t)
    # DOP853 gives up when its step underflows (found by tests/test_fuzz.py: masses 125846, 1e-6, 1e-6
    # expanding, 13 of 600 samples): keep the part it did and say so, like a diverged run
    stopped = len(t) < len(t_asked)
    if len(t) < 2:
        raise Diverged("masses", values["masses"], "the N-body integration stopped at the start (its step "
                       "underflowed); less extreme mass ratios")
    p_euler = p_euler[: len(t)]
    d1 = np.linalg.norm(P[:, 1] - P[:, 0], axis=1)
    d2 = np.linalg.norm(P[:, 2] - P[:, 1], axis=1)
    ratio = d2 / d1
    ratio_err = float(np.max(np.abs(ratio / alpha - 1)))
    p_err = float(np.max(np.abs(d1 / p_euler - 1)))
    # the restricted problem: L1, L2, L3 for the given mass ratio
    mr, d = values["mass_ratio"], values["distance_km"]
    L = col.lagrange_distances(mr, d)
    Lm = col.lagrange_distances_cr3bp(mr, d)
    tt = col.translator_table_errors()
    metrics = {
        "alpha": alpha,
        "ratio_max_rel_deviation": ratio_err,
        "spacing_vs_euler_max_rel_error": p_err,
        "L1_km": L[0], "L2_km": L[1], "L3_km": L[2],
        "translator_L1_error_km": tt["L_error_km"][0],
        "translator_L2_error_km": tt["L_error_km"][1],
        "translator_L3_error_km": tt["L_error_km"][2],
    }
    comps = [
        Comparison("α = BC/AB (quintic, §7 Eq. 33)", alpha, float(np.median(ratio)), None, "",
                   f"N-body (DOP853) keeps the ratio to {ratio_err:.1e}"),
        Comparison("AB spacing / Euler's law", 1.0, float(d1[-1] / p_euler[-1]), None, "",
                   {"rotating": "rigid rotation: spacing constant",
                    "collapse": "Case II: spacing ∝ cos²φ, t ∝ φ + sinφ cosφ",
                    "expansion": "Case I: p = n²(r² − a²)"}[motion]),
    ]
    for k, name in enumerate(("L1", "L2", "L3")):
        comps.append(Comparison(f"{name} distance from the primary", L[k], Lm[k], None, "km",
                                "Euler's quintic vs the zero of the restricted problem's effective-potential gradient"))
    for k, name in enumerate(("L1", "L2", "L3")):
        comps.append(Comparison(f"translator's table {name} (5.98e24, 7.34e22 kg, 384400 km)", tt["L_km_table"][k],
                                tt["L_km"][k], None, "km",
                                f"table − quintic root = {tt['L_error_km'][k]:+.1f} km "
                                f"(α table {tt['alpha_table'][k]} vs {tt['alpha'][k]:.6f})"))
    notes = [
        "The translator's Earth–Moon table (end of the 1767 paper) is off: with its own inputs the quintic gives "
        f"L1 = {tt['L_km'][0]:.0f} km (table 326490, {tt['L_error_km'][0]:+.0f} km), "
        f"L2 = {tt['L_km'][1]:.0f} km (table 448755, {tt['L_error_km'][1]:+.0f} km), "
        f"L3 = {tt['L_km'][2]:.0f} km (table 381686, {tt['L_error_km'][2]:+.0f} km).",
        "Eqs. (17), (19), (22), (24), (27) print 'B ∓ C' / 'B − C'; re-derived, the coefficient is B + C.",
    ]
    if motion == "rotating":
        notes.append("The rigidly turning line is a true solution but an unstable one (for every choice of masses): "
                     f"round-off grows to a {ratio_err:.1e} change of the ratio in {values['turns']:g} turns; "
                     "give it more turns to watch the line break.")
    # L-point markers in the rotating frame of the primaries (units of the primaries' distance,
    # primary at the origin), for the restricted-case scene
    Lx = np.array([L[0], L[1], -L[2]]) / d
    bodies = {"A": P[:, 0], "B": P[:, 1], "C": P[:, 2]}
    traj = orbit_trajectory(t, bodies, "G=1 units", series={"ratio_BC_over_AB": ratio, "spacing_AB": d1})
    for k, name in enumerate(("L1", "L2", "L3")):
        traj.series[f"{name}_x_over_distance"] = np.full(len(t), Lx[k])
    if motion == "rotating":  # angle of the frame turning with the line (for the co-rotating view)
        traj.series["frame_angle_rad"] = Om * t
    result = Result("collinear", values, traj, metrics, comps, notes,
                    plot_series={"BC/AB (simulated)": ratio, "α (Euler)": np.full(len(t), alpha),
                                 "AB spacing (simulated)": d1, "AB spacing (Euler)": p_euler})
    if stopped:
        msg = (f"diverged at t={t[-1]:.6g}: the N-body integration stopped (DOP853's step underflowed: masses "
               f"{A:g}, {B:g}, {C:g} are too unequal for rtol 1e-12); showing the part up to there "
               f"({len(t)} of {len(t_asked)} samples)")
        result.status = "diverged"
        result.warnings.append(msg)
        result.notes.append(msg)
    return result


def _restricted(values, alpha):
    """Primary, secondary (mass_ratio) and a massless satellite released at rest in the turning
    frame at one Lagrange point; markers L1–L5 turn with the primaries (inertial frame, unit
    distance). L1–L3 are unstable: the satellite drifts off after a few turns; L4/L5 hold for
    μ < 0.0385 (Gascheau)."""
    mr = values["mass_ratio"]
    mu = mr / (1 + mr)
    pts = col.lagrange_points_rotating(mr)
    x0, y0 = pts[values["lagrange_point"]]
    pos = np.array([[-mu, 0, 0], [1 - mu, 0, 0], [x0, y0, 0.0]])
    vel = np.zeros((3, 3))
    vel[:, 0], vel[:, 1] = -pos[:, 1], pos[:, 0]  # rate 1 about z
    t = np.linspace(0.0, values["turns"] * 2 * math.pi, 1200)
    t, P, V = integrate_dop853([1 - mu, mu, 0.0], pos, vel, t)
    c, s = np.cos(t), np.sin(t)
    bodies = {"primary": P[:, 0], "secondary": P[:, 1], "satellite": P[:, 2]}
    for k, (x, y) in pts.items():
        bodies[k] = np.stack([c * x - s * y, s * x + c * y, np.zeros_like(t)], axis=1)
    # satellite in the turning frame and its drift from the point
    xs = c * P[:, 2, 0] + s * P[:, 2, 1]
    ys = -s * P[:, 2, 0] + c * P[:, 2, 1]
    drift = np.hypot(xs - x0, ys - y0)
    L = col.lagrange_distances(mr, values["distance_km"])
    Lm = col.lagrange_distances_cr3bp(mr, values["distance_km"])
    tt = col.translator_table_errors()
    CJ = {k: float(col.jacobi_function(x, y, mr)) for k, (x, y) in pts.items()}
    metrics = {"alpha": alpha, "L1_km": L[0], "L2_km": L[1], "L3_km": L[2],
               "satellite_drift_max": float(drift.max()),
               "translator_L1_error_km": tt["L_error_km"][0], "translator_L2_error_km": tt["L_error_km"][1],
               "translator_L3_error_km": tt["L_error_km"][2]}
    metrics.update({f"jacobi_constant_{k}": v for k, v in CJ.items()})
    comps = [Comparison(f"{n} distance from the primary", L[k], Lm[k], None, "km",
                        "Euler's quintic vs the zero of the effective-potential gradient") for k, n in enumerate(("L1", "L2", "L3"))]
    comps += [Comparison(f"translator's table {n}", tt["L_km_table"][k], tt["L_km"][k], None, "km",
                         f"table − quintic root = {tt['L_error_km'][k]:+.1f} km") for k, n in enumerate(("L1", "L2", "L3"))]
    notes = [f"satellite released at {values['lagrange_point']}: largest drift {drift.max():.2e} distances in "
             f"{values['turns']:g} turns (L1–L3 are unstable; L4/L5 stable for μ < 0.0385)",
             "zero-velocity curves (drawn in the scene): levels of 2Ω = x² + y² + 2(1−μ)/r1 + 2μ/r2 through "
             "L1, L2, L3 (jacobi_constant_* metrics); a satellite with Jacobi constant C_J = 2Ω − v² (v: speed in "
             "the turning frame) stays where 2Ω ≥ C_J and cannot cross the curve 2Ω = C_J",
             "The translator's Earth–Moon table (end of the 1767 paper) is off: with its own inputs the quintic "
             f"gives L1 = {tt['L_km'][0]:.0f} km (table {tt['L_km_table'][0]:.0f}, {tt['L_error_km'][0]:+.0f} km), "
             f"L2 = {tt['L_km'][1]:.0f} km (table {tt['L_km_table'][1]:.0f}, {tt['L_error_km'][1]:+.0f} km), "
             f"L3 = {tt['L_km'][2]:.0f} km (table {tt['L_km_table'][2]:.0f}, {tt['L_error_km'][2]:+.0f} km)."]
    traj = orbit_trajectory(t, bodies, "orbits/2π", series={"satellite_corotating_x": xs,
                                                            "satellite_corotating_y": ys,
                                                            "frame_angle_rad": t})
    # zero-velocity curves: 2Ω on a grid of the turning plane, levels through L1–L5 (= C_J there)
    X, Y, Z = col.zero_velocity_grid(mr, n=241, extent=1.6)
    extras = {"zero_velocity": {"x": X[0], "y": Y[:, 0], "two_omega": Z, "levels": CJ},
              "lagrange_points": {k: (float(x), float(y)) for k, (x, y) in pts.items()}}
    return Result("collinear", values, traj, metrics, comps, notes,
                  plot_series={"satellite drift from the point (distances)": drift}, extras=extras)


register(Scenario(
    name="collinear",
    title="Three bodies on a line: Euler's quintic",
    section="Euler 1767, §1–§11",
    group=GROUP,
    summary=("Three masses can stay on one straight line if the ratio of their spacings is the single "
            "positive root α of Euler's quintic. Watch them turn rigidly as a line, collapse from rest "
            "(all distances shrinking ∝ cos²φ) or fly apart, the ratio held by a direct integration of "
            "the three bodies. With a massless third body the roots give the Lagrange points L1, L2, "
            "L3."),
    params=(
        Param("masses", (3.0, 1.0, 2.0), 1e-6, 1e6, "G=1 mass", "masses A, B, C in their order on the line",
              kind="vec3"),
        Param("motion", "rotating", unit="",
              help="rigid rotation, Case II collapse from rest, Case I expansion, or the restricted problem "
                   "(a massless satellite at a Lagrange point of primary + secondary)",
              kind="choice", choices=("rotating", "collapse", "expansion", "restricted")),
        Param("lagrange_point", "L1", kind="choice", choices=("L1", "L2", "L3", "L4", "L5"),
              help="restricted: where the satellite is released"),
        Param("turns", 2.0, 0.1, 20.0, "turns", "rotating: number of turns shown"),
        Param("phi_max_deg", 80.0, 1.0, 89.0, "deg", "collapse: stop at this φ (φ = 90° is the collision)"),
        Param("energy", 0.5, 1e-3, 100.0, "G=1 units", "expansion: energy per unit reduced mass (> 0)",
              exclusive_min=True),
        Param("mass_ratio", col.MOON_EARTH_MASS_RATIO, 1e-9, 1.0, "1",
              "restricted case: secondary/primary mass (Moon/Earth, IAU 2009: 0.0123000371)"),
        Param("distance_km", col.EARTH_MOON_DISTANCE_KM, 1.0, 1e10, "km", "restricted case: primary–secondary distance"),
    ),
    simulate_fn=_collinear,
    euler_formula=("(A+B)α⁵ + (3A+2B)α⁴ + (3A+B)α³ − (B+3C)α² − (2B+3C)α − (B+C) = 0 (§7, Eq. 33)\n"
                   "p̈ = −(D/2) p⁻², D/2 = A + B + C/(α+1)² − C/α²\n"
                   "Case II: p ∝ cos²φ, t = n³a² (φ + sin φ cos φ)"),
    kind="orbit",
    presets=(
        ("Collinear: turning as a rigid line", {}),
        ("Collinear: collapse from rest", {"motion": "collapse"}),
        ("Collinear: flying apart", {"motion": "expansion"}),
        ("Earth–Moon L1", {"motion": "restricted", "lagrange_point": "L1"}),
        ("Earth–Moon L2", {"motion": "restricted", "lagrange_point": "L2"}),
    ),
))


# --- syzygy (1766) -------------------------------------------------------------------------

def _syzygy(values, progress=None):
    from ..three_body import syzygy as sz

    m, n = values["mass_ratio"], values["moon_revolutions_per_year"]
    side, A = values["side"], math.radians(values["amplitude_deg"])
    if side == "conjunction":
        alpha = sz.equilibrium_conjunction(m)
        series_e, series_c = sz.euler_series_conjunction(m), sz.series_conjunction(m)
    else:
        alpha = sz.equilibrium_opposition(m)
        series_e, series_c = sz.euler_series_opposition(m), sz.series_opposition(m)
    scale = sz.lunar_units_per_sun_distance(m, n)  # a/c: lunar distances per Sun distance
    modes = sz.linear_modes(m, side)
    # the displayed run: Euler's start (or the exact linear mode) + optional seed of the escape
    s0 = sz.initial_state(m, A, side, values["start"], values["escape_seed"])
    t, S, _ = sz.integrate(m, s0, 2 * math.pi * values["duration_yr"], n_samples=4000)
    eta, v = sz.eta_and_distance(S, side)
    left = t[-1] < 2 * math.pi * values["duration_yr"] * (1 - 1e-9)
    # a clean measurement: the exact linear mode at a tiny amplitude plus a tinier seed of the
    # escape; fit η = a cos ωt + b sin ωt + c e^{λt} + d e^{−λt} in the linear regime
    A_meas = 1e-6
    tm, Sm, _ = sz.integrate(m, sz.initial_state(m, A_meas, side, "linear-mode", 1e-9), 2 * math.pi * 2.0,
                             n_samples=8000)
    etam, _ = sz.eta_and_distance(Sm, side)
    w_meas, lam_meas, fit_res = sz.fit_swing_and_escape(tm, etam, A_meas)
    w_run, n_half_run = sz.measured_frequency(t, eta, 1.5 * A)
    # amplitude relation of §16 on the displayed run's first swing
    first = t <= (2 * math.pi / sz.HILL_FREQUENCY)
    ratio = float((v[first].max() - v[first].min()) / (2 * alpha * max(np.abs(eta[first]).max(), 1e-300)))
    Vo = modes["osc_vector"]
    ratio_linear = float(abs(Vo[0]) / abs(Vo[1]))
    b_lunar = alpha * scale
    eta_e, v_e = sz.euler_oscillation(alpha, A, t, side)
    metrics = {
        "syzygy_distance_lunar_units": b_lunar,
        "syzygy_distance_lunar_units_euler": (EULER_N2 / 3.0) ** (1.0 / 3.0),
        "alpha_sun_distance": alpha,
        "oscillation_frequency": w_meas,
        "oscillation_frequency_euler": sz.HILL_FREQUENCY,
        "oscillation_frequency_linear": modes["frequency"],
        "oscillation_frequency_run": w_run,
        "escape_exponent": lam_meas,
        "escape_exponent_linear": modes["escape_exponent"],
        "escape_exponent_hill": sz.HILL_ESCAPE_EXPONENT,
        "amplitude_ratio": ratio,
        "amplitude_ratio_euler": sz.AMPLITUDE_COEFFICIENT,
        "amplitude_ratio_linear": ratio_linear,
        "fit_rms_residual_rel": fit_res,
        "escape_time_yr": float(t[-1] / (2 * math.pi)) if left else float("nan"),
        "swings_before_escape": float(n_half_run) / 2.0,
    }
    comps = [
        Comparison("syzygy distance (lunar distances)", (EULER_N2 / 3.0) ** (1.0 / 3.0), b_lunar, None, "c",
                   "Euler: v ≈ c·(n²/3)^{1/3} with n² = 175, 'about four'; simulated: root of §7/§9 with today's n, m"),
        Comparison("α = v/a: Euler's 4-term series vs root", series_e, alpha, series_c, "",
                   "modern column: the series with the 4th coefficient corrected (4/243, not 1/81)"),
        Comparison("oscillation frequency (Sun's mean motion = 1)", sz.HILL_FREQUENCY, w_meas, modes["frequency"], "",
                   "Euler/Hill √(√28 − 1); simulated: fit of η on the full equations; modern: linearised full problem"),
        Comparison("v = b(1 − k·A cos ω): k", sz.AMPLITUDE_COEFFICIENT, ratio, ratio_linear, "",
                   "half the swing of v/b over the η amplitude on the first swing; modern: centre eigenvector"),
        Comparison("escape exponent (real root Euler missed)", None, lam_meas, modes["escape_exponent"], "",
                   f"Hill limit √(√28 + 1) = {sz.HILL_ESCAPE_EXPONENT:.4f}; e-folding every "
                   f"{1 / lam_meas / (2 * math.pi) * 365.25:.1f} days"),
    ]
    notes = [
        "Euler linearised about syzygy and assumed an oscillation; the same characteristic equation "
        "λ⁴ − 2λ² − 27 = 0 has the real root λ² = 1 + √28: the Moon leaves after a few swings.",
        "§7's substitution '2 − α = x' should read x = 1 − α; §9 prints (1−α)³ for (1+α)³; the 4th term of "
        "the series (§8, §9) should be 4mε/243, not mε/81.",
        "Sun drawn at 3 syzygy distances along its true direction (true distance "
        f"{scale:.0f} lunar distances).",
    ]
    if values["start"] == "euler":
        notes.append("Euler's start (his first-order solution at ω = 0, Hill's approximation) differs from the true "
                     "centre mode by terms of order v/u ≈ 1%: that small share of the unstable mode is enough for "
                     "the Moon to leave within about one swing.")
    # bodies: Earth-centred inertial frame, lunar distances (the Sun turns at rate 1)
    sgn = 1.0 if side == "conjunction" else -1.0
    c, s = np.cos(t), np.sin(t)
    xr, yr = S[:, 0] * scale, S[:, 1] * scale
    moon = np.stack([c * xr - s * yr, s * xr + c * yr, np.zeros_like(t)], axis=1)
    sun = 3.0 * b_lunar * np.stack([c, s, np.zeros_like(t)], axis=1)
    traj = orbit_trajectory(t / (2 * math.pi), {"sun": sun, "earth": np.zeros_like(moon), "moon": moon}, "yr",
                            series={"moon_corotating_x": xr, "moon_corotating_y": yr,
                                    "eta_deg": np.degrees(eta), "distance_over_b": v / alpha,
                                    "frame_angle_rad": t})  # the Sun's direction turns at rate 1
    return Result("syzygy", values, traj, metrics, comps, notes, plot_series={
        "η simulated (deg)": np.degrees(eta), "η Euler A sin αζ (deg)": np.degrees(eta_e),
        "v/b simulated": v / alpha, "v/b Euler 1 − 0.3117 A cos αζ": v_e / alpha},
        extras={"syzygy_point_lunar": (sgn * b_lunar, 0.0, 0.0)})


EULER_N2 = 175.0


def _syzygy_params():
    from ..three_body import syzygy as sz

    return (
        Param("side", "conjunction", kind="choice", choices=("conjunction", "opposition"),
              help="Moon between Earth and Sun (§7) or beyond the Earth (§9)"),
        Param("amplitude_deg", 0.05, 0.0, 20.0, "deg", "A: amplitude of η, the Moon's angle from the Sun line"),
        Param("start", "linear-mode", kind="choice", choices=("euler", "linear-mode"),
              help="Euler's first-order solution at ω = 0, or the exact linear centre mode"),
        Param("escape_seed", 0.0, 0.0, 0.1, "b", "extra displacement along the unstable direction"),
        Param("duration_yr", 3.0, 0.1, 20.0, "yr", "run length (the run stops when the Moon has left)"),
        Param("mass_ratio", sz.EARTH_SUN_MASS_RATIO, 1e-9, 1e-2, "1",
              "m = n²c³/a³ = M_earth/M_sun (IAU 2009: 3.0035e-6)"),
        Param("moon_revolutions_per_year", sz.MOON_REVOLUTIONS_PER_YEAR, 1.0, 100.0, "1/yr",
              "n: sidereal months per sidereal year (13.369; Euler: √175 = 13.23); sets the lunar unit"),
    )


register(Scenario(
    name="syzygy",
    title="The Moon kept in syzygy with the Sun",
    section="Euler 1766, §5–§16",
    group=GROUP,
    summary=("Four times farther out than it is, the Moon could stay lined up with the Sun and the "
            "Earth (today's Sun–Earth Lagrange points L1 and L2). Euler found its small swing about "
            "that line, at √(√28 − 1) ≈ 2.07 times the Sun's motion: Hill's result, a century early. "
            "The same equation shows that the line-up is unstable: nudge the Moon along the unstable "
            "direction and watch it leave after a few swings."),
    params=_syzygy_params(),
    simulate_fn=_syzygy,
    euler_formula=("m(1 − α)² = α² − α²(1 − α)³ (§7)\n"
                   "η = A sin ω, v = b(1 − 0.3117 A cos ω), ω = αζ, α⁴ + 2α² = 27 (§16)"),
    kind="orbit",
    presets=(
        ("Syzygy: the small swing (Hill)", {}),
        ("Syzygy: Euler's own start", {"start": "euler"}),
        ("Syzygy: beyond the Earth (opposition)", {"side": "opposition"}),
        ("Syzygy: the Moon leaves", {"escape_seed": 0.01, "duration_yr": 6.0}),
    ),
))


# --- lunar-perturbation (1768) ---------------------------------------------------------------

def _lunar(values, progress=None):
    from ..three_body import lunar_elements as le

    el0, sun, mu, mus = le.initial_conditions(values["eccentricity"], values["inclination_deg"],
                                              sun_eccentricity=values["sun_eccentricity"])
    el0 = le.calibrate_mean_elements(el0, sun, mu, mus, le.MOON_J2000["sidereal_month_days"],
                                     values["eccentricity"], math.radians(values["inclination_deg"]))
    if progress:
        progress(0.1)
    days = values["duration_yr"] * le.YEAR_DAYS
    h, ds = values["step_days"], values["sample_days"]
    series = values["solar_force"] == "euler-series"
    t, E = le.integrate_rk4("elements", el0, days, h, ds, mu, mus, sun, euler_series=series)
    if progress:
        progress(0.5)
    r0, v0 = le.elements_to_cartesian(el0, mu)
    _, C = le.integrate_rk4("cartesian", np.concatenate([r0[0], v0[0]]), days, h, ds, mu, mus, sun)
    if progress:
        progress(0.9)
    P = le.elements_to_position(E)
    err = float(np.max(np.linalg.norm(P - C[:, :3], axis=1)))
    na = le.node_and_apse(t, E)
    inc = np.degrees(E[:, 4])
    fo = le.first_order_rates(sun, le.MOON_J2000["sidereal_month_days"], math.radians(values["inclination_deg"]))
    node_fo = 2 * math.pi / abs(fo["node_rate"]) / le.YEAR_DAYS
    apse_fo = 2 * math.pi / abs(fo["apse_rate"]) / le.YEAR_DAYS
    # Euler's identities (§VII–IX) on a dense 60-day piece of the Cartesian solution
    td, Cd = le.integrate_rk4("cartesian", np.concatenate([r0[0], v0[0]]), 60.0, h, h, mu, mus, sun)
    Ed = le.cartesian_to_elements(Cd[:, :3], Cd[:, 3:], mu)
    id1, id2 = le.euler_identity_residuals(td, Ed, Cd[:, :3], Cd[:, 3:])
    # the dΥ equation with the sign as printed (§XXVII.4), same 60 days
    _, Ep = le.integrate_rk4("elements", el0, 60.0, h, h, mu, mus, sun, printed_sign=True)
    err_printed = float(np.max(np.linalg.norm(le.elements_to_position(Ep) - Cd[: len(Ep), :3], axis=1)))
    metrics = {
        "node_period_yr": na["node_period_yr"],
        "apse_period_yr": na["apse_period_yr"],
        "inclination_min_deg": float(inc.min()),
        "inclination_max_deg": float(inc.max()),
        "eccentricity_min": float(E[:, 1].min()),
        "eccentricity_max": float(E[:, 1].max()),
        "elements_vs_cartesian_max_error": err,
        "elements_vs_cartesian_max_error_km": err * le.KM_PER_UNIT,
        "node_period_first_order_yr": node_fo,
        "apse_period_first_order_yr": apse_fo,
        "apse_first_order_fraction": fo["apse_rate"] / na["apse_rate"],
        "printed_sign_error_60d": err_printed,
        "identity_inclination_node_residual": id1,
        "identity_latitude_argument_residual": id2,
        "sidereal_month_days": 2 * math.pi / le.mean_motion(t, E),
    }
    comps = [
        Comparison("regression of the node", node_fo, na["node_period_yr"], le.NODE_PERIOD_SIDEREAL_YR, "yr",
                   "Euler column: first-order rate (3/4)n'²/n·cos i; modern: 6793.48 d against the stars, the frame of "
                   "this model (the often quoted 6798.38 d counts from the moving equinox)"),
        Comparison("advance of the apsides", apse_fo, na["apse_period_yr"], le.APSE_PERIOD_YR, "yr",
                   f"first order gives {fo['apse_rate'] / na['apse_rate']:.2f} of the motion — the historical "
                   "'half the apse motion' (Clairaut 1747); modern: 3232.6 d against the stars"),
        Comparison("inclination min", None, float(inc.min()), le.INCLINATION_RANGE_DEG[0], "deg", "osculating, period ≈ 173 d"),
        Comparison("inclination max", None, float(inc.max()), le.INCLINATION_RANGE_DEG[1], "deg", ""),
        Comparison("Euler's elements vs Cartesian integration, max distance", 0.0, err, None, "lunar distance",
                   "same forces, same RK4 step: the element equations (sign of §XXVII.4 corrected) reproduce the orbit"),
        Comparison("§XXVII.4 with the printed sign: max distance after 60 d", None, err_printed, None,
                   "lunar distance", "the sign error makes the orbit wrong within weeks"),
        Comparison("dω sin σ − dψ sin ω cos σ (§VII)", 0.0, id1, None, "rel.",
                   "along the Cartesian solution, osculating elements, 4th-order differences"),
        Comparison("dσ − (d∅ − dψ cos ω) (§IX)", 0.0, id2, None, "rel.", ""),
    ]
    notes = [
        "§XXVII item 4 (dΥ) prints '−' before the term n v²u(1/w³ − 1/u³)/q[…]: it must be '+'. With the printed "
        "sign the anomaly equation contradicts Euler's own relation q(d∅ − dΥ) sin Υ = dp/v − dq cos Υ.",
        "§XXVIII item 2 prints dω/sin σ; it is dω/sin ω.",
        "Initial elements: J2000 mean elements (Simon et al. 1994); the osculating a, e, i are adjusted so the "
        "mean sidereal month, mean e and mean i match (27.3217 d, 0.0549, 5.145°).",
        "Sun drawn at 3 lunar distances along its true direction (true distance ≈ 389 lunar distances).",
    ]
    if series:
        notes.append("Element equations with Euler's §XXXIII expansion of 1/w³; the Cartesian reference keeps the "
                     "exact force, so elements_vs_cartesian_max_error measures the neglected (v/u)³ terms.")
    # bodies (lunar distances), at most ~20000 samples for drawing
    stride = max(1, int(math.ceil(len(t) / 20000)))
    sl = slice(None, None, stride)
    tt = t[sl]
    sunpos = np.array([le.sun_state(float(x), np.asarray(sun, float))[:2] for x in tt])
    sund = 3.0 * sunpos / np.linalg.norm(sunpos, axis=1)[:, None]
    sund = np.concatenate([sund, np.zeros((len(tt), 1))], axis=1)
    Es = E[sl]
    psi, om = Es[:, 3], Es[:, 4]
    normal = np.stack([np.sin(om) * np.sin(psi), -np.sin(om) * np.cos(psi), np.cos(om)], axis=1)
    node_deg = np.degrees(np.unwrap(psi))
    varpi_deg = np.degrees(np.unwrap(na["varpi"][sl]))
    years = tt / le.YEAR_DAYS
    series = {"node_longitude_deg": np.degrees(np.mod(psi, 2 * np.pi)), "inclination_deg": np.degrees(om),
              "perigee_longitude_deg": np.degrees(np.mod(na["varpi"][sl], 2 * np.pi)), "eccentricity": Es[:, 1],
              "orbit_normal_x": normal[:, 0], "orbit_normal_y": normal[:, 1], "orbit_normal_z": normal[:, 2],
              "frame_angle_rad": np.unwrap(np.arctan2(sunpos[:, 1], sunpos[:, 0]))}  # the Sun's longitude
    traj = orbit_trajectory(years, {"sun": sund, "earth": np.zeros((len(tt), 3)), "moon": P[sl]}, "yr", series)
    plot = {
        "node longitude (deg, simulated)": node_deg,
        "node longitude (deg, first order)": node_deg[0] + np.degrees(fo["node_rate"]) * tt,
        "inclination (deg)": np.degrees(om),
        "perigee longitude (deg, simulated)": varpi_deg,
        "perigee longitude (deg, first order: half)": varpi_deg[0] + np.degrees(fo["apse_rate"]) * tt,
    }
    return Result("lunar-perturbation", values, traj, metrics, comps, notes, plot_series=plot)


register(Scenario(
    name="lunar-perturbation",
    title="The Moon perturbed by the Sun, by its elements",
    section="Euler 1768, §XIII–§XXXIV",
    group=GROUP,
    summary=("Euler wrote the Moon's motion as eight equations for its orbital elements (the size, "
            "shape, tilt and orientation of its orbit) and could not integrate them. Here they are "
            "integrated for decades. Look at the plot: the orbit plane turns backwards once in 18.6 "
            "years while its tilt nods between 5.0° and 5.3°, and the perigee advances once in 8.85 "
            "years, twice as fast as first-order theory gives."),
    params=(
        Param("duration_yr", 40.0, 1.0, 200.0, "yr", "length of the run"),
        Param("step_days", 0.025, 0.005, 0.2, "d", "fixed RK4 step (the error scales as step⁴)"),
        Param("sample_days", 0.5, 0.05, 10.0, "d", "spacing of the stored states"),
        Param("eccentricity", 0.0549, 0.005, 0.3, "1", "Moon's mean eccentricity"),
        Param("inclination_deg", 5.145396, 0.1, 60.0, "deg", "Moon's mean inclination to the ecliptic"),
        Param("sun_eccentricity", 0.0167086, 0.0, 0.3, "1", "eccentricity of the Sun's apparent orbit"),
        Param("solar_force", "exact", kind="choice", choices=("exact", "euler-series"),
              help="exact 1/w³, or Euler's §XXXIII expansion to second order in v/u in the element equations"),
    ),
    simulate_fn=_lunar,
    euler_formula=("dψ = −n v³ u d∅ sin σ sin(θ − ψ)/p · (1/w³ − 1/u³) (§XXVIII)\n"
                   "dω / sin ω = dψ / tan σ, dσ = d∅ − dψ cos ω"),
    kind="orbit",
    check=lambda v: (_ for _ in ()).throw(ParameterError("sample_days", v["sample_days"],
                                                         f"at least step_days = {v['step_days']:g} d"))
    if v["sample_days"] < v["step_days"] else None,
    presets=(
        ("Moon's orbit: node and perigee over 40 years", {}),
        ("Moon's orbit: one node cycle", {"duration_yr": 19.0}),
        ("Moon's orbit: Euler's series for the Sun's force", {"solar_force": "euler-series"}),
    ),
))
