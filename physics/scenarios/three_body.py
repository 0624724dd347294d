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
from .base import Comparison, Result, Scenario, register

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
    t, P, V = integrate_dop853([A, B, C], pos0, vel0, t)
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
    # L-point markers in the rotating frame of the primaries (units of the primaries' distance,
    # primary at the origin), for the restricted-case scene
    Lx = np.array([L[0], L[1], -L[2]]) / d
    bodies = {"A": P[:, 0], "B": P[:, 1], "C": P[:, 2]}
    traj = orbit_trajectory(t, bodies, "G=1 units", series={"ratio_BC_over_AB": ratio, "spacing_AB": d1})
    for k, name in enumerate(("L1", "L2", "L3")):
        traj.series[f"{name}_x_over_distance"] = np.full(len(t), Lx[k])
    return Result("collinear", values, traj, metrics, comps, notes,
                  plot_series={"BC/AB (simulated)": ratio, "α (Euler)": np.full(len(t), alpha),
                               "AB spacing (simulated)": d1, "AB spacing (Euler)": p_euler})


register(Scenario(
    name="collinear",
    title="Three bodies on a line: Euler's quintic",
    section="Euler 1767, §1–§11",
    group=GROUP,
    summary=("Three masses stay on a line if the ratio of their spacings is the single positive root α of "
             "Euler's quintic. Watch them turn rigidly, collapse from rest (distances ∝ cos²φ) or fly apart, "
             "the ratio held by a direct integration; with a massless third body the roots give L1, L2, L3."),
    params=(
        Param("masses", (3.0, 1.0, 2.0), 1e-6, 1e6, "G=1 mass", "masses A, B, C in their order on the line",
              kind="vec3"),
        Param("motion", "rotating", unit="", help="rigid rotation, Case II collapse from rest, Case I expansion",
              kind="choice", choices=("rotating", "collapse", "expansion")),
        Param("turns", 2.0, 0.1, 20.0, "turns", "rotating: number of turns shown"),
        Param("phi_max_deg", 80.0, 1.0, 89.0, "deg", "collapse: stop at this φ (φ = 90° is the collision)"),
        Param("energy", 0.5, 1e-3, 100.0, "G=1 units", "expansion: energy per unit reduced mass (> 0)",
              exclusive_min=True),
        Param("mass_ratio", col.MOON_EARTH_MASS_RATIO, 1e-9, 1.0, "1",
              "restricted case: secondary/primary mass (Moon/Earth, IAU 2009: 0.0123000371)"),
        Param("distance_km", col.EARTH_MOON_DISTANCE_KM, 1.0, 1e10, "km", "restricted case: primary–secondary distance"),
    ),
    simulate_fn=_collinear,
    euler_formula=(r"$(A+B)\alpha^5+(3A+2B)\alpha^4+(3A+B)\alpha^3-(B+3C)\alpha^2-(2B+3C)\alpha-(B+C)=0$"
                   r" (§7, Eq. 33); $\ddot p=-\tfrac{D}{2}p^{-2}$, $\tfrac D2=A+B+\tfrac{C}{(\alpha+1)^2}-\tfrac{C}{\alpha^2}$;"
                   r" Case II: $p\propto\cos^2\varphi$, $t=n^3a^2(\varphi+\sin\varphi\cos\varphi)$"),
    kind="orbit",
))
