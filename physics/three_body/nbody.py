"""Direct N-body integrations used by the three-body scenarios and as independent references.

- `integrate_dop853`: Newtonian N bodies (G = 1 unless given), scipy DOP853 at tight
  tolerance; small N, any dimension 3.
- `integrate_rebound`: the same problem with REBOUND (IAS15 by default), imported lazily so
  that `physics` does not need it unless asked.
"""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp
from ..rebound_run import integrate_to


def _accelerations(pos: np.ndarray, masses: np.ndarray, G: float) -> np.ndarray:
    d = pos[None, :, :] - pos[:, None, :]  # d[i, j] = r_j − r_i
    r2 = np.sum(d * d, axis=2)
    np.fill_diagonal(r2, 1.0)
    inv3 = r2 ** -1.5
    np.fill_diagonal(inv3, 0.0)
    return G * np.einsum("ij,ijk->ik", inv3 * masses[None, :], d)


def with_progress(rhs, t0: float, t1: float, progress, every: int = 200):
    """`rhs` calling `progress(fraction of [t0, t1] reached)` every `every` evaluations: an adaptive
    scipy integration can then be cancelled (the callback raises) and shows how far it is."""
    if progress is None:
        return rhs
    span = (t1 - t0) or 1.0
    count = [0]

    def f(t, y, *args):
        count[0] += 1
        if count[0] % every == 0:
            progress(min(1.0, max(0.0, (t - t0) / span)))
        return rhs(t, y, *args)

    return f


def integrate_dop853(masses, pos0, vel0, t_eval, G: float = 1.0, rtol: float = 1e-12, atol: float = 1e-14,
                     events=None, progress=None):
    """Positions (len(t_eval), N, 3) and velocities of N point masses, DOP853. `progress(frac)` is
    called every 200 right-hand-side evaluations (it may raise to stop the run)."""
    masses = np.asarray(masses, float)
    n = len(masses)
    y0 = np.concatenate([np.asarray(pos0, float).ravel(), np.asarray(vel0, float).ravel()])

    def rhs(t, y):
        pos = y[: 3 * n].reshape(n, 3)
        return np.concatenate([y[3 * n:], _accelerations(pos, masses, G).ravel()])

    t_eval = np.asarray(t_eval, float)
    sol = solve_ivp(with_progress(rhs, t_eval[0], t_eval[-1], progress), (t_eval[0], t_eval[-1]), y0,
                    method="DOP853", t_eval=t_eval, rtol=rtol, atol=atol, events=events)
    y = sol.y.T
    return sol.t, y[:, : 3 * n].reshape(-1, n, 3), y[:, 3 * n:].reshape(-1, n, 3)


def integrate_rebound(masses, pos0, vel0, t_eval, G: float = 1.0, integrator: str = "ias15", dt: float | None = None):
    """Positions (len(t_eval), N, 3) and velocities with REBOUND (IAS15 adaptive by default,
    or WHFast with a fixed step dt)."""
    import rebound

    sim = rebound.Simulation()
    sim.G = G
    for m, p, v in zip(masses, pos0, vel0):
        sim.add(m=float(m), x=float(p[0]), y=float(p[1]), z=float(p[2]),
                vx=float(v[0]), vy=float(v[1]), vz=float(v[2]))
    sim.integrator = integrator
    if dt is not None:
        sim.dt = dt
    t_eval = np.asarray(t_eval, float)
    sim.t = float(t_eval[0])
    n = len(masses)
    P = np.empty((len(t_eval), n, 3))
    V = np.empty((len(t_eval), n, 3))
    buf = np.empty((n, 3))
    for k, t in enumerate(t_eval):
        integrate_to(sim, float(t))
        sim.serialize_particle_data(xyz=buf)
        P[k] = buf
        sim.serialize_particle_data(vxvyvz=buf)
        V[k] = buf
    return t_eval, P, V
