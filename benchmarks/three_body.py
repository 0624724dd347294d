"""Benchmark: the Moon perturbed by the Sun over 2 years (Euler 1768). theoria: Euler's element
equations (physics.three_body.lunar_elements), compiled fixed-step RK4 at 0.025 d. Baseline:
scipy DOP853 on the Cartesian equations of the same forces (plain numpy right-hand side) at
rtol 1e-12 (about the same error as theoria). Errors: largest distance (lunar distances, daily samples) from DOP853 at rtol 1e-13."""
from __future__ import annotations

import math
import time

import numpy as np
from scipy.integrate import solve_ivp

from theoria.physics import kepler
from theoria.physics.constants import JULIAN_YEAR_DAYS
from theoria.physics.three_body import lunar_elements as le

from . import register_bench


def _rhs(t, y, mu, mus, sun):
    a_s, es, ns, M0, varpi = sun
    E = kepler.eccentric_anomaly_scalar(M0 + ns * t, es)
    f = kepler.true_anomaly_scalar(E, es)
    u = a_s * kepler.radius_scalar(E, es)
    R = u * np.array([math.cos(f + varpi), math.sin(f + varpi), 0.0])
    r = y[:3]
    d = R - r
    acc = -mu * r / np.linalg.norm(r) ** 3 + mus * (d / np.linalg.norm(d) ** 3 - R / u**3)
    return np.concatenate([y[3:], acc])


def _dop853(y0, days, mu, mus, sun, rtol):
    t = np.arange(0.0, days + 1e-9, 1.0)
    sol = solve_ivp(_rhs, (0.0, days), y0, method="DOP853", t_eval=t, args=(mu, mus, sun), rtol=rtol,
                    atol=rtol * 1e-2)
    return sol.y[:3].T


@register_bench("lunar-elements-2yr")
def lunar_elements_2yr():
    el, sun, mu, mus = le.initial_conditions()
    r0, v0 = le.elements_to_cartesian(el, mu)
    y0 = np.concatenate([r0[0], v0[0]])
    days = 2 * JULIAN_YEAR_DAYS
    le.integrate_rk4("elements", el, 1.0, 0.025, 1.0, mu, mus, sun)  # compile outside the timing
    t0 = time.perf_counter()
    _, E = le.integrate_rk4("elements", el, days, 0.025, 1.0, mu, mus, sun)
    ts = time.perf_counter() - t0
    t0 = time.perf_counter()
    base = _dop853(y0, days, mu, mus, sun, 1e-12)
    bs = time.perf_counter() - t0
    ref = _dop853(y0, days, mu, mus, sun, 1e-13)
    n = min(len(ref), len(E))
    return {
        "theoria_s": ts,
        "baseline_s": bs,
        "theoria_error": float(np.max(np.linalg.norm(le.elements_to_position(E[:n]) - ref[:n], axis=1))),
        "baseline_error": float(np.max(np.linalg.norm(base[:n] - ref[:n], axis=1))),
        "rk4_steps": int(days / 0.025),
    }
