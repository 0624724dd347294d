"""Many free rigid bodies advanced together (sweeps over moments or starting spins).

Each body takes exactly the steps of the single-body integrator (`physics.integrator`: the exact
torque-free flow of `physics.free_flow`, Jacobi's elliptic functions for L and the precession
quadrature for the attitude), so a batch reproduces single runs bit for bit; the batch is spread
over the cores (numba `prange`). Nothing is shared between free bodies but the step: the gain is
the parallel loop and one call instead of N.
"""
from __future__ import annotations

import numba as nb
import numpy as np

from .errors import ParameterError
from .inertia import validate_moments
from .free_flow import prepare
from .integrator import SCHEMES, _run


@nb.njit(parallel=True, cache=True, nogil=True)
def _batch(L, q, I, h, n_steps, stride, kick, drift_c, out_L, out_q):
    n = L.shape[0]
    tq = np.zeros(3)
    pos = np.zeros((1, 1, 1, 3))
    gm = np.zeros(0)
    c3 = np.zeros(7)
    for i in nb.prange(n):
        Li0, Ii = L[i].copy(), I[i].copy()
        ip, c, tab = prepare(Li0, Ii, h)  # the free orbit's constants from the first state, as the integrator
        last = np.empty(7)
        _run(Li0, q[i].copy(), Ii, h, n_steps, stride, kick, drift_c, tq, False, pos, gm, c3, 0.0,
             out_L[i], out_q[i], last, ip, c, tab)
        L[i] = last[:3]
        q[i] = last[3:]


def free_body_batch(inertia, omega0, q0, duration, step, stride=1):
    """N free bodies: inertia (N, 3) or (3,), omega0 (N, 3) body-frame rates, q0 (N, 4) or (4,)
    attitudes (w, x, y, z). Returns (t, L (N, rows, 3), q (N, rows, 4)) at t = 0 and every `stride`
    steps, as `physics.integrator.integrate` for each body (whole steps of at most `step`; a
    duration that is not a whole number of strides ends on the last whole stride)."""
    w = np.atleast_2d(np.asarray(omega0, float))
    N = w.shape[0]
    I = np.broadcast_to(np.asarray(inertia, float), (N, 3)).copy()
    for i in range(N):
        I[i] = validate_moments(I[i])
    qq = np.broadcast_to(np.asarray(q0, float), (N, 4)).copy()
    qq /= np.linalg.norm(qq, axis=1)[:, None]
    if not (np.isfinite(step) and step > 0):
        raise ParameterError("step", step, "a finite step > 0")
    if not (np.isfinite(duration) and duration > 0):
        raise ParameterError("duration", duration, "a finite duration > 0")
    n_steps = max(1, int(np.ceil(duration / step - 1e-9)))
    h = duration / n_steps
    stride = max(1, int(stride))
    rows = n_steps // stride
    n_steps = rows * stride
    L = I * w
    out_L = np.empty((N, rows + 1, 3))
    out_q = np.empty((N, rows + 1, 4))
    sch = SCHEMES["strang"]
    _batch(L, qq, I, h, n_steps, stride, sch["kick"], sch["drift"], out_L, out_q)
    return h * stride * np.arange(rows + 1), out_L, out_q
