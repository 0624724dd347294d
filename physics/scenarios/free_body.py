"""Chapter 15: the body left to itself (§805, §808), the middle-axis flip, and the first
motion of a body at rest under given moments (§806)."""
from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from ..euler_ch15 import flip_interval_808, initial_axis, vis_viva
from ..free_flow import free_flow
from ..inertia import validate_moments
from ..integrator import integrate
from ..params import Param, ParameterError
from ..torque_free_exact import free_motion
from ..trajectory import Trajectory
from .base import Comparison, Result, Scenario, register

MAX_SAMPLES = 20000  # states kept for drawing; the integrator steps finer

_INERTIA = dict(kind="vec3", minimum=1e-6, maximum=1e6, unit="kg m^2",
                help="principal moments A, B, C about the body x, y, z axes")


def _check_body(values):
    validate_moments(values["inertia"], "inertia")


def _stride(duration, step):
    n = max(1, int(np.ceil(duration / step - 1e-9)))
    return max(1, int(np.ceil(n / MAX_SAMPLES)))


def _run(values, omega0, torque=None, progress=None):
    I = validate_moments(values["inertia"], "inertia")
    t, L, q = integrate(I, omega0, values["duration"], values["step"], torque_body=torque,
                        stride=_stride(values["duration"], values["step"]), progress=progress)
    return Trajectory(t, q, L, I)


def _drift_metrics(traj):
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


# --- free-tumble -------------------------------------------------------------------------

def _free_tumble(values, progress=None):
    w0 = np.array(values["omega0"])
    if not np.any(w0):
        raise ParameterError("omega0", values["omega0"], "not all zero (a body at rest stays at rest)")
    traj = _run(values, w0, progress=progress)
    I = traj.inertia
    m = _drift_metrics(traj)
    m["energy_J"] = float(traj.energy[0])
    m["angular_momentum_kg_m2_per_s"] = float(traj.momentum_norm[0])
    comps = [Comparison("vis viva A x² + B y² + C z² (§805: constant)", float(vis_viva(w0, I)),
                        float(2 * traj.energy[-1]), float(vis_viva(w0, I)), "J")]
    try:
        fm = free_motion(I, w0)
        m["polhode_period_s"] = fm.polhode_period
        circ = "ABC"[fm.circulation_axis]
        # Euler: §808's quadrature gives the time between two sign changes of ω on the middle axis,
        # half a polhode period; simulated: twice the mean spacing of those sign changes in the run
        vals, counts = np.unique(I, return_counts=True)
        if len(vals) == 3:
            euler = 2.0 * flip_interval_808(I, w0)
            how = "Euler: twice the §808 quadrature"
        else:  # two equal moments: §808's reduction divides by their difference; his equations with
            # A = B give dz = 0 and x, y turning at the constant rate (C − A) z / A: a circle
            s_ax = int(np.nonzero(I == vals[counts == 1][0])[0][0])
            a_mom = float(vals[counts == 2][0])
            euler = 2 * np.pi * a_mom / abs((I[s_ax] - a_mom) * w0[s_ax])
            how = "Euler: §808's equations with two equal moments, 2πA/|(C − A) ω_C|"
        euler = float(euler) if np.isfinite(euler) else None
        tc = middle_axis_crossings(traj)
        measured = 2.0 * float(np.mean(np.diff(tc))) if len(tc) >= 2 else None
        if euler is not None:
            m["polhode_period_euler_808_s"] = euler
        if measured is not None:
            m["polhode_period_measured_s"] = measured
        comps.append(Comparison("polhode period", euler, measured, fm.polhode_period, "s",
                                f"ω circulates about the {circ} axis; {how}; modern: 4K(k)/λ, k² = {fm.m:.6g}" +
                                ("" if measured is not None else "; the run is too short to see two crossings")))
    except ValueError as e:  # a permanent rotation or a sphere has no polhode
        comps.append(Comparison("polhode", None, None, None, "", str(e)))
    return Result("free-tumble", values, traj, m, comps,
                  plot_series={"ω₁": traj.omega_body[:, 0], "ω₂": traj.omega_body[:, 1],
                               "ω₃": traj.omega_body[:, 2]})


register(Scenario(
    name="free-tumble",
    title="The body left to itself",
    section="§805, §808",
    group="ch. 15",
    summary=("A body with three different moments A < B < C, thrown spinning and left alone. Look at "
            "the two arrows: the angular momentum L (purple) stays fixed in space while the rotation "
            "axis ω (orange) wanders. On the body, ω traces a closed curve, the polhode (yellow); in "
            "space its tip runs on a fixed plane, the invariable plane, tracing the herpolhode (cyan). "
            "Euler's vis viva (the energy, §805) and |L| stay constant."),
    params=(
        Param("inertia", (2.0, 3.0, 4.0), **_INERTIA),
        Param("omega0", (1.0, 0.5, 1.5), kind="vec3", minimum=-50, maximum=50, unit="rad/s",
              help="initial angular velocity on the body axes"),
        Param("duration", 20.0, 0.0, 1e6, "s", "length of the run", exclusive_min=True, step=1.0),
        Param("step", 0.01, 0.0, 10.0, "s", "integrator step", exclusive_min=True, step=0.001),
    ),
    simulate_fn=_free_tumble,
    check=_check_body,
    euler_formula=("dx + (cc − bb)/aa · yz dt = 0, and the same for y and z in turn (§808)\n"
                   "aa·xx + bb·yy + cc·zz = const (vis viva, §805)\n"
                   "x, y, z: rates about the principal axes; aa, bb, cc: the moments A, B, C"),
    presets=(
        ("Tumble: ω wanders widely", {}),
        ("Tumble: spin near the long axis, a small polhode", {"omega0": (2.0, 0.3, 0.3)}),
        ("Tumble: spin near the short axis, a small polhode", {"omega0": (0.3, 0.3, 2.0)}),
        ("Symmetric top (A = B): a steady cone", {"inertia": (3.0, 3.0, 4.0), "omega0": (1.0, 0.0, 1.5)}),
    ),
))


# --- middle-axis-flip --------------------------------------------------------------------

def _check_flip(values):
    I = validate_moments(values["inertia"], "inertia")
    if values["spin"] == 0:  # found by tests/test_fuzz.py: the error named "omega0", not a parameter here
        raise ParameterError("spin", values["spin"], "nonzero (a body at rest does not flip), allowed range [-50, 50] rad/s")
    s = np.sort(I)
    if not (s[0] < s[1] < s[2]):
        raise ParameterError("inertia", values["inertia"],
                             "three different moments (with two equal there is no middle axis)")


def _middle_axis_flip(values, progress=None):
    I = validate_moments(values["inertia"], "inertia")
    lo, mid, hi = np.argsort(I)
    w0 = np.zeros(3)
    w0[mid] = values["spin"]
    w0[lo] = w0[hi] = values["perturbation"] * values["spin"]
    traj = _run(values, w0, progress=progress)
    m = _drift_metrics(traj)
    fm = free_motion(I, w0)
    exact = fm.flip_interval
    euler = flip_interval_808(I, w0)
    tc = middle_axis_crossings(traj)
    measured = float(np.mean(np.diff(tc))) if len(tc) >= 2 else float("nan")
    m.update(flip_interval=measured, flip_interval_exact=exact, flip_interval_euler_808=euler,
             flips_seen=float(len(tc)))
    notes = []
    if len(tc) < 2:
        notes.append(f"fewer than two flips in {values['duration']:g} s: run longer than {2 * exact:.3g} s "
                     "to measure the interval")
    comps = [Comparison("interval between flips", euler, measured, exact, "s",
                        "Euler: §808 quadrature; modern: 2K(k)/λ (Jacobi)")]
    return Result("middle-axis-flip", values, traj, m, comps, notes,
                  plot_series={"ω on middle axis": traj.omega_body[:, mid],
                               "ω on smallest-moment axis": traj.omega_body[:, lo],
                               "ω on largest-moment axis": traj.omega_body[:, hi]})


register(Scenario(
    name="middle-axis-flip",
    title="Brick: the flip about the middle axis",
    section="§805, §808",
    group="ch. 15",
    summary=("Spin a brick (or a tennis racket) about the axis of its middle moment B and it cannot "
            "stay there: after a quiet while it turns over, then again, at regular intervals (the "
            "Dzhanibekov or tennis-racket effect). Watch the body flip while L stays fixed. The time "
            "between flips follows from Euler's quadrature of §808 (in modern terms 2K(k)/λ, with "
            "Jacobi's complete elliptic integral K); the smaller the first nudge, the longer the wait."),
    params=(
        Param("inertia", (1.0, 2.0, 3.0), **_INERTIA),
        Param("spin", 6.0, -50.0, 50.0, "rad/s", "initial rate about the middle axis", step=0.1),
        Param("perturbation", 0.01, 1e-9, 0.5, "1",
              "rates about the other two axes, as a fraction of the spin", step=0.001),
        Param("duration", 30.0, 0.0, 1e6, "s", "length of the run", exclusive_min=True, step=1.0),
        Param("step", 0.005, 0.0, 10.0, "s", "integrator step", exclusive_min=True, step=0.001),
    ),
    simulate_fn=_middle_axis_flip,
    check=_check_flip,
    euler_formula=("dt = −𝔄 dx √(𝔅ℭ) / [ √(𝔄xx − 𝔄a² + 𝔅b²) · √(𝔄xx − 𝔄a² + ℭc²) ] (§808)"),
    presets=(
        ("Brick: the flip", {}),
        ("Brick: a big nudge, frequent flips", {"perturbation": 0.2}),
        ("Brick: a tiny nudge (10⁻⁶), rare flips", {"perturbation": 1e-06}),
        ("Brick: nearly symmetric, slow flips", {"inertia": (1.0, 1.9, 2.0)}),
    ),
))


# --- initial-axis ------------------------------------------------------------------------

def _check_initial(values):
    _check_body(values)
    if not np.any(values["torque"]):
        raise ParameterError("torque", values["torque"], "not all zero (with no moment the body stays at rest)")


def _initial_axis(values, progress=None):
    I = validate_moments(values["inertia"], "inertia")
    tau = np.array(values["torque"])
    traj = _run(values, np.zeros(3), torque=tau, progress=progress)
    try:
        axis_e, acc_e = initial_axis(tau, I)
    except ValueError:  # a torque so small that I⁻¹τ underflows (1e-200): found while fuzzing
        raise ParameterError("torque", values["torque"], "not practically zero (|component| ≳ 1e-150), "
                             "each component in [-1000, 1000] N m") from None
    # the numerical start: one short step from rest (ω = ω̇₀t + O(t³), so the axis is O(t²) off)
    h = values["probe_time"]
    _, L, _ = integrate(I, np.zeros(3), h, h / 4, torque_body=tau)
    w = L[-1] / I
    axis_n = w / np.linalg.norm(w)
    acc_n = float(np.linalg.norm(w) / h)
    ang = float(np.arctan2(np.linalg.norm(np.cross(axis_e, axis_n)), axis_e @ axis_n))
    m = {
        "axis_angle_error_rad": ang,
        "angular_acceleration_euler_rad_per_s2": acc_e,
        "angular_acceleration_simulated_rad_per_s2": acc_n,
        "axis_cos_alpha_euler": float(axis_e[0]), "axis_cos_beta_euler": float(axis_e[1]),
        "axis_cos_gamma_euler": float(axis_e[2]),
        "axis_cos_alpha_simulated": float(axis_n[0]), "axis_cos_beta_simulated": float(axis_n[1]),
        "axis_cos_gamma_simulated": float(axis_n[2]),
    }
    comps = [Comparison("angular acceleration dγ'/dt", acc_e, acc_n, acc_e, "rad/s²",
                        f"simulated over the first {h:g} s"),
             Comparison("angle between Euler's axis and the numerical one", 0.0, ang, 0.0, "rad",
                        "O(t²) from the gyroscopic term, which Euler's first instant omits")]
    return Result("initial-axis", values, traj, m, comps,
                  plot_series={"|ω|": np.linalg.norm(traj.omega_body, axis=1)})


register(Scenario(
    name="initial-axis",
    title="A body at rest set turning",
    section="§806, §807",
    group="ch. 15",
    summary=("A body at rest is given constant moments (torques) P, Q, R about its principal axes. It "
            "does not start to turn about the axis of the torque, but about the axis whose direction "
            "cosines are in the ratio P/A : Q/B : R/C (§806), tilted toward the axes that are easiest "
            "to turn, with angular acceleration √(P²/A² + Q²/B² + R²/C²). As it gains speed the axis "
            "wanders away."),
    params=(
        Param("inertia", (1.0, 2.0, 2.5), **_INERTIA),
        Param("torque", (1.0, 1.0, 1.0), kind="vec3", minimum=-1e3, maximum=1e3, unit="N m",
              help="moments P, Q, R about the body axes (constant in the body)"),
        Param("probe_time", 1e-3, 0.0, 1.0, "s", "how long after the start the axis is measured",
              exclusive_min=True, step=1e-4),
        Param("duration", 5.0, 0.0, 1e5, "s", "length of the run", exclusive_min=True, step=0.5),
        Param("step", 0.002, 0.0, 1.0, "s", "integrator step", exclusive_min=True, step=0.001),
    ),
    simulate_fn=_initial_axis,
    check=_check_initial,
    euler_formula=("cos α : cos β : cos γ = P/aa : Q/bb : R/cc (§806)\n"
                   "α, β, γ: angles of the starting axis with the principal axes; aa, bb, cc: the moments A, B, C"),
    presets=(
        ("Start: equal torques, an unequal axis", {}),
        ("Start: torque at 45° between A and B, axis at 27°", {"torque": (1.0, 1.0, 0.0)}),
        ("Start: torque about C only, turns about C", {"torque": (0.0, 0.0, 1.0)}),
    ),
))
