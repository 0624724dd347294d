"""A body at rest set turning by given moments (ch. 15, §806–807): the starting axis has
cosines ∝ P/A : Q/B : R/C.

Check row E3.
"""
from __future__ import annotations

import numpy as np
from ..physics.euler_ch15 import initial_axis
from ..physics.inertia import validate_moments
from ..physics.integrator import integrate
from ..physics.params import Param, ParameterError
from .drawing import Arrows, Camera, Label, Segments, _project, standard
from .base import Comparison, Run, Scenario, register
from . import _validity
from scipy.integrate import solve_ivp
from ..physics.euler_equations import omega_dot
from .checks import register_check
from ._rigid_body import INERTIA_PARAM, body_cost, check_body, integrate_body


def _check_initial(values):
    check_body(values)
    if not np.any(values["torque"]):
        raise ParameterError("torque", values["torque"], "not all zero (with no moment the body stays at rest)")


def _initial_axis(values, progress=None):
    I = validate_moments(values["inertia"], "inertia")
    tau = np.array(values["torque"])
    traj = integrate_body(values, np.zeros(3), torque=tau, progress=progress)
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
    comps = [Comparison("how fast the spin grows, dγ'/dt (γ' = |ω|)", acc_e, acc_n, acc_e, "rad/s²",
                        f"simulated over the first {h:g} s"),
             Comparison("angle between Euler's axis and the numerical one", 0.0, ang, 0.0, "rad",
                        "O(t²) from the gyroscopic term, which Euler's first instant omits")]
    # the step against the fastest period: the turn of the body at the largest rate it reaches
    w_max = float(np.max(np.linalg.norm(traj.omega_body, axis=1)))
    warnings = _validity.add([], _validity.coarse_step(values["step"], 2 * np.pi / w_max if w_max > 0 else np.inf,
                                                       "the turn of the body at the largest rate it reaches", "s", "step"))
    return Run("initial-axis", values, traj, m, comps, warnings=warnings,
                  plot_series={"|ω|": np.linalg.norm(traj.omega_body, axis=1)})


TORQUE_COLOR = (45, 45, 45)  # apart from ω (orange) and L (purple), which starts along the torque
EULER_AXIS_COLOR = (0, 150, 140)


def _draw(run, spec, view):
    """The body and Poinsot's picture, with what §806 is about, both fixed in the body: the torque
    (P, Q, R) as an arrow, and the axis Euler predicts the body starts to turn about (cosines
    ∝ P/A : Q/B : R/C) as a line through the centre. At the start ω (orange) lies on Euler's axis,
    not on the torque; then it wanders off as the body gains speed."""
    d = standard(run, spec, view)
    tr = run.trajectory
    tau = np.asarray(run.params["torque"], float)
    t_hat = tau / np.linalg.norm(tau)
    axis, _ = initial_axis(tau, tr.inertia)
    axis = axis / np.linalg.norm(axis)
    reach = 1.7
    # name the axis at the end the camera sees farther from the body, its text running outward
    ends, _ = _project(np.array([reach * axis, -reach * axis, np.zeros(3)]), d.camera)
    far = 0 if np.linalg.norm(ends[0] - ends[2]) >= np.linalg.norm(ends[1] - ends[2]) else 1
    tip = (reach + 0.05) * axis * (1 if far == 0 else -1)
    side = "center-left" if ends[far][0] >= ends[2][0] else "center-right"
    d.add(Arrows(name="body/torque", origins=np.zeros((1, 3)), vectors=(1.45 * t_hat)[None], colors=(TORQUE_COLOR,),
                 shaft_radius=0.03, head_radius=0.075, head_length=0.14),
          Label(name="body/torque/label", text="torque (P, Q, R)", position=1.58 * t_hat, anchor="bottom-right"),
          Segments(name="body/euler_axis", points=np.array([[-reach * axis, reach * axis]], np.float32),
                   colors=EULER_AXIS_COLOR, thickness=0.02),
          Label(name="body/euler_axis/label", text="Euler's axis: P/A : Q/B : R/C (§806)", position=tip, anchor=side))
    return d
def _cost(values):
    """The run over `duration` at `step`, the probe run (probe_time in 4 steps) and |ω| kept."""
    return body_cost(values, extra_steps=4, series=1)


register(Scenario(
    series_units={r"\|ω\|": "rad/s"},
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
        Param("inertia", (1.0, 2.0, 2.5), **INERTIA_PARAM),
        Param("torque", (1.0, 1.0, 1.0), kind="vec3", minimum=-1e3, maximum=1e3, unit="N m",
              help="moments P, Q, R about the body axes (constant in the body)",
              label="Torques P, Q, R about the body axes"),
        # from a nanosecond: at 1e-300 s the rate ω = τt/I squared underflows, and its direction
        # was 0/0
        Param("probe_time", 1e-3, 1e-9, 1.0, "s", "how long after the start the axis is measured",
              step=1e-4, label="Axis measured after", advanced=True),
        Param("duration", 5.0, 0.0, 1e5, "s", "length of the run", exclusive_min=True, step=0.5,
              label="Length of the run"),
        Param("step", 0.002, 0.0, 1.0, "s", "integrator step", exclusive_min=True, step=0.001,
              label="Integrator step", advanced=True),
    ),
    camera=Camera((2.6, 2.6, 1.9), (0.0, 0.0, 0.0)),
    simulate_fn=_initial_axis,
    draw=_draw,
    cost_fn=_cost,
    check=_check_initial,
    euler_formula=("cos α : cos β : cos γ = P/aa : Q/bb : R/cc (§806)\n"
                   "α, β, γ: angles of the starting axis with the principal axes; aa, bb, cc: the moments A, B, C"),
    presets=(
        ("Start: equal torques, an unequal axis", {}),
        ("Start: torque at 45° between A and B, axis at 27°", {"torque": (1.0, 1.0, 0.0)}),
        ("Start: torque about C only, turns about C", {"torque": (0.0, 0.0, 1.0)}),
    ),
    metric_units={r"axis_cos_(alpha|beta|gamma)_(euler|simulated)": ""},  # direction cosines of the axis
))


@register_check("E3", "body at rest: axis ∝ P/A : Q/B : R/C and dγ'/dt", "§806")
def e3():
    I = np.array([1.0, 2.0, 2.5])
    tau = np.array([1.0, -0.7, 0.4])
    axis, acc = initial_axis(tau, I)
    h = 1e-2
    _, L, _ = integrate(I, np.zeros(3), h, h / 8, torque_body=tau)
    w = L[-1] / I
    # independent reference: Euler's full equations from rest by DOP853 at tight tolerance
    ref = solve_ivp(lambda t, y: omega_dot(y, I, tau), (0, h), np.zeros(3), method="DOP853",
                    rtol=1e-13, atol=1e-16).y[:, -1]

    def angle(a, b):
        return float(np.arctan2(np.linalg.norm(np.cross(a, b)), a @ b))

    # Euler's first instant against the finite start: ω(t) = ω̇₀t + O(t³), so the axis moves
    # O((|ω̇₀|t)²) ≈ 1e-4 and |ω|/t changes by the same order
    euler_gap = max(angle(axis, ref), abs(np.linalg.norm(ref) / h / acc - 1))
    sim_err = max(angle(w, ref), float(np.linalg.norm(w - ref) / np.linalg.norm(ref)))
    tol = (acc * h) ** 2
    return dict(euler=acc, simulated=float(np.linalg.norm(w) / h), modern=float(np.linalg.norm(ref) / h),
                rel_error=euler_gap, tolerance=tol, passed=bool(euler_gap <= tol and sim_err <= 1e-6),
                unit="rad/s²",
                note=f"Euler's §806 axis and rate vs DOP853 of the full equations after {h:g} s: {euler_gap:.2g}, "
                     f"within the (|ω̇₀|t)² = {tol:.2g} his first instant neglects (ω = ω̇₀t + O(t³)); "
                     f"theoria vs DOP853 {sim_err:.2g} (Strang splitting error at h/8, must be ≤ 1e-6)")
