"""How good is Euler's first-order torque (§815–818)? The torque 3GM/s³·ŝ×Iŝ and the §818 force
on the centre against an exact integration over a homogeneous ellipsoid, as F comes in.

Check rows E5 (the torque's error falls as (size/s)²) and E6 (the force's).
"""
from __future__ import annotations

import numpy as np
from ..physics import quaternion as quat
from ..physics.params import Param, ParameterError
from ..physics.trajectory import Trajectory
from .drawing import Camera
from .base import Comparison, Run, Scenario, register
from .budget import Cost, trajectory_bytes
from ..physics.gravity_gradient import (fitted_order, force_error_vs_size, torque_error_vs_size)
from .checks import register_check
from .drawing import Label, Option, Segments, Sphere, unit
from ._ch16_drawing import F_COLOR, body_scene, line_from_centre, readout_position


def _gg_accuracy(values, progress=None):
    from ..physics.gravity_gradient import fitted_order, force_error_vs_size, torque_error_vs_size
    from ..physics.inertia import ellipsoid_moments

    a = np.array(values["semi_axes"], float)
    d = np.array(values["direction"], float)
    if not np.linalg.norm(d) > 0:
        raise ParameterError("direction", values["direction"], "not the zero vector")
    if np.ptp(a) == 0:  # a homogeneous sphere: no torque, and its pull is a point mass's exactly
        raise ParameterError("semi_axes", values["semi_axes"], "semi-axes not all equal (a sphere feels no "
                             "torque and pulls as a point mass: there is no error to measure)")
    u = d / np.linalg.norm(d)
    ratios = np.geomspace(values["min_ratio"], values["max_ratio"], values["n_points"])
    et = torque_error_vs_size(a, u, ratios)
    ef = force_error_vs_size(a, u, ratios)
    I = ellipsoid_moments(a)
    # the "time" axis of this trajectory is size/distance, so every plot is error vs size/s
    n = len(ratios)
    traj = Trajectory(ratios, np.tile(quat.IDENTITY, (n, 1)), np.zeros((n, 3)), I, time_unit="size/distance",
                      bodies={"attractor": u[None, :] * a.max() / ratios[:, None]})
    small = ratios <= 0.1 * ratios.max() if n > 2 else np.ones(n, bool)
    sel = small if small.sum() >= 2 else np.ones(n, bool)
    m = {"torque_error_order": fitted_order(ratios[sel], et[sel]), "force_error_order": fitted_order(ratios[sel], ef[sel]),
         "torque_rel_error_at_max_ratio": float(et[-1]), "force_rel_error_at_max_ratio": float(ef[-1]),
         "torque_rel_error_at_min_ratio": float(et[0])}
    comps = [Comparison("order of the torque error in size/s (§816)", 2.0, m["torque_error_order"]),
             Comparison("order of the §818 force error in size/s", 2.0, m["force_error_order"])]
    notes = ["Across the run, F comes in from far away: the horizontal axis is size/distance (the largest semi-axis over s); exact values by Gauss quadrature "
             "over the homogeneous ellipsoid (16×16×32 points; converged to ~10⁻⁶ relative at s = 1.25 sizes)."]
    series = {"torque_rel_error": et, "force_rel_error": ef, "ratio_squared": ratios**2}
    traj.series.update(series)
    warnings = [f"The {what} error does not fall on a straight line against size/s (its points {off:.2f} decades "
                f"off the fitted line): for a body this near a sphere (semi-axes {_axes(a)}) the error at small sizes "
                "is the rounding of the exact quadrature, not the approximation's, so the fitted order is not its "
                "order. Make the semi-axes differ more."
                for what, err in (("torque", et), ("force", ef)) if (off := _off_line(ratios[sel], err[sel])) > OFF_LINE]
    return Run("gravity-gradient-accuracy", values, traj, m, comps, notes, plot_series=series, warnings=warnings)


OFF_LINE = 0.05  # decades: an error curve further than this from its fitted power law is not one


def _off_line(ratios, errors) -> float:
    """The largest distance (decades) of log10(error) from its least-squares line in log10(ratio)."""
    x, y = np.log10(ratios), np.log10(np.maximum(errors, 1e-300))
    fit = np.polyval(np.polyfit(x, y, 1), x)
    return float(np.max(np.abs(y - fit)))


def _axes(a) -> str:
    return ", ".join(f"{v:.8g}" for v in a)


F_VIEW = 2.8  # scene units (the body's largest semi-axis is 1): the farthest F of a sweep is drawn here


def _draw(run, spec, view):
    """The run is a sweep of F's distance s (trajectory.t = size/s), so playback brings F in from
    far away: F nearer at every frame, at its true distance at the nearest (`drawn_distance`; the
    caption says where it is drawn nearer),
    labelled with the relative errors of Euler's torque and of the §818 force at that distance
    (the run's plot_series)."""
    d, _ = body_scene(run, spec, view, bodies={})  # F is drawn at its distance, not on a sphere of directions
    d.pace = np.linspace(0.0, 1.0, d.n_frames)  # the distances are on a log scale: one each equal share of playback
    tr = run.trajectory
    if not view.option("attractor", spec) or "attractor" not in tr.bodies:
        return d
    f = d.frames
    dist = 1.0 / np.asarray(tr.t, float)[f]  # in sizes (largest semi-axis) from the centre
    drawn = drawn_distance(dist)
    pos = unit(np.asarray(tr.bodies["attractor"], float)[f]) * drawn[:, None]
    nan = np.full(len(tr.t), np.nan)
    et = np.asarray(run.plot_series.get("torque_rel_error", nan), float)[f]
    ef = np.asarray(run.plot_series.get("force_rel_error", nan), float)[f]
    text = [f"F at s = {s:.3g} sizes{' (drawn nearer, on a log scale)' if s > 1.001 * r else ''}: torque error "
            f"{100 * a:.2g} %, force error {100 * b:.2g} %" for s, r, a, b in zip(dist, drawn, et, ef)]
    d.add(Sphere(name="F", radius=0.1, color=F_COLOR, position=pos),
          Label(name="F/label", text="F", position=(0.0, 0.0, 0.22)),
          Label(name="F_readout", text=text, position=readout_position(d, down=2.0, left=1.8)),
          Segments(name="F_direction", points=line_from_centre(pos), colors=F_COLOR, thickness=0.012))
    return d


def drawn_distance(s: np.ndarray) -> np.ndarray:
    """Where F is drawn for true distances `s` (in sizes): the nearest at its true distance (or at
    0.75 F_VIEW if that is farther), the farthest at F_VIEW, those between on a log scale, so that F
    comes in at every frame of the sweep (100 sizes to 2: it waited at F_VIEW for all but the last
    frames while only the caption changed)."""
    s = np.asarray(s, float)
    near, far = float(np.min(s)), float(np.max(s))
    lo = min(near, 0.75 * F_VIEW)
    if far <= near * (1 + 1e-12):
        return np.full_like(s, lo)
    return lo + (F_VIEW - lo) * np.log(s / near) / np.log(far / near)


def _check_ratios(v):
    if not v["min_ratio"] < v["max_ratio"]:
        raise ParameterError("min_ratio", v["min_ratio"], f"less than max_ratio (here {v['max_ratio']:g})")


def _cost(values):
    """No integrator: one quadrature over the ellipsoid per distance; n_points samples, F's
    position and three series each."""
    n = values["n_points"]
    return Cost(0, n, trajectory_bytes(n, bodies=1, series=3))


register(Scenario(
    series_units={"attractor_[xyz]": "m", "omega_body_[xyz]": "rad/s", "L_body_[xyz]": "kg m^2/s", "energy": "J",
                  "(torque|force)_rel_error": "", "ratio_squared": ""},  # a body at rest: ω, L, E are 0
    name="gravity-gradient-accuracy",
    title="How good is Euler's first-order torque?",
    section="§815–818",
    group="ch. 16",
    summary=("Euler keeps only the first term of the pull in powers of size/distance (§816). Here the "
            "pull of F is integrated exactly over a homogeneous ellipsoid and compared with his "
            "formula at many distances: the relative error of his torque, and of the small extra force "
            "on the centre (§818), falls as (size/distance)². It reaches about 6% when F is only two "
            "body sizes away."),
    params=(
        Param("semi_axes", (1.0, 0.8, 0.6), 1e-3, 1e3, "m", "semi-axes a, b, c of the ellipsoid", kind="vec3",
              label="Semi-axes a, b, c"),
        Param("direction", (0.6, 0.5, 0.3), -1.0, 1.0, "", "direction of F in the body frame", kind="vec3",
              label="Direction of F in the body"),
        Param("min_ratio", 0.01, 1e-3, 0.5, "", "smallest size/distance", label="Smallest size / distance"),
        Param("max_ratio", 0.5, 0.01, 0.8, "", "largest size/distance (F outside the body)",
              label="Largest size / distance"),
        Param("n_points", 12, 3, 60, "", "number of distances", kind="int", label="Number of distances", advanced=True),
    ),
    camera=Camera((-2.0, 3.8, 2.2), (0.0, 0.0, 0.0)),
    overlays={'celestial': False, 'axis_trail': False, 'polhode': False, 'vectors': False},
    simulate_fn=_gg_accuracy,
    draw=_draw,
    options={"attractor": Option("F at its distance, with the errors there")},
    cost_fn=_cost,
    euler_formula=("τ = (3GM/s³) ŝ × I ŝ + O(size²/s²) (§815–816)"),
    check=lambda v: _check_ratios(v),
    presets=(
        ("Accuracy: F from 100 to 2 body sizes away", {}),
        ("Accuracy: a long needle", {"semi_axes": (1.0, 0.2, 0.2)}),
        ("Accuracy: nearly a sphere", {"semi_axes": (1.0, 0.98, 0.96)}),
    ),
    # the errors' orders are the slopes of log error against log size/distance
    metric_units={"torque_error_order": "", "force_error_order": "", r"(torque|force)_rel_error_at_(max|min)_ratio": ""},
))


# a homogeneous ellipsoid with three different axes, F in a generic direction
_SEMI = np.array([1.0, 0.8, 0.6])


_DIR = np.array([0.6, 0.5, 0.3])


@register_check("E5", "first-order torque 3GM/s³·ŝ×Iŝ vs exact integration over an ellipsoid", "§815–817")
def e5():
    ratios = np.array([0.1, 0.05, 0.025])
    err = torque_error_vs_size(_SEMI, _DIR, ratios)
    order = fitted_order(ratios, err)
    return {"euler": 2.0, "simulated": order, "modern": None, "rel_error": abs(order - 2.0) / 2.0,
            "tolerance": 0.02, "unit": "order in size/s",
            "note": (f"relative torque error {err[0]:.2e}, {err[1]:.2e}, {err[2]:.2e} at size/s = 0.1, 0.05, "
                     "0.025: order 2 expected (odd multipoles vanish for a centred symmetric body); the "
                     "O((size/s)⁴) term bends the fitted slope by ~(size/s)² ≈ 1%")}


@register_check("E6", "extra 1/s⁴ force on the centre of mass vs exact integration", "§818")
def e6():
    ratios = np.array([0.1, 0.05, 0.025])
    err = force_error_vs_size(_SEMI, _DIR, ratios)
    order = fitted_order(ratios, err)
    return {"euler": 2.0, "simulated": order, "modern": None, "rel_error": abs(order - 2.0) / 2.0,
            "tolerance": 0.02, "unit": "order in size/s",
            "note": (f"Euler's §818 force (monopole removed) off the exact one by {err[0]:.2e}, {err[1]:.2e}, "
                     f"{err[2]:.2e} at size/s = 0.1, 0.05, 0.025: the next term is O(s⁻⁶), relative (size/s)²")}
