"""Three bodies on a line (Euler 1767, §1–§11): the quintic of the collinear configurations,
homothetic collapse and expansion, and the collinear points of the restricted problem.

Check rows E11: the quintic's root held by an N-body collapse, the Earth–Moon L1–L3 against
published values, and the translator's table.
"""
from __future__ import annotations

import math
import numpy as np
from ..physics.constants import EARTH_MOON_DISTANCE_KM, MOON_EARTH_MASS_RATIO
from ..physics.params import Param, ParameterError
from ..physics.three_body import collinear as col
from ..physics.three_body.nbody import integrate_dop853
from .drawing import Camera, Drawing, Label, ORBIT_RADIUS, Segments, View, clock_of, new_drawing
from . import _three_body_drawing as tbd
from .base import Diverged, Comparison, Run, Scenario, get, register
from .budget import Cost, trajectory_bytes
from .checks import register_check
from ._three_body import GROUP, orbit_trajectory

# a three-body run has left its configuration when the spacing ratio of the turning line is this
# far (relative) from α, or the satellite this far (in primary–secondary distances) from its point
LINE_BROKEN = 0.01
SATELLITE_LEFT = 0.1


# DOP853 (rtol 1e-12) steps, measured on the defaults and presets: 48-98 for the three-body motions
# (2 turns, a collapse, an expansion), 96-177 for the restricted case over 2 turns
DOP853_STEPS_PER_TURN = 100
# The turning line is unstable (Euler's collinear solutions are): after a turn or two the bodies
# leave it and meet closely, and every further turn took 250-560 steps (four mass sets, 1-20 turns:
# 9,437 steps and 2 s for 20 turns of the defaults, 122 steps for their 2). Costed at the first
# turns' rate alone, 15 turns were expected to take a quarter of a second and took 1.3: the server
# ran them without a preview, as quick, and they waited behind the class for over 30 s.
DOP853_STEPS_PER_TURN_OFF_LINE = 500
TURNS_ON_LINE = 2
DOP853_STEPS_HOMOTHETIC = 200
N_SAMPLES = 600  # samples of the three-body motions
N_SAMPLES_RESTRICTED = 1200
ZERO_VELOCITY_GRID = 241  # points per side of the restricted case's grid of 2Ω


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
    nsamp = N_SAMPLES
    if motion == "restricted":
        return _restricted(values, alpha, progress)
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
    t, P, V = integrate_dop853([A, B, C], pos0, vel0, t, progress=progress)
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
                   f"the three bodies integrated directly (an 8th-order Runge–Kutta integrator, DOP853) keep the ratio to {ratio_err:.1e}"),
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
    warnings = []
    if motion == "rotating" and ratio_err > LINE_BROKEN:
        k = int(np.argmax(np.abs(ratio / alpha - 1) > LINE_BROKEN))
        warnings.append(
            f"The line broke: after {Om * t[k] / (2 * math.pi):.3g} turns the spacing ratio is {LINE_BROKEN:.0%} off "
            f"Euler's α (largest {ratio_err:.2g}): the rigidly turning line is unstable for every choice of masses, "
            "so α and the constant spacing describe only the part before.")
    result = Run("collinear", values, traj, metrics, comps, notes, warnings=warnings,
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


def _restricted(values, alpha, progress=None):
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
    t = np.linspace(0.0, values["turns"] * 2 * math.pi, N_SAMPLES_RESTRICTED)
    t, P, V = integrate_dop853([1 - mu, mu, 0.0], pos, vel, t, progress=progress)
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
    X, Y, Z = col.zero_velocity_grid(mr, n=ZERO_VELOCITY_GRID, extent=1.6)
    extras = {"zero_velocity": {"x": X[0], "y": Y[:, 0], "two_omega": Z, "levels": CJ},
              "lagrange_points": {k: (float(x), float(y)) for k, (x, y) in pts.items()}}
    warnings = []
    if drift.max() > SATELLITE_LEFT:
        k = int(np.argmax(drift > SATELLITE_LEFT))
        warnings.append(
            f"The satellite left {values['lagrange_point']}: {SATELLITE_LEFT:g} distances away after "
            f"{t[k] / (2 * math.pi):.3g} turns (largest {drift.max():.2g}); "
            + ("L1–L3 are unstable for every mass ratio" if values["lagrange_point"] in ("L1", "L2", "L3")
               else f"L4 and L5 hold only for μ < 0.0385 (Gascheau; here μ = {mu:.3g})")
            + ", so the point describes only the start of the run.")
    return Run("collinear", values, traj, metrics, comps, notes, warnings=warnings,
                  plot_series={"satellite drift from the point (distances)": drift}, extras=extras)


# ---- the scene ---------------------------------------------------------------------------------

L_POINTS = ("L1", "L2", "L3", "L4", "L5")
LEVEL_COLORS = {"L1": (230, 70, 70), "L2": (240, 160, 40), "L3": (70, 140, 240)}  # zero-velocity curves
OPTIONS = tbd.corotating_option(False, "co-rotating frame (turning with the bodies)")


def _lagrange_points(run) -> dict:
    """L1–L5 in the turning frame of the primaries (units of their distance): the physics' points,
    or where the run's L-point bodies start (the turning frame and the inertial one agree at t = 0)."""
    pts = run.extras.get("lagrange_points")
    if pts is None:
        b = run.trajectory.bodies
        pts = {k: tuple(np.asarray(b[k], float)[0, :2]) for k in L_POINTS if k in b}
    return {k: (float(x), float(y)) for k, (x, y) in (pts or {}).items()}


EARTH_MOON_NAMES = {"primary": "earth", "secondary": "moon"}


def _draw(run: Run, spec: Scenario, view: View) -> Drawing:
    """The line through the three bodies with a BC/AB read-out (rotating, collapse, expansion) or,
    for the restricted problem, L1–L5 (labelled) and the zero-velocity curves through L1, L2, L3
    (levels of 2Ω = C_J). The construction turns with the primaries in the inertial view and
    stands still in the co-rotating one, where the bodies are drawn in co-rotating coordinates."""
    d = new_drawing(run, spec)
    tr, f = run.trajectory, d.frames
    corot = tbd.corotating(run, spec, view)
    restricted = "lagrange_points" in run.extras
    pts = _lagrange_points(run)
    bodies = tbd.body_positions(run, skip=L_POINTS, turn=corot)  # L-points: markers, not bodies with trails
    if restricted and run.params.get("mass_ratio") == MOON_EARTH_MASS_RATIO:
        # the Earth and the Moon themselves: drawn and named as in every other scene (the Earth
        # was a yellow "primary", the Sun's colour)
        bodies = {EARTH_MOON_NAMES.get(n, n): v for n, v in bodies.items()}
    span = tbd.largest_distance(bodies)
    if pts:
        span = max(span, 1.1 * max(np.hypot(x, y) for x, y in pts.values()))
    # restricted: the satellite starts on its L-point's marker and the secondary sits between L1
    # and L2, so the bodies are named by colour in a key rather than by labels on the L-points' own
    k = tbd.draw_bodies(d, run, bodies, span, unnamed=tuple(bodies) if restricted else ())
    tbd.turning_frame(d, run, corot)
    R = ORBIT_RADIUS
    t = np.asarray(tr.t, float)[f]
    if restricted:
        for name, (x, y) in pts.items():
            tbd.marker(d, f"{tbd.TURNING}/L/{name}", (k * x, k * y, 0.0))
            # below the marker
            d.add(Label(name=f"{tbd.TURNING}/L/{name}/label", text=name, position=(0.0, -0.13, 0.0)))
        zv = run.extras.get("zero_velocity")
        if zv is not None:
            for name, col in LEVEL_COLORS.items():
                if name in zv["levels"]:
                    segs = k * tbd.contour_segments(zv["x"], zv["y"], zv["two_omega"], zv["levels"][name])
                    if len(segs):
                        d.add(Segments(name=f"{tbd.TURNING}/zero_velocity/{name}", points=segs, colors=col,
                                       thickness=0.008))
            d.add(Label(name="zero_velocity_key", text="zero-velocity curves (2Ω = the Jacobi constant): L1 red, L2 orange, L3 blue",
                        position=(-R, -R, 0.0)))
        tbd.body_key(d, list(bodies), (-R, 1.2 * R, 0.0))  # under the read-out
        tbd.line(d, f"{tbd.TURNING}/axis", (-1.25 * k, 0, 0), (1.25 * k, 0, 0), thickness=0.004)
        drift = run.plot_series.get("satellite drift from the point (distances)")
        where = run.params.get("lagrange_point", "its point")
        from ..app.format import human_number  # "2.24 × 10⁻⁷", as the panel writes numbers

        orbits = clock_of(run).scale  # t in the turning frame's radians, read out in its turns
        turns = [f"{x:.3g}" for x in np.asarray(t, float)[: len(f)] * orbits]
        texts = [f"t = {n} orbit{'' if n == '1' else 's'}" +
                 (f"   satellite {human_number(drift[i], 3)} from {where}" if drift is not None else "")
                 for n, i in zip(turns, f)]
    else:
        # the line through the three bodies: they start on x and turn with the frame
        P = [np.asarray(tr.bodies[n], float) for n in ("A", "B", "C") if n in tr.bodies]
        ext = 1.15 * k * max(float(np.max(np.abs(p[:, 0]))) for p in P) if P else R
        tbd.line(d, f"{tbd.TURNING}/line", (-ext, 0, 0), (ext, 0, 0))
        r = tr.series.get("ratio_BC_over_AB")
        alpha = run.metrics.get("alpha")
        texts = [(f"BC/AB = {r[i]:.6f}  (α = {alpha:.6f})  t = {t[j]:.3g}" if r is not None and alpha is not None
                  else f"t = {t[j]:.3g}") for j, i in enumerate(f)]
    tbd.readout(d, texts, (-R, 1.3 * R, 0.0))  # above the bodies' circle and their names
    return d


def _cost(values):
    """One DOP853 run (the turning line: slower once it has broken up); kept: 600 samples of the
    three bodies (1200 and the five L-point markers in the restricted case) with their integrated
    state and the ratio and spacing series."""
    motion = values["motion"]
    if motion == "restricted":
        grid = 3 * 8 * ZERO_VELOCITY_GRID**2
        return Cost(DOP853_STEPS_PER_TURN * values["turns"], N_SAMPLES_RESTRICTED,
                    trajectory_bytes(N_SAMPLES_RESTRICTED, bodies=6 + 5, series=3, extra=grid))
    turns = values["turns"]
    steps = (DOP853_STEPS_PER_TURN * turns + DOP853_STEPS_PER_TURN_OFF_LINE * max(0.0, turns - TURNS_ON_LINE)
             if motion == "rotating" else DOP853_STEPS_HOMOTHETIC)
    series = 8 if motion == "rotating" else 7
    return Cost(steps, N_SAMPLES, trajectory_bytes(N_SAMPLES, bodies=6, series=series))


register(Scenario(
    series_units={"[A-Za-z0-9_]+_[xyz]": "G=1 units", "spacing_AB": "G=1 units", "AB spacing .*": "G=1 units",
                  "satellite drift .*": "G=1 units",  # lengths in the unit distance of the masses, G = 1
                  "ratio_BC_over_AB": "", "BC/AB .*": "", "α .*": "", "L[1-5]_x_over_distance": ""},
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
              kind="vec3", label="Masses A, B, C in order on the line"),
        Param("motion", "rotating", unit="",
              help="rigid rotation, Case II collapse from rest, Case I expansion, or the restricted problem "
                   "(a massless satellite at a Lagrange point of primary + secondary)",
              kind="choice", choices=("rotating", "collapse", "expansion", "restricted"),
              label="Motion",
              choice_labels=("turning as a rigid line", "collapse from rest", "flying apart", "a satellite at a Lagrange point")),
        Param("lagrange_point", "L1", kind="choice", choices=("L1", "L2", "L3", "L4", "L5"),
              help="restricted: where the satellite is released", label="Lagrange point",
              applies={"motion": "restricted"}),
        Param("turns", 2.0, 0.1, 20.0, "turns", "rotating: number of turns shown", label="Turns shown",
              applies={"motion": ("rotating", "restricted")}),
        Param("phi_max_deg", 80.0, 1.0, 89.0, "deg", "collapse: stop at this φ (φ = 90° is the collision)",
              label="Collapse: stop at φ", applies={"motion": "collapse"}),
        Param("energy", 0.5, 1e-3, 100.0, "G=1 units", "expansion: energy per unit reduced mass (> 0)",
              exclusive_min=True, label="Flying apart: energy", applies={"motion": "expansion"}),
        Param("mass_ratio", MOON_EARTH_MASS_RATIO, 1e-9, 1.0, "1",
              "restricted case: secondary/primary mass (Moon/Earth, IAU 2009: 0.0123000371)",
              label="Satellite case: Moon/Earth mass ratio"),
        Param("distance_km", EARTH_MOON_DISTANCE_KM, 1.0, 1e10, "km", "restricted case: primary–secondary distance",
              label="Satellite case: Earth–Moon distance"),
    ),
    camera=Camera((0.0, -0.9, 3.4), (0.0, 0.0, 0.0)),  # from above: L1–L5, zero-velocity curves
    simulate_fn=_collinear,
    draw=_draw,
    options=OPTIONS,
    cost_fn=_cost,
    preview={"turns": 1.0},  # the first turn while many are computed (20 turns take ~3 s)
    euler_formula=("(A+B)α⁵ + (3A+2B)α⁴ + (3A+B)α³ − (B+3C)α² − (2B+3C)α − (B+C) = 0 (§7, Eq. 33)\n"
                   "p̈ = −(D/2) p⁻², D/2 = A + B + C/(α+1)² − C/α²\n"
                   "Case II: p ∝ cos²φ, t = n³a² (φ + sin φ cos φ)"),
    kind="orbit",
    presets=(
        ("Collinear: turning as a rigid line", {}),
        ("Collinear: collapse from rest", {"motion": "collapse"}),
        ("Collinear: flying apart", {"motion": "expansion"}),
        ("Earth–Moon L1: the satellite drifts off (unstable)", {"motion": "restricted", "lagrange_point": "L1"}),
        ("Earth–Moon L2", {"motion": "restricted", "lagrange_point": "L2"}),
    ),
    metric_units={"alpha": "", "ratio_max_rel_deviation": "", "spacing_vs_euler_max_rel_error": "",
                  "satellite_drift_max": "", "jacobi_constant_L[1-5]": ""},  # in the restricted problem's units (distance 1, G(M + m) = 1)
))


@register_check("E11", "collinear three bodies: the quintic's α held by an N-body collapse (Case II)", "Euler 1767 §7–§11")
def e11():
    A, B, C = 3.0, 1.0, 2.0
    alpha = col.quintic_root(A, B, C)
    K = col.kepler_constant(A, B, C, alpha)
    pos = np.zeros((3, 3))
    pos[:, 0] = col.positions_on_line(A, B, C, alpha, 1.0)
    phi = np.linspace(0.0, 1.3, 40)
    t, p = col.homothetic_collapse(K, 1.0, phi)
    _, P, _ = integrate_dop853([A, B, C], pos, np.zeros((3, 3)), t)
    d1 = P[:, 1, 0] - P[:, 0, 0]
    d2 = P[:, 2, 0] - P[:, 1, 0]
    ratio = d2 / d1
    rel = max(float(np.max(np.abs(ratio / alpha - 1))), float(np.max(np.abs(d1 / p - 1))))
    return dict(euler=alpha, simulated=float(ratio[-1]), modern=alpha, rel_error=rel, tolerance=1e-8, unit="",
                note="masses (3,1,2) from rest down to φ = 1.3 rad (spacing 0.07 of the start): the ratio BC/AB and "
                     "p = p0 cos²φ at t = √(p0³/2K)(φ + sinφ cosφ) hold to the DOP853 tolerance (1e-12)")


# Earth–Moon mass parameter of the published CR3BP tables: Koon, Lo, Marsden & Ross, *Dynamical
# Systems, the Three-Body Problem and Space Mission Design* (2011), label it μ = 1.215e-2; their
# six-digit x of L1, L2, L3 are those of the full JPL value 0.01215058561 (with μ = 0.01215
# exactly, L1 would be 0.836918, 3e-6 off — six times the printed rounding).
KLMR_MU = 0.012150585609624


KLMR_L_X = (0.836915, 1.155682, -1.005063)


@register_check("E11.earth-moon-L", "Earth–Moon L1, L2, L3: Euler's quintic vs the effective-potential root vs published", "Euler 1767 §7")
def e11_lpoints():
    mu = KLMR_MU
    L = col.lagrange_distances(mu / (1 - mu), 1.0)  # Euler: the quintic (33), α of each point
    ours = np.array([L[0] - mu, L[1] - mu, -(L[2] + mu)])  # rotating-frame x, barycentre at 0
    # independent route: zeros of ∂Ω/∂x of the restricted problem (no quintic, no α)
    Lc = col.lagrange_distances_cr3bp(mu / (1 - mu), 1.0)
    sim = np.array([Lc[0] - mu, Lc[1] - mu, -(Lc[2] + mu)])
    pub = np.array(KLMR_L_X)
    rel_pub = float(np.max(np.abs(sim - pub) / np.abs(pub)))
    rel_routes = float(np.max(np.abs(ours / sim - 1)))
    tol_pub = float(np.max(5e-7 / np.abs(pub)))  # half a unit of the table's sixth decimal
    tol_routes = 1e-12  # both roots are solved to xtol 1e-15 in double precision
    return dict(euler=float(ours[0]), simulated=float(sim[0]), modern=float(pub[0]), rel_error=rel_pub,
                tolerance=tol_pub, passed=rel_pub <= tol_pub and rel_routes <= tol_routes,
                unit="Earth–Moon distance (x of L1)",
                note=f"μ = {mu}; Euler (quintic) x = {ours[0]:.7f}, {ours[1]:.7f}, {ours[2]:.7f}; simulated = roots of the "
                     f"effective-potential gradient x = {sim[0]:.7f}, {sim[1]:.7f}, {sim[2]:.7f}; the two routes agree to "
                     f"{rel_routes:.1e} (must be ≤ 1e-12); vs Koon, Lo, Marsden & Ross (2011) 0.836915, 1.155682, −1.005063: "
                     f"rel_error = largest difference, tolerance = half a unit of the sixth decimal")


@register_check("E11.translator-table", "translation note, not physics: the translator's Earth–Moon table vs the quintic's root", "Bistafa 2019, after §11")
def e11_table():
    """Not a check of Euler or of the simulation: it records that the numbers printed in the
    translation's 'Applications' table are a numerical slip. The row passes when the slip is
    larger than the table's own rounding (so it is a real slip, not rounding) and smaller than
    0.1% (so the translator used the same equation, Eq. 33)."""
    tt = col.translator_table_errors()
    err = np.abs(np.array(tt["L_error_km"]))
    rel = float(np.max(err / np.array(tt["L_km"])))
    alpha_err = np.abs(np.array(tt["alpha_error"]))
    rounding = np.array([0.5e-5, 0.5e-6, 0.5e-5])  # the table prints α to 5, 6, 5 decimals
    is_slip = bool(np.all(alpha_err[:2] > 10 * rounding[:2]))
    return dict(euler=tt["L_km_table"][1], simulated=None, modern=tt["L_km"][1], rel_error=rel,
                tolerance=1e-3, passed=is_slip and rel <= 1e-3, unit="km (L2)",
                note="translation note (no simulation): Euler column = the translator's printed table, modern = the root of "
                     "Eq. (33) with the table's own inputs; table − root = {:+.0f}, {:+.0f}, {:+.0f} km for L1, L2, L3; its α1, α2 "
                     "miss the root by {:.1e}, {:.1e}, far more than the printed digits' rounding: a numerical slip, not a "
                     "different equation".format(*tt["L_error_km"], *alpha_err[:2]))


@register_check("E11.leaves", "three-body runs that leave their configuration say so: the turning line breaks, "
                "the satellite leaves L1", "Euler 1767 §7–§11, modern")
def e11_leaves():
    sc = get("collinear")
    line = sc.simulate({"turns": 20.0})
    sat = sc.simulate({"motion": "restricted", "lagrange_point": "L1", "turns": 2.0})
    calm = sc.simulate({"motion": "restricted", "lagrange_point": "L4", "turns": 2.0})
    ok = (any(w.startswith("The line broke") for w in line.warnings)
          and any(w.startswith("The satellite left L1") for w in sat.warnings) and not calm.warnings)
    return dict(euler=line.metrics["alpha"], simulated=None, modern=None, rel_error=0.0 if ok else 1.0, tolerance=0.0,
                passed=ok, unit="",
                note=f"20 turns of the line: the ratio strays {line.metrics['ratio_max_rel_deviation']:.2g} from α "
                     f"(warned above {LINE_BROKEN:g}); a satellite at Earth–Moon L1 drifts "
                     f"{sat.metrics['satellite_drift_max']:.2g} distances in 2 turns (warned above {SATELLITE_LEFT:g}); "
                     "one at L4 stays (no warning)")
