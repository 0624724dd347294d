"""The body left to itself (ch. 15, §805, §808): Poinsot's picture, vis viva and |L| conserved,
the polhode period by Euler's quadrature.

Check rows E1 (the invariants and the state after 10⁶ steps) and E4 (the attitude from Euler's
direction cosines, §809–811).
"""
from __future__ import annotations

import numpy as np
from ..physics.euler_ch15 import flip_interval_808, vis_viva
from ..physics.integrator import integrate
from ..physics.params import Param, ParameterError
from ..physics.torque_free_exact import free_motion
from .drawing import Camera
from .base import Comparison, Run, Scenario, register
from scipy.integrate import solve_ivp
from ..physics import quaternion as quat
from ..physics.euler_equations import direction_cosines_dot, omega_dot
from ..physics.torque_free_exact import exact_free_motion
from .checks import register_check
from ._rigid_body import (DRIFT_UNITS, INERTIA_PARAM, MAX_SAMPLES, body_cost, check_body, drift_metrics, free_body_warnings,
                          integrate_body, middle_axis_crossings)


def _free_tumble(values, progress=None):
    w0 = np.array(values["omega0"])
    if not np.any(w0):
        raise ParameterError("omega0", values["omega0"], "not all zero (a body at rest stays at rest)")
    traj = integrate_body(values, w0, progress=progress)
    I = traj.inertia
    m = drift_metrics(traj)
    m["energy_J"] = float(traj.energy[0])
    m["angular_momentum_kg_m2_per_s"] = float(traj.momentum_norm[0])
    comps = [Comparison("vis viva A x² + B y² + C z² (§805: constant)", float(vis_viva(w0, I)),
                        float(2 * traj.energy[-1]), float(vis_viva(w0, I)), "J")]
    warnings: list[str] = []
    try:
        fm = free_motion(I, w0)
        warnings = free_body_warnings(traj, fm, "the polhode period", step=values["step"])
        m["polhode_period_s"] = fm.polhode_period
        circ = "ABC"[fm.circulation_axis]
        # Euler: §808's quadrature gives the time between two sign changes of ω on the middle axis,
        # half a polhode period; simulated: twice the mean spacing of those sign changes in the run
        vals, counts = np.unique(I, return_counts=True)
        if len(vals) == 3:
            euler = 2.0 * flip_interval_808(I, w0)
            how = "Euler: twice the §808 quadrature"
        else:  # two equal moments: §808's reduction divides by their difference; his equations with
            # A = B give dz = 0 and x, y turning at the constant rate (C − A) z / A: a circle
            s_ax = int(np.nonzero(I == vals[counts == 1][0])[0][0])
            a_mom = float(vals[counts == 2][0])
            euler = 2 * np.pi * a_mom / abs((I[s_ax] - a_mom) * w0[s_ax])
            how = "Euler: §808's equations with two equal moments, 2πA/|(C − A) ω_C|"
        euler = float(euler) if np.isfinite(euler) else None
        tc = middle_axis_crossings(traj)
        measured = 2.0 * float(np.mean(np.diff(tc))) if len(tc) >= 2 else None
        why = "; the run is too short to see two crossings"
        if np.max(np.diff(traj.t), initial=0.0) > 0.25 * fm.polhode_period:  # sign changes between samples unseen
            measured = None
            why = ("; the kept states are too far apart to see each crossing (a long run keeps at most "
                   f"{MAX_SAMPLES:,} states: shorten the run)")
        if euler is not None:
            m["polhode_period_euler_808_s"] = euler
        if measured is not None:
            m["polhode_period_measured_s"] = measured
        if np.isfinite(fm.polhode_period):
            comps.append(Comparison("polhode period", euler, measured, fm.polhode_period, "s",
                                    f"ω circulates about the {circ} axis; {how}; modern: 4K(k)/λ, k² = {fm.m:.6g}" +
                                    ("" if measured is not None else why)))
        else:  # ω exactly on the middle axis: 1 − k² = 0
            comps.append(Comparison("polhode period", None, None, fm.polhode_period, "s",
                                    "ω starts exactly on the middle axis: a permanent rotation, but unstable (§808); "
                                    "it lies on the separatrix, whose period is infinite. The least nudge sets the "
                                    "body flipping (the middle-axis-flip scene)",
                                    missing="on the separatrix the period is infinite: none is measured"))
    except ValueError as e:  # a permanent rotation or a sphere has no polhode
        comps.append(Comparison("polhode", None, None, None, "", str(e)))
        warnings = free_body_warnings(traj, None, step=values["step"])
    return Run("free-tumble", values, traj, m, comps, warnings=warnings,
                  plot_series={"ω₁": traj.omega_body[:, 0], "ω₂": traj.omega_body[:, 1],
                               "ω₃": traj.omega_body[:, 2]})


register(Scenario(
    series_units={"ω[₁₂₃]": "rad/s"},  # Euler's p, q, r
    name="free-tumble",
    title="The body left to itself",
    section="§805, §808",
    group="ch. 15",
    summary=("A body with three different moments A < B < C, thrown spinning and left alone. Look at "
            "the two arrows: the angular momentum L (purple) stays fixed in space while the rotation "
            "axis ω (orange) wanders. On the body, ω traces a closed curve, the polhode (yellow); in "
            "space its tip runs on a fixed plane, the invariable plane, tracing the herpolhode (cyan). "
            "Euler's vis viva (the energy, §805) and |L| stay constant."),
    params=(
        Param("inertia", (2.0, 3.0, 4.0), **INERTIA_PARAM),
        Param("omega0", (1.0, 0.5, 1.5), kind="vec3", minimum=-50, maximum=50, unit="rad/s",
              help="initial angular velocity on the body axes", label="Initial spin ω on the body axes"),
        Param("duration", 20.0, 0.0, 1e6, "s", "length of the run", exclusive_min=True, step=1.0,
              label="Length of the run"),
        Param("step", 0.01, 0.0, 10.0, "s", "integrator step", exclusive_min=True, step=0.001,
              label="Integrator step", advanced=True),
    ),
    camera=Camera((3.0, 2.3, 1.8), (0.0, 0.0, 0.0)),
    simulate_fn=_free_tumble,
    cost_fn=body_cost,
    check=check_body,
    euler_formula=("dx + (cc − bb)/aa · yz dt = 0, and the same for y and z in turn (§808)\n"
                   "aa·xx + bb·yy + cc·zz = const (vis viva, §805)\n"
                   "x, y, z: rates about the principal axes; aa, bb, cc: the moments A, B, C"),
    presets=(
        ("Tumble: ω wanders widely", {}),
        ("Tumble: spin near the long axis, a small polhode", {"omega0": (2.0, 0.3, 0.3)}),
        ("Tumble: spin near the short axis, a small polhode", {"omega0": (0.3, 0.3, 2.0)}),
        ("Symmetric top (A = B): a steady cone", {"inertia": (3.0, 3.0, 4.0), "omega0": (1.0, 0.0, 1.5)}),
    ),
    metric_units=DRIFT_UNITS,
))


TRIAXIAL = (np.array([1.0, 2.0, 3.0]), np.array([0.3, 1.0, 0.2]))


def spin_period(omega0) -> float:
    return 2 * np.pi / float(np.linalg.norm(omega0))


@register_check("E1", "vis viva and |L| conserved without torque; state after 10^6 steps at T/50", "§805, §808")
def e1():
    I, w0 = TRIAXIAL
    h = spin_period(w0) / 50
    t, L, q = integrate(I, w0, 1e6 * h, h, stride=1000)
    E = np.sum(L * L / I, axis=1)  # vis viva A x² + B y² + C z² = Σ L²/I
    G = np.linalg.norm(L, axis=1)
    drift = max(np.max(np.abs(E / E[0] - 1)), np.max(np.abs(G / G[0] - 1)))
    # the conservation is built into the exact free flow; what can go wrong is the motion on the
    # invariant curves: compare the final state with the exact elliptic solution (scipy, Carlson)
    w_ex, q_ex = exact_free_motion(I, w0, t[-1:])
    att = float(quat.angle_between(q[-1], q_ex[0]))
    dw = float(np.max(np.abs(L[-1] / I - w_ex[0])) / np.linalg.norm(w0))
    return dict(euler=float(vis_viva(w0, I)), simulated=float(E[-1]),
                modern=float(vis_viva(w_ex[0], I)), rel_error=float(drift), tolerance=1e-12,
                passed=bool(drift <= 1e-12 and att <= 1e-8 and dw <= 1e-8), unit="J (vis viva)",
                note=f"over 10^6 steps (~20,000 spins): vis viva and |L| drift {drift:.2g} (tolerance 1e-12); "
                     f"final ω {dw:.2g} (relative) and attitude {att:.2g} rad from the exact solution (must be "
                     "≤ 1e-8: the quadrature of ψ and round-off add ~1e-16 of phase per step)")


@register_check("E4", "attitude from Euler's direction cosines, 100 spin periods", "§809–811")
def e4():
    I, w0 = TRIAXIAL
    T = spin_period(w0)
    t_end = 100 * T
    # theoria at T/50
    t, L, q = integrate(I, w0, t_end, T / 50, stride=5000)
    # modern: the exact elliptic solution
    _, q_ex = exact_free_motion(I, w0, [t_end])
    err = float(quat.angle_between(q[-1], q_ex[-1]))
    # Euler: §808 for x, y, z and §811 for the cosines (p, q, r) of the fixed pole Z on the body
    # axes, integrated together by DOP853 at tight tolerance
    def rhs(_, y):
        return np.concatenate([omega_dot(y[:3], I), direction_cosines_dot(y[3:], y[:3])])

    z_body0 = np.array([0.0, 0.0, 1.0])  # attitude starts at the identity
    sol = solve_ivp(rhs, (0, t_end), np.concatenate([w0, z_body0]), method="DOP853", rtol=1e-13, atol=1e-14)
    r_euler = float(sol.y[5, -1])  # cos n: cosine of the arc from the pole Z to the C axis
    r_theoria = float(quat.rotate_inverse(q[-1], z_body0)[2])
    r_exact = float(quat.rotate_inverse(q_ex[-1], z_body0)[2])
    return dict(euler=r_euler, simulated=r_theoria, modern=r_exact, rel_error=err, tolerance=1e-8,
                unit="cos n (pole Z on the C axis)",
                note=f"attitude error of theoria against the exact solution {err:.2g} rad; "
                     f"Euler's §811 by DOP853 differs from exact by {abs(r_euler - r_exact):.2g}")
