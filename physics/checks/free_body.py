"""Check rows E1–E4 (ch. 15): the free body and the first motion under given moments."""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from .. import quaternion as quat
from ..euler_ch15 import flip_interval_808, initial_axis, vis_viva
from ..euler_equations import direction_cosines_dot, omega_dot
from ..integrator import integrate
from ..scenarios import get
from ..torque_free_exact import exact_free_motion, free_motion
from .base import register_check

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
                note=f"over 10^6 steps (~20,000 spins): vis viva and |L| drift {drift:.2g} (tolerance 1e-12, issue 2); "
                     f"final ω {dw:.2g} (relative) and attitude {att:.2g} rad from the exact solution (must be "
                     "≤ 1e-8: the quadrature of ψ and round-off add ~1e-16 of phase per step)")


@register_check("E2", "interval between flips about the middle axis", "§808")
def e2():
    r = get("middle-axis-flip").simulate()
    m = r.metrics
    rel = max(abs(m["flip_interval"] / m["flip_interval_exact"] - 1),
              abs(m["flip_interval_euler_808"] / m["flip_interval_exact"] - 1))
    return dict(euler=m["flip_interval_euler_808"], simulated=m["flip_interval"], modern=m["flip_interval_exact"],
                rel_error=rel, tolerance=1e-9, unit="s",
                note="Euler: his §808 quadrature evaluated; modern: 2K(k)/λ; simulated: mean spacing of sign changes")


@register_check("E3", "body at rest: axis ∝ P/A : Q/B : R/C and dγ'/dt", "§806")
def e3():
    I = np.array([1.0, 2.0, 2.5])
    tau = np.array([1.0, -0.7, 0.4])
    axis, acc = initial_axis(tau, I)
    h = 1e-2
    _, L, _ = integrate(I, np.zeros(3), h, h / 8, torque_body=tau)
    w = L[-1] / I
    # independent reference: Euler's full equations from rest by DOP853 at tight tolerance
    ref = solve_ivp(lambda t, y: omega_dot(y, I, tau), (0, h), np.zeros(3), method="DOP853",
                    rtol=1e-13, atol=1e-16).y[:, -1]

    def angle(a, b):
        return float(np.arctan2(np.linalg.norm(np.cross(a, b)), a @ b))

    # Euler's first instant against the finite start: ω(t) = ω̇₀t + O(t³), so the axis moves
    # O((|ω̇₀|t)²) ≈ 1e-4 and |ω|/t changes by the same order
    euler_gap = max(angle(axis, ref), abs(np.linalg.norm(ref) / h / acc - 1))
    sim_err = max(angle(w, ref), float(np.linalg.norm(w - ref) / np.linalg.norm(ref)))
    tol = (acc * h) ** 2
    return dict(euler=acc, simulated=float(np.linalg.norm(w) / h), modern=float(np.linalg.norm(ref) / h),
                rel_error=euler_gap, tolerance=tol, passed=bool(euler_gap <= tol and sim_err <= 1e-6),
                unit="rad/s²",
                note=f"Euler's §806 axis and rate vs DOP853 of the full equations after {h:g} s: {euler_gap:.2g}, "
                     f"within the (|ω̇₀|t)² = {tol:.2g} his first instant neglects (ω = ω̇₀t + O(t³)); "
                     f"theoria vs DOP853 {sim_err:.2g} (Strang splitting error at h/8, must be ≤ 1e-6)")


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
