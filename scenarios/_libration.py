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


def run_samples(n_steps: float) -> float:
    """States kept by a run of n_steps steps at `stride_for(n_steps)` (physics.integrator)."""
    from ..physics.integrator import samples_kept

    return samples_kept(n_steps, stride_for(n_steps)) if np.isfinite(n_steps) else MAX_SAMPLES + 1
