"""Shared by the spin–orbit scenarios (ch. 16, §820–838, and Hyperion): the planar body and the
angle ζ between its A axis and F.
"""
from __future__ import annotations

import numpy as np
from ..physics import quaternion as quat


MAX_SAMPLES = 6000


def planar_moments(gamma):
    """(A, B, C) with C = 1 and (B − A)/C = γ: A = 0.75 − γ/2, B = 0.75 + γ/2 (a real body for
    |γ| ≤ 0.5)."""
    return np.array([0.75 - 0.5 * gamma, 0.75 + 0.5 * gamma, 1.0])


def zeta_of(traj_q, positions):
    """Euler's ζ = angle of F from the body's A axis, measured about C (unwrapped)."""
    s = quat.rotate_inverse(traj_q, positions)
    return np.unwrap(np.arctan2(s[:, 1], s[:, 0]))


def stride_for(n_steps):
    return max(1, int(np.ceil(n_steps / MAX_SAMPLES)))


def batched_planar_runs(lam0, lamdot0, strength, orbit, duration, step, stride, C=1.0, tide_rate=None,
                        scheme="yoshida4"):
    """Many planar spin–orbit runs at once (physics.spin_orbit_batch: one shared orbit, the batch
    compiled and vectorised), returned as the rigid-body integrator (`physics.integrator.integrate`)
    returns one: per body (t, L_body, q_wxyz) at t = 0, every `stride` steps and the end, with the
    same step (duration split into whole steps of at most `step`). The body turns about its C axis
    (z): q = (cos λ/2, 0, 0, sin λ/2), L = (0, 0, C λ̇)."""
    from ..physics.spin_orbit_batch import planar_batch

    lam0 = np.atleast_1d(np.asarray(lam0, float))
    n_steps = max(1, int(np.ceil(duration / step - 1e-9)))
    h = duration / n_steps
    out = planar_batch(lam0, lamdot0, strength, orbit, h, n_steps, scheme=scheme, tide_rate=tide_rate, stride=stride)
    rows = n_steps // stride
    tail = n_steps % stride != 0
    t = np.concatenate([[0.0], h * stride * np.arange(1, rows + 1)] + ([[h * n_steps]] if tail else []))
    runs = []
    wd0 = np.broadcast_to(np.asarray(lamdot0, float), lam0.shape)
    for i in range(lam0.shape[0]):
        th = np.concatenate([[lam0[i]], out["theta_samples"][i]] + ([[out["theta"][i]]] if tail else []))
        wd = np.concatenate([[wd0[i]], out["thetadot_samples"][i]] + ([[out["thetadot"][i]]] if tail else []))
        z = np.zeros_like(th)
        q = np.stack([np.cos(0.5 * th), z, z, np.sin(0.5 * th)], axis=1)
        L = np.stack([z, z, C * wd], axis=1)
        runs.append((t, L, q))
    return runs
def run_samples(n_steps: float) -> float:
    """States kept by a run of n_steps steps at `stride_for(n_steps)` (physics.integrator)."""
    from ..physics.integrator import samples_kept

    return samples_kept(n_steps, stride_for(n_steps)) if np.isfinite(n_steps) else MAX_SAMPLES + 1
