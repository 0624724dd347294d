"""Benchmarks of the batched kernels that sweeps run on: body-steps per second of many bodies
advanced together, against the one-at-a-time path measured in the same run (its time per step
extrapolated to the batch's steps), and the largest difference between the two (round-off).

- `sweep libration-eccentric 4096 bodies`: the planar kernel (physics.spin_orbit_batch, Yoshida 4,
  the orbit of e = 0.1 tabulated once, (B − A)/C spread over the batch) against the rigid-body
  integrator a libration-eccentric run uses today (physics.integrator, the same scheme and kick
  times, the exact free flow between the kicks).
- `sweep hyperion lyapunov 4096 bodies`: the Hyperion chaos map (Blanes–Moan 4, tangent map) against
  the section kernel called once per start, as a loop over starts would.
- `sweep tidal-capture 4096 bodies`: the same with the constant-time-lag tide in every kick.
- `sweep free-body 256 bodies`: many free bodies (physics.free_body_batch) against one call of the
  integrator per body (the same steps: identical results, the gain is the cores).
"""
from __future__ import annotations

import time

import numpy as np

from theoria.physics import libration as lib
from theoria.physics import quaternion as quat
from theoria.physics.free_body_batch import free_body_batch
from theoria.physics.integrator import PointMass, integrate
from theoria.physics.orbits import KeplerOrbit
from theoria.physics.spin_orbit_batch import planar_batch

from . import register_bench

N_BODIES = 4096
GOAL = 1e8  # body-steps per second on the 2-core machine


def _row(n_bodies, steps, t_batch, t_single_per_step, n_single, err):
    bs = n_bodies * steps
    return {"theoria_s": t_batch, "baseline_s": t_single_per_step * bs, "theoria_error": float(err),
            "baseline_error": 0.0, "body_steps_per_s": bs / t_batch,
            "baseline_body_steps_per_s": 1.0 / t_single_per_step, "goal_body_steps_per_s": GOAL,
            "bodies": n_bodies, "steps": steps, "baseline_bodies_timed": n_single}


@register_bench("sweep libration-eccentric 4096 bodies")
def libration_batch():
    e, spo, orbits = 0.1, 400, 5
    orb = KeplerOrbit(a=1.0, e=e, n=1.0)
    h, n = 2 * np.pi / spo, spo * orbits
    gam = np.linspace(0.01, 0.3, N_BODIES)
    lam0 = np.linspace(-0.2, 0.2, N_BODIES)
    w0 = np.full(N_BODIES, 1.05)
    planar_batch(lam0[:16], w0[:16], 1.5 * gam[:16], orb, h, 4)  # compile outside the timing
    t0 = time.perf_counter()
    out = planar_batch(lam0, w0, 1.5 * gam, orb, h, n)
    tb = time.perf_counter() - t0
    idx = [0, N_BODIES // 2, N_BODIES - 1]
    integrate(np.array([0.75, 0.75, 1.0]), [0, 0, 1.0], 4 * h, h, masses=[PointMass(1.0, orb.position)], scheme="yoshida4")
    err, t_single = 0.0, 0.0
    for i in idx:
        I = np.array([0.75 - gam[i] / 2, 0.75 + gam[i] / 2, 1.0])
        t0 = time.perf_counter()
        _, L, q = integrate(I, [0, 0, w0[i]], n * h, h, q0=quat.from_axis_angle([0, 0, 1], lam0[i]),
                            masses=[PointMass(1.0, orb.position)], scheme="yoshida4", stride=n)
        t_single += time.perf_counter() - t0
        th = 2 * np.arctan2(q[-1, 3], q[-1, 0])
        err = max(err, abs(np.remainder(th - out["theta"][i] + np.pi, 2 * np.pi) - np.pi), abs(L[-1, 2] - out["thetadot"][i]))
    return _row(N_BODIES, n, tb, t_single / (len(idx) * n), len(idx), err)


@register_bench("sweep hyperion lyapunov 4096 bodies")
def hyperion_batch():
    e, w0, spo, no = 0.1, 0.89, 48, 200
    orb = KeplerOrbit(a=1.0, e=e, n=1.0)
    th0 = np.zeros(N_BODIES)
    wd0 = np.linspace(0.5, 3.0, N_BODIES)
    planar_batch(th0[:16], wd0[:16], 0.5 * w0**2, orb, 2 * np.pi / spo, 4, scheme="blanes-moan4", lyapunov=True)
    t0 = time.perf_counter()
    out = planar_batch(th0, wd0, 0.5 * w0**2, orb, 2 * np.pi / spo, spo * no, scheme="blanes-moan4", lyapunov=True,
                       renorm=spo, stride=spo)
    tb = time.perf_counter() - t0
    lib.spin_orbit_section([0.0], [1.0], e, w0, 2, spo, lyapunov=True)
    idx = [0, 1, 2, 3]
    t0 = time.perf_counter()
    ref = [lib.spin_orbit_section([th0[i]], [wd0[i]], e, w0, no, spo, lyapunov=True) for i in idx]
    ts = (time.perf_counter() - t0) / (len(idx) * spo * no)
    # the two kernels differ by round-off per step; compare the first passage (chaos amplifies later ones)
    err = max(abs(out["thetadot_samples"][i, 0] - ref[k][1][0, 0]) for k, i in enumerate(idx))
    return _row(N_BODIES, spo * no, tb, ts, len(idx), err)


@register_bench("sweep tidal-capture 4096 bodies")
def tidal_batch():
    e, w0, spo, no = 0.07, 0.1, 48, 400
    orb = KeplerOrbit(a=1.0, e=e, n=1.0)
    th0 = np.linspace(0, np.pi, N_BODIES, endpoint=False)
    planar_batch(th0[:16], 1.8, 0.5 * w0**2, orb, 2 * np.pi / spo, 4, scheme="blanes-moan4", tide_rate=5e-5)
    t0 = time.perf_counter()
    out = planar_batch(th0, 1.8, 0.5 * w0**2, orb, 2 * np.pi / spo, spo * no, scheme="blanes-moan4", tide_rate=5e-5)
    tb = time.perf_counter() - t0
    idx = [0, 1000, 4000]
    t0 = time.perf_counter()
    one = [planar_batch(th0[i:i + 1], 1.8, 0.5 * w0**2, orb, 2 * np.pi / spo, spo * no, scheme="blanes-moan4",
                        tide_rate=5e-5) for i in idx]
    ts = (time.perf_counter() - t0) / (len(idx) * spo * no)
    err = max(abs(out["theta"][i] - o["theta"][0]) + abs(out["thetadot"][i] - o["thetadot"][0]) for i, o in zip(idx, one))
    r = _row(N_BODIES, spo * no, tb, ts, len(idx), err)
    r["baseline"] = "the same kernel, one body per call"
    return r


@register_bench("sweep free-body 256 bodies")
def free_body_batch_row():
    rng = np.random.default_rng(1)
    N = 256
    I = np.array([2.0, 3.0, 4.0]) * (1 + 0.1 * rng.random((N, 3)))
    w = rng.normal(size=(N, 3))
    dur, h = 20.0, 0.01
    free_body_batch(I[:2], w[:2], [1, 0, 0, 0], 0.05, h)
    t0 = time.perf_counter()
    t, L, q = free_body_batch(I, w, [1, 0, 0, 0], dur, h, stride=100)
    tb = time.perf_counter() - t0
    integrate(I[0], w[0], 0.05, h)
    idx = [0, 1, 2, 3]
    t0 = time.perf_counter()
    ref = [integrate(I[i], w[i], dur, h, stride=100) for i in idx]
    ts = (time.perf_counter() - t0) / (len(idx) * round(dur / h))
    err = max(float(np.max(np.abs(r[1] - L[i])) + np.max(np.abs(r[2] - q[i]))) for r, i in zip(ref, idx))
    return _row(N, int(round(dur / h)), tb, ts, len(idx), err)
