"""Structure-preserving integrator for a rigid body under torques (Lie–Poisson splitting).

The body's motion splits into the free rigid body, whose flow is computed exactly
(`free_flow.drift`: keeps E, |L| and the spatial L to round-off), and the torques, which enter
as kicks L ← L + τ·δt with the attitude frozen (Touma & Wisdom 1994). For torques that depend
on the attitude only (a gravity gradient) the kick is the exact flow of the potential, so the
composition is symplectic:
  - "strang":   kick(h/2) · free(h) · kick(h/2), second order;
  - "yoshida4": Yoshida's triple jump of it, fourth order.
The error is proportional to the torque: a free body is integrated exactly at any step.

Torques supported in the compiled loop: a constant body-frame torque (P, Q, R) and the
first-order gravity gradient of point masses (Euler §815, MacCullagh):
    τ_body = 3GM/s⁵ · (s × I s),   s the body-frame vector from the centre to the mass,
and, optionally, the next term of the body's field, its degree-3 harmonics (`Degree3Field`;
physics.gravity_field), acted on by the same point masses.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import numba as nb
import numpy as np

from . import quaternion as quat
from .free_flow import drift, prepare, rotate_inverse
from .gravity_field import degree3_torque_into
from .inertia import validate_moments
from .errors import ParameterError, StepTooLarge

_W1 = 1.0 / (2.0 - 2.0 ** (1.0 / 3.0))
_W0 = -(2.0 ** (1.0 / 3.0)) * _W1

# stage j: kick by kick[j]·h at time t + at[j]·h, then drift by drift[j]·h
SCHEMES = {
    "strang": dict(kick=np.array([0.5, 0.5]), drift=np.array([1.0, 0.0]), at=np.array([0.0, 1.0]), order=2),
    "yoshida4": dict(
        kick=np.array([_W1 / 2, (_W1 + _W0) / 2, (_W0 + _W1) / 2, _W1 / 2]),
        drift=np.array([_W1, _W0, _W1, 0.0]),
        at=np.array([0.0, _W1, _W1 + _W0, 1.0]),
        order=4,
    ),
}


@dataclass(frozen=True)
class PointMass:
    """A mass pulling on the body: gm = G·M, position(t) → (N,3) inertial vector from the
    body's centre to the mass at the times t (N,)."""

    gm: float
    position: Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class Degree3Field:
    """The body's degree-3 gravity field: unnormalised coefficients (C30, C31, S31, C32, S32,
    C33, S33) on the principal axes (C30 = −J3), and `mr2_over_c_times_r` = (M R²/C)·R, the
    scale that turns G·M_point into the torque divided by C (physics.gravity_field; R in the
    unit of the positions)."""

    coefficients: Sequence[float]
    mr2_over_c_times_r: float


@nb.njit(cache=True, nogil=True)
def _torque_into(t, q, I, tq, pos, gm, c3, k3):
    """The body-frame torque at attitude q, written into t (no array made per kick)."""
    t[0], t[1], t[2] = tq[0], tq[1], tq[2]
    for p in range(gm.shape[0]):
        s = rotate_inverse(q, pos[p])
        r2 = s[0] * s[0] + s[1] * s[1] + s[2] * s[2]
        f = 3.0 * gm[p] / (r2 * r2 * np.sqrt(r2))
        Is0, Is1, Is2 = I[0] * s[0], I[1] * s[1], I[2] * s[2]
        t[0] += f * (s[1] * Is2 - s[2] * Is1)
        t[1] += f * (s[2] * Is0 - s[0] * Is2)
        t[2] += f * (s[0] * Is1 - s[1] * Is0)
        if k3 != 0.0:
            degree3_torque_into(t, s, c3, gm[p] * k3)


@nb.njit(cache=True, nogil=True)
def _run(L, q, I, h, n_steps, stride, kick, drift_c, tq, has_tq, pos, gm, c3, k3, out_L, out_q, last, ip, c, tab):
    """n_steps steps of the splitting; every `stride` steps the state goes to out_L, out_q
    (row 0 is the initial state), the final state to `last` (L then q). pos: (n_steps, n_stages,
    n_masses, 3). (ip, c, tab): the free flow's constants, `prepare(L0, I, h)` of the run's first
    state (used when no torque acts: the orbit's invariants, k² and 1 − k², are then those of
    the start for the whole run, not recomputed from states where rounding has touched them).

    Returns nothing: a compiled function that returns arrays has numba run Python code to box
    them, and a Ctrl-C that arrived during the loop is raised inside that code, where numba
    cannot pass it on (SystemError "... returned a result with an exception set"). With nothing
    to box, the interrupt surfaces in `integrate`, between chunks."""
    out_L[0] = L
    out_q[0] = q
    free = (not has_tq) and gm.shape[0] == 0
    tau = np.empty(3)
    row = 1
    for k in range(n_steps):
        if free:
            L, q = drift(L, q, I, h, ip, c, tab)
        else:
            for j in range(kick.shape[0]):
                _torque_into(tau, q, I, tq, pos[k, j], gm, c3, k3)
                dt = kick[j] * h
                L = np.array((L[0] + dt * tau[0], L[1] + dt * tau[1], L[2] + dt * tau[2]))
                if drift_c[j] != 0.0:
                    ipj, cj, tabj = prepare(L, I, drift_c[j] * h)
                    L, q = drift(L, q, I, drift_c[j] * h, ipj, cj, tabj)
        if (k + 1) % stride == 0:
            out_L[row] = L
            out_q[row] = q
            row += 1
    last[:3] = L
    last[3:] = q


MAX_STEPS_PER_RUN = 1e15  # beyond any budget: guards the compiled loop's integer counters


def step_count(duration: float, step: float) -> float:
    """Steps `integrate` takes over `duration` at (at most) `step`: a whole number of steps fills
    the duration. A float (inf for an absurd ratio), so that a budget can be checked before any
    integer is formed."""
    if not duration > 0:
        return 0.0
    ratio = duration / step
    if not np.isfinite(ratio) or ratio > MAX_STEPS_PER_RUN:
        return float("inf")
    return float(max(1, int(np.ceil(ratio - 1e-9))))


def samples_kept(n_steps: float, stride: int) -> float:
    """States `integrate` returns for n_steps steps kept every `stride`: the initial state, one
    per `stride` steps, and the last state when it is not on the stride."""
    if not np.isfinite(n_steps):
        return float("inf")
    n, s = int(n_steps), max(1, int(stride))
    return float(1 + n // s + (1 if n % s else 0))


def integrate(
    inertia,
    omega0,
    duration: float,
    step: float,
    q0=quat.IDENTITY,
    torque_body: Sequence[float] | None = None,
    masses: Sequence[PointMass] = (),
    scheme: str = "strang",
    stride: int = 1,
    t0: float = 0.0,
    progress: Callable[[float], None] | None = None,
    chunk_steps: int = 20000,
    field3: Degree3Field | None = None,
):
    """Integrate from t0 over `duration` in steps of (at most) `step`.

    Returns (t, L_body, q): the states every `stride` steps (the last state always included).
    The step is shortened so that a whole number of steps fills the duration.
    """
    I = validate_moments(inertia)
    if not (np.isfinite(step) and step > 0):
        raise ParameterError("step", step, "a finite step > 0")
    if not (np.isfinite(duration) and duration >= 0):
        raise ParameterError("duration", duration, "a finite duration >= 0")
    w0 = np.asarray(omega0, float)
    if w0.shape != (3,) or not np.all(np.isfinite(w0)):
        raise ParameterError("omega0", omega0, "three finite numbers")
    sch = SCHEMES[scheme]
    if step_count(duration, step) > MAX_STEPS_PER_RUN:  # 1e-300 s steps: refused, not an overflow
        raise ParameterError("step", step, f"at most {MAX_STEPS_PER_RUN:.0e} steps per run "
                             f"(duration {duration:g} / step {step:g})")
    n_steps = int(step_count(duration, step))
    h = duration / n_steps if n_steps else step
    stride = max(1, int(stride))
    tq = np.zeros(3) if torque_body is None else np.asarray(torque_body, float)
    has_tq = torque_body is not None and bool(np.any(tq != 0))
    gm = np.array([m.gm for m in masses], float)
    c3 = np.zeros(7) if field3 is None else np.asarray(field3.coefficients, float).reshape(7)
    k3 = 0.0 if field3 is None else float(field3.mr2_over_c_times_r)
    L = I * w0
    q = quat.normalize(np.asarray(q0, float))
    t_out = [np.array([t0])]
    L_out = [L[None]]
    q_out = [q[None]]
    done = 0
    consts = None
    while done < n_steps:
        if stride <= chunk_steps:  # whole strides a chunk: every kept state of the chunk returned
            n = min(chunk_steps - chunk_steps % stride, n_steps - done)
            every = stride
        else:
            # kept states further apart than a chunk (a long run at a fine step): pieces of at most
            # a chunk, each ending at or before the next kept state, so that the progress line and
            # a stop (Ctrl-C) are honoured every chunk_steps steps, not once per kept state
            n = min(chunk_steps, stride - done % stride, n_steps - done)
            every = n
        if masses:
            tk = t0 + h * (done + np.arange(n)[:, None] + sch["at"][None, :])
            pos = np.stack([np.asarray(m.position(tk.ravel()), float).reshape(n, len(sch["at"]), 3) for m in masses], axis=2)
        else:
            pos = np.zeros((n, len(sch["at"]), 0, 3))  # no mass: an empty axis, indexable at every step
        rows = n // every
        oL = np.empty((rows + 1, 3))
        oq = np.empty((rows + 1, 4))
        last = np.empty(7)
        try:
            if consts is None:
                consts = prepare(L, I, h)  # the free orbit's constants, from the first state, once
            _run(L, q, I, h, n, every, sch["kick"], sch["drift"], tq, has_tq, pos, gm, c3, k3, oL, oq, last, *consts)
            L, q = last[:3].copy(), last[3:].copy()
        except ZeroDivisionError:  # found by tests/test_fuzz.py: spin 1e-155 with moments ~1e-6 underflows
            raise ParameterError("parameters", "these values", "rates so small that their squares underflow "
                                 "(|ω| below ~1e-150): practically at rest; use larger rates or torques") from None
        except StepTooLarge:  # free_flow.prepare refuses a step far too large for the spin reached
            raise ParameterError("step", step, f"too large for the spin this run reaches near t={t0 + h * done:.4g} "
                                 "(thousands of turns per step); use a smaller step, torque or spread of moments") from None
        if every == stride or (done + n) % stride == 0:
            t_out.append(t0 + h * (done + every * np.arange(1, rows + 1)))
            L_out.append(oL[1:])
            q_out.append(oq[1:])
        done += n
        if done == n_steps and done % stride:  # the last, unaligned state
            t_out.append(np.array([t0 + h * done]))
            L_out.append(L[None])
            q_out.append(q[None])
        if progress is not None:
            progress(done / n_steps)
    return np.concatenate(t_out), np.concatenate(L_out), np.concatenate(q_out)
