"""Benchmark: a spin–orbit surface of section (Hyperion, WPM 1984: e = 0.1, ω₀ = 0.89) of
200 starts × 500 periapse passages. theoria: the ensemble in one compiled loop, 4th-order
symplectic fixed step with the orbit tabulated once (physics.libration.spin_orbit_section).
Baseline: scipy DOP853 with the whole ensemble in one state vector (its fastest use), rtol
1e-8 (chosen so that both reach about the same error). Errors: largest |Δθ̇| over the ensemble
at the first passage (later passages are dominated by the chaos, Lyapunov times of ~1 orbit)
against DOP853 at rtol 1e-13. The theoria scheme is Blanes & Moan's 4th-order SRKN."""
from __future__ import annotations

import time

import numpy as np

from theoria.physics import libration as lib
from theoria.scenarios.hyperion import ensemble_starts

from . import register_bench

E, W0 = 0.1, 0.89


@register_bench("spin-orbit-section-200x500")
def spin_orbit_section():
    th0, wd0 = ensemble_starts(200)
    n_orb, spo = 500, 48
    lib.spin_orbit_section(th0[:2], wd0[:2], E, W0, 2, spo)  # compile outside the timing
    t0 = time.perf_counter()
    T, W = lib.spin_orbit_section(th0, wd0, E, W0, n_orb, spo)
    ts = time.perf_counter() - t0
    t0 = time.perf_counter()
    Ts, Ws = lib.spin_orbit_section_scipy(th0, wd0, E, W0, n_orb, rtol=1e-8, atol=1e-10)
    bs = time.perf_counter() - t0
    _, Wr = lib.spin_orbit_section_scipy(th0, wd0, E, W0, 1, rtol=1e-13, atol=1e-14)
    return {
        "theoria_s": ts,
        "baseline_s": bs,
        "theoria_error": float(np.max(np.abs(W[:, 0] - Wr[:, 0]))),
        "baseline_error": float(np.max(np.abs(Ws[:, 0] - Wr[:, 0]))),
        "points": int(T.size),
        "steps_per_orbit": spo,
    }
