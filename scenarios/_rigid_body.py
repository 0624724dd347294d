"""Shared by the ch. 15 scenarios: the body's moments as a parameter and its integration.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import brentq
from ..physics.errors import ParameterError
from ..physics.free_flow import free_flow
from ..physics.inertia import validate_moments
from ..physics.integrator import integrate, samples_kept, step_count
from ..physics.trajectory import Trajectory
from .budget import Cost, trajectory_bytes


MAX_SAMPLES = 20000  # states kept for drawing; the integrator steps finer


INERTIA_PARAM = dict(kind="vec3", minimum=1e-6, maximum=1e6, unit="kg m^2",
                help="principal moments A, B, C about the body x, y, z axes", label="Moments of inertia A, B, C")


# The slowest rate a free body is run at: below ~1e-110 rad/s Euler's quadrature for the flip
# (§808) underflows to NaN, below ~1e-155 the exact period does, and a rate's square vanishes
# below ~1e-162. A body turning once in 1e100 seconds is at rest for any class or paper.
SLOWEST_RATE_RAD_PER_S = 1e-100


def check_rate(name: str, given, rates, fastest: float = 50.0) -> None:
    """Refuse a body's starting rates that are all zero or too slow to compute with."""
    if not np.max(np.abs(np.asarray(rates, float))) >= SLOWEST_RATE_RAD_PER_S:
        raise ParameterError(name, given, f"a rate other than 0 (a body at rest does not move), from "
                                          f"{-fastest:g} to {fastest:g} rad/s and at least "
                                          f"{SLOWEST_RATE_RAD_PER_S:g} rad/s in size")


def check_body(values):
    validate_moments(values["inertia"], "inertia")
    if "omega0" in values:
        check_rate("omega0", values["omega0"], values["omega0"])


def stride_for(duration, step):
    n = max(1, int(np.ceil(duration / step - 1e-9)))
    return max(1, int(np.ceil(n / MAX_SAMPLES)))


def body_cost(values, extra_steps=0.0, series=0) -> Cost:
    """The cost of `integrate_body` over the values' duration at their step (plus `extra_steps`
    of side integrations), keeping `series` new scalar series beside the state."""
    n = step_count(values["duration"], values["step"])
    samples = samples_kept(n, stride_for(values["duration"], values["step"])) if np.isfinite(n) else MAX_SAMPLES + 1
    return Cost(n + extra_steps, samples, trajectory_bytes(samples, series=series))


def integrate_body(values, omega0, torque=None, progress=None):
    I = validate_moments(values["inertia"], "inertia")
    t, L, q = integrate(I, omega0, values["duration"], values["step"], torque_body=torque,
                        stride=stride_for(values["duration"], values["step"]), progress=progress)
    return Trajectory(t, q, L, I)


DRIFT_UNITS = {"energy_rel_drift": "", "momentum_rel_drift": ""}  # largest |E/E₀ − 1|, ||L|/|L₀| − 1|


def drift_metrics(traj):
    de, dl = traj.relative_drift()
    return {"energy_rel_drift": de, "momentum_rel_drift": dl}


def middle_axis_crossings(traj: Trajectory) -> np.ndarray:
    """Times where ω on the middle axis changes sign (the flips), each located to round-off by
    root-finding on the exact free flow from the sample before it (valid for a free body)."""
    I = traj.inertia
    k = int(np.argsort(I)[1])
    w = traj.omega_body[:, k]
    idx = np.nonzero(np.sign(w[:-1]) * np.sign(w[1:]) < 0)[0]
    out = []
    for i in idx:
        L0, q0 = traj.L_body[i], traj.quat_wxyz[i]
        f = lambda d: free_flow(L0, q0, I, d)[0][k]  # noqa: E731
        out.append(traj.t[i] + brentq(f, 0.0, traj.t[i + 1] - traj.t[i], xtol=1e-14, rtol=1e-15))
    return np.array(out)


# the interval between flips (or the polhode period) must be fixed by the starting rates to this
# relative precision, or the run says it is not
PERIOD_PRECISION = 1e-6


def free_body_warnings(traj: Trajectory, fm, what: str = "the interval between flips", step: float | None = None) -> list[str]:
    """Validity of a free body's run: stored samples dense enough for the spin and the polhode
    (aliasing), and 1 − k² fixed by the starting rates near the separatrix. `step`: the
    integrator's, to say what would help (a long run keeps MAX_SAMPLES states whatever the step)."""
    from . import _validity

    out: list[str] = []
    span = float(traj.t[-1] - traj.t[0]) if len(traj.t) else 0.0
    if step is not None and span < 10 * step:  # a run of 0.001 s at a 0.01-s step: two states, nothing to see
        out.append(f"The run ({span:.3g} s) is only {span / step:.2g} steps long (step {step:.3g} s): it holds "
                   f"{len(traj.t)} states, too few to show or measure the motion; set the step to at most "
                   f"{span / 100:.3g} s (a hundredth of the run).")
    if len(traj.t) >= 2:
        spacing = float(np.max(np.diff(traj.t)))
        remedy = None
        if step is not None and spacing > 1.5 * step:
            remedy = (f"A run keeps at most {MAX_SAMPLES:,} states (here {spacing:.3g} s apart, whatever the step): "
                      "shorten the run.")
        w = float(np.max(np.linalg.norm(traj.omega_body, axis=1)))
        spin_period = 2 * np.pi / w if w > 0 else np.inf
        flip = fm.flip_interval if fm is not None else np.inf
        _validity.add(out, _validity.sparse_samples(spacing, spin_period, "the turn of the body about its axis",
                                                    "s", "step", remedy),
                      _validity.sparse_samples(spacing, flip, "the interval between sign changes of ω on the middle "
                                               "axis, half the polhode period", "s", "step", remedy))
    if fm is not None and fm.period_rel_uncertainty > PERIOD_PRECISION:
        out.append(
            f"Near the separatrix: 1 − k² = {fm.m1:.3g} is the difference of two terms "
            f"{fm.m1_rel_uncertainty / (4 * np.finfo(float).eps):.2g} times larger, so the rounding of the starting rates alone leaves {what} uncertain by "
            f"{fm.period_rel_uncertainty:.1e} (relative), more than {PERIOD_PRECISION:g}: start nearer a principal axis "
            "or farther from the separatrix to fix it.")
    return out
