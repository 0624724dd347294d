"""Benchmark: the free body over 100 spin periods, theoria's integrator against scipy DOP853
tuned to the same or better final error (or to its best, if it cannot reach ours)."""
from __future__ import annotations

import time

import numpy as np
from scipy.integrate import solve_ivp

from theoria.physics import quaternion as quat
from theoria.physics.euler_equations import rhs_state
from theoria.physics.integrator import integrate
from theoria.physics.torque_free_exact import exact_free_motion

from . import register_bench


def _best_of(fn, n=3):
    best, out = float("inf"), None
    for _ in range(n):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def _error(w, q, w_ex, q_ex, w_scale):
    return max(float(np.max(np.abs(w - w_ex))) / w_scale, float(np.max(quat.angle_between(q, q_ex))))


@register_bench("free-body-100-periods")
def free_body():
    I = np.array([1.0, 2.0, 3.0])
    w0 = np.array([0.3, 1.0, 0.2])
    T = 2 * np.pi / np.linalg.norm(w0)
    t_end, h = 100 * T, T / 50
    n_out = 5000
    t_eval = np.linspace(0, t_end, n_out + 1)
    w_ex, q_ex = exact_free_motion(I, w0, t_eval)
    scale = float(np.linalg.norm(w0))
    integrate(I, w0, 10 * h, h)  # compile outside the timing

    def ours():
        t, L, q = integrate(I, w0, t_end, h, stride=1)
        return L[::1] / I, q

    t_ours, (w, q) = _best_of(ours)
    e_ours = _error(w, q, w_ex, q_ex, scale)  # h divides t_end: samples are at t_eval
    y0 = np.concatenate([w0, quat.IDENTITY])
    baseline = None
    for rtol in (1e-10, 1e-11, 1e-12, 1e-13):
        def base(rtol=rtol):
            s = solve_ivp(rhs_state, (0, t_end), y0, method="DOP853", rtol=rtol, atol=rtol * 1e-2,
                          t_eval=t_eval, args=(I,))
            return s.y[:3].T, quat.normalize(s.y[3:].T)

        tb, (wb, qb) = _best_of(base, n=1)
        eb = _error(wb, qb, w_ex, q_ex, scale)
        baseline = (tb, eb, rtol)
        if eb <= e_ours:
            break
    tb, eb, rtol = baseline
    return {"theoria_s": t_ours, "baseline_s": tb, "theoria_error": e_ours, "baseline_error": eb,
            "baseline_rtol": rtol, "samples": n_out + 1, "steps": int(round(t_end / h))}
